// Muscle fibres: an anisotropic energy density added to a region's isotropic law (the paper's
// materials are isotropic; this is the fibre term that production flesh tools put on muscles). With a
// the unit fibre direction at rest and lambda = |F a| the fibre stretch (lambda^2 = I5 = a^T F^T F a),
//
//   Psi_f(F) = psi(lambda) = k/2 (lambda - 1)^2 [lambda > 1]            passive: resists stretch only
//                          + alpha sigma (G(lambda) - G(1))            active: alpha in [0, 1] the activation
//
// where G' = g is the active force-length curve: 0 up to the contraction limit lambda_min, a smoothstep
// s^2 (3 - 2 s), s = (lambda - lambda_min) / (1 - lambda_min), up to the rest length, and 1 beyond. So the
// active fibre stress alpha sigma g(lambda) pulls the fibre shorter, and vanishes at lambda_min: an
// activated muscle shortens towards lambda_min and never past it (where psi is flat, nothing in this
// term pushes further). Psi_f is 0 at rest (lambda = 1) whatever the activation, and 0 at any F when
// k = 0 and alpha = 0.
//
// Derivatives (n = F a / lambda, the fibre's current direction):
//   P = dPsi_f/dF = psi'(lambda) n a^T
//   d2Psi_f/dF2 = psi''(lambda) vec(n a^T) vec(n a^T)^T + psi'(lambda)/lambda (I - n n^T) (x) a a^T
// The Hessian's eigen-system is closed-form (as for the sqrt(I5) energies of Kim and Eberle, "Dynamic
// Deformables", SIGGRAPH 2022 course, anisotropy chapter): eigenvalue psi'' on vec(n a^T), psi'/lambda on
// the two vec(t a^T) with t perpendicular to n, and 0 on the six vec(m b^T) with b perpendicular to a.
// Projection clamps (or takes the magnitude of) the two scalars. Here psi', psi'' >= 0 everywhere (g and
// g' are non-negative, the passive part is convex), so the exact Hessian is already PSD; the projection
// is kept so that another force-length curve (with a descending limb) stays safe.
#pragma once

#include <sinew/materials/material.hpp>

#include <cmath>
#include <string>

namespace sinew {

// The fibre law of one muscle: its parameters, trivially copyable (captured by value in a kernel).
struct FiberLaw {
  double stiffness = 0.0;   // k: the passive fibre's modulus in stretch (stress units)
  double max_stress = 0.0;  // sigma: the active stress at full activation, at and beyond rest length
  double limit = 0.6;       // lambda_min: the contraction limit, in (0, 1)

  // psi(lambda), psi'(lambda), psi''(lambda) at activation `alpha`.
  KOKKOS_INLINE_FUNCTION void curve(double lambda, double alpha, double& psi, double& d1, double& d2) const {
    psi = d1 = d2 = 0.0;
    if (lambda > 1.0) {
      const double x = lambda - 1.0;
      psi = 0.5 * stiffness * x * x;
      d1 = stiffness * x;
      d2 = stiffness;
    }
    if (alpha == 0.0) return;
    const double L = 1.0 - limit, as = alpha * max_stress;
    // G(lambda) - G(1): G(1) = L / 2 (the integral of the smoothstep over [lambda_min, 1]).
    if (lambda >= 1.0) {
      psi += as * (lambda - 1.0);
      d1 += as;
    } else if (lambda > limit) {
      const double s = (lambda - limit) / L;
      psi += as * (L * (s * s * s - 0.5 * s * s * s * s) - 0.5 * L);
      d1 += as * s * s * (3.0 - 2.0 * s);
      d2 += as * 6.0 * s * (1.0 - s) / L;
    } else {
      psi -= as * 0.5 * L;
    }
  }

