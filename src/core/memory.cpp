#include <sinew/core/memory.hpp>

#include <cstdio>
#include <cstdlib>
#include <unistd.h>

namespace sinew {

double resident_mb() {
  std::FILE* f = std::fopen("/proc/self/statm", "r");
  if (!f) return 0.0;
  long pages = 0, resident = 0;
  const int n = std::fscanf(f, "%ld %ld", &pages, &resident);
  std::fclose(f);
  return n == 2 ? static_cast<double>(resident) * static_cast<double>(sysconf(_SC_PAGESIZE)) / (1024.0 * 1024.0) : 0.0;
}

void trace_memory(const char* what) {
  static const bool on = std::getenv("SINEW_MEMORY_TRACE") != nullptr;
  static double last = 0.0;
  if (!on) return;
  const double now = resident_mb();
  std::fprintf(stderr, "[memory] %s: %.1f MB (%+.1f MB)\n", what, now, now - last);
  last = now;
}

}  // namespace sinew
