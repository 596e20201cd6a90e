// Whether a Newton iteration updates the preconditioner for its new Jacobian or keeps the one it has,
// as one explicit state machine kept across the solves of a run (the preconditioner outlives them).
//
// An update is MueLu's "reuse: type" path (the Galerkin products and smoothers of the new matrix on the
// prolongators of the last setup from scratch) and costs about as much as the CG solve it serves (on the
// 48k-cell human: 0.6 s per Newton iteration against 0.8 s of CG). A kept one is the last update's
// hierarchy applied to the new matrix (the Jacobian is refilled in place, so the fine level's smoother
// multiplies by the new values). Through the small changes of a Newton iteration near a solution, or of a
// load step of a slow motion, it stays nearly as good; through a large rotation (the twist's first
// iterations) it can be useless (441 CG instead of 9, or no convergence in 2,000). So:
//  - a kept preconditioner has a CG budget: 2 `factor` times the iterations per digit of residual
//    reduction of the first solve after the last update (per digit, because the Eisenstat-Walker
//    tolerance changes from solve to solve), times the digits asked now, and at least `min_budget` (a
//    budget of `factor` alone made the human's kept solves fail at 18 of 18 iterations and cost a redone
//    iteration each);
//  - a kept solve over budget, or whose direction does not descend, is repeated at once on the same
//    Jacobian with an updated preconditioner (`retried`, by the solver's RetryingSolve: within the Newton
//    iteration, which neither assembles again nor counts twice, where the line search used to step 0 and
//    redo the iteration), and nothing is kept again in that solve until the residual is ten times below
//    where the kept one failed (as HessianPolicy's fall-back after a direction that does not descend);
//  - a kept solve within budget but slower than `factor` times the baseline's rate, a step the line
//    search had to cut, or one that did not halve the residual (the state is where the quadratic model is
//    poor and the Jacobian changes the most), has the next iteration update. The last matters beyond the
//    preconditioner's cost: CG to the same relative residual with a weaker preconditioner leaves more
//    error in the smooth, nearly incompressible modes, and where Newton is far from its quadratic region
//    that costs iterations (the 30^3 twist kept its preconditioner through a stretch of full steps that
//    did not reduce the residual and took 163 Newton iterations and a cut instead of 56).
// Its inputs are global counts and norms, so every rank makes the same decisions.
//
//   Updated --(solve within factor x baseline, full step)--> Kept --(over budget / no descent)--> retried, Updated
#pragma once

#include <algorithm>
#include <cmath>

namespace sinew {

class PreconditionerLag {
 public:
  static constexpr int min_budget = 10;

  // enabled = false: update for every Jacobian (the budget is then never set).
  PreconditionerLag(bool enabled, double factor) : enabled_(enabled), factor_(factor) {}

  static double digits(double tolerance) { return std::max(1.0, -std::log10(tolerance)); }

  // A new nonlinear solve: failures of the last one are forgotten.
  void start() { keep_below_ = HUGE_VAL; }

  // Before a Jacobian's linear solver is initialized, at a state of residual `residual`, for a solve to the
  // relative `tolerance`: update the preconditioner (true), or keep it, with CG limited to `budget`?
  // `exact`: whether this Jacobian is the exact Hessian (HessianPolicy). One set up on a projected Hessian
  // is never kept for an exact one: where the projection clamped, the exact Hessian is softer along the
  // very modes the kept hierarchy treats as stiff, and on BCN's whole clip 147 of the 460 switches to the
  // exact Hessian failed with the kept preconditioner and were redone (an assembly and a failed CG each).
  bool update(double residual, double tolerance, int& budget, bool exact = false) {
    kept_ = enabled_ && !update_next_ && baseline_ > 0.0 && residual < keep_below_ && !(exact && !set_up_exact_);
    if (!kept_) {
      update_next_ = false;
      baseline_ = 0.0;
      set_up_exact_ = exact;
      ++updates_;
      return true;
    }
    budget = std::max(min_budget, static_cast<int>(std::ceil(2.0 * factor_ * baseline_ * digits(tolerance))));
    return false;
  }

  // After that linear solve: `iterations` CG to `tolerance`, converged or not (over budget), at residual
  // `residual`. (A kept one that failed has been retried before this is told: a failure here is one
  // that no update can mend now, and the next Jacobian updates.)
  void solved(int iterations, double tolerance, bool converged, double residual) {
    if (!enabled_) return;
    solved_at_ = residual;
    const double per_digit = iterations / digits(tolerance);
    if (!kept_)
      baseline_ = converged ? std::max(per_digit, 1.0) : 0.0;
    else if (!converged)
      fail(residual);
    else if (per_digit > factor_ * baseline_)
      update_next_ = true;
  }

  // After the line search, with the residual it reached: a step it had to cut, or one that did not halve
  // the residual, has the next iteration update.
  void stepped(double step, double residual) {
    if (step < 1.0 || !(residual < 0.5 * solved_at_)) update_next_ = true;
  }

  // The kept preconditioner's solve at residual `residual` just failed (over budget, or a direction that
  // does not descend) and the preconditioner is updated now, for the same Jacobian (`exact`: whether it
  // is the exact Hessian), and the solve repeated. The repeated solve's `solved` sets the new baseline.
  void retried(double residual, bool exact) {
    fail(residual);
    update_next_ = false;
    kept_ = false;
    baseline_ = 0.0;
    set_up_exact_ = exact;
    ++updates_;
    ++retries_;
  }

  // A new linear solver (a new Newton group, a new matrix pattern): its first preconditioner is set up
  // afresh whatever this says.
  void reset() {
    update_next_ = true;
    baseline_ = 0.0;
    kept_ = false;
  }

  bool kept() const { return kept_; }
  int updates() const { return updates_; }  // preconditioner setups and updates so far
  int retries() const { return retries_; }  // linear solves repeated in place so far

 private:
  void fail(double residual) {
    update_next_ = true;
    keep_below_ = 0.1 * residual;
  }

  bool enabled_;
  double factor_;
  bool update_next_ = true, kept_ = false;
  bool set_up_exact_ = false;  // whether the last update was for an exact Hessian
  double baseline_ = 0.0;         // CG iterations per digit of the first solve after the last update
  double keep_below_ = HUGE_VAL;  // after a failure: keep again only once the residual is below this
  double solved_at_ = HUGE_VAL;   // the residual at which the last linear solve's Jacobian was taken
  int updates_ = 0, retries_ = 0;
};

}  // namespace sinew
