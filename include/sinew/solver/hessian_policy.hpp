// Which Hessian Newton assembles, as one explicit state machine per solve.
//
// The PSD-projected Hessian (the paper's safeguard, Sec. 4) gives a descent direction from any state,
// inverted ones included, but wherever an element is non-convex it is not the true Hessian, which turns
// Newton's final quadratic convergence linear. So: project until the residual has dropped below
// `exact_below` times the solve's first residual with no point inverted or undefined, then use the
// exact Hessian; fall back to projection for the rest of the solve at the first sign that the state is
// not yet in the quadratic region: a direction that does not descend, a step the line search had to cut
// below 1/2, or a failed line search. A failed solve is worth redoing with projection only when it used
// the exact Hessian at all.
//
//   Projected <--(small residual, nothing tangled)--> Exact --(bad direction or short step)--> FellBack
#pragma once

namespace sinew {

class HessianPolicy {
 public:
  enum class Mode { Projected, Exact, FellBack };

  explicit HessianPolicy(double exact_below = 0.0) : exact_below_(exact_below) {}

  double exact_below() const { return exact_below_; }
  Mode mode() const { return mode_; }
  bool exact_used() const { return exact_used_; }
  bool last_exact() const { return last_exact_; }

  // A new solve whose first residual is `initial_residual`.
  void start(double initial_residual) {
    f0_ = initial_residual;
    mode_ = Mode::Projected;
    exact_used_ = last_exact_ = false;
  }

  // Before each Jacobian: the residual of the current state, and whether any point is inverted or
  // undefined. Returns whether to assemble the exact Hessian. Until a fall-back, the choice follows the
  // current state (a residual that grows again, or a state that tangles, goes back to projection).
  bool next_jacobian(double residual, bool tangled) {
    if (mode_ != Mode::FellBack)
      mode_ = exact_below_ > 0.0 && f0_ > 0.0 && residual < exact_below_ * f0_ && !tangled ? Mode::Exact : Mode::Projected;
    last_exact_ = mode_ == Mode::Exact;
    exact_used_ = exact_used_ || last_exact_;
    return last_exact_;
  }

  // The line search's findings about a direction computed from the last Jacobian.
  void direction_not_descent() { fall_back(); }
  void step_taken(double step) {
    if (step < 0.5) fall_back();
  }
  void line_search_failed() { fall_back(); }

  // Redo a failed solve with projection throughout?
  bool retry_projected() const { return exact_used_; }

 private:
  void fall_back() {
    if (last_exact_) mode_ = Mode::FellBack;
  }

  double exact_below_;
  double f0_ = 0.0;
  Mode mode_ = Mode::Projected;
  bool exact_used_ = false, last_exact_ = false;
};

}  // namespace sinew
