// Shared helpers for material tests: random deformation gradients, finite differences, LAPACK eigen.
#pragma once

#include <sinew/materials/parameters.hpp>

#include <Teuchos_LAPACK.hpp>

#include <algorithm>
#include <array>
#include <random>
#include <string>
#include <vector>

namespace sinew::test {

inline Mat3 random_rotation(std::mt19937_64& rng) {
  std::normal_distribution<double> n(0.0, 1.0);
  double q[4], len = 0.0;
  for (double& x : q) {
    x = n(rng);
    len += x * x;
  }
  len = std::sqrt(len);
  return rotation_of_quaternion(q[0] / len, q[1] / len, q[2] / len, q[3] / len);
}

inline Mat3 with_singular_values(std::mt19937_64& rng, double s0, double s1, double s2) {
  return random_rotation(rng) * Mat3::diag(s0, s1, s2) * transpose(random_rotation(rng));
}

struct Sample {
  Mat3 F;
  std::string kind;
};

// Deformation gradients of every kind the issue asks for. Singular values of inverted samples keep
// s1 - |s2| >= 0.1: models whose energy depends on where the reflection sits (corotational, filtered
// Neo-Hookean) have a kink where |s1| = |s2| with s2 < 0, which no finite difference can cross.
inline std::vector<Sample> sample_deformations(std::mt19937_64& rng, int per_kind, bool include_inverted = true) {
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::vector<Sample> out;
  auto sorted = [](double a, double b, double c) {
    std::array<double, 3> s{a, b, c};
    std::sort(s.begin(), s.end(), [](double x, double y) { return x > y; });
    return s;
  };
  for (int n = 0; n < per_kind; ++n) {
    auto s = sorted(0.3 + 2.2 * u(rng), 0.3 + 2.2 * u(rng), 0.3 + 2.2 * u(rng));
    out.push_back({with_singular_values(rng, s[0], s[1], s[2]), "general"});
    // Nearly flat: one singular value ~1e-3.
    s = sorted(0.4 + 1.5 * u(rng), 0.4 + 1.5 * u(rng), 0.0);
    out.push_back({with_singular_values(rng, s[0], s[1], 1e-3 * (0.5 + u(rng))), "nearly flat"});
    // Nearly collapsed to a line: two singular values ~1e-3.
    const double a = 0.5 + 2.0 * u(rng), b = 1e-3 * (1.5 + u(rng)), c = 1e-3 * (0.2 + u(rng)) * 0.5;
    out.push_back({with_singular_values(rng, a, b, c), "nearly collapsed"});
    // Repeated singular values.
    const double r = 0.5 + u(rng);
    out.push_back({with_singular_values(rng, r + 0.7, r, r), "repeated"});
    out.push_back({with_singular_values(rng, r, r, r), "isotropic"});
    if (include_inverted) {
      s = sorted(0.5 + 1.5 * u(rng), 0.5 + 1.5 * u(rng), 0.0);
      const double s2 = -(0.05 + (s[1] - 0.1 - 0.05) * u(rng));
      out.push_back({with_singular_values(rng, s[0], s[1], s2), "inverted"});
    }
  }
  return out;
}

inline double norm(const Mat3& A) { return std::sqrt(frobenius2(A)); }
inline double norm(const Mat9& H) {
  double s = 0;
  for (double x : H.a) s += x * x;
  return std::sqrt(s);
}

inline double norm_diff(const Mat9& A, const Mat9& B) {
  Mat9 D;
  for (int k = 0; k < 81; ++k) D.a[k] = A.a[k] - B.a[k];
  return norm(D);
}

// Finite-difference step for F: `base` times the smallest |singular value| (floored at 1e-4, capped at 1),
// since energies with a log J or 1/(s_i + s_j) term curve on that length scale.
inline double fd_step(const Mat3& F, double base) {
  const Svd3 d = svd3(F);
  const double smin = std::min({std::fabs(d.s[0]), std::fabs(d.s[1]), std::fabs(d.s[2])});
  return base * std::min(1.0, std::max(smin, 1e-4));
}

// Central-difference gradient of the energy.
template <class M>
Mat3 fd_pk1(const M& m, const Mat3& F, double h) {
  Mat3 P;
  for (int k = 0; k < 9; ++k) {
    Mat3 Fp = F, Fm = F;
    Fp[k] += h;
    Fm[k] -= h;
    P[k] = (m.energy(Fp) - m.energy(Fm)) / (2.0 * h);
  }
  return P;
}

// Central-difference Jacobian of PK1: column c = d vec(P) / d vec(F)_c.
template <class M>
Mat9 fd_hessian(const M& m, const Mat3& F, double h) {
  Mat9 H;
  for (int c = 0; c < 9; ++c) {
    Mat3 Fp = F, Fm = F;
    Fp[c] += h;
    Fm[c] -= h;
    const Mat3 Pp = m.pk1(Fp), Pm = m.pk1(Fm);
    for (int r = 0; r < 9; ++r) H(r, c) = (Pp[r] - Pm[r]) / (2.0 * h);
  }
  return H;
}

// LAPACK dsyev: eigenvalues ascending and eigenvectors (column k of Z, column-major) of a symmetric H.
inline void lapack_eigen(const Mat9& H, std::array<double, 9>& w, std::array<double, 81>& Z) {
  Teuchos::LAPACK<int, double> lapack;
  for (int r = 0; r < 9; ++r)
    for (int c = 0; c < 9; ++c) Z[r + 9 * c] = 0.5 * (H(r, c) + H(c, r));
  std::array<double, 64 * 9> work;
  int info = 0;
  lapack.SYEV('V', 'U', 9, Z.data(), 9, w.data(), work.data(), static_cast<int>(work.size()), &info);
  if (info != 0) throw std::runtime_error("dsyev failed");
}

// Numerical projection: eigen-decompose with LAPACK and filter the eigenvalues.
inline Mat9 lapack_projected(const Mat9& H, Projection p) {
  std::array<double, 9> w;
  std::array<double, 81> Z;
  lapack_eigen(H, w, Z);
  Mat9 out = Mat9::zero();
  for (int k = 0; k < 9; ++k) {
    const double e = filter_eigenvalue(w[k], p);
    for (int r = 0; r < 9; ++r)
      for (int c = 0; c < 9; ++c) out(r, c) += e * Z[r + 9 * k] * Z[c + 9 * k];
  }
  return out;
}

// Whether a model's energy exists for inverted F (Neo-Hookean's log J does not): tests then leave
// inverted samples out, whatever the model, so that a new model needs no test edits.
inline bool defined_when_inverted(const MaterialSpec& spec) {
  return with_material(spec, [](const auto& m) { return m.defined(Mat3::diag(1.0, 1.0, -1.0)); });
}

// Every model of the library at one (E, nu), with the default model parameters.
inline std::vector<MaterialSpec> all_models(double E, double nu) {
  std::vector<MaterialSpec> out;
  for (std::size_t k = 0; k < material_model_names().size(); ++k)
    out.push_back(material_defaults(static_cast<MaterialModel>(k), E / (2.0 * (1.0 + nu)), E * nu / ((1.0 + nu) * (1.0 - 2.0 * nu))));
  return out;
}

}  // namespace sinew::test
