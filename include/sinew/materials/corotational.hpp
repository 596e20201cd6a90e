// Corotational elasticity, Eq. 3 (McAdams et al. 2011, Irving et al. 2004):
//   Psi = mu ||F - R||_F^2 + lambda/2 tr^2(S - I),  F = R S from the rotation-variant SVD.
// In singular values: Psi = mu sum (s_i - 1)^2 + lambda/2 (sum s_i - 3)^2.
// Note: differentiating Eq. 3 gives P = R [2 mu (S - I) + lambda tr(S - I) I]; Eq. 4 prints mu instead of
// 2 mu, which belongs to the mu/2 ||F - R||^2 form of Sec. 5.1. With Eq. 3 as written, (mu, lambda) are
// the Lame constants (checked against Hooke's law in the tests).
// The twist eigenvalue 2 mu + (2 lambda (tr S - 3) - 4 mu)/(s_i + s_j) is singular at s_i = -s_j
// (the rotation is undefined there); its denominator is floored in magnitude at 1e-6.
#pragma once

#include <sinew/materials/material.hpp>

namespace sinew {

KOKKOS_INLINE_FUNCTION double floored_pair_sum(double si, double sj) {
  const double d = si + sj;
  const double floor = 1e-6;
  if (d >= 0.0) return d > floor ? d : floor;
  return d < -floor ? d : -floor;
}

struct Corotational : SigmaModel<Corotational> {
  static constexpr const char* name = "corotational";
  static constexpr const char* equation = "Eq. 3";
  using Options = NoOptions;
  double mu = 0, lambda = 0;

  static Corotational make(double mu_L, double lambda_L, const Options&) { return from_lame(mu_L, lambda_L); }
  std::string invalid() const { return ""; }

  static Corotational from_lame(double mu_L, double lambda_L) {
    Corotational m;
    m.mu = mu_L;
    m.lambda = lambda_L;
    return m;
  }

  KOKKOS_INLINE_FUNCTION double psi_sigma(const double s[3]) const {
    const double t = s[0] + s[1] + s[2] - 3.0;
    double e = 0.0;
    for (int i = 0; i < 3; ++i) e += (s[i] - 1.0) * (s[i] - 1.0);
    return mu * e + 0.5 * lambda * t * t;
  }

  KOKKOS_INLINE_FUNCTION void sigma_terms(const double s[3], double dpsi[3], SigmaEigensystem& es) const {
    const double t = s[0] + s[1] + s[2] - 3.0;
    for (int i = 0; i < 3; ++i) {
      dpsi[i] = 2.0 * mu * (s[i] - 1.0) + lambda * t;
      for (int j = 0; j < 3; ++j) es.A[i][j] = lambda + (i == j ? 2.0 * mu : 0.0);
    }
    for (int k = 0; k < 3; ++k) {
      const int i = (k + 1) % 3, j = (k + 2) % 3;
      es.flip[k] = 2.0 * mu;
      es.twist[k] = 2.0 * mu + (2.0 * lambda * t - 4.0 * mu) / floored_pair_sum(s[i], s[j]);
    }
  }
};

}  // namespace sinew
