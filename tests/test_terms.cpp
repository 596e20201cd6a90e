// The terms of the total energy, each on its own: values against closed forms, gradients and Hessians
// against finite differences, PSD Hessians against LAPACK, and the same sums on 1 thread, 2 threads and
// 2 ranks.
#include "material_test_utils.hpp"
#include "system_test_utils.hpp"

#include <sinew/algebra/terms/external_force.hpp>

#include <Tpetra_Core.hpp>
#include <Tpetra_Vector.hpp>
#include <gtest/gtest.h>

using namespace sinew;
using namespace sinew::test;

namespace {

auto world() { return Tpetra::getDefaultComm(); }

MaterialSpec snh(double density = 1000.0) {
  MaterialSpec s = test::all_models(1.0, 0.45)[static_cast<std::size_t>(MaterialModel::StableNeoHookean)];
  s.density = density;
  return s;
}

}  // namespace

// E_ext = -int b . u dV for a body force b per reference volume. For u = c + G (X - X0) on the box
// [0, 1] x [0, 0.8] x [0, 1.2] (interior nodes jittered, so elements are not affine), the integral is
// -(b . c) V - b . G (centroid - X0) V, which the elements' quadrature integrates exactly.
TEST(Terms, BodyForcePotentialIsMinusTheWorkOfTheLoad) {
  for (auto type : {ElementType::Hex8, ElementType::Tet4}) {
    MeshSpec spec = box(3, type, 4);
    spec.jitter = 0.2;
    System sys(world(), build_mesh(spec, *world()), snh());
    const std::array<double, 3> b{0.3, -1.1, 2.0}, c{0.01, 0.02, -0.03}, X0{0.1, 0.2, 0.3};
    const double G[3][3] = {{0.01, 0.02, 0.0}, {-0.01, 0.0, 0.03}, {0.02, 0.01, -0.02}};
    sys.set_body_force(b);
    auto u = sys.create_vector();
    set_displacement(sys, *u, [&](const std::array<double, 3>& X, int i, long long) {
      double v = c[i];
      for (int j = 0; j < 3; ++j) v += G[i][j] * (X[j] - X0[j]);
      return v;
    });
    auto f = sys.create_vector();
    const auto t = sys.evaluate(*u, f.get(), nullptr);
    const double V = 1.0 * 0.8 * 1.2, centroid[3] = {0.5, 0.4, 0.6};
    double expected = 0.0;
    for (int i = 0; i < 3; ++i) {
      double Gc = 0.0;
      for (int j = 0; j < 3; ++j) Gc += G[i][j] * (centroid[j] - X0[j]);
      expected -= b[i] * (c[i] + Gc) * V;
    }
    EXPECT_NEAR(t.external, expected, 1e-12 * std::fabs(expected)) << to_string(type);
    EXPECT_NEAR(t.energy, t.elastic + t.external, 1e-14 * std::fabs(t.energy));
    EXPECT_NEAR(sys.reference_volume(), V, 1e-12);
    // The force is the gradient: its external part sums to -b V per component (internal forces sum to
    // zero, being those of a translation-invariant energy).
    const auto fg = gather(*f);
    double sum[3] = {0, 0, 0};
    for (std::size_t k = 0; k < fg.size(); ++k) sum[k % 3] += fg[k];
    for (int i = 0; i < 3; ++i) EXPECT_NEAR(sum[i], -b[i] * V, 1e-11) << to_string(type);
  }
}

// Gravity weighs each node by its lumped mass: the total load is g times density times volume, and the
// lumped masses sum to the mass.
TEST(Terms, GravityWeighsTheLumpedMass) {
  const double rho = 1070.0;
  System sys(world(), build_mesh(box(3, ElementType::Tet4), *world()), snh(rho));
  double m = 0.0, V = 0.0;
  for (double x : sys.nodal_mass()) m += x;
  for (double x : sys.nodal_volume()) V += x;
  double gm = 0.0, gV = 0.0;
  Teuchos::reduceAll(*world(), Teuchos::REDUCE_SUM, m, Teuchos::outArg(gm));
  Teuchos::reduceAll(*world(), Teuchos::REDUCE_SUM, V, Teuchos::outArg(gV));
  EXPECT_NEAR(gV, 0.96, 1e-12);
  EXPECT_NEAR(gm, rho * 0.96, 1e-9);
  sys.set_gravity({0.0, 0.0, -9.81});
  auto u = sys.create_vector();
  u->putScalar(0.25);  // a translation: no elastic energy
  const auto t = sys.evaluate(*u, nullptr, nullptr);
  EXPECT_NEAR(t.elastic, 0.0, 1e-12);
  EXPECT_NEAR(t.external, 9.81 * 0.25 * rho * 0.96, 1e-9);
}

