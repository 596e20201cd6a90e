// The shared interface of Sinew's hyperelastic models and the eigen-system machinery they share.
//
// Every model is a small struct of parameters (trivially copyable, so it can be captured by value in a
// Kokkos kernel) with these KOKKOS_INLINE_FUNCTION members, all functions of the deformation gradient F:
//
//   double energy(const Mat3& F) const;                    // Psi(F), zero at rest
//   Mat3   pk1(const Mat3& F) const;                       // P = dPsi/dF
//   Mat9   hessian(const Mat3& F) const;                   // d2Psi/dvec(F)^2, vec as in Eq. 17
//   Mat9   projected_hessian(const Mat3& F, Projection) const;  // from the closed-form eigen-system
//   bool   defined(const Mat3& F) const;                   // false where Psi is +inf (Neo-Hookean, J<=0)
//
// and, on the host side, what the model list (model_list.hpp) needs to offer it to users:
//
//   static constexpr const char* name;                     // the XML "Model" value
//   static constexpr const char* equation;                 // where the paper defines it
//   using Options = ...;                                   // its parameters beyond (mu_L, lambda_L)
//   static Model make(double mu_L, double lambda_L, const Options&);
//   std::string invalid() const;                           // why these parameters make no stable
//                                                          // material ("" when they do)
//
// Options is a struct of numbers whose `visit` names each with its default, range and documentation
// (core/section.hpp): the model's parameters are declared next to its equations and nowhere else.
// Models never allocate and never call host-only code in their device members.
//
// All models here are isotropic, so their Hessian diagonalizes in the basis built from the
// rotation-variant SVD F = U Sigma V^T (Sec. 4.6, Appendix A): three "scaling" directions
// U diag(q) V^T, whose coefficients solve the 3x3 stretch-space Hessian d2Psi/dsigma2, and for each
// pair (i, j) of singular values a "twist" U (e_i e_j^T - e_j e_i^T) V^T / sqrt2 and a "flip"
// U (e_i e_j^T + e_j e_i^T) V^T / sqrt2 eigenvector with scalar eigenvalues. A model only has to give
// those scalars; `SigmaEigensystem::assemble` rebuilds the (projected) 9x9 matrix.
#pragma once

#include <sinew/core/section.hpp>
#include <sinew/core/small_matrix.hpp>
#include <sinew/core/sym_eigen.hpp>
#include <sinew/materials/svd3.hpp>

#include <string>

namespace sinew {

// The Options of a model whose only parameters are the two Lame constants.
struct NoOptions {
  template <class V>
  void visit(V&) {}
};

// How a Hessian is made positive semi-definite.
enum class Projection {
  None,   // the exact Hessian, indefinite wherever the energy is non-convex
  Clamp,  // negative eigenvalues set to zero (the paper, Sec. 4)
  Abs,    // negative eigenvalues replaced by their magnitude (Chen et al., SIGGRAPH 2024)
  // Per quadrature point: exact where J > 0, clamped (or abs) where the point is inverted. Newton near
  // convergence with a few inverted points: the rest of the body keeps its exact Hessian (and Newton
  // its quadratic convergence), the inverted points their descent guarantee.
  ExactUninvertedClamp,
  ExactUninvertedAbs
};

// The projection a point of Jacobian J gets.
KOKKOS_INLINE_FUNCTION Projection point_projection(Projection p, double J) {
  if (p == Projection::ExactUninvertedClamp) return J > 0.0 ? Projection::None : Projection::Clamp;
  if (p == Projection::ExactUninvertedAbs) return J > 0.0 ? Projection::None : Projection::Abs;
  return p;
}

KOKKOS_INLINE_FUNCTION double filter_eigenvalue(double e, Projection p) {
  if (p == Projection::Clamp) return e > 0.0 ? e : 0.0;
  if (p == Projection::Abs) return e >= 0.0 ? e : -e;
  return e;
}

// Pair k of singular values is (i, j) = ((k+1)%3, (k+2)%3); k is the "third" index, so the paper's
// twist/flip eigenvalues for pair k (Eq. 46-48) involve sigma_k.
struct SigmaEigensystem {
  Svd3 svd;
  double A[3][3];   // d2Psi/dsigma_i dsigma_j (scaling block)
  double twist[3];  // eigenvalue of U (e_i e_j^T - e_j e_i^T) V^T / sqrt2
  double flip[3];   // eigenvalue of U (e_i e_j^T + e_j e_i^T) V^T / sqrt2

