// Classical Neo-Hookean, Eq. 5:  Psi = mu/2 (I_C - 3) - mu log J + lambda/2 (log J)^2.
// Defined only for J > 0: there the energy is +inf and `defined` is false, while P and the Hessian
// stay finite (mu F and mu Id) so that no NaN can enter an assembled system; callers that see an
// undefined point must reject the state (the line search does).
// Its Hessian has the form of Eq. 52 with gI = mu, gF = 0, gG = (lambda (1 - log J) + mu)/J^2,
// gH = (lambda log J - mu)/J, so the closed-form eigen-system of Sec. 4.6 applies.
#pragma once

#include <sinew/materials/material.hpp>

namespace sinew {

struct NeoHookean : InvariantModel<NeoHookean> {
  static constexpr const char* name = "neohookean";
  static constexpr const char* equation = "Eq. 5";
  using Options = NoOptions;
  double mu = 0, lambda = 0;

  static NeoHookean make(double mu_L, double lambda_L, const Options&) { return from_lame(mu_L, lambda_L); }
  std::string invalid() const { return ""; }

  static NeoHookean from_lame(double mu_L, double lambda_L) {
    NeoHookean m;
    m.mu = mu_L;
    m.lambda = lambda_L;
    return m;
  }

  KOKKOS_INLINE_FUNCTION bool defined(const Mat3& F) const { return det(F) > 0.0; }

  KOKKOS_INLINE_FUNCTION double energy(const Mat3& F) const {
    const double J = det(F);
    if (!(J > 0.0)) return HUGE_VAL;
    const double lJ = std::log(J);
    return 0.5 * mu * (frobenius2(F) - 3.0) - mu * lJ + 0.5 * lambda * lJ * lJ;
  }

  KOKKOS_INLINE_FUNCTION Mat3 pk1(const Mat3& F) const {
    const double J = det(F);
    if (!(J > 0.0)) return mu * F;
    return mu * F + ((lambda * std::log(J) - mu) / J) * cofactor(F);
  }

  KOKKOS_INLINE_FUNCTION InvariantCoefficients coefficients(const Mat3& F) const {
    const double J = det(F);
    if (!(J > 0.0)) return InvariantCoefficients{mu, 0.0, 0.0, 0.0};
    const double lJ = std::log(J);
    return InvariantCoefficients{mu, 0.0, (lambda * (1.0 - lJ) + mu) / (J * J), (lambda * lJ - mu) / J};
  }
};

}  // namespace sinew
