// The quasi-static run: load steps with step cutting, progress lines, log and output.
#pragma once

#include <sinew/driver/config.hpp>

namespace sinew {

struct RunOptions {
  bool quiet = false;  // no progress lines (errors still go to stderr)
};

// Exit codes of a run.
enum ExitCode { kSuccess = 0, kFailure = 1, kUsage = 2, kInputError = 3, kNoConvergence = 4 };

// Runs a scene on all ranks of the default communicator; returns the process exit code. Never
// throws for input or convergence problems: they are reported on stderr by rank 0.
int run_scene(const SceneConfig& scene, const RunOptions& options);

}  // namespace sinew
