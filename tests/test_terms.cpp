// The terms of the total energy, each on its own: values against closed forms, gradients and Hessians
// against finite differences, PSD Hessians against LAPACK, and the same sums on 1 thread, 2 threads and
// 2 ranks.
#include "material_test_utils.hpp"
#include "scene_test_utils.hpp"
#include "system_test_utils.hpp"

#include <sinew/algebra/terms/external_force.hpp>
#include <sinew/driver/run.hpp>
#include <sinew/scenes/scene.hpp>
#include <sinew/scenes/terms/pressure.hpp>

#include <Teuchos_CommHelpers.hpp>
#include <Tpetra_CrsMatrix.hpp>
#include <Tpetra_Import.hpp>

#include <Tpetra_Core.hpp>
#include <Tpetra_Vector.hpp>
#include <gtest/gtest.h>

using namespace sinew;
using namespace sinew::test;

namespace {

auto world() { return Tpetra::getDefaultComm(); }

// A box [0, 1] x [0, 0.8] x [0, 1.2] of 4 x 4 x 6 hex8 cells (Young 1000, nu 0.3) with the Pressure
// section `loads`, and `conditions` under Loading/Boundary conditions.
std::string loaded_box(const std::string& loads, const std::string& conditions, int steps = 1) {
  return R"x(<ParameterList name="Sinew">
  <Parameter name="Scene" type="string" value="loaded_box"/>
  <ParameterList name="Mesh">
    <Parameter name="Type" type="string" value="box"/>
    <Parameter name="Elements" type="Array(int)" value="{4, 4, 6}"/>
    <Parameter name="Upper corner" type="Array(double)" value="{1.0, 0.8, 1.2}"/>
  </ParameterList>
  <ParameterList name="Material">
    <Parameter name="Model" type="string" value="stable-neohookean"/>
    <Parameter name="Young modulus" type="double" value="1000.0"/>
    <Parameter name="Poisson ratio" type="double" value="0.3"/>
  </ParameterList>
  <ParameterList name="Loading">
    <Parameter name="Steps" type="int" value=")x" + std::to_string(steps) + R"x("/>
    <ParameterList name="Boundary conditions">)x" + conditions + R"x(</ParameterList>
  </ParameterList>
  <ParameterList name="Pressure">)x" + loads + R"x(</ParameterList>
  <ParameterList name="Solver">
    <Parameter name="Absolute tolerance" type="double" value="1.0e-10"/>
  </ParameterList>
  )x" + logs_only_output() + R"x(
</ParameterList>)x";
}

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
    EXPECT_NEAR(t.share("external"), expected, 1e-12 * std::fabs(expected)) << to_string(type);
    EXPECT_NEAR(t.energy, t.share("elastic") + t.share("external"), 1e-14 * std::fabs(t.energy));
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
  EXPECT_NEAR(t.share("elastic"), 0.0, 1e-12);
  EXPECT_NEAR(t.share("external"), 9.81 * 0.25 * rho * 0.96, 1e-9);
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

// A pressure p on the face z+ (area 0.8) and a traction t on the face x+ (area 0.96): the term's energy
// at a rigid translation c is -(t 0.96 - p 0.8 e_z) . c (exact: the nodal loads of each face sum to its
// load), its gradient the same loads at any u (summed over the nodes), zero before the load is set,
// half at load 0.5; the Hessian is zero.
TEST(Terms, APressureAndATractionLoadTheirFacesWithTheirAreas) {
  const std::string loads = R"x(
    <ParameterList name="lid"><Parameter name="Region" type="string" value="face z+"/>
      <Parameter name="Pressure" type="double" value="50.0"/></ParameterList>
    <ParameterList name="side"><Parameter name="Region" type="string" value="face x+"/>
      <Parameter name="Traction" type="Array(double)" value="{3.0, -2.0, 7.0}"/></ParameterList>)x";
  SceneConfig c = config(loaded_box(loads, R"x(<ParameterList name="base"><Parameter name="Region" type="string" value="face z-"/></ParameterList>)x"),
                         "test_results/pressure_unit");
  Scene scene(c.scene(), world());
  System& sys = scene.system();
  const auto* term = sys.find_term<PressureTerm>();
  ASSERT_NE(term, nullptr);
  const std::array<double, 3> load{3.0 * 0.96, -2.0 * 0.96, 7.0 * 0.96 - 50.0 * 0.8};
  for (int d = 0; d < 3; ++d) EXPECT_NEAR(term->resultant()[d], load[d], 1e-12) << d;
  const std::array<double, 3> shift{0.3, -0.1, 0.2};
  auto u = sys.create_vector();
  set_displacement(sys, *u, [&](const std::array<double, 3>&, int comp, long long) { return shift[comp]; });
  auto f = sys.create_vector();
  for (double t : {0.0, 0.5, 1.0}) {
    sys.set_load(t);
    const EvaluationTotals e = sys.evaluate(*u, nullptr, nullptr);
    const double expected = -t * (load[0] * shift[0] + load[1] * shift[1] + load[2] * shift[2]);
    EXPECT_NEAR(e.share("pressure"), expected, 1e-12) << "load " << t;
    // The gradient of the term alone, unconstrained, at a random state: minus the loads.
    set_displacement(sys, *u, [&](const std::array<double, 3>&, int comp, long long gid) { return 0.1 * hash_unit(gid, comp); });
    sys.gradient(*u, *f, term);
    const auto g = gather(*f);
    for (int d = 0; d < 3; ++d) {
      double sum = 0.0;
      for (std::size_t k = d; k < g.size(); k += 3) sum += g[k];
      EXPECT_NEAR(sum, -t * load[d], 1e-12) << "load " << t << ", component " << d;
    }
    set_displacement(sys, *u, [&](const std::array<double, 3>&, int comp, long long) { return shift[comp]; });
  }
  // Linear in u: no Hessian at all.
  EXPECT_EQ(max_abs(term_hessian(sys, *term, *u)), 0.0);
}

