// The quasi-static run: load steps with step cutting, progress lines, log, output and checkpoints.
#pragma once

#include <sinew/algebra/system.hpp>
#include <sinew/driver/config.hpp>
#include <sinew/io/output.hpp>

#include <functional>
#include <memory>
#include <vector>

namespace sinew {

struct RunOptions {
  bool quiet = false;        // no progress lines (errors still go to stderr)
  std::string restart_file;  // continue from this checkpoint (empty: start from the beginning)
  bool restart_anyway = false;  // accept a checkpoint whose physics sections differ from the scene's
};

class Scene;
class NonlinearSolver;
class Stepper;

// One run: the scene, its solver, its stepper (quasi-static or dynamic) and output, and the step loop.
class Simulation {
 public:
  // Collective over comm (default: all ranks); throws InputError for bad input.
  Simulation(const SceneConfig& config, const RunOptions& options,
             Teuchos::RCP<const Teuchos::Comm<int>> comm = Teuchos::null);
  ~Simulation();
  // Runs the remaining load steps; returns the exit code: success, no convergence (after writing the
  // last converged state), or 128 + N when stopped by signal N (after writing a checkpoint).
  int run();

  // The collective "should we stop, and why" check run between Newton iterations and after each step:
  // returns a signal number, 0 to go on. The default asks whether any rank received SIGINT or SIGTERM;
  // tests replace it to stop at a chosen point.
  void set_stop_check(std::function<int()> check);
  // The state to start from instead of the scene's initial state (and, for a dynamic run, its
  // velocity): a mode shape, a state from elsewhere. Before run(); not with a restart.
  void set_initial(const Vector& u, const Vector* velocity = nullptr);
  // Called after every completed step with its record and the state (tests, tools).
  void set_step_observer(std::function<void(const StepRecord&, const Vector& u)> observer) { observer_ = std::move(observer); }

  Scene& scene() { return *scene_; }
  const Vector& displacement() const { return *u_; }
  // A dynamic run's velocity (null for a quasi-static one).
  const Vector* velocity() const;
  const std::vector<StepRecord>& records() const { return records_; }
  const Output& output() const { return *out_; }

 private:
  enum class StepOutcome { Done, Stopped, Failed };
  void print_header() const;
  // Advances the state through load step k, cutting the increment when a solve fails.
  StepOutcome advance(int k, StepRecord& rec);
  // The bones' run-up from the rest pose to load 0 before step 1 (Scene::run_up_steps).
  StepOutcome run_up();
  // A solve's progress callback: each Newton iterate's residual into `residuals`, its newton.csv row
  // (for step, at load t) and its progress line.
  std::function<void(const NewtonIterate&)> newton_progress(int step, double t, std::vector<double>& residuals);
  // Solves for the step's state from trial (its prescribed values set): rounds of the terms (System::round: contact's detection
  // and tractions) and solves until no term asks for another.
  // Pulls the step's first guess back where a term bounds the path to it (System::admit_guess).
  // Returns the fraction of the way taken (1: the whole guess).
  double admit_guess(Vector& trial);
  SolveReport solve(Vector& trial, const std::function<void(const NewtonIterate&)>& progress, StepRecord& rec);
  void print_step(const StepRecord& rec) const;
  // Collective: the step file of the current state, with the terms' node fields and a velocity.
  void write_step(int step, double load);
  // Collective: checkpoint.h5 of where the run stands (the state, the predictor's history, a velocity,
  // the terms' states).
  void checkpoint();
  void print_summary() const;

  SceneConfig config_;
  RunOptions opt_;
  Teuchos::RCP<const Teuchos::Comm<int>> comm_;
  std::unique_ptr<Scene> scene_;
  std::unique_ptr<NonlinearSolver> solver_;
  std::unique_ptr<Stepper> stepper_;  // load steps with predictors, or a time integrator
  std::unique_ptr<Output> out_;
  Teuchos::RCP<Vector> u_;
  Teuchos::RCP<Vector> u_previous_;  // the converged state before u_ (at at_.previous_load), for the predictor
  std::vector<StepRecord> records_;
  std::vector<std::string> summary_;  // the terms' lines for the last step (System::summary)
  LoadState at_;  // where the run stands: the state in u_
  std::function<int()> stop_check_;
  std::function<void(const StepRecord&, const Vector&)> observer_;
  bool initial_given_ = false;
  // u_ is an equilibrium (rest, a converged step, a checkpoint's state), where the tangent predictor's
  // linearisation holds; a scrambled or given initial state is not (from the scramble the predictor
  // took 605 Newton iterations instead of 347).
  bool at_equilibrium_ = false;
  int stop_signal_ = 0;
  bool talk_ = false;
  double started_ = 0.0;     // wall clock at the start of run(), seconds
  double start_load_ = 0.0;  // load of the state run() started from (for the time estimate)
  std::vector<std::pair<double, double>> pace_;  // (load, wall clock) where steps started: the estimate's pace
};

// Runs a scene on all ranks of the default communicator; returns the process exit code. Never
// throws: input and convergence problems are reported on stderr by rank 0.
int run_scene(const SceneConfig& scene, const RunOptions& options);

}  // namespace sinew