  // Rank-one "unit" matrix U e_a e_b^T V^T = u_a v_b^T.
  KOKKOS_INLINE_FUNCTION Mat3 unit(int a, int b) const {
    Mat3 M;
    for (int c = 0; c < 3; ++c)
      for (int r = 0; r < 3; ++r) M(r, c) = svd.U(r, a) * svd.V(c, b);
    return M;
  }

  // Twist U (e_i e_j^T - e_j e_i^T) V^T / sqrt2 and flip U (e_i e_j^T + e_j e_i^T) V^T / sqrt2 of pair k.
  KOKKOS_INLINE_FUNCTION void pair_modes(int k, Mat3& T, Mat3& L) const {
    const double inv_sqrt2 = 0.70710678118654752440;
    const Mat3 Wij = unit((k + 1) % 3, (k + 2) % 3), Wji = unit((k + 2) % 3, (k + 1) % 3);
    T = inv_sqrt2 * (Wij - Wji);
    L = inv_sqrt2 * (Wij + Wji);
  }

  // All nine eigenpairs of the exact Hessian: evals[k] with unit eigenvector vec(Q[k]).
  // Order: scaling 0-2 (from a 3x3 symmetric eigen-solve of A), twist 3-5, flip 6-8 (pair k = 0..2).
  KOKKOS_INLINE_FUNCTION void eigenpairs(double evals[9], Mat3 Q[9]) const {
    double S[9], ev[3], W[9];
    for (int a = 0; a < 3; ++a)
      for (int b = 0; b < 3; ++b) S[3 * a + b] = A[a][b];
    jacobi_eigen<3>(S, ev, W);
    const Mat3 D[3] = {unit(0, 0), unit(1, 1), unit(2, 2)};
    for (int m = 0; m < 3; ++m) {
      evals[m] = ev[m];
      Q[m] = W[0 * 3 + m] * D[0] + W[1 * 3 + m] * D[1] + W[2 * 3 + m] * D[2];
    }
    for (int k = 0; k < 3; ++k) {
      pair_modes(k, Q[3 + k], Q[6 + k]);
      evals[3 + k] = twist[k];
      evals[6 + k] = flip[k];
    }
  }

  // Whether the scaling block A is positive definite (its leading principal minors are positive), in
  // which case every projection leaves it as it is.
  KOKKOS_INLINE_FUNCTION bool scaling_block_definite() const {
    const double m1 = A[0][0], m2 = A[0][0] * A[1][1] - A[0][1] * A[1][0];
    const double m3 = A[0][0] * (A[1][1] * A[2][2] - A[1][2] * A[2][1]) - A[0][1] * (A[1][0] * A[2][2] - A[1][2] * A[2][0]) +
                      A[0][2] * (A[1][0] * A[2][1] - A[1][1] * A[2][0]);
    return m1 > 0.0 && m2 > 0.0 && m3 > 0.0;
  }

