// Which Hessian Newton assembles, as one explicit state machine per solve.
//
// The PSD-projected Hessian (the paper's safeguard, Sec. 4) gives a descent direction from any state,
// inverted ones included, but wherever an element is non-convex it is not the true Hessian, which turns
// Newton's final quadratic convergence linear. So: project until the residual has dropped below
// `exact_below` times the solve's first residual, or below an absolute floor near the convergence
// threshold (set_exact_floor: a step that starts near equilibrium would otherwise creep there with
// projected steps), then use the exact Hessian; how inverted points take
// part is `Inverted`: PerPoint (exact where J > 0, projected where J <= 0), Exact (their exact Hessian
// too), both only while at most a few points are inverted (`few`, a fraction of all; a tangle of many
// keeps the whole Hessian projected: with the exact Hessian a scrambled cube settled in a tangled
// equilibrium instead of going back to rest), or WholeMesh (any inverted point keeps the whole Hessian
// projected); undefined points (Neo-Hookean, J <= 0) always do. Fall back to projection at the first
// sign that the state is not yet in the quadratic region: a direction that does not descend, a step the
// line search had to cut below 1/2, an exact solve over its CG budget (exact_budget.hpp), or a failed
// line search; try the exact Hessian again once projected
// Newton has brought the residual ten times below where it failed, and after a short step or a failed
// line search also after 2, 4, 8, ... projected iterations (the k-th such fall-back of the solve waits
// 2^k), whichever comes first. Projected Newton near a crease converges linearly (on the 48k-cell
// human's crouch, 0.88-0.92 per iteration), so the ten-fold drop alone cost 11-14 iterations after each
// short exact step, although the exact Hessian tried again a few iterations later converged
// quadratically (steps 5-9 of the crouch: 135 -> 112 Newton iterations). A direction that does not
// descend (CG met negative curvature) at a state with inverted points waits for the ten-fold drop only:
// retried by count, the scramble's indefinite exact Hessians cost a wasted iteration each (347 -> 352).
// At a state with none it means a saddle of the energy (the flesh pinched between bones buckles): the
// projected steps then slide off it, the residual growing for a while, and the ten-fold drop below the
// saddle's residual may take tens of iterations after the slide (the corotational human's fourth step:
// 50 iterations without converging, then 42 more with projection only), so there the exact Hessian is
// tried again after 4, 8, 16, ... projected iterations (`saddle_wait`), and `saddle()` tells the line
// search it may step further along a direction that keeps descending (EnergyBacktrack). A failed solve
// is worth redoing with projection only when it used the exact Hessian at all.
// Where a term's step limit (the contact barrier's collision test) held the last step short of 1,
// surface points are still closing on faces whose barrier the Hessian does not see yet: the exact
// Hessian waits for a step that was not held (no fall-back counted; a later solve of the same load step
// goes on from the last one's). On huesitos' curl (quasi-static) only 23 of the 63 exact directions
// that followed a held step were stepped along by 1/2 or more, against 192 of 259 after other steps;
// waiting took the clip from 881 to 701 Newton iterations and ten corpus runs from 5,799 to 5,414
// (docs/performance.md).
//
// The exact tier has the elastic energy's exact Hessian, but the other terms keep their PSD projections:
// a contact barrier's pair Hessian kappa (b'' grad D grad D^T + b' hess D) is indefinite (b' < 0), and
// its projection clamps the curvature along which the pair's surfaces slide on each other. Where the
// flesh is soft against it Newton then converges linearly: on BCN_Epileptic's clip (step 34, 1,138
// pairs) the exact Hessian's curvature along the Newton directions was 1.8e-5 where the energy's was
// 8.5e-6 (the barrier's 6.9e-6 against -2.4e-6, measured by differences of the gradient), so the line
// search lengthened every step to 1.7-2.0 Newton steps and |F| fell by 0.8-0.97 per iteration for 25
// iterations. Such a lengthened exact step is the sign: after one (past long_step), the exact-terms
// tier also drops the other terms' projections (EnergyTerm: TermInput::exact_terms), until one of its
// directions fails as an exact one can (it does not descend, its CG runs over budget, its step is short
// or the line search fails), which goes back to the exact tier, not to projection, for the rest of the
// solve. Measured on the quasi-static corpus (1 thread, Newton iterations): BCN's clip 872 -> 794, the
// jump 480 -> 461, huesitos 700 -> 695. Turned on by every exact step of full length instead, BCN 769
// but huesitos 797 and the dynamic Wuson run 296 -> 309 (directions of the total exact Hessian that
// fail cost a redone iteration each); keeping a failure for the whole load step, BCN 833.
//
//   Projected <--(small residual, nothing tangled, last step not held)--> Exact --(bad direction or short step)--> FellBack
//   Exact --(a step lengthened past long_step)--> Exact with the terms' exact Hessians --(a failure)--> Exact
//   FellBack --(residual 10x below the failure's, or after a short step 2^k projected iterations, or
//               after a saddle 4 x 2^k)--> Exact
#pragma once

