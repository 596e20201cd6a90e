// Stable Neo-Hookean (Smith, de Goes, Kim 2018), Eq. 14 with the regularized origin barrier:
//   Psi = mu/2 (I_C - 3) + lambda/2 (J - alpha)^2 - mu/2 log(I_C + 1)  [- Psi(I), so Psi(I) = 0]
// with alpha = 1 + 3 mu / (4 lambda) (rest stability; the paper's printed Sec. 3.3 value is an erratum).
// Lame reparameterization (Eq. 15-16 as corrected): mu = 4/3 mu_L, lambda = lambda_L + 5/6 mu_L.
#pragma once

#include <sinew/materials/material.hpp>
#include <sinew/materials/mean_dilatation.hpp>

namespace sinew {

struct StableNeoHookean : InvariantModel<StableNeoHookean> {
  static constexpr const char* name = "stable-neohookean";
  static constexpr const char* equation = "Eq. 14 (Lame map Eq. 15-16)";
  using Options = NoOptions;
  double mu = 0, lambda = 0, alpha = 0, psi_rest = 0;

  static StableNeoHookean make(double mu_L, double lambda_L, const Options&) { return from_lame(mu_L, lambda_L); }
  // Eq. 15-16 need lambda > 0 after the reparameterization for alpha to exist.
  std::string invalid() const {
    return lambda > 0.0 ? "" : "stable-neohookean needs lambda_L + 5/6 mu_L > 0 (nu > -0.3125 roughly)";
  }

  static StableNeoHookean from_lame(double mu_L, double lambda_L) {
    StableNeoHookean m;
    m.mu = 4.0 / 3.0 * mu_L;
    m.lambda = lambda_L + 5.0 / 6.0 * mu_L;
    m.alpha = 1.0 + 3.0 * m.mu / (4.0 * m.lambda);
    m.psi_rest = m.energy(Mat3::identity());
    return m;
  }

  KOKKOS_INLINE_FUNCTION double energy(const Mat3& F) const {
    const double Ic = frobenius2(F), J = det(F);
    return 0.5 * mu * (Ic - 3.0) + 0.5 * lambda * (J - alpha) * (J - alpha) - 0.5 * mu * std::log(Ic + 1.0) -
           psi_rest;
  }

  // Eq. 18: P = mu (1 - 1/(I_C + 1)) F + lambda (J - alpha) dJ/dF
  KOKKOS_INLINE_FUNCTION Mat3 pk1(const Mat3& F) const {
    const double Ic = frobenius2(F), J = det(F);
    return (mu * (1.0 - 1.0 / (Ic + 1.0))) * F + (lambda * (J - alpha)) * cofactor(F);
  }

  // Its volume term lambda/2 (J - alpha)^2 (the rest does not depend on J): mean dilatation splits it off.
  KOKKOS_INLINE_FUNCTION VolumeTerm volume_term() const { return VolumeTerm{lambda, alpha}; }

  // Eq. 22 / 41 in the form of Eq. 52: mu_T Id + 2mu/(I_C+1)^2 f f^T + lambda g g^T + lambda (J - alpha) H_J.
  KOKKOS_INLINE_FUNCTION InvariantCoefficients coefficients(const Mat3& F) const {
    const double Ic = frobenius2(F), J = det(F);
    const double r = 1.0 / (Ic + 1.0);
    return InvariantCoefficients{mu * (1.0 - r), 2.0 * mu * r * r, lambda, lambda * (J - alpha)};
  }
};

}  // namespace sinew
