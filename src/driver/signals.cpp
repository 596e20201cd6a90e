// SIGINT/SIGTERM: the first only records the signal, and the run stops at its next safe point (between
// Newton iterations, or after a step) with a checkpoint. A second one means the user will not wait (a
// long CG, a large MueLu setup): exit at once, leaving the last checkpoint on disk.
#include <sinew/driver/signals.hpp>

#include <unistd.h>

#include <csignal>

namespace sinew {

namespace {
volatile std::sig_atomic_t g_signal = 0;

extern "C" void record_signal(int sig) {
  if (g_signal != 0) {
    static const char msg[] = "\nsinew: second interrupt: exiting now; the last checkpoint stays on disk\n";
    const ssize_t ignored = ::write(STDERR_FILENO, msg, sizeof msg - 1);  // async-signal-safe
    (void)ignored;
    ::_exit(128 + sig);
  }
  g_signal = sig;
}
}  // namespace

void install_signal_handlers() {
  struct sigaction sa {};
  sa.sa_handler = record_signal;
  sigemptyset(&sa.sa_mask);
  sa.sa_flags = 0;
  sigaction(SIGINT, &sa, nullptr);
  sigaction(SIGTERM, &sa, nullptr);
}

int pending_signal() { return static_cast<int>(g_signal); }

}  // namespace sinew