#include <algorithm>

namespace sinew {

class HessianPolicy {
 public:
  enum class Mode { Projected, Exact, FellBack };
  enum class Inverted { Exact, PerPoint, WholeMesh };

  explicit HessianPolicy(double exact_below = 0.0, Inverted inverted = Inverted::PerPoint)
      : exact_below_(exact_below), inverted_(inverted) {}

  // In Exact mode: whether inverted points get their exact Hessian too (else their projection).
  bool exact_at_inverted() const { return inverted_ == Inverted::Exact; }

  double exact_below() const { return exact_below_; }
  // Also exact once the residual is below `floor` (absolute), however large the solve's first residual
  // was (0: the relative rule only). Set per solve to 'Exact Hessian within' times the |F| that ends it.
  void set_exact_floor(double floor) { exact_floor_ = floor; }
  Mode mode() const { return mode_; }
  bool exact_used() const { return exact_used_; }
  bool last_exact() const { return last_exact_; }
  // The exact-terms tier (see the top of this file): on or off for the solves to come.
  void set_exact_terms(bool on) { exact_terms_ = on; }
  // Whether the last exact Jacobian has the other terms' unprojected Hessians too.
  bool last_exact_terms() const { return last_exact_terms_; }
  // Whether this solve fell back from the exact Hessian at least once (it may have tried it again since).
  bool fell_back() const { return fell_back_; }
  // Whether an exact direction of this solve did not descend at a state with no inverted point.
  bool saddle() const { return saddle_; }

  // A new solve whose first residual is `initial_residual`.
  void start(double initial_residual) {
    f0_ = initial_residual;
    mode_ = Mode::Projected;
    exact_used_ = last_exact_ = fell_back_ = false;
    retry_below_ = 0.0;
    saddle_ = false;
    short_falls_ = saddle_falls_ = wait_ = projected_since_ = 0;
    last_exact_terms_ = terms_fell_ = lengthened_ = false;
  }

  // After the k-th short step or failed line search of a solve (k = 0, 1, ...), the exact Hessian is
  // tried again after first_wait * 2^k projected Jacobians at the latest.
  static constexpr int first_wait = 2;
  // After the k-th direction that did not descend at a state with no inverted point (a saddle), after
  // saddle_wait * 2^k. The corotational human's fourth step (0 inverted points): 92 Newton iterations
  // with the ten-fold drop only, 41 with 4; with the longer steps of saddle() 40 with 4, 42 with 2.
  static constexpr int saddle_wait = 4;

  // The largest fraction of inverted points that still allows the exact Hessian (PerPoint, Exact).
  static constexpr double few = 0.01;

  // An exact step the line search lengthened past this many Newton steps (the energy softer along its
  // direction than the Hessian says) turns the exact-terms tier on.
  static constexpr double long_step = 1.2;