// System::relax_nodes (nonlinear Gauss-Seidel on the nodes that hold the residual): one interior node
// pulled far from its place, under a body force, is moved back to where its whole force (elastic and
// external, as evaluate() computes it) vanishes, the energy falls by what the local solves report, and
// no other node moves. A wrong frozen share of the gradient (the external load) would leave a force
// there; a wrong patch would move the energy by another amount.
TEST(Terms, NodeRelaxationReturnsAPulledNodeToItsEquilibriumAndLowersTheEnergy) {
  for (auto type : {ElementType::Hex8, ElementType::Tet4}) {
    MeshSpec spec = box(4, type);
    spec.jitter = 0.15;
    System sys(world(), build_mesh(spec, *world()), snh());
    sys.set_body_force({0.0, -0.3, 0.2});
    // The node nearest the box's centre (the same one on every rank: chosen by reference position).
    const std::array<double, 3> c{0.5, 0.4, 0.6};
    const auto pulled_centre = [&](const std::array<double, 3>& X, int i, long long) {
      const double d2 = (X[0] - c[0]) * (X[0] - c[0]) + (X[1] - c[1]) * (X[1] - c[1]) + (X[2] - c[2]) * (X[2] - c[2]);
      const double pull[3] = {0.06, -0.04, 0.05};
      return d2 < 0.01 ? pull[i] : 0.0;
    };
    auto u = sys.create_vector();
    set_displacement(sys, *u, pulled_centre);
    auto f = sys.create_vector();
    const double E0 = sys.evaluate(*u, f.get(), nullptr).energy;
    const auto before = gather(*u), f0 = gather(*f);
    std::size_t pulled = 0, count = 0;
    for (std::size_t k = 0; k < before.size(); k += 3)
      if (before[k] != 0.0) {
        pulled = k / 3;
        ++count;
      }
    ASSERT_EQ(count, 1u) << to_string(type);
    const double fn0 = std::hypot(f0[3 * pulled], f0[3 * pulled + 1], f0[3 * pulled + 2]);
    // A share of |F|^2 that only the pulled node holds, no rings: that node alone.
    NodeRelaxationSettings settings;
    const NodeRelaxationTotals t = sys.relax_nodes(*u, *f, 0.3, 0, settings);
    EXPECT_EQ(t.nodes, 1) << to_string(type);
    EXPECT_GT(t.iterations, 1) << to_string(type);
    const double E1 = sys.evaluate(*u, f.get(), nullptr).energy;
    EXPECT_LT(E1, E0) << to_string(type);
    EXPECT_NEAR(E0 - E1, t.decrease, 1e-9 * std::fabs(E0)) << to_string(type);
    const auto after = gather(*u), f1 = gather(*f);
    const double fn1 = std::hypot(f1[3 * pulled], f1[3 * pulled + 1], f1[3 * pulled + 2]);
    EXPECT_LT(fn1, 1e-3 * fn0) << to_string(type) << ": force " << fn0 << " -> " << fn1;
    for (std::size_t k = 0; k < after.size(); ++k)
      if (k / 3 != pulled) EXPECT_EQ(after[k], before[k]) << to_string(type) << " DOF " << k;
    EXPECT_GT(std::fabs(after[3 * pulled] - before[3 * pulled]), 0.01) << to_string(type);
    // With rings the neighbours move too, and the energy falls further.
    auto u2 = sys.create_vector();
    set_displacement(sys, *u2, pulled_centre);
    sys.evaluate(*u2, f.get(), nullptr);
    const NodeRelaxationTotals t2 = sys.relax_nodes(*u2, *f, 0.3, 1, settings);
    EXPECT_GT(t2.nodes, 1) << to_string(type);
    EXPECT_LT(sys.evaluate(*u2, nullptr, nullptr).energy, E1) << to_string(type);
  }
}