  // sum_k filter(e_k) vec(Q_k) vec(Q_k)^T. The twist and flip eigenvalues are scalars; the scaling block
  // is used as is (sum_ab A_ab vec(D_a) vec(D_b)^T, no eigen-decomposition) for the exact Hessian and
  // whenever it is positive definite, which is the common case: the projection then only filters the
  // six scalars, and the result is the same matrix as through the eigenpairs.
  KOKKOS_INLINE_FUNCTION Mat9 assemble(Projection p) const {
    Mat9 H = Mat9::zero();
    if (p == Projection::None || scaling_block_definite()) {
      const Mat3 D[3] = {unit(0, 0), unit(1, 1), unit(2, 2)};
      for (int a = 0; a < 3; ++a)
        for (int b = 0; b < 3; ++b) H.add_outer(A[a][b], D[a], D[b]);
      for (int k = 0; k < 3; ++k) {
        Mat3 T, L;
        pair_modes(k, T, L);
        const double et = filter_eigenvalue(twist[k], p), el = filter_eigenvalue(flip[k], p);
        if (et != 0.0) H.add_sym_outer(et, T);
        if (el != 0.0) H.add_sym_outer(el, L);
      }
      return H;
    }
    double ev[9];
    Mat3 Q[9];
    eigenpairs(ev, Q);
    for (int m = 0; m < 9; ++m) {
      const double e = filter_eigenvalue(ev[m], p);
      if (e != 0.0) H.add_sym_outer(e, Q[m]);
    }
    return H;
  }

  // Smallest eigenvalue of the exact Hessian (for diagnostics and the material-point tool).
  KOKKOS_INLINE_FUNCTION double min_eigenvalue() const {
    double ev[9];
    Mat3 Q[9];
    eigenpairs(ev, Q);
    double m = ev[0];
    for (int k = 1; k < 9; ++k) m = ev[k] < m ? ev[k] : m;
    return m;
  }
};

// ---------------------------------------------------------------------------------------------
// Models written in the invariants I_C = ||F||^2 and J = det F (SNH Eq. 14, Eq. 13, Neo-Hookean
// Eq. 5, Fung Eq. 53, Arruda-Boyce Eq. 58) all have a Hessian of the form of Eq. 52:
//     H = gI * Id + gF * f f^T + gG * g g^T + gH * H_J,   f = vec(F), g = vec(dJ/dF).
// ---------------------------------------------------------------------------------------------
struct InvariantCoefficients {
  double gI, gF, gG, gH;
};

// Exact Hessian of Eq. 52 built directly in F space (no SVD needed).
KOKKOS_INLINE_FUNCTION Mat9 invariant_hessian(const Mat3& F, const InvariantCoefficients& c) {
  Mat9 H = Mat9::zero();
  H.add_identity(c.gI);
  if (c.gF != 0.0) H.add_sym_outer(c.gF, F);
  H.add_sym_outer(c.gG, cofactor(F));
  add_volume_hessian(H, c.gH, F);
  return H;
}

// Closed-form eigen-system of Eq. 52 (Sec. 4.6 with eta = gF/gH, rho = gG/gH as in Sec. 5.3):
// twist/flip eigenvalues gI +- gH * sigma_k (Eq. 46-48), and the scaling block in stretch space,
//   A_ii = gI + gF s_i^2 + gG (s_j s_k)^2,   A_ij = gF s_i s_j + gG s_k J + gH s_k,
// whose eigenvalues are the roots of the cubic Eq. 42 (solved here as a 3x3 symmetric problem,
// which stays robust when roots coincide).
KOKKOS_INLINE_FUNCTION SigmaEigensystem invariant_eigensystem(const Svd3& d, const InvariantCoefficients& c) {
  SigmaEigensystem es;
  es.svd = d;
  const double* s = d.s;
  const double g[3] = {s[1] * s[2], s[0] * s[2], s[0] * s[1]};
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) {
      double a = c.gF * s[i] * s[j] + c.gG * g[i] * g[j];
      if (i == j)
        a += c.gI;
      else
        a += c.gH * s[3 - i - j];
      es.A[i][j] = a;
    }
  }
  for (int k = 0; k < 3; ++k) {
    es.twist[k] = c.gI + c.gH * s[k];
    es.flip[k] = c.gI - c.gH * s[k];
  }
  return es;
}

