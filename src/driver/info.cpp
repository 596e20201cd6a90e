// sinew --version: versions, Kokkos backends compiled in and the one in use, MPI and HDF5.
#include <sinew/driver/info.hpp>
#include <sinew/version.hpp>

#include <Kokkos_Core.hpp>
#include <Tpetra_Core.hpp>
#include <Tpetra_Map.hpp>
#include <Trilinos_version.h>
#include <hdf5.h>
#include <mpi.h>

#include <sstream>

namespace sinew {

std::string execution_space_summary() {
  using Exec = Kokkos::DefaultExecutionSpace;
  std::ostringstream os;
  os << Exec::name() << " (" << Exec::concurrency() << (Exec::concurrency() == 1 ? " thread)" : " threads)");
  return os.str();
}

std::string build_info() {
  std::ostringstream os;
  os << "Sinew " << SINEW_VERSION_STRING << " - quasi-static Stable Neo-Hookean flesh simulation\n";
  os << "Trilinos " << TRILINOS_VERSION_STRING << " (Tpetra, Belos, MueLu, NOX, Stratimikos)\n";
  os << "Kokkos " << KOKKOS_VERSION / 10000 << "." << (KOKKOS_VERSION / 100) % 100 << "." << KOKKOS_VERSION % 100
     << ", backends compiled in:";
  std::string backends = SINEW_KOKKOS_BACKENDS;
  for (auto& c : backends) c = (c == ';') ? ' ' : c;
  os << " " << backends << "\n";
  os << "Kokkos execution space in use: " << execution_space_summary() << "\n";
  os << "Tpetra node: " << Tpetra::Map<>::node_type::name() << "\n";
  int ranks = 1;
  MPI_Comm_size(MPI_COMM_WORLD, &ranks);
  char lib[MPI_MAX_LIBRARY_VERSION_STRING];
  int len = 0;
  MPI_Get_library_version(lib, &len);
  std::string libs(lib, len);
  if (auto cut = libs.find_first_of(",\n"); cut != std::string::npos) libs.resize(cut);
  os << "MPI ranks: " << ranks << " (" << libs << ")\n";
  unsigned maj = 0, min = 0, rel = 0;
  H5get_libversion(&maj, &min, &rel);
  os << "HDF5 " << maj << "." << min << "." << rel
#ifdef H5_HAVE_PARALLEL
     << " (parallel)"
#endif
     << "\n";
  return os.str();
}

}  // namespace sinew
