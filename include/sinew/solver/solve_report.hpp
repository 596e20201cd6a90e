// What one nonlinear solve reports: its outcome as an enum (never a string to compare), iteration
// counts and the time split the log and the performance suite read.
#pragma once

#include <cmath>

#include <string>

namespace sinew {

enum class SolveStatus {
  Converged,
  Interrupted,       // a stop was requested (SIGINT/SIGTERM) between Newton iterations
  MaxIterations,     // no convergence within the iteration limit
  NonFinite,         // NaN or Inf in the residual
  LineSearchFailed,  // no step decreased the merit function
  UndefinedEnergy,   // the end state has points where the energy is +inf (Neo-Hookean inverted)
  SolverError        // an exception from the linear solver or preconditioner (see `detail`)
};

// One Newton iteration, for progress lines.
struct NewtonIterate {
  int iteration = 0;
  double residual = 0.0;  // L2 norm of the force residual after the iteration
  double step = 0.0;      // line-search step length
  int linear_iterations = 0;
  bool exact_hessian = false;  // the iteration's direction came from the unprojected Hessian
  bool exact_terms = false;    // ... with every term's unprojected too (HessianPolicy's exact_terms tier)
  // The largest entry of the iteration's Newton direction (before the line search scales it): how far
  // the full step would move a node along one axis, in length units. Where |F| stalls, a direction that
  // stays large says Newton is still travelling (a crawl or a slide), one that shrinks says it is close.
  // NaN where unknown (a line search other than the energy backtracking).
  double direction_max = 0.0;
  // The longest step along that direction a term allowed (a contact barrier's continuous collision
  // test: no surface point through a face), where it was shorter than the longest step the line
  // search tries ('Maximum step'); +inf where nothing bounded it. A step at its bound was cut short by
  // contact, not by the energy.
  double step_bound = HUGE_VAL;
};

struct SolveReport {
  SolveStatus status = SolveStatus::SolverError;
  std::string detail;  // the exception text of a SolverError
  int max_iterations = 0;
  bool exact_hessian_used = false;       // some Newton direction came from the unprojected Hessian
  bool exact_hessian_fell_back = false;  // ... and the solve went back to projection (HessianPolicy)
  int newton_iterations = 0;
  int linear_iterations = 0;  // CG iterations summed over the Newton iterations
  int preconditioner_updates = 0;  // Newton iterations whose preconditioner was set up or updated
  int retried_solves = 0;          // linear solves repeated with an updated one after a kept one failed (PreconditionerLag)
  int exact_over_budget = 0;       // exact solves over their CG budget (ExactSolveBudget), solved again projected
  long long relaxed_nodes = 0;     // nodes moved by the node relaxations kept ('Solver/Node relaxation')
  double initial_residual = 0.0, final_residual = 0.0;
  double seconds_assembly = 0.0, seconds_preconditioner = 0.0, seconds_linear = 0.0, seconds_line_search = 0.0,
         seconds_total = 0.0;

  bool converged() const { return status == SolveStatus::Converged; }

  // Why it stopped, for people.
  std::string reason() const {
    switch (status) {
      case SolveStatus::Converged: return "converged";
      case SolveStatus::Interrupted: return "interrupted";
      case SolveStatus::MaxIterations: return "no convergence in " + std::to_string(max_iterations) + " Newton iterations";
      case SolveStatus::NonFinite: return "non-finite residual (NaN or Inf)";
      case SolveStatus::LineSearchFailed: return "line search failed to decrease the merit function";
      case SolveStatus::UndefinedEnergy: return "the state has inverted points where the energy is undefined (+inf)";
      case SolveStatus::SolverError: return "solver exception: " + detail;
    }
    return "?";
  }

  // Adds the iteration counts and times of a later attempt at the same step.
  void accumulate(const SolveReport& r) {
    exact_hessian_used = exact_hessian_used || r.exact_hessian_used;
    exact_hessian_fell_back = exact_hessian_fell_back || r.exact_hessian_fell_back;
    newton_iterations += r.newton_iterations;
    linear_iterations += r.linear_iterations;
    preconditioner_updates += r.preconditioner_updates;
    retried_solves += r.retried_solves;
    exact_over_budget += r.exact_over_budget;
    relaxed_nodes += r.relaxed_nodes;
    seconds_assembly += r.seconds_assembly;
    seconds_preconditioner += r.seconds_preconditioner;
    seconds_linear += r.seconds_linear;
    seconds_line_search += r.seconds_line_search;
    seconds_total += r.seconds_total;
  }
};

}  // namespace sinew