  // Before each Jacobian: the residual of the current state, the fraction of its points that are
  // inverted, and whether any point is undefined. Returns whether to assemble the exact Hessian. Until a
  // fall-back, the choice follows the current state (a residual that grows again, or a state that
  // tangles, goes back to projection).
  // `held`: the last step was held short of 1 by a step limit (a contact barrier's collision test):
  // the state is where pairs are still closing, so the exact Hessian waits for a step that was not held.
  bool next_jacobian(double residual, double inverted_fraction, bool undefined = false, bool held = false) {
    const bool tangled =
        undefined || (inverted_ == Inverted::WholeMesh ? inverted_fraction > 0.0 : inverted_fraction > few);
    last_residual_ = residual;
    last_inverted_ = inverted_fraction;
    if (mode_ == Mode::FellBack && (residual < retry_below_ || (wait_ > 0 && projected_since_ >= wait_)))
      mode_ = Mode::Projected;  // far enough, or long enough: may try again
    if (mode_ == Mode::FellBack) ++projected_since_;
    if (mode_ != Mode::FellBack) {
      const bool small = exact_below_ > 0.0 && ((f0_ > 0.0 && residual < exact_below_ * f0_) || residual < exact_floor_);
      mode_ = small && !tangled && !held ? Mode::Exact : Mode::Projected;
    }
    last_exact_ = mode_ == Mode::Exact;
    last_exact_terms_ = last_exact_ && exact_terms_ && lengthened_ && !terms_fell_;
    exact_used_ = exact_used_ || last_exact_;
    return last_exact_;
  }

  // The line search's findings about a direction computed from the last Jacobian.
  // With nothing inverted it is a saddle, retried by count; with inverted points the ten-fold drop only.
  void direction_not_descent() {
    if (terms_fall()) return;
    if (last_exact_ && !(last_inverted_ > 0.0)) {
      saddle_ = true;
      fall_back(saddle_wait, &saddle_falls_);
    } else {
      fall_back(0, nullptr);
    }
  }
  void step_taken(double step) {
    if (step < 0.5 && !terms_fall()) fall_back(first_wait, &short_falls_);
    if (last_exact_ && !last_exact_terms_ && step > long_step) lengthened_ = true;
  }
  void line_search_failed() {
    if (!terms_fall()) fall_back(first_wait, &short_falls_);
  }
  // An exact solve that did not converge within its CG budget (ExactSolveBudget): as a short step.
  void exact_solve_over_budget() {
    if (!terms_fall()) fall_back(first_wait, &short_falls_);
  }

  // Redo a failed solve with projection throughout?
  bool retry_projected() const { return exact_used_; }

 private:
  // A failure of the exact-terms tier goes back to the exact tier (the terms projected) for the rest of
  // the solve, not to projection. Returns whether it was that tier's.
  bool terms_fall() {
    if (!last_exact_terms_) return false;
    terms_fell_ = true;
    return true;
  }

  // From an exact Jacobian: FellBack until the ten-fold drop, or after first * 2^k projected Jacobians
  // where `falls` counts k (and is counted up); no count (null) waits for the drop only.
  void fall_back(int first, int* falls) {
    if (!last_exact_) return;
    mode_ = Mode::FellBack;
    fell_back_ = true;
    retry_below_ = 0.1 * last_residual_;
    wait_ = falls ? first << std::min((*falls)++, 20) : 0;
    projected_since_ = 0;
  }

  double exact_below_;
  double exact_floor_ = 0.0;
  Inverted inverted_ = Inverted::PerPoint;
  double f0_ = 0.0;
  Mode mode_ = Mode::Projected;
  bool exact_used_ = false, last_exact_ = false, fell_back_ = false, saddle_ = false;
  // After a short step or a saddle: FellBack for wait_ projected Jacobians at most (0: until retry_below_).
  int short_falls_ = 0, saddle_falls_ = 0, wait_ = 0, projected_since_ = 0;
  double last_residual_ = 0.0, last_inverted_ = 0.0, retry_below_ = 0.0;  // FellBack until the residual is below retry_below_
  // The exact-terms tier: offered, last used, failed in this solve, and an exact step lengthened.
  bool exact_terms_ = false, last_exact_terms_ = false, terms_fell_ = false, lengthened_ = false;
};

}  // namespace sinew
