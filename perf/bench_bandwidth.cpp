// Memory-bandwidth bound and one CG iteration against it.
//   triad: a = b + s c on Kokkos Views (STREAM's triad), bytes = 24 per entry;
//   cg_iteration: y = K p, two dot products and three vector updates on the assembled stiffness of a
//   hex8 lattice, bytes = 12 per nonzero + 128 per row (values, column indices, and the vector traffic).
// Prints one JSON object. Usage: bench_bandwidth [--cells N] [--reps R]
#include <sinew/algebra/system.hpp>

#include <Kokkos_Core.hpp>
#include <Tpetra_Core.hpp>
#include <Tpetra_CrsMatrix.hpp>
#include <Tpetra_Vector.hpp>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>

using namespace sinew;
using Clock = std::chrono::steady_clock;

int main(int argc, char** argv) {
  Tpetra::ScopeGuard scope(&argc, &argv);
  int cells = 40, reps = 20;
  for (int i = 1; i + 1 < argc; ++i) {
    if (!std::strcmp(argv[i], "--cells")) cells = std::atoi(argv[i + 1]);
    if (!std::strcmp(argv[i], "--reps")) reps = std::atoi(argv[i + 1]);
  }
  auto comm = Tpetra::getDefaultComm();
  // Triad on arrays far larger than the caches (3 x 32M doubles = 768 MB at the default size).
  const std::size_t n = static_cast<std::size_t>(cells) >= 40 ? (std::size_t(1) << 25) : (std::size_t(1) << 20);
  Kokkos::View<double*> a("a", n), b("b", n), c("c", n);
  Kokkos::deep_copy(b, 1.0);
  Kokkos::deep_copy(c, 2.0);
  double best_triad = 1e300;
  for (int r = 0; r < reps; ++r) {
    const auto t0 = Clock::now();
    Kokkos::parallel_for("triad", n, KOKKOS_LAMBDA(const std::size_t i) { a(i) = b(i) + 3.0 * c(i); });
    Kokkos::fence();
    best_triad = std::min(best_triad, std::chrono::duration<double>(Clock::now() - t0).count());
  }
  const double triad_gbs = 24.0 * n / best_triad / 1e9;

  MeshSpec ms;
  ms.cells = {cells, cells, cells};
  MaterialSpec mat;
  mat.mu_L = 1.0;
  mat.lambda_L = 24.5;
  System sys(comm, build_mesh(ms, *comm), mat);
  auto u = sys.create_vector();
  u->putScalar(0.0);
  auto K = sys.create_matrix();
  sys.evaluate(*u, nullptr, K.get());
  Vector p(sys.owned_dofs()), y(sys.owned_dofs()), x(sys.owned_dofs()), res(sys.owned_dofs());
  p.randomize();
  res.randomize();
  x.putScalar(0.0);
  double best_cg = 1e300;
  for (int r = 0; r < reps; ++r) {
    const auto t0 = Clock::now();
    K->apply(p, y);
    const double pKp = p.dot(y);
    const double alpha = 1e-3 / (std::fabs(pKp) + 1.0);
    x.update(alpha, p, 1.0);
    res.update(-alpha, y, 1.0);
    const double rr = res.dot(res);
    p.update(1.0, res, 1e-3 * rr / (rr + 1.0));
    best_cg = std::min(best_cg, std::chrono::duration<double>(Clock::now() - t0).count());
  }
  const double rows = static_cast<double>(K->getGlobalNumRows()), nnz = static_cast<double>(K->getGlobalNumEntries());
  const double cg_bytes = 12.0 * nnz + 128.0 * rows;
  const double cg_gbs = cg_bytes / best_cg / 1e9;
  if (comm->getRank() == 0)
    std::printf("{\"backend\": \"%s\", \"threads\": %d, \"ranks\": %d, \"triad_GBps\": %.3f, \"cg_rows\": %.0f, "
                "\"cg_nonzeros\": %.0f, \"cg_iteration_seconds\": %.6f, \"cg_GBps\": %.3f, \"cg_fraction_of_triad\": %.3f}\n",
                Kokkos::DefaultExecutionSpace::name(), Kokkos::DefaultExecutionSpace::concurrency(), comm->getSize(),
                triad_gbs, rows, nnz, best_cg, cg_gbs, cg_gbs / triad_gbs);
  return 0;
}
