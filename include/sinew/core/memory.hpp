// The process's resident memory now, for SINEW_MEMORY_TRACE (the run summary's peak comes from
// getrusage): with that variable set, each phase that allocates a large share of a run (mesh, element
// data, graph, matrix, preconditioner, Krylov solve) prints the resident memory after it to stderr,
// which is how docs/performance.md splits the bytes per DOF. With transparent huge pages (sinew's
// default, src/driver/main.cpp) resident memory grows in 2 MB steps: SINEW_HUGE_PAGES=0 for small runs.
#pragma once

namespace sinew {

// Resident memory now, in MB (from /proc/self/statm; 0 where that cannot be read).
double resident_mb();

// With SINEW_MEMORY_TRACE set: "[memory] <what>: <resident> MB (<change> MB)" on stderr, every rank.
void trace_memory(const char* what);

}  // namespace sinew
