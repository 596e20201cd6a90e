// The linear tolerance of what may be Newton's last iteration.
//
// NOX's Eisenstat-Walker forcing term eta asks CG for a residual of eta |F| (nonlinear_solver.cpp keeps
// it within ['Linear tolerance', 1e-2]). Where Newton converges quadratically (the exact Hessian), the
// next |F| is about that linear residual plus a term quadratic in |F|, so a forcing term with eta |F|
// above the convergence threshold all but guarantees one more iteration, however small the quadratic
// term: the 969k-DOF stretch's first step went 1.48 -> 1.46e-2 with eta = 1e-2 against a threshold of
// 1e-2, and took a fourth Newton iteration (18 CG, a fifth of the step) for the missing third of a digit.
// So when eta |F| is above half the threshold but within ten times of it, solve to half the threshold
// instead (never below `floor`, the forcing term's own minimum); further from convergence eta stands
// (tightening there would over-solve iterations whose |F| the quadratic term dominates).
#pragma once

#include <algorithm>

namespace sinew {

// eta: the forcing term's tolerance; residual: |F| now; threshold: the |F| that ends the solve.
inline double finishing_tolerance(double eta, double residual, double threshold, double floor) {
  if (!(residual > 0.0) || !(threshold > 0.0) || !(eta > 0.0)) return eta;
  const double want = 0.5 * threshold / residual;
  if (want >= eta || want < 0.1 * eta) return eta;
  return std::max(want, floor);
}

}  // namespace sinew
