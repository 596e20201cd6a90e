// SIGINT/SIGTERM: the handler only records the signal; the run checks it at safe points (between Newton
// iterations and after each step), agrees on it across ranks, writes a checkpoint and exits.
#pragma once

namespace sinew {

void install_signal_handlers();
// The last signal received by this process (0: none).
int pending_signal();

}  // namespace sinew