// Divided differences used by the stretch-space models for the twist and flip eigenvalues
// (Psi_i + Psi_j)/(s_i + s_j) and (Psi_i - Psi_j)/(s_i - s_j). When the denominator vanishes the
// limit is the one of a symmetric energy: A_ii + A_ij (twist) or A_ii - A_ij (flip). Models whose
// limit does not exist (corotational at s_i = -s_j) handle that themselves before calling these.
KOKKOS_INLINE_FUNCTION double flip_quotient(double dpi, double dpj, double si, double sj, double Aii, double Aij) {
  const double den = si - sj;
  const double scale = std::fabs(si) + std::fabs(sj) + 1e-300;
  if (std::fabs(den) > 1e-7 * scale) return (dpi - dpj) / den;
  return Aii - Aij;
}
KOKKOS_INLINE_FUNCTION double twist_quotient(double dpi, double dpj, double si, double sj, double Aii, double Aij) {
  const double den = si + sj;
  const double scale = std::fabs(si) + std::fabs(sj) + 1e-300;
  if (std::fabs(den) > 1e-7 * scale) return (dpi + dpj) / den;
  return Aii + Aij;
}

// PK1 of a stretch-space energy: P = U diag(dPsi/dsigma) V^T.
KOKKOS_INLINE_FUNCTION Mat3 pk1_from_sigma(const Svd3& d, const double dpsi[3]) {
  return d.U * Mat3::diag(dpsi[0], dpsi[1], dpsi[2]) * transpose(d.V);
}

// ---------------------------------------------------------------------------------------------
// CRTP bases: a model supplies only its physics; the plumbing to Hessians and projections is shared.
// ---------------------------------------------------------------------------------------------

// For models of Eq. 52 form. Derived provides `InvariantCoefficients coefficients(const Mat3& F)`.
template <class Derived>
struct InvariantModel {
  KOKKOS_INLINE_FUNCTION bool defined(const Mat3&) const { return true; }
  KOKKOS_INLINE_FUNCTION Mat9 hessian(const Mat3& F) const { return invariant_hessian(F, self().coefficients(F)); }
  KOKKOS_INLINE_FUNCTION SigmaEigensystem eigensystem(const Mat3& F) const {
    return invariant_eigensystem(svd3(F), self().coefficients(F));
  }
  KOKKOS_INLINE_FUNCTION Mat9 projected_hessian(const Mat3& F, Projection p) const {
    if (p == Projection::None) return hessian(F);
    return eigensystem(F).assemble(p);
  }

 private:
  KOKKOS_INLINE_FUNCTION const Derived& self() const { return static_cast<const Derived&>(*this); }
};

// For models written in the singular values. Derived provides
//   double psi_sigma(const double s[3]) const;
//   void sigma_terms(const double s[3], double dpsi[3], SigmaEigensystem& es) const;
// where sigma_terms fills dpsi = dPsi/dsigma and es.A, es.twist, es.flip.
template <class Derived>
struct SigmaModel {
  KOKKOS_INLINE_FUNCTION bool defined(const Mat3&) const { return true; }
  KOKKOS_INLINE_FUNCTION double energy(const Mat3& F) const { return self().psi_sigma(svd3(F).s); }
  KOKKOS_INLINE_FUNCTION Mat3 pk1(const Mat3& F) const {
    SigmaEigensystem es;
    es.svd = svd3(F);
    double dpsi[3];
    self().sigma_terms(es.svd.s, dpsi, es);
    return pk1_from_sigma(es.svd, dpsi);
  }
  KOKKOS_INLINE_FUNCTION SigmaEigensystem eigensystem(const Mat3& F) const {
    SigmaEigensystem es;
    es.svd = svd3(F);
    double dpsi[3];
    self().sigma_terms(es.svd.s, dpsi, es);
    return es;
  }
  KOKKOS_INLINE_FUNCTION Mat9 hessian(const Mat3& F) const { return eigensystem(F).assemble(Projection::None); }
  KOKKOS_INLINE_FUNCTION Mat9 projected_hessian(const Mat3& F, Projection p) const {
    return eigensystem(F).assemble(p);
  }

 private:
  KOKKOS_INLINE_FUNCTION const Derived& self() const { return static_cast<const Derived&>(*this); }
};

}  // namespace sinew
