// St. Venant-Kirchhoff, Eq. 50, optionally with the compression term of Kikuuwe et al. 2009, Eq. 51:
//   Psi = mu ||E||_F^2 + lambda/2 tr^2(E) + kappa/12 ((1 - J)/6)^3 [J < 1 only],  E = (F^T F - I)/2.
// kappa = 0 gives plain StVK (Eq. 50). The Kikuuwe term is C2 at J = 1 and a function of J alone, so it
// adds K'(J) (+-s_k) to the twist/flip eigenvalues and K'' g g^T + K' d2J/dsigma2 to the scaling block.
#pragma once

#include <sinew/materials/material.hpp>

#include <optional>

namespace sinew {

struct StVK : SigmaModel<StVK> {
  static constexpr const char* name = "stvk";
  static constexpr const char* equation = "Eq. 50";
  using Options = NoOptions;
  double mu = 0, lambda = 0, kappa = 0;

  static StVK make(double mu_L, double lambda_L, const Options&) { return from_lame(mu_L, lambda_L, 0.0); }
  std::string invalid() const { return ""; }

  static StVK from_lame(double mu_L, double lambda_L, double kappa = 0.0) {
    StVK m;
    m.mu = mu_L;
    m.lambda = lambda_L;
    m.kappa = kappa;
    return m;
  }

  // Kikuuwe term K(J) and its first two derivatives.
  KOKKOS_INLINE_FUNCTION void kikuuwe(double J, double& K, double& K1, double& K2) const {
    if (kappa == 0.0 || J >= 1.0) {
      K = K1 = K2 = 0.0;
      return;
    }
    const double x = (1.0 - J) / 6.0;
    K = kappa / 12.0 * x * x * x;
    K1 = -kappa / 24.0 * x * x;
    K2 = kappa / 72.0 * x;
  }

  KOKKOS_INLINE_FUNCTION double psi_sigma(const double s[3]) const {
    double E[3], tr = 0.0, e2 = 0.0;
    for (int i = 0; i < 3; ++i) {
      E[i] = 0.5 * (s[i] * s[i] - 1.0);
      tr += E[i];
      e2 += E[i] * E[i];
    }
    double K, K1, K2;
    kikuuwe(s[0] * s[1] * s[2], K, K1, K2);
    return mu * e2 + 0.5 * lambda * tr * tr + K;
  }

  KOKKOS_INLINE_FUNCTION void sigma_terms(const double s[3], double dpsi[3], SigmaEigensystem& es) const {
    double E[3], tr = 0.0;
    for (int i = 0; i < 3; ++i) {
      E[i] = 0.5 * (s[i] * s[i] - 1.0);
      tr += E[i];
    }
    const double g[3] = {s[1] * s[2], s[0] * s[2], s[0] * s[1]};
    double K, K1, K2;
    kikuuwe(s[0] * s[1] * s[2], K, K1, K2);
    for (int i = 0; i < 3; ++i) {
      dpsi[i] = s[i] * (2.0 * mu * E[i] + lambda * tr) + K1 * g[i];
      for (int j = 0; j < 3; ++j) {
        double a = lambda * s[i] * s[j] + K2 * g[i] * g[j];
        if (i == j)
          a += 2.0 * mu * E[i] + lambda * tr + 2.0 * mu * s[i] * s[i];
        else
          a += K1 * s[3 - i - j];
        es.A[i][j] = a;
      }
    }
    for (int k = 0; k < 3; ++k) {
      const int i = (k + 1) % 3, j = (k + 2) % 3;
      const double si = s[i], sj = s[j];
      es.flip[k] = mu * (si * si + si * sj + sj * sj - 1.0) + lambda * tr - K1 * s[k];
      es.twist[k] = mu * (si * si - si * sj + sj * sj - 1.0) + lambda * tr + K1 * s[k];
    }
  }
};

// StVK with the Kikuuwe compression term (Eq. 51): the same energy with kappa > 0.
struct StVKKikuuwe : StVK {
  static constexpr const char* name = "stvk-kikuuwe";
  static constexpr const char* equation = "Eq. 51";
  struct Options {
    std::optional<double> kappa;
    template <class V>
    void visit(V& v) {
      v.optional("Kikuuwe kappa", kappa, "stvk-kikuuwe: compression stiffness kappa of Eq. 51 (default 1e4 E)",
                 Range::positive());
    }
  };

  static StVKKikuuwe make(double mu_L, double lambda_L, const Options& o) {
    // The term is tiny near J = 1 (Eq. 51), so a useful kappa scales with the stiffness: 1e4 E by default.
    const double E = mu_L * (3.0 * lambda_L + 2.0 * mu_L) / (lambda_L + mu_L);
    StVKKikuuwe m;
    static_cast<StVK&>(m) = from_lame(mu_L, lambda_L, o.kappa.value_or(1.0e4 * E));
    return m;
  }
  std::string invalid() const { return kappa > 0.0 ? "" : "'Kikuuwe kappa' must be positive"; }
};

}  // namespace sinew
