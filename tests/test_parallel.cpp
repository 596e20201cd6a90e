// The material kernels inside Kokkos parallel_for on the default execution space (OpenMP with the
// threads CTest gives it) and over MPI ranks, compared with plain serial evaluation.
#include "material_test_utils.hpp"

#include <sinew/core/hash.hpp>

#include <Kokkos_Core.hpp>
#include <Tpetra_Core.hpp>
#include <Tpetra_Map.hpp>
#include <Tpetra_Vector.hpp>
#include <gtest/gtest.h>

#include <cstdlib>

using namespace sinew;

namespace {

// Deterministic F for global index i, the same on every rank and thread.
KOKKOS_INLINE_FUNCTION Mat3 deformation(std::int64_t i) {
  Mat3 F = Mat3::identity();
  for (int k = 0; k < 9; ++k) F[k] += 1.2 * (unit_hash(i, k, 1) - 0.5);
  if (i % 5 == 0) F.set_col(2, Vec3{{-F(0, 2), -F(1, 2), -F(2, 2)}});  // some inverted ones
  return F;
}

using Exec = Kokkos::DefaultExecutionSpace;

}  // namespace

TEST(Parallel, ThreadsAndRanksAsConfigured) {
  if (const char* t = std::getenv("SINEW_EXPECT_THREADS")) {
    EXPECT_EQ(Exec::concurrency(), std::atoi(t));
  }
  if (const char* r = std::getenv("SINEW_EXPECT_RANKS")) {
    int size = 0;
    MPI_Comm_size(MPI_COMM_WORLD, &size);
    EXPECT_EQ(size, std::atoi(r));
  }
}

TEST(Parallel, MaterialKernelsMatchSerial) {
  const int n = 4000;
  for (const auto& spec : test::all_models(1.0, 0.45)) {
    with_material(spec, [&](auto m) {
      Kokkos::View<double*, Exec> psi("psi", n);
      Kokkos::View<double* [9], Exec> P("P", n);
      Kokkos::View<double* [81], Exec> H("H", n);
      const Projection proj = Projection::Clamp;
      Kokkos::parallel_for(
          "material_batch", Kokkos::RangePolicy<Exec>(0, n), KOKKOS_LAMBDA(const int i) {
            const Mat3 F = deformation(i);
            psi(i) = m.defined(F) ? m.energy(F) : 0.0;
            const Mat3 Pi = m.pk1(F);
            for (int k = 0; k < 9; ++k) P(i, k) = Pi[k];
            const Mat9 Hi = m.projected_hessian(F, proj);
            for (int k = 0; k < 81; ++k) H(i, k) = Hi.a[k];
          });
      auto psi_h = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), psi);
      auto P_h = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), P);
      auto H_h = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), H);
      double worst = 0.0;
      for (int i = 0; i < n; ++i) {
        const Mat3 F = deformation(i);
        const double e = m.defined(F) ? m.energy(F) : 0.0;
        worst = std::max(worst, std::fabs(psi_h(i) - e) / std::max(1.0, std::fabs(e)));
        const Mat3 Pi = m.pk1(F);
        for (int k = 0; k < 9; ++k) worst = std::max(worst, std::fabs(P_h(i, k) - Pi[k]) / std::max(1.0, std::fabs(Pi[k])));
        const Mat9 Hi = m.projected_hessian(F, proj);
        for (int k = 0; k < 81; ++k)
          worst = std::max(worst, std::fabs(H_h(i, k) - Hi.a[k]) / std::max(1.0, std::fabs(Hi.a[k])));
      }
      EXPECT_LT(worst, 1e-13) << to_string(spec.model) << " on " << Exec::name();
    });
  }
}

TEST(Parallel, DistributedEnergySumMatchesSerial) {
  // Each rank evaluates the energy of the deformations it owns in a Tpetra map; the global sum must
  // equal a serial evaluation of all of them.
  auto comm = Tpetra::getDefaultComm();
  using Map = Tpetra::Map<>;
  using GO = Map::global_ordinal_type;
  const GO n = 10007;
  auto map = Teuchos::rcp(new Map(static_cast<Tpetra::global_size_t>(n), 0, comm));
  Tpetra::Vector<> energy(map);
  const auto m = StableNeoHookean::from_lame(1.0, 20.0);
  {
    auto local = energy.getLocalViewDevice(Tpetra::Access::OverwriteAll);
    const GO first = map->getMinGlobalIndex();
    using DevExec = Tpetra::Vector<>::execution_space;
    Kokkos::parallel_for(
        "energy", Kokkos::RangePolicy<DevExec>(0, static_cast<int>(map->getNodeNumElements())),
        KOKKOS_LAMBDA(const int i) { local(i, 0) = m.energy(deformation(first + i)); });
  }
  const double total = energy.norm1();
  Tpetra::Vector<> ones(map);
  ones.putScalar(1.0);
  const double sum = energy.dot(ones);
  double serial = 0.0, serial_abs = 0.0;
  for (GO i = 0; i < n; ++i) {
    serial += m.energy(deformation(i));
    serial_abs += std::fabs(m.energy(deformation(i)));
  }
  EXPECT_NEAR(sum, serial, 1e-12 * serial_abs);
  EXPECT_NEAR(total, serial_abs, 1e-12 * serial_abs);
  if (comm->getSize() > 1) {
    EXPECT_LT(map->getNodeNumElements(), static_cast<std::size_t>(n));
  }
}
