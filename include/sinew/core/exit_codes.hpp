// Exit codes of the executables, and the one place that maps what a run throws to a message and a code.
#pragma once

#include <functional>

namespace sinew {

enum class ExitCode : int {
  Success = 0,
  Failure = 1,        // an internal error
  Usage = 2,          // a bad command line
  InputError = 3,     // a bad scene, mesh or checkpoint
  NoConvergence = 4,  // a load step did not converge after every cut (the last converged state is written)
};
// A run stopped by SIGINT/SIGTERM exits with 128 + the signal number, after writing a checkpoint.
inline int signal_exit_code(int sig) { return 128 + sig; }
inline int code(ExitCode c) { return static_cast<int>(c); }

// Runs fn; a UsageError becomes "PROGRAM: ... (see --help)" and exit 2, an InputError becomes "PROGRAM: input error [kind]: ..." and exit 3, any other exception
// "PROGRAM: error: ..." and exit 1. Only `report` (rank 0) prints.
int run_guarded(const char* program, bool report, const std::function<int()>& fn);

}  // namespace sinew