// A bar pulled by a traction sigma = 1 (a thousandth of Young's modulus) on its face x+, held by
// rollers on x-, y- and z- (uniaxial stress, which hex8 represent exactly): at equilibrium the rollers'
// reaction carries the load (sum of the x gradient over x- = -sigma A, to 1e-9); the face x+ moves as
// one (the nodal loads are the consistent ones: equal loads per node would bend it); the stretches F =
// diag(1 + ux, 1 + uy / 0.8, 1 + uz / 1.2) satisfy the material point's uniaxial equilibrium, P(F) =
// diag(sigma, 0, 0) (to 1e-6 sigma); in two load steps the same end state.
TEST(Terms, ABarPulledByATractionIsInUniaxialEquilibrium) {
  const std::string loads = R"x(<ParameterList name="pull"><Parameter name="Region" type="string" value="face x+"/>
      <Parameter name="Traction" type="Array(double)" value="{1.0, 0.0, 0.0}"/></ParameterList>)x";
  const std::string rollers = R"x(
      <ParameterList name="x"><Parameter name="Region" type="string" value="face x-"/><Parameter name="Components" type="string" value="x"/></ParameterList>
      <ParameterList name="y"><Parameter name="Region" type="string" value="face y-"/><Parameter name="Components" type="string" value="y"/></ParameterList>
      <ParameterList name="z"><Parameter name="Region" type="string" value="face z-"/><Parameter name="Components" type="string" value="z"/></ParameterList>)x";
  std::vector<double> ends;
  for (int steps : {1, 2}) {
    Simulation sim(config(loaded_box(loads, rollers, steps), "test_results/pressure_bar" + std::to_string(steps)), RunOptions{true, ""});
    ASSERT_EQ(sim.run(), 0);
    const System& sys = sim.scene().system();
    auto f = sys.create_vector();
    sys.gradient(sim.displacement(), *f);
    const auto g = gather(*f), u = gather(sim.displacement());
    auto X = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), sys.mesh().X);
    double reaction = 0.0, lo = HUGE_VAL, hi = -HUGE_VAL, corner[3] = {0, 0, 0};
    for (std::size_t n = 0; n < sys.mesh().n_owned_nodes; ++n) {
      const auto gid = static_cast<std::size_t>(sys.mesh().node_gid[n]);
      if (X(n, 0) < 1e-12) reaction += g[3 * gid];
      if (X(n, 0) > 1.0 - 1e-12) {
        lo = std::min(lo, u[3 * gid]);
        hi = std::max(hi, u[3 * gid]);
      }
      if (X(n, 0) > 1.0 - 1e-12 && X(n, 1) > 0.8 - 1e-12 && X(n, 2) > 1.2 - 1e-12)
        for (int d = 0; d < 3; ++d) corner[d] = u[3 * gid + d];
    }
    double all[4] = {0, 0, 0, 0}, mine[4] = {reaction, corner[0], corner[1], corner[2]}, glo = 0.0, ghi = 0.0;
    Teuchos::reduceAll(*world(), Teuchos::REDUCE_SUM, 4, mine, all);
    Teuchos::reduceAll(*world(), Teuchos::REDUCE_MIN, lo, Teuchos::outArg(glo));
    Teuchos::reduceAll(*world(), Teuchos::REDUCE_MAX, hi, Teuchos::outArg(ghi));
    EXPECT_NEAR(all[0], -0.96, 1e-9);
    EXPECT_LT(ghi - glo, 1e-9 * ghi);
    const Mat3 F = Mat3::diag(1.0 + all[1], 1.0 + all[2] / 0.8, 1.0 + all[3] / 1.2);
    const Mat3 P = with_material(sys.material(), [&](const auto& law) { return law.pk1(F); });
    EXPECT_NEAR(P(0, 0), 1.0, 1e-6);
    EXPECT_NEAR(P(1, 1), 0.0, 1e-6);
    EXPECT_NEAR(P(2, 2), 0.0, 1e-6);
    EXPECT_GT(all[1], 5e-4);  // it did stretch (about sigma / E)
    ends.push_back(all[1]);
    if (world()->getRank() == 0)
      std::printf("%d step(s): stretch %.6e, lateral %.6e %.6e, reaction %.9f, P = diag(%.9f, %.2e, %.2e)\n", steps, all[1],
                  all[2] / 0.8, all[3] / 1.2, all[0], P(0, 0), P(1, 1), P(2, 2));
  }
  EXPECT_NEAR(ends[0], ends[1], 1e-9);
}
