// Filtered Neo-Hookean in the manner of Irving et al. 2004 / Teran et al. 2005: the Neo-Hookean energy
// (Eq. 5) in singular values, Psi = mu/2 (sum s_i^2 - 3) - mu L + lambda/2 L^2 with L = sum l(s_i), where
// l(s) = log s above the threshold s_f and its second-order Taylor extension below it:
//   l(s) = log s_f + d/s_f - d^2/(2 s_f^2),  d = s - s_f   (s < s_f).
// The energy is then C2, finite for every F (inverted ones included), and equal to Neo-Hookean wherever
// all s_i >= s_f. Reflections sit in the smallest singular value (Irving's convention), so unlike SNH
// this energy depends on that convention. The paper's PhysBAM runs used s_f = 0.25 (Sec. 6).
#pragma once

#include <sinew/materials/corotational.hpp>

namespace sinew {

struct FilteredNeoHookean : SigmaModel<FilteredNeoHookean> {
  static constexpr const char* name = "filtered-neohookean";
  static constexpr const char* equation = "Eq. 5, filtered below s_f";
  struct Options {
    double threshold;
    template <class V>
    void visit(V& v) {
      v.entry("Filter threshold", threshold, 0.25,
              "filtered-neohookean: singular-value threshold s_f below which log s is replaced by its Taylor "
              "extension (the paper's PhysBAM runs used 0.25)",
              Range::open(0.0, 1.0));
    }
  };
  double mu = 0, lambda = 0, threshold = 0;

  static FilteredNeoHookean make(double mu_L, double lambda_L, const Options& o) { return from_lame(mu_L, lambda_L, o.threshold); }
  std::string invalid() const { return ""; }

  static FilteredNeoHookean from_lame(double mu_L, double lambda_L, double threshold) {
    FilteredNeoHookean m;
    m.mu = mu_L;
    m.lambda = lambda_L;
    m.threshold = threshold;
    return m;
  }

  KOKKOS_INLINE_FUNCTION void ell(double s, double& l, double& l1, double& l2) const {
    if (s >= threshold) {
      l = std::log(s);
      l1 = 1.0 / s;
      l2 = -1.0 / (s * s);
    } else {
      const double d = s - threshold, inv = 1.0 / threshold;
      l = std::log(threshold) + d * inv - 0.5 * d * d * inv * inv;
      l1 = inv - d * inv * inv;
      l2 = -inv * inv;
    }
  }

  KOKKOS_INLINE_FUNCTION double psi_sigma(const double s[3]) const {
    double L = 0.0, i1 = 0.0;
    for (int i = 0; i < 3; ++i) {
      double l, l1, l2;
      ell(s[i], l, l1, l2);
      L += l;
      i1 += s[i] * s[i];
    }
    return 0.5 * mu * (i1 - 3.0) - mu * L + 0.5 * lambda * L * L;
  }

  KOKKOS_INLINE_FUNCTION void sigma_terms(const double s[3], double dpsi[3], SigmaEigensystem& es) const {
    double l[3], l1[3], l2[3], L = 0.0;
    for (int i = 0; i < 3; ++i) {
      ell(s[i], l[i], l1[i], l2[i]);
      L += l[i];
    }
    const double c = lambda * L - mu;
    for (int i = 0; i < 3; ++i) {
      dpsi[i] = mu * s[i] + c * l1[i];
      for (int j = 0; j < 3; ++j) es.A[i][j] = lambda * l1[i] * l1[j] + (i == j ? mu + c * l2[i] : 0.0);
    }
    for (int k = 0; k < 3; ++k) {
      const int i = (k + 1) % 3, j = (k + 2) % 3;
      // Divided differences of l'; l' is C1 with l'' continuous, so the coincident limit is l''.
      const double dd = flip_quotient(l1[i], l1[j], s[i], s[j], l2[i], 0.0);
      es.flip[k] = mu + c * dd;
      es.twist[k] = mu + c * (l1[i] + l1[j]) / floored_pair_sum(s[i], s[j]);
    }
  }
};

}  // namespace sinew
