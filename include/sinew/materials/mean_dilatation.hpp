// Mean dilatation (Nagtegaal, Parks, Rice 1974; Simo, Taylor, Pister 1985): the volume term of a law
//   Psi(F) = Psi_dev(F) + lambda/2 (J - alpha)^2,   Psi_dev independent of J,
// evaluated on the element's mean dilatation Jbar = (1/V) sum_q w_q J_q (its current over its reference
// volume: 2x2x2 Gauss integrates a trilinear hex's J exactly) instead of at each quadrature point. One
// volume constraint per element instead of eight is what keeps a nearly incompressible hex8 from
// locking. The element energy
//   E_e = sum_q w_q Psi_dev(F_q) + V lambda/2 (Jbar - alpha)^2
// (the pure mean dilatation, s = 1 below) has the gradient
//   sum_q w_q [P(F_q) + lambda (Jbar - J_q) cof F_q] : dF_q/dx
// (the law's own PK1 with the volume factor taken at Jbar), and the Hessian
//   sum_q w_q G_q^T [H(F_q) - lambda g g^T + lambda (Jbar - J_q) H_J(F_q)] G_q + (lambda / V) b b^T,
// b = sum_q w_q G_q^T vec(cof F_q) (= V dJbar/dx): per point the law's Eq. 52 form with gG lowered by
// lambda and gH = lambda (Jbar - alpha), whose closed-form eigen-system (Sec. 4.6) projects it, plus a
// rank-one element term that is positive semi-definite as it stands. So the projected element matrix is
// PSD. It is not exact even at rest: without lambda g g^T the point's block has the uniform-scaling
// eigenvalue gI + 3 gF - 2 |gH| (SNH at rest: -3 mu / 8), which the projection clamps (the volume
// stiffness is in the element's rank-one term); the solver's exact phase (Projection none) sums the
// blocks unprojected. For an affine motion every J_q equals Jbar and the element is the law's own.
// A share s of the volume term on the mean and 1 - s at the points ('Material/Mean dilatation share'):
//   E_e = sum_q w_q [Psi(F_q) - s lambda/2 (J_q - alpha)^2] + s V lambda/2 (Jbar - alpha)^2,
// the formulas above with lambda replaced by s lambda in the split (pk1, gG, gH, b b^T). Why: with s = 1
// the paper's full pi twist at nu = 0.49 does not converge (15^3: Newton stalls near load 0.94; 30^3: still
// cutting the second step at load 0.83 after 10 minutes;
// the pressure times H_J acts on modes that change J at the points but not its mean, the mean-dilatation
// hex's known instability at large strain, and nothing else stiffens them); the (1 - s) lambda kept at the
// points does. Measured on that twist (docs/performance.md): s = 0.5, 0.8, 0.9 converge at 15^3 and 30^3,
// 0.95 fails at 30^3; the energy at pi/2 (how much the element locks) at 15^3 is 6,480.6 with the paper's
// element, 6,425.0 with 0.8, 6,412.5 with 0.9 and 6,394.8 with 1 (30^3: 6,411.8, 6,384.5, 6,379.2, 6,372.4).
// Off by default ('Material/Volumetric'): the paper's element integrates the whole law at every point.
#pragma once

#include <sinew/materials/material.hpp>

#include <type_traits>
#include <utility>

namespace sinew {

// A law's volume term lambda/2 (J - alpha)^2 (a law with one provides `VolumeTerm volume_term() const`).
struct VolumeTerm {
  double lambda = 0.0, alpha = 1.0;
};

template <class M, class = void>
struct has_volume_term : std::false_type {};
template <class M>
struct has_volume_term<M, std::void_t<decltype(std::declval<const M&>().volume_term())>> : std::true_type {};

// The law at one point of an element whose mean dilatation is Jbar, with the share `share` of its volume
// term on the mean: Psi_dev (energy), the gradient's per-point part (pk1) and the per-point Hessian block
// (coefficients, projected as any Eq. 52 law).
template <class Law>
struct MeanDilatationPoint : InvariantModel<MeanDilatationPoint<Law>> {
  Law law;
  double Jbar = 1.0;
  double share = 1.0;  // the volume term's share on the mean dilatation (the rest stays at the points)

  KOKKOS_INLINE_FUNCTION bool defined(const Mat3& F) const { return law.defined(F); }
  KOKKOS_INLINE_FUNCTION double energy(const Mat3& F) const { return deviatoric(law.energy(F), det(F)); }
  // Psi_dev from the law's own energy density psi at a point of dilatation J.
  KOKKOS_INLINE_FUNCTION double deviatoric(double psi, double J) const {
    const VolumeTerm v = law.volume_term();
    return psi - 0.5 * share * v.lambda * (J - v.alpha) * (J - v.alpha);
  }
  KOKKOS_INLINE_FUNCTION Mat3 pk1(const Mat3& F) const {
    return law.pk1(F) + (share * law.volume_term().lambda * (Jbar - det(F))) * cofactor(F);
  }
  KOKKOS_INLINE_FUNCTION InvariantCoefficients coefficients(const Mat3& F) const {
    const double lambda = share * law.volume_term().lambda;
    InvariantCoefficients c = law.coefficients(F);
    c.gG -= lambda;
    c.gH += lambda * (Jbar - det(F));
    return c;
  }
  // The element's own part: s V lambda/2 (Jbar - alpha)^2.
  KOKKOS_INLINE_FUNCTION double element_energy(double V) const {
    const VolumeTerm v = law.volume_term();
    return 0.5 * share * V * v.lambda * (Jbar - v.alpha) * (Jbar - v.alpha);
  }
};

}  // namespace sinew
