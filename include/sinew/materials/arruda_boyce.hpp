// Arruda-Boyce, three-term form of Eq. 58:
//   Psi = mu/2 (I_C - 3) + mu b1/4 (I_C^2 - 9) + mu b2/6 (I_C^3 - 27) + lambda/2 (J - alpha)^2   [- Psi(I)]
// P (Eq. 59) = mu (1 + b1 I_C + b2 I_C^2) F + lambda (J - alpha) dJ/dF, alpha = 1 + mu/lambda (1 + 3 b1 + 9 b2).
// Hessian Eq. 60: gI = mu (1 + b1 I_C + b2 I_C^2), gF = 2 mu (b1 + 2 b2 I_C), gG = lambda, gH = lambda (J - alpha).
//
// Parameters: b1, b2 >= 0 (hardening) and the small-strain response of Hooke's law with (mu_L, lambda_L):
// mu (1 + 3 b1 + 9 b2) = mu_L and lambda = lambda_L + mu_L - 2 mu (b1 + 6 b2).
#pragma once

#include <sinew/materials/material.hpp>

#include <sstream>

namespace sinew {

struct ArrudaBoyce : InvariantModel<ArrudaBoyce> {
  static constexpr const char* name = "arruda-boyce";
  static constexpr const char* equation = "Eq. 58";
  struct Options {
    double beta1, beta2;
    template <class V>
    void visit(V& v) {
      v.entry("Arruda-Boyce beta1", beta1, 0.05, "arruda-boyce: beta1 of Eq. 58", Range::non_negative());
      v.entry("Arruda-Boyce beta2", beta2, 0.005, "arruda-boyce: beta2 of Eq. 58", Range::non_negative());
    }
  };
  double mu = 0, lambda = 0, b1 = 0, b2 = 0, alpha = 0, psi_rest = 0;

  static ArrudaBoyce make(double mu_L, double lambda_L, const Options& o) { return from_lame(mu_L, lambda_L, o.beta1, o.beta2); }
  std::string invalid() const {
    if (lambda > 0.0) return "";
    std::ostringstream os;
    os.precision(6);
    os << "'Arruda-Boyce beta1'/'beta2' leave a non-positive volume stiffness lambda = " << lambda << " at rest";
    return os.str();
  }

  static ArrudaBoyce from_lame(double mu_L, double lambda_L, double beta1, double beta2) {
    ArrudaBoyce m;
    m.b1 = beta1;
    m.b2 = beta2;
    m.mu = mu_L / (1.0 + 3.0 * beta1 + 9.0 * beta2);
    m.lambda = lambda_L + mu_L - 2.0 * m.mu * (beta1 + 6.0 * beta2);
    m.alpha = 1.0 + m.mu / m.lambda * (1.0 + 3.0 * beta1 + 9.0 * beta2);
    m.psi_rest = m.energy(Mat3::identity());
    return m;
  }

  KOKKOS_INLINE_FUNCTION double energy(const Mat3& F) const {
    const double Ic = frobenius2(F), J = det(F);
    return 0.5 * mu * (Ic - 3.0) + 0.25 * mu * b1 * (Ic * Ic - 9.0) + mu * b2 / 6.0 * (Ic * Ic * Ic - 27.0) +
           0.5 * lambda * (J - alpha) * (J - alpha) - psi_rest;
  }

  KOKKOS_INLINE_FUNCTION Mat3 pk1(const Mat3& F) const {
    const double Ic = frobenius2(F), J = det(F);
    return (mu * (1.0 + b1 * Ic + b2 * Ic * Ic)) * F + (lambda * (J - alpha)) * cofactor(F);
  }

  KOKKOS_INLINE_FUNCTION InvariantCoefficients coefficients(const Mat3& F) const {
    const double Ic = frobenius2(F), J = det(F);
    return InvariantCoefficients{mu * (1.0 + b1 * Ic + b2 * Ic * Ic), 2.0 * mu * (b1 + 2.0 * b2 * Ic), lambda,
                                 lambda * (J - alpha)};
  }
};

}  // namespace sinew
