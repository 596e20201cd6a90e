// Build and run-time configuration report (sinew --version / --info).
#pragma once

#include <string>

namespace sinew {

// Multi-line report: Sinew, Trilinos and Kokkos versions, Kokkos backends compiled in and the one in
// use with its thread count, the Tpetra node, MPI ranks and library, HDF5 version.
// Needs Kokkos and MPI initialized (call inside Tpetra::ScopeGuard).
std::string build_info();

// The default Kokkos execution space in use, e.g. "OpenMP (2 threads)".
std::string execution_space_summary();

}  // namespace sinew
