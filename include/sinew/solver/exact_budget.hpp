// The CG budget of a linear solve on the exact Hessian.
//
// Where the exact Hessian is due (HessianPolicy) but the state is not yet where it is positive definite
// (flesh pinched or inverted at a crease), CG on it runs long and, past its negative curvature, returns
// a direction metres long that the line search cuts to a hundredth: on the 48k-cell human's whole
// capture with the barrier, the 148 exact iterations whose step stayed below 1/2 took 12,345 of the
// run's 31,188 CG iterations (up to 244 in one solve, where the projected solve before took 28). The
// exact solves that went on to a step of 1/2 or more took at most 4 times the CG per digit of the
// projected solve before them in 377 of 387 cases (BCN_Epileptic's clip: 422 of 425; the BVH jump:
// all 132). So an exact solve gets `factor` times the last projected solve's CG per digit of residual
// reduction, times the digits it is asked for, and at least `min_budget`; one that does not converge
// within it is not stepped along: the iteration is redone from the same state with the projected
// Hessian (HessianPolicy::exact_solve_over_budget). The floor of 100 leaves alone every exact solve
// that went on to a step of 1/2 in those runs and still catches the human's runaways (about 6,400 of
// their 12,345 CG); with a floor of 30 one redone iteration put the corpus clips on other paths (BCN
// -12%, huesitos +12% Newton iterations) and two blocks pressed together on 2 ranks ended 7e-6 away
// from the 1-rank state (the springs' end state depends on the path).
// Its inputs are global counts, so every rank makes the same decisions.
#pragma once

#include <sinew/solver/preconditioner_lag.hpp>

#include <algorithm>
#include <cmath>

namespace sinew {

class ExactSolveBudget {
 public:
  static constexpr double factor = 4.0;
  static constexpr int min_budget = 100;

  // After a linear solve on the projected Hessian: `iterations` CG to the relative `tolerance`.
  void projected_solved(int iterations, double tolerance, bool converged) {
    if (converged && iterations > 0) per_digit_ = iterations / PreconditionerLag::digits(tolerance);
  }
  // The most CG an exact solve to `tolerance` may take, within `ceiling` (no projected solve yet: the
  // ceiling).
  int budget(double tolerance, int ceiling) const {
    if (!(per_digit_ > 0.0)) return ceiling;
    const double b = std::ceil(factor * per_digit_ * PreconditionerLag::digits(tolerance));
    return std::min(ceiling, std::max(min_budget, static_cast<int>(std::min(b, static_cast<double>(ceiling)))));
  }

 private:
  double per_digit_ = 0.0;  // CG per digit of the last converged projected solve
};

}  // namespace sinew
