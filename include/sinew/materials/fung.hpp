// Stabilized Fung hardening, Eq. 53:
//   Psi = mu0/2 (I_C - 3) + lambda/2 (J - alpha)^2 + gamma/2 (exp(mu1/2 (I_C - 3)) - 1)   [- Psi(I)]
//
// Erratum (checked by finite differences in tests/test_materials.cpp): differentiating Eq. 53 gives
//   P = (mu0 + gamma mu1/2 e) F + lambda (J - alpha) dJ/dF,   e = exp(mu1/2 (I_C - 3)),
// i.e. half the exponential term printed in Eq. 54, and the Eq. 52 coefficients
//   gI = mu0 + gamma mu1/2 e,  gF = gamma mu1^2/2 e,  gG = lambda,  gH = lambda (J - alpha)
// (Eq. 55-56 print gamma mu1 and 2 gamma mu1^2); rest stability then needs
// alpha = 1 + (mu0 + gamma mu1/2)/lambda. We follow the energy, Eq. 53.
//
// Parameters: the small-strain response equals Hooke's law with (mu_L, lambda_L). The user picks the
// fraction f in [0, 1) of the small-strain shear modulus carried by the exponential term and the
// hardening exponent mu1 > 0; then gamma mu1/2 = f mu_L, mu0 = (1 - f) mu_L and
// lambda = lambda_L + mu_L - gamma mu1^2/2 (from matching the rest Hessian to Hooke's).
#pragma once

#include <sinew/materials/material.hpp>

#include <sstream>

namespace sinew {

struct Fung : InvariantModel<Fung> {
  static constexpr const char* name = "fung";
  static constexpr const char* equation = "Eq. 53";
  struct Options {
    double fraction, exponent;
    template <class V>
    void visit(V& v) {
      v.entry("Fung fraction", fraction, 0.5,
              "fung: share f of the small-strain shear modulus carried by the exponential term", Range::closed_open(0.0, 1.0));
      v.entry("Fung exponent", exponent, 1.0, "fung: hardening exponent mu1 of Eq. 53", Range::positive());
    }
  };
  double mu0 = 0, lambda = 0, gamma = 0, mu1 = 0, alpha = 0, psi_rest = 0;
  Options options{};

  static Fung make(double mu_L, double lambda_L, const Options& o) { return from_lame(mu_L, lambda_L, o.fraction, o.exponent); }
  std::string invalid() const {
    if (lambda > 0.0) return "";
    std::ostringstream os;
    os.precision(6);
    os << "'Fung exponent' " << options.exponent << " with 'Fung fraction' " << options.fraction
       << " leaves a non-positive volume stiffness lambda = " << lambda
       << " at rest; lower one of them (f * mu1 must stay below 1 + lambda_L/mu_L)";
    return os.str();
  }

  static Fung from_lame(double mu_L, double lambda_L, double fraction, double mu1) {
    Fung m;
    m.options = {fraction, mu1};
    m.mu1 = mu1;
    m.gamma = 2.0 * fraction * mu_L / mu1;
    m.mu0 = (1.0 - fraction) * mu_L;
    m.lambda = lambda_L + mu_L - 0.5 * m.gamma * mu1 * mu1;
    m.alpha = 1.0 + (m.mu0 + 0.5 * m.gamma * mu1) / m.lambda;
    m.psi_rest = m.energy(Mat3::identity());
    return m;
  }

  // exp(mu1/2 (I_C - 3)), capped so that absurd stretches give huge but finite numbers.
  KOKKOS_INLINE_FUNCTION double expo(double Ic) const {
    const double x = 0.5 * mu1 * (Ic - 3.0);
    return std::exp(x < 600.0 ? x : 600.0);
  }

  KOKKOS_INLINE_FUNCTION double energy(const Mat3& F) const {
    const double Ic = frobenius2(F), J = det(F);
    return 0.5 * mu0 * (Ic - 3.0) + 0.5 * lambda * (J - alpha) * (J - alpha) + 0.5 * gamma * (expo(Ic) - 1.0) -
           psi_rest;
  }

  KOKKOS_INLINE_FUNCTION Mat3 pk1(const Mat3& F) const {
    const double Ic = frobenius2(F), J = det(F);
    return (mu0 + 0.5 * gamma * mu1 * expo(Ic)) * F + (lambda * (J - alpha)) * cofactor(F);
  }

  KOKKOS_INLINE_FUNCTION InvariantCoefficients coefficients(const Mat3& F) const {
    const double Ic = frobenius2(F), J = det(F), e = expo(Ic);
    return InvariantCoefficients{mu0 + 0.5 * gamma * mu1 * e, 0.5 * gamma * mu1 * mu1 * e, lambda, lambda * (J - alpha)};
  }
};

}  // namespace sinew