  // Why these parameters make no fibre law ("" when they do).
  std::string invalid() const {
    if (!(stiffness >= 0.0) || !std::isfinite(stiffness)) return "'Fiber stiffness' must be >= 0";
    if (!(max_stress >= 0.0) || !std::isfinite(max_stress)) return "'Maximum stress' must be >= 0";
    if (!(limit > 0.0 && limit < 1.0)) return "'Contraction limit' must lie in (0, 1)";
    return "";
  }
};

// One element's fibre as a model of material.hpp's shape (energy, pk1, hessian, projected_hessian,
// defined), so the element loop's point evaluation serves it: the law, the unit fibre direction at rest
// and the activation now.
struct FiberPoint {
  FiberLaw law;
  double a[3] = {1.0, 0.0, 0.0};
  double activation = 0.0;

  KOKKOS_INLINE_FUNCTION bool defined(const Mat3&) const { return true; }
  // F a and its length lambda.
  KOKKOS_INLINE_FUNCTION double stretch(const Mat3& F, double Fa[3]) const {
    for (int i = 0; i < 3; ++i) Fa[i] = F(i, 0) * a[0] + F(i, 1) * a[1] + F(i, 2) * a[2];
    return std::sqrt(Fa[0] * Fa[0] + Fa[1] * Fa[1] + Fa[2] * Fa[2]);
  }
  KOKKOS_INLINE_FUNCTION double stretch(const Mat3& F) const {
    double Fa[3];
    return stretch(F, Fa);
  }
  KOKKOS_INLINE_FUNCTION double energy(const Mat3& F) const {
    double psi, d1, d2;
    law.curve(stretch(F), activation, psi, d1, d2);
    return psi;
  }
  KOKKOS_INLINE_FUNCTION Mat3 pk1(const Mat3& F) const {
    double Fa[3], psi, d1, d2;
    const double lambda = stretch(F, Fa);
    law.curve(lambda, activation, psi, d1, d2);
    Mat3 P = Mat3::zero();
    if (d1 == 0.0 || !(lambda > 0.0)) return P;  // psi' = 0 wherever lambda <= lambda_min
    for (int K = 0; K < 3; ++K)
      for (int i = 0; i < 3; ++i) P(i, K) = d1 * Fa[i] / lambda * a[K];
    return P;
  }
  // sum of e_n vec(n a^T) vec(n a^T)^T + e_t (I - n n^T) (x) a a^T, entry (i + 3K, j + 3L) (vec of Eq. 17).
  KOKKOS_INLINE_FUNCTION Mat9 assemble(double e_n, double e_t, const double n[3]) const {
    Mat9 H = Mat9::zero();
    for (int K = 0; K < 3; ++K)
      for (int i = 0; i < 3; ++i)
        for (int L = 0; L < 3; ++L)
          for (int j = 0; j < 3; ++j)
            H(i + 3 * K, j + 3 * L) = (e_n * n[i] * n[j] + e_t * ((i == j ? 1.0 : 0.0) - n[i] * n[j])) * a[K] * a[L];
    return H;
  }
  // The two non-zero eigenvalues (psi'' along vec(n a^T), psi'/lambda twice), and n.
  KOKKOS_INLINE_FUNCTION bool eigenvalues(const Mat3& F, double& e_n, double& e_t, double n[3]) const {
    double Fa[3], psi, d1, d2;
    const double lambda = stretch(F, Fa);
    law.curve(lambda, activation, psi, d1, d2);
    e_n = d2;
    e_t = lambda > 0.0 ? d1 / lambda : 0.0;
    if (!(lambda > 0.0) || (d1 == 0.0 && d2 == 0.0)) return false;
    for (int i = 0; i < 3; ++i) n[i] = Fa[i] / lambda;
    return true;
  }
  KOKKOS_INLINE_FUNCTION Mat9 hessian(const Mat3& F) const { return projected_hessian(F, Projection::None); }
  KOKKOS_INLINE_FUNCTION Mat9 projected_hessian(const Mat3& F, Projection p) const {
    double e_n, e_t, n[3];
    if (!eigenvalues(F, e_n, e_t, n)) return Mat9::zero();
    const Projection q = point_projection(p, det(F));
    return assemble(filter_eigenvalue(e_n, q), filter_eigenvalue(e_t, q), n);
  }
};

}  // namespace sinew
