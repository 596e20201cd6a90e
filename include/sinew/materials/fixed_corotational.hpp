// "Fixed" corotational (Stomakhin et al. 2012), Eq. 49:
//   Psi = mu ||F - R||_F^2 + lambda/2 (J - 1)^2 = mu sum (s_i - 1)^2 + lambda/2 (s0 s1 s2 - 1)^2.
// Twist eigenvalue 2 mu + lambda (J - 1) s_k - 4 mu/(s_i + s_j), flip 2 mu - lambda (J - 1) s_k.
#pragma once

#include <sinew/materials/corotational.hpp>

namespace sinew {

struct FixedCorotational : SigmaModel<FixedCorotational> {
  static constexpr const char* name = "fixed-corotational";
  static constexpr const char* equation = "Eq. 49";
  using Options = NoOptions;
  double mu = 0, lambda = 0;

  static FixedCorotational make(double mu_L, double lambda_L, const Options&) { return from_lame(mu_L, lambda_L); }
  std::string invalid() const { return ""; }

  static FixedCorotational from_lame(double mu_L, double lambda_L) {
    FixedCorotational m;
    m.mu = mu_L;
    m.lambda = lambda_L;
    return m;
  }

  KOKKOS_INLINE_FUNCTION double psi_sigma(const double s[3]) const {
    const double J = s[0] * s[1] * s[2];
    double e = 0.0;
    for (int i = 0; i < 3; ++i) e += (s[i] - 1.0) * (s[i] - 1.0);
    return mu * e + 0.5 * lambda * (J - 1.0) * (J - 1.0);
  }

  KOKKOS_INLINE_FUNCTION void sigma_terms(const double s[3], double dpsi[3], SigmaEigensystem& es) const {
    const double J = s[0] * s[1] * s[2];
    const double g[3] = {s[1] * s[2], s[0] * s[2], s[0] * s[1]};
    for (int i = 0; i < 3; ++i) {
      dpsi[i] = 2.0 * mu * (s[i] - 1.0) + lambda * (J - 1.0) * g[i];
      for (int j = 0; j < 3; ++j)
        es.A[i][j] = lambda * g[i] * g[j] + (i == j ? 2.0 * mu : lambda * (J - 1.0) * s[3 - i - j]);
    }
    for (int k = 0; k < 3; ++k) {
      const int i = (k + 1) % 3, j = (k + 2) % 3;
      es.flip[k] = 2.0 * mu - lambda * (J - 1.0) * s[k];
      es.twist[k] = 2.0 * mu + lambda * (J - 1.0) * s[k] - 4.0 * mu / floored_pair_sum(s[i], s[j]);
    }
  }
};

}  // namespace sinew
