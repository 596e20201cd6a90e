// Assembly throughput: elements per second for energy + force + projected stiffness on a lattice, on the
// Serial backend and on the default one (OpenMP with OMP_NUM_THREADS threads) in the same run; plus the
// matrix refill alone (resumeFill / zero / fillComplete) to separate Tpetra's overhead from the kernels.
#include <sinew/algebra/system.hpp>

#include <Tpetra_Core.hpp>
#include <Tpetra_CrsMatrix.hpp>
#include <Tpetra_Vector.hpp>
#include <benchmark/benchmark.h>

#include <cstdlib>
#include <map>
#include <optional>
#include <memory>

using namespace sinew;

namespace {

struct Problem {
  std::unique_ptr<System> sys;
  Teuchos::RCP<Vector> u, f;
  Teuchos::RCP<CrsMatrix> K;
};

// One system per (element type, size), built on first use and kept for the whole run; cleared before
// Kokkos and MPI are finalized.
std::map<std::pair<int, int>, Problem> cache;

Problem& problem(ElementType type, int n) {
  auto key = std::make_pair(static_cast<int>(type), n);
  auto it = cache.find(key);
  if (it != cache.end()) return it->second;
  MeshSpec ms;
  ms.element = type;
  ms.cells = {n, n, n};
  MaterialSpec mat;
  mat.mu_L = 1.0;
  mat.lambda_L = 24.5;
  Problem p;
  p.sys = std::make_unique<System>(Tpetra::getDefaultComm(), build_mesh(ms, *Tpetra::getDefaultComm()), mat);
  p.u = p.sys->create_vector();
  p.u->randomize(-0.01, 0.01);
  p.f = p.sys->create_vector();
  p.K = p.sys->create_matrix();
  return cache.emplace(key, std::move(p)).first->second;
}

void assembly(benchmark::State& state, ElementType type, Backend backend) {
  const int n = static_cast<int>(state.range(0));
  Problem& p = problem(type, n);
  // SINEW_BENCH_EXACT_HESSIAN=1: the unprojected Hessian, to see what the projection costs.
  std::optional<sinew::Projection> proj;
  if (std::getenv("SINEW_BENCH_EXACT_HESSIAN")) proj = sinew::Projection::None;
  for (auto _ : state) p.sys->evaluate(*p.u, p.f.get(), p.K.get(), backend, proj);
  const double elements = static_cast<double>(p.sys->mesh().global_elements);
  state.counters["elements_per_s"] = benchmark::Counter(elements * state.iterations(), benchmark::Counter::kIsRate);
  state.counters["threads"] = backend == Backend::Serial ? 1 : Kokkos::DefaultExecutionSpace::concurrency();
}

void refill_only(benchmark::State& state) {
  Problem& p = problem(ElementType::Hex8, static_cast<int>(state.range(0)));
  for (auto _ : state) {
    p.K->resumeFill();
    p.K->setAllToScalar(0.0);
    p.K->fillComplete();
  }
  state.counters["nonzeros"] = static_cast<double>(p.K->getGlobalNumEntries());
}

}  // namespace

int main(int argc, char** argv) {
  Tpetra::ScopeGuard scope(&argc, &argv);
  for (auto type : {ElementType::Hex8, ElementType::Tet4}) {
    const std::string t = to_string(type);
#ifdef KOKKOS_ENABLE_SERIAL
    benchmark::RegisterBenchmark(("assembly/snh/" + t + "/Serial").c_str(),
                                 [type](benchmark::State& s) { assembly(s, type, Backend::Serial); })
        ->Arg(4)->Arg(20)->Arg(40)->Unit(benchmark::kMillisecond)->UseRealTime();
#endif
    benchmark::RegisterBenchmark(("assembly/snh/" + t + "/" + Kokkos::DefaultExecutionSpace::name()).c_str(),
                                 [type](benchmark::State& s) { assembly(s, type, Backend::Default); })
        ->Arg(4)->Arg(20)->Arg(40)->Unit(benchmark::kMillisecond)->UseRealTime();
  }
  benchmark::RegisterBenchmark("assembly/matrix_refill_only/hex8", refill_only)->Arg(4)->Arg(40)->Unit(benchmark::kMillisecond)->UseRealTime();
  benchmark::Initialize(&argc, argv);
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  cache.clear();
  return 0;
}
