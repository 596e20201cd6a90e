// Quasi-static equilibrium solve of one load step: NOX Newton with a line search on the Thyra
// ModelEvaluator route, Belos CG preconditioned by MueLu smoothed aggregation (3 DOFs per node, six
// rigid-body modes, coordinates) through Stratimikos. Every NOX, Belos and MueLu parameter can be set
// from the scene's "Solver" sublist; Sinew's defaults fill in the rest.
//
// All of NOX, Thyra, Stratimikos, Belos and MueLu stay inside src/solver/nonlinear_solver.cpp.
#pragma once

#include <sinew/algebra/elastic_system.hpp>

#include <functional>
#include <memory>
#include <string>

namespace Teuchos {
class ParameterList;
}

namespace sinew {

// The accepted "Solver" entries (NOX and Stratimikos sublists are validated by those packages).
Teuchos::ParameterList valid_solver_parameters();

// One Newton iteration, for progress lines.
struct NewtonIterate {
  int iteration = 0;
  double residual = 0.0;   // L2 norm of the force residual after the iteration
  double step = 0.0;       // line-search step length
  int linear_iterations = 0;
};

struct SolveReport {
  bool converged = false;
  std::string reason;           // why it stopped when not converged
  int newton_iterations = 0;
  int linear_iterations = 0;    // CG iterations summed over the Newton iterations
  double initial_residual = 0.0, final_residual = 0.0;
  double seconds_assembly = 0.0, seconds_preconditioner = 0.0, seconds_linear = 0.0, seconds_line_search = 0.0,
         seconds_total = 0.0;

  // Adds the iteration counts and times of a later attempt at the same step.
  void accumulate(const SolveReport& r) {
    newton_iterations += r.newton_iterations;
    linear_iterations += r.linear_iterations;
    seconds_assembly += r.seconds_assembly;
    seconds_preconditioner += r.seconds_preconditioner;
    seconds_linear += r.seconds_linear;
    seconds_line_search += r.seconds_line_search;
    seconds_total += r.seconds_total;
  }
};

class NonlinearSolver {
 public:
  // solver_params: the scene's "Solver" sublist (may be empty).
  NonlinearSolver(ElasticSystem& system, const Teuchos::ParameterList& solver_params);
  ~NonlinearSolver();

  // Solves force(u) = 0 starting from u (its Dirichlet entries hold the prescribed values, which stay).
  // Never throws for a failed solve: linear-solver breakdowns, line-search failures and non-finite
  // values are reported in SolveReport::reason.
  SolveReport solve(Vector& u, const std::function<void(const NewtonIterate&)>& progress = {});

  double absolute_tolerance() const;

  // Called after every Newton iteration (collectively); returning true stops the solve with reason
  // "interrupted".
  void set_interrupt(std::function<bool()> interrupt);

 private:
  SolveReport solve_once(Vector& u, const std::function<void(const NewtonIterate&)>& progress);
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace sinew
