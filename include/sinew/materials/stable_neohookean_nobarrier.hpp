// Stable Neo-Hookean without the origin barrier, Eq. 13 (Appendix D; meant for nu >= 0.4):
//   Psi = mu/2 (I_C - 3) - mu (J - 1) + lambda/2 (J - 1)^2
//       = mu/2 (I_C - 3) + lambda/2 (J - alpha)^2 + const,  alpha = 1 + mu/lambda.
// Lame reparameterization: mu = mu_L, lambda = lambda_L + mu_L. Hessian Eq. 65.
#pragma once

#include <sinew/materials/material.hpp>
#include <sinew/materials/mean_dilatation.hpp>

namespace sinew {

struct StableNeoHookeanNoBarrier : InvariantModel<StableNeoHookeanNoBarrier> {
  static constexpr const char* name = "stable-neohookean-nobarrier";
  static constexpr const char* equation = "Eq. 13 (Appendix D)";
  using Options = NoOptions;
  double mu = 0, lambda = 0, alpha = 0;

  static StableNeoHookeanNoBarrier make(double mu_L, double lambda_L, const Options&) { return from_lame(mu_L, lambda_L); }
  std::string invalid() const { return lambda > 0.0 ? "" : "stable-neohookean-nobarrier needs lambda_L + mu_L > 0"; }

  static StableNeoHookeanNoBarrier from_lame(double mu_L, double lambda_L) {
    StableNeoHookeanNoBarrier m;
    m.mu = mu_L;
    m.lambda = lambda_L + mu_L;
    m.alpha = 1.0 + m.mu / m.lambda;
    return m;
  }

  KOKKOS_INLINE_FUNCTION double energy(const Mat3& F) const {
    const double Ic = frobenius2(F), J = det(F);
    return 0.5 * mu * (Ic - 3.0) - mu * (J - 1.0) + 0.5 * lambda * (J - 1.0) * (J - 1.0);
  }

  KOKKOS_INLINE_FUNCTION Mat3 pk1(const Mat3& F) const {
    return mu * F + (lambda * (det(F) - alpha)) * cofactor(F);
  }

  // Its volume term lambda/2 (J - alpha)^2 (the rest does not depend on J): mean dilatation splits it off.
  KOKKOS_INLINE_FUNCTION VolumeTerm volume_term() const { return VolumeTerm{lambda, alpha}; }

  KOKKOS_INLINE_FUNCTION InvariantCoefficients coefficients(const Mat3& F) const {
    return InvariantCoefficients{mu, 0.0, lambda, lambda * (det(F) - alpha)};
  }
};

}  // namespace sinew
