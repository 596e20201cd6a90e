// Material kernel throughput: energy + PK1 + projected Hessian per second, for every model, on the
// Serial and the OpenMP execution space in the same run (OpenMP uses OMP_NUM_THREADS threads).
#include <sinew/materials/models.hpp>

#include <Kokkos_Core.hpp>
#include <benchmark/benchmark.h>

using namespace sinew;

namespace {

KOKKOS_INLINE_FUNCTION Mat3 sample_F(int i) {
  // Cheap deterministic spread of stretches and shears, a fifth of them inverted.
  const double a = 0.6 + 0.8 * ((i * 37) % 101) / 100.0, b = 0.2 * (((i * 53) % 97) / 96.0 - 0.5);
  Mat3 F = Mat3::diag(a, 1.0 / std::sqrt(a), (i % 5 == 0 ? -1.0 : 1.0) / std::sqrt(a));
  F(0, 1) = b;
  F(1, 2) = -b;
  return F;
}

template <class Exec>
void bench(benchmark::State& state, MaterialModel model) {
  const int n = static_cast<int>(state.range(0));
  MaterialSpec spec = material_defaults(model, 1.0, 24.5);
  options_of<StVKKikuuwe>(spec).kappa = 1e4;
  Kokkos::View<double*, typename Exec::memory_space> out("out", n);
  with_material(spec, [&](auto m) {
    for (auto _ : state) {
      Kokkos::parallel_for(
          "material_eval", Kokkos::RangePolicy<Exec>(0, n), KOKKOS_LAMBDA(const int i) {
            const Mat3 F = sample_F(i);
            const double e = m.energy(F);
            const Mat3 P = m.pk1(F);
            const Mat9 H = m.projected_hessian(F, Projection::Clamp);
            out(i) = e + P[0] + H.a[0] + H.a[80];
          });
      Kokkos::fence();
    }
  });
  state.counters["evals_per_s"] = benchmark::Counter(static_cast<double>(n) * state.iterations(), benchmark::Counter::kIsRate);
  state.counters["threads"] = Exec::concurrency();
}

}  // namespace

int main(int argc, char** argv) {
  Kokkos::ScopeGuard kokkos(argc, argv);
  for (std::size_t k = 0; k < material_model_names().size(); ++k) {
    const auto m = static_cast<MaterialModel>(k);
    const std::string name = material_model_names()[k];
#ifdef KOKKOS_ENABLE_SERIAL
    benchmark::RegisterBenchmark(("material/" + name + "/Serial").c_str(),
                                 [m](benchmark::State& s) { bench<Kokkos::Serial>(s, m); })
        ->Arg(64)->Arg(1 << 16)->UseRealTime();
#endif
#ifdef KOKKOS_ENABLE_OPENMP
    benchmark::RegisterBenchmark(("material/" + name + "/OpenMP").c_str(),
                                 [m](benchmark::State& s) { bench<Kokkos::OpenMP>(s, m); })
        ->Arg(64)->Arg(1 << 16)->UseRealTime();
#endif
  }
  benchmark::Initialize(&argc, argv);
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
