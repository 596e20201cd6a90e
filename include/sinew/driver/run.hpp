// The quasi-static run: load steps with step cutting, progress lines, log and output.
#pragma once

#include <sinew/algebra/elastic_system.hpp>
#include <sinew/driver/config.hpp>

#include <memory>
#include <vector>

namespace sinew {

struct RunOptions {
  bool quiet = false;        // no progress lines (errors still go to stderr)
  std::string restart_file;  // continue from this checkpoint (empty: start from the beginning)
};

// Exit codes of a run.
// A run stopped by SIGINT/SIGTERM exits with 128 + the signal number, after writing a checkpoint.
enum ExitCode { kSuccess = 0, kFailure = 1, kUsage = 2, kInputError = 3, kNoConvergence = 4 };

class Scene;
class NonlinearSolver;
class Output;
struct StepRecord;

// One quasi-static run: the scene, its solver and output, and the load-step loop.
class Simulation {
 public:
  // Collective over comm (default: all ranks); throws InputError for bad input.
  Simulation(const SceneConfig& config, const RunOptions& options,
             Teuchos::RCP<const Teuchos::Comm<int>> comm = Teuchos::null);
  ~Simulation();
  // Runs all load steps; returns kSuccess or kNoConvergence (after writing the last converged state).
  int run();
  Scene& scene() { return *scene_; }
  const Vector& displacement() const { return *u_; }
  const std::vector<StepRecord>& records() const { return records_; }
  const Output& output() const { return *out_; }

 private:
  SceneConfig config_;
  RunOptions opt_;
  std::unique_ptr<Scene> scene_;
  std::unique_ptr<NonlinearSolver> solver_;
  std::unique_ptr<Output> out_;
  Teuchos::RCP<Vector> u_;
  std::vector<StepRecord> records_;
  int first_step_ = 1;       // 1, or the step after the checkpoint a restart continues from
  double start_load_ = 0.0;  // load fraction of the state in u_ at the start
};

// Runs a scene on all ranks of the default communicator; returns the process exit code. Never
// throws for input or convergence problems: they are reported on stderr by rank 0.
int run_scene(const SceneConfig& scene, const RunOptions& options);

}  // namespace sinew
