// How large a mesh rank 0 can read: the time and peak memory of reading a Gmsh file on rank 0 and
// distributing it over all ranks (Zoltan2 multi-jagged, ghost layer, node data), for the README.
//   mpirun -np R bench_mesh FILE.msh
// Prints one JSON object: elements, nodes, read and distribute seconds, peak resident memory per rank
// (rank 0 holds the whole file while reading) and the bytes per element that peak means on rank 0.
#include <sinew/discretization/mesh_file.hpp>
#include <sinew/discretization/partition.hpp>

#include <Teuchos_CommHelpers.hpp>
#include <Tpetra_Core.hpp>

#include <sys/resource.h>

#include <chrono>
#include <cstdio>

namespace {
double now() { return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count(); }
double peak_mb() {
  rusage ru{};
  getrusage(RUSAGE_SELF, &ru);
  return static_cast<double>(ru.ru_maxrss) / 1024.0;
}
}  // namespace

int main(int argc, char** argv) {
  Tpetra::ScopeGuard scope(&argc, &argv);
  auto comm = Tpetra::getDefaultComm();
  if (argc != 2) {
    if (comm->getRank() == 0) std::fprintf(stderr, "usage: bench_mesh FILE.msh\n");
    return 2;
  }
  try {
    const double before_mb = peak_mb();
    comm->barrier();
    const double t0 = now();
    sinew::MeshFile file;
    if (comm->getRank() == 0) file = sinew::read_mesh_file(argv[1]);
    const double t1 = now();
    const double read_mb = peak_mb();
    comm->barrier();
    const double t2 = now();
    const sinew::Mesh mesh = sinew::distribute_mesh(std::move(file), *comm);
    comm->barrier();
    const double t3 = now();
    double peak = peak_mb(), max_peak = 0.0, min_peak = 0.0;
    Teuchos::reduceAll(*comm, Teuchos::REDUCE_MAX, 1, &peak, &max_peak);
    Teuchos::reduceAll(*comm, Teuchos::REDUCE_MIN, 1, &peak, &min_peak);
    unsigned long long local = mesh.local_elements(), most = 0;
    Teuchos::reduceAll(*comm, Teuchos::REDUCE_MAX, 1, &local, &most);
    if (comm->getRank() == 0)
      std::printf("{\"ranks\": %d, \"elements\": %lld, \"nodes\": %lld, \"read_s\": %.2f, \"distribute_s\": %.2f, "
                  "\"rank0_peak_mb\": %.0f, \"rank0_read_mb\": %.0f, \"rank0_base_mb\": %.0f, \"max_peak_mb\": %.0f, "
                  "\"min_peak_mb\": %.0f, \"most_local_elements\": %llu, \"rank0_bytes_per_element\": %.0f}\n",
                  comm->getSize(), static_cast<long long>(mesh.global_elements), static_cast<long long>(mesh.global_nodes),
                  t1 - t0, t3 - t2, peak, read_mb, before_mb, max_peak, min_peak, most,
                  (peak - before_mb) * 1048576.0 / static_cast<double>(mesh.global_elements));
  } catch (const std::exception& e) {
    std::fprintf(stderr, "bench_mesh: %s\n", e.what());
    return 3;
  }
  return 0;
}
