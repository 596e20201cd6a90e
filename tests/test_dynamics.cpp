// Dynamics (scenes/time.hpp, algebra/terms/inertia.hpp, driver/dynamics.hpp): mass matrices against
// density x volume, free fall against g t^2 / 2 with the integrators' orders, a small oscillation's
// period against the linear mode of the same K and M (LAPACK), implicit midpoint's energy and momenta,
// backward Euler's dissipation, a restarted run equal to an uninterrupted one, 1 thread = 2 threads =
// 2 ranks.
#include "scene_test_utils.hpp"
#include "system_test_utils.hpp"

#include <sinew/algebra/terms/inertia.hpp>
#include <sinew/core/parameters.hpp>
#include <sinew/core/xml_input.hpp>
#include <sinew/driver/run.hpp>
#include <sinew/scenes/scene.hpp>

#include <Teuchos_LAPACK.hpp>
#include <Tpetra_Core.hpp>
#include <Tpetra_CrsMatrix.hpp>
#include <Tpetra_Vector.hpp>
#include <gtest/gtest.h>

#include <filesystem>

using namespace sinew;
using namespace sinew::test;

namespace {

auto world() { return Tpetra::getDefaultComm(); }
std::string tag() { return "_np" + std::to_string(world()->getSize()) + "_t" + std::to_string(Kokkos::DefaultExecutionSpace::concurrency()); }

// A box scene with a Time section; `extra_loading` and `bcs` go into Loading.
std::string scene_xml(const std::string& integrator, int frames, double rate, int substeps, const std::string& loading,
                      const std::string& mesh = R"x(<Parameter name="Elements" type="Array(int)" value="{2, 2, 2}"/>
    <Parameter name="Upper corner" type="Array(double)" value="{0.1, 0.1, 0.1}"/>)x",
                      const std::string& time_extra = "", double E = 1e5, double nu = 0.3) {
  return R"x(<ParameterList name="Sinew">
  <Parameter name="Scene" type="string" value="dyn"/>
  <ParameterList name="Mesh">
    )x" + mesh + R"x(
  </ParameterList>
  <ParameterList name="Material">
    <Parameter name="Model" type="string" value="stable-neohookean"/>
    <Parameter name="Young modulus" type="double" value=")x" + format_number(E) + R"x("/>
    <Parameter name="Poisson ratio" type="double" value=")x" + format_number(nu) + R"x("/>
  </ParameterList>
  <ParameterList name="Loading">)x" + loading + R"x(
  </ParameterList>
  <ParameterList name="Time">
    <Parameter name="Integrator" type="string" value=")x" + integrator + R"x("/>
    <Parameter name="Frames" type="int" value=")x" + std::to_string(frames) + R"x("/>
    <Parameter name="Frame rate" type="double" value=")x" + format_number(rate) + R"x("/>
    <Parameter name="Substeps" type="int" value=")x" + std::to_string(substeps) + R"x("/>)x" + time_extra + R"x(
  </ParameterList>
  <ParameterList name="Solver">
    <Parameter name="Absolute tolerance" type="double" value="1.0e-10"/>
  </ParameterList>
  <ParameterList name="Output">
    <Parameter name="HDF5" type="bool" value="false"/>
    <Parameter name="Surface OBJ" type="bool" value="false"/>
    <Parameter name="Checkpoint every" type="int" value="0"/>
  </ParameterList>
</ParameterList>)x";
}

// Mass-weighted mean of the displacement's component c (the centre of mass's displacement).
double com_displacement(const System& sys, const Vector& u, int c) {
  auto v = u.getLocalViewHost(Tpetra::Access::ReadOnly);
  double s[2] = {0.0, 0.0}, g[2];
  for (std::size_t n = 0; n < sys.mesh().n_owned_nodes; ++n) {
    s[0] += sys.nodal_mass()[n] * v(3 * n + c, 0);
    s[1] += sys.nodal_mass()[n];
  }
  Teuchos::reduceAll(*sys.comm(), Teuchos::REDUCE_SUM, 2, s, g);
  return g[0] / g[1];
}

}  // namespace

// 1^T M 1 = rho V per component for both elements and both forms (jittered hex8: not affine), the
// consistent matrix symmetric positive definite, the lumped one its row sums.
TEST(Dynamics, MassMatricesWeighDensityTimesVolume) {
  for (auto type : {ElementType::Hex8, ElementType::Tet4}) {
    MeshSpec spec = box(2, type, 3);
    spec.jitter = 0.2;
    MaterialSpec law = material_defaults(MaterialModel::StableNeoHookean, 1.0, 1.0);
    law.density = 1070.0;
    System sys(world(), build_mesh(spec, *world()), law);
    const double V = 1.0 * 0.8 * 1.2;
    for (bool lumped : {true, false}) {
      auto M = sys.mass_matrix(lumped);
      auto ones = sys.create_vector(), Mones = sys.create_vector();
      ones->putScalar(1.0);
      M->apply(*ones, *Mones);
      EXPECT_NEAR(ones->dot(*Mones), 3 * 1070.0 * V, 1e-9) << to_string(type) << (lumped ? " lumped" : " consistent");
      const auto D = dense(*M);
      double asym = 0.0;
      for (std::size_t i = 0; i < D.size(); ++i)
        for (std::size_t j = 0; j < D.size(); ++j) asym = std::max(asym, std::fabs(D[i][j] - D[j][i]));
      EXPECT_LT(asym, 1e-12 * max_abs(D));
      EXPECT_GT(min_eigenvalue(D), 0.0);
      if (lumped) continue;
      // The lumped matrix is the consistent one's row sums.
      auto Ml = sys.mass_matrix(true);
      auto a = sys.create_vector(), b = sys.create_vector();
      Ml->apply(*ones, *a);
      a->update(-1.0, *Mones, 1.0);
      EXPECT_LT(a->normInf(), 1e-12 * Mones->normInf());
    }
  }
}

// A free body under gravity: its centre of mass falls g t^2 / 2. Backward Euler is first order (the
// error halves with the time step: x_n = g h^2 n (n + 1) / 2); implicit midpoint is exact for a
// constant force.
// Each step of a fall starts in equilibrium: the first guess moves the body on by reach^2 g
// (EnergyTerm::add_load_acceleration), so no step needs a Newton iteration.
TEST(Dynamics, FreeFallFollowsHalfGTSquaredFromFirstGuessesInEquilibrium) {
  const std::string gravity = R"x(<Parameter name="Gravity" type="Array(double)" value="{0, 0, -9.81}"/>)x";
  auto newton = [](const Simulation& sim) {
    int n = 0;
    for (const auto& r : sim.records()) n += r.solve.newton_iterations;
    return n;
  };
  double error[2];
  for (int k = 0; k < 2; ++k) {
    const int steps = 10 << k;
    Simulation sim(config(scene_xml("backward-euler", steps, steps / 0.1, 1, gravity), "test_results/fall_be" + tag()),
                   RunOptions{true, ""});
    ASSERT_EQ(sim.run(), 0);
    EXPECT_EQ(newton(sim), 0);
    error[k] = std::fabs(com_displacement(sim.scene().system(), sim.displacement(), 2) + 0.5 * 9.81 * 0.01);
    EXPECT_NEAR(error[k], 0.5 * 9.81 * 0.1 * (0.1 / steps), 1e-9);
  }
  EXPECT_NEAR(error[0] / error[1], 2.0, 0.02);
  Simulation mid(config(scene_xml("implicit-midpoint", 10, 100.0, 1, gravity), "test_results/fall_im" + tag()),
                 RunOptions{true, ""});
  ASSERT_EQ(mid.run(), 0);
  EXPECT_EQ(newton(mid), 0);
  EXPECT_NEAR(com_displacement(mid.scene().system(), mid.displacement(), 2), -0.5 * 9.81 * 0.01, 1e-10);
  EXPECT_NEAR(mid.records().back().kinetic, 0.5 * 1.0 * std::pow(9.81 * 0.1, 2), 1e-8);  // m = 1000 kg/m^3 x 1e-3 m^3
}

namespace {

// A cantilever of 1 x 1 x 6 hex8 cells (0.1 x 0.15 x 0.6: the two bending modes apart), clamped at
// z = 0 (along z, so that 2 ranks split it).
const std::string beam = R"x(<Parameter name="Elements" type="Array(int)" value="{1, 1, 6}"/>
    <Parameter name="Upper corner" type="Array(double)" value="{0.1, 0.15, 0.6}"/>)x";
const std::string clamp = R"x(<ParameterList name="Boundary conditions">
      <ParameterList name="root"><Parameter name="Region" type="string" value="face z-"/></ParameterList>
    </ParameterList>)x";

struct Mode {
  double omega;
  std::vector<double> shape;  // by global DOF, M-normalized, zero at fixed DOFs
};

// The lowest mode of K phi = omega^2 M phi on the free DOFs (LAPACK dsygv), K the exact Hessian at rest.
Mode lowest_mode(const System& sys) {
  auto u = sys.create_vector();
  auto K = sys.create_matrix();
  sys.evaluate(*u, nullptr, K.get(), Backend::Default, Projection::None);
  const auto Kd = dense(*K), Md = dense(*sys.mass_matrix(true));
  const std::vector<char> fixed = fixed_flags(sys);
  std::vector<int> free;
  for (std::size_t i = 0; i < Kd.size(); ++i)
    if (!fixed[i]) free.push_back(static_cast<int>(i));
  const int n = static_cast<int>(free.size());
  std::vector<double> A(n * n), B(n * n), w(n), work(64 * n);
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j) {
      A[i + n * j] = 0.5 * (Kd[free[i]][free[j]] + Kd[free[j]][free[i]]);
      B[i + n * j] = Md[free[i]][free[j]];
    }
  int info = 0;
  Teuchos::LAPACK<int, double>().SYGV(1, 'V', 'U', n, A.data(), n, B.data(), n, w.data(), work.data(), 64 * n, &info);
  EXPECT_EQ(info, 0);
  Mode m{std::sqrt(w[0]), std::vector<double>(Kd.size(), 0.0)};
  for (int i = 0; i < n; ++i) m.shape[free[i]] = A[i];  // column 0, B-normalized
  return m;
}

// Sets a vector from values by global DOF.
void set_global(Vector& v, const std::vector<double>& values) {
  auto h = v.getLocalViewHost(Tpetra::Access::OverwriteAll);
  for (std::size_t i = 0; i < h.extent(0); ++i) h(i, 0) = values[v.getMap()->getGlobalElement(static_cast<LO>(i))];
}

// The modal coordinate phi^T M u after every step of a run started from amplitude * phi.
std::vector<double> modal_history(const std::string& integrator, const Mode& mode, double period, int per_period,
                                  int periods, const std::string& out, std::vector<double>* total_energy = nullptr) {
  const double amplitude = 1e-4;  // 0.1 mm tip motion on a 0.6 m beam: the linear range
  Simulation sim(config(scene_xml(integrator, per_period * periods, per_period / period, 1, clamp, beam), out), RunOptions{true, ""});
  const System& sys = sim.scene().system();
  auto u0 = sys.create_vector();
  std::vector<double> start(mode.shape);
  for (double& x : start) x *= amplitude;
  set_global(*u0, start);
  sim.set_initial(*u0);
  auto phi = sys.create_vector(), Mphi = sys.create_vector();
  set_global(*phi, mode.shape);
  sys.mass_matrix(true)->apply(*phi, *Mphi);
  std::vector<double> q{amplitude};
  sim.set_step_observer([&](const StepRecord& r, const Vector& u) {
    q.push_back(Mphi->dot(u));
    if (total_energy) total_energy->push_back(r.kinetic + r.totals.share("elastic"));
  });
  EXPECT_EQ(sim.run(), 0);
  return q;
}

// The period from the zero crossings of a sampled signal (linear interpolation between samples).
double measured_period(const std::vector<double>& q, double h) {
  std::vector<double> crossings;
  for (std::size_t k = 1; k < q.size(); ++k)
    if ((q[k - 1] > 0.0) != (q[k] > 0.0)) crossings.push_back(h * (k - 1 + q[k - 1] / (q[k - 1] - q[k])));
  EXPECT_GE(crossings.size(), 4u);
  return 2.0 * (crossings.back() - crossings.front()) / static_cast<double>(crossings.size() - 1);
}

}  // namespace

// A small oscillation of the cantilever from its first mode: the period is the linear one, 2 pi /
// omega_1, to 1% with 32 steps per period, and the midpoint rule's period error shrinks 4x when the
// time step halves (second order).
TEST(Dynamics, OscillationPeriodMatchesTheLinearMode) {
  Simulation probe(config(scene_xml("implicit-midpoint", 1, 1.0, 1, clamp, beam), "test_results/mode" + tag()), RunOptions{true, ""});
  const Mode mode = lowest_mode(probe.scene().system());
  const double T = 2.0 * M_PI / mode.omega;
  double err[2];
  for (int k = 0; k < 2; ++k) {
    const int per = 16 << k;
    const auto q = modal_history("implicit-midpoint", mode, T, per, 3, "test_results/oscillate" + tag());
    const double Tm = measured_period(q, T / per);
    err[k] = Tm / T - 1.0;
    if (k == 1) EXPECT_LT(std::fabs(err[k]), 0.01) << "period " << Tm << " vs " << T;
  }
  if (world()->getRank() == 0)
    std::printf("[ info ] period %.6g s; midpoint error %.3e (16 steps/period), %.3e (32): ratio %.3f\n", T, err[0], err[1],
                err[0] / err[1]);
  // Midpoint lengthens the period by (omega h)^2 / 12 to leading order: 4x less at half the step.
  EXPECT_GT(err[0], 0.0);
  EXPECT_NEAR(err[0] / err[1], 4.0, 0.4);
}

// No loads, no damping: the midpoint rule keeps the total energy of the small oscillation within 1%
// over 100 periods; backward Euler loses it monotonically.
TEST(Dynamics, MidpointKeepsEnergyBackwardEulerDissipates) {
  Simulation probe(config(scene_xml("implicit-midpoint", 1, 1.0, 1, clamp, beam), "test_results/mode2" + tag()), RunOptions{true, ""});
  const Mode mode = lowest_mode(probe.scene().system());
  const double T = 2.0 * M_PI / mode.omega;
  std::vector<double> e_mid, e_be;
  modal_history("implicit-midpoint", mode, T, 12, 100, "test_results/energy_im" + tag(), &e_mid);
  modal_history("backward-euler", mode, T, 12, 2, "test_results/energy_be" + tag(), &e_be);
  const double e0 = e_mid.front();
  double drift = 0.0;
  for (double e : e_mid) drift = std::max(drift, std::fabs(e / e0 - 1.0));
  EXPECT_LT(drift, 0.01);
  if (world()->getRank() == 0)
    std::printf("[ info ] midpoint: largest energy drift over 100 periods %.3e; backward Euler keeps %.3e of it after 2\n",
                drift, e_be.back() / e_be.front());
  for (std::size_t k = 1; k < e_be.size(); ++k) EXPECT_LE(e_be[k], e_be[k - 1] * (1.0 + 1e-9)) << "step " << k;
  EXPECT_LT(e_be.back(), 0.1 * e_be.front());
  EXPECT_GT(e_be.back(), 1e-6 * e_be.front());  // still above the solver's noise: the loss is the integrator's
}

namespace {

// sum M v and sum x x M v (lumped), on every rank.
std::array<double, 6> momenta(const System& sys, const Vector& u, const Vector& v) {
  auto X = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), sys.mesh().X);
  auto uh = u.getLocalViewHost(Tpetra::Access::ReadOnly);
  auto vh = v.getLocalViewHost(Tpetra::Access::ReadOnly);
  std::array<double, 6> local{}, global{};
  for (std::size_t n = 0; n < sys.mesh().n_owned_nodes; ++n) {
    const double m = sys.nodal_mass()[n];
    double x[3], p[3];
    for (int c = 0; c < 3; ++c) {
      x[c] = X(n, c) + uh(3 * n + c, 0);
      p[c] = m * vh(3 * n + c, 0);
      local[c] += p[c];
    }
    local[3] += x[1] * p[2] - x[2] * p[1];
    local[4] += x[2] * p[0] - x[0] * p[2];
    local[5] += x[0] * p[1] - x[1] * p[0];
  }
  Teuchos::reduceAll(*sys.comm(), Teuchos::REDUCE_SUM, 6, local.data(), global.data());
  return global;
}

}  // namespace

// A free body thrown and spinning fast enough to deform (no loads): the midpoint rule keeps its linear
// and angular momentum to the solver's tolerance; backward Euler keeps the linear one (and loses
// angular momentum, as it damps).
TEST(Dynamics, MidpointConservesMomenta) {
  const std::string spin = R"x(
    <Parameter name="Initial velocity" type="Array(double)" value="{0.3, -0.2, 0.5}"/>
    <Parameter name="Initial spin" type="Array(double)" value="{20, 35, -50}"/>)x";
  for (const std::string integrator : {"implicit-midpoint", "backward-euler"}) {
    Simulation sim(config(scene_xml(integrator, 20, 400.0, 1, "", R"x(<Parameter name="Elements" type="Array(int)" value="{3, 2, 2}"/>
    <Parameter name="Upper corner" type="Array(double)" value="{0.15, 0.1, 0.1}"/>)x", spin, 2e4),
                          "test_results/momenta" + tag()),
                   RunOptions{true, ""});
    const System& sys = sim.scene().system();
    std::vector<std::array<double, 6>> history;
    sim.set_step_observer([&](const StepRecord&, const Vector& u) { history.push_back(momenta(sys, u, *sim.velocity())); });
    ASSERT_EQ(sim.run(), 0);
    const auto& first = history.front();
    double lin = 0.0, ang = 0.0, lin_scale = 0.0, ang_scale = 0.0;
    for (int c = 0; c < 3; ++c) {
      lin_scale = std::max(lin_scale, std::fabs(first[c]));
      ang_scale = std::max(ang_scale, std::fabs(first[3 + c]));
    }
    for (const auto& h : history)
      for (int c = 0; c < 3; ++c) {
        lin = std::max(lin, std::fabs(h[c] - first[c]));
        ang = std::max(ang, std::fabs(h[3 + c] - first[3 + c]));
      }
    EXPECT_LT(lin, 1e-8 * lin_scale) << integrator;
    if (world()->getRank() == 0)
      std::printf("[ info ] %s: linear momentum drift %.2e, angular %.2e (relative)\n", integrator.c_str(), lin / lin_scale,
                  ang / ang_scale);
    if (integrator == "implicit-midpoint") EXPECT_LT(ang, 1e-7 * ang_scale) << integrator;
    else EXPECT_GT(ang, 1e-4 * ang_scale) << integrator;
    if (integrator == "implicit-midpoint")
      agree_with_reference(gather(sim.displacement()), world()->getRank(), 1e-6);
  }
}

// A dynamic run stopped in the middle and restarted from its checkpoint ends where the uninterrupted
// one does (the velocity travels in the checkpoint).
TEST(Dynamics, ARestartedRunContinuesTheSameTrajectory) {
  const std::string loading = std::string(R"x(<Parameter name="Gravity" type="Array(double)" value="{-9.81, 0, 0}"/>)x") + clamp;
  auto make = [&](const std::string& out) {
    SceneConfig c = config(scene_xml("implicit-midpoint", 12, 60.0, 2, loading, beam), out);
    c.params.output.checkpoint_every = 1;
    return c;
  };
  Simulation whole(make("test_results/dyn_whole" + tag()), RunOptions{true, ""});
  ASSERT_EQ(whole.run(), 0);
  const std::string dir = "test_results/dyn_stopped" + tag();
  {
    Simulation first(make(dir), RunOptions{true, ""});
    int steps = 0;
    first.set_stop_check([&] { return ++steps == 9 ? 15 : 0; });  // SIGTERM after 9 of 24 steps
    EXPECT_EQ(first.run(), 128 + 15);
  }
  Simulation rest(make(dir), RunOptions{true, dir + "/checkpoint.h5"});
  ASSERT_EQ(rest.run(), 0);
  // gather is collective: outside any rank-0 block.
  const double du = rel_diff(gather(whole.displacement()), gather(rest.displacement()));
  const double dv = rel_diff(gather(*whole.velocity()), gather(*rest.velocity()));
  EXPECT_LT(du, 1e-8);
  EXPECT_LT(dv, 1e-8);
  if (world()->getRank() == 0) std::printf("[ info ] restarted vs uninterrupted: %.2e (displacement), %.2e (velocity)\n", du, dv);
}

// The paper's drop, small (tests/scenes/squash_small.xml): a blob falls on three cylinders, comes to
// rest on them, is squashed to half its height by a plate and let go. Contact holds at every step (no
// point deeper than the thickness, nothing inverted), it comes back to its shape (a twentieth of the
// squashed elastic energy left) on the cylinders (not through them: the centre of mass as high as
// before the plate came).
TEST(Dynamics, ADroppedBlobIsSquashedAndRecovers) {
  auto p = read_parameter_file(std::string(SINEW_SOURCE_DIR) + "/tests/scenes/squash_small.xml");
  p->sublist("Mesh").set("File", std::string(SINEW_SOURCE_DIR) + "/tests/meshes/blob_coarse.msh");
  p->sublist("Output").set("Directory", "test_results/squash" + tag());
  p->sublist("Output").set("HDF5", false);
  p->sublist("Output").set("Surface OBJ", false);
  Simulation sim(make_scene(p, "squash_small"), RunOptions{true, ""});
  ASSERT_EQ(sim.run(), 0);
  const auto& rec = sim.records();
  const double thickness = sim.scene().contact()->settings().thickness;
  double peak = 0.0, before_press = 0.0;
  for (const auto& r : rec) {
    EXPECT_LT(r.totals.penetration, thickness) << "step " << r.step;
    EXPECT_GT(r.totals.min_J, 0.0) << "step " << r.step;
    peak = std::max(peak, r.totals.share("elastic"));
    if (r.load <= 0.25) before_press = r.totals.share("external");  // at rest on the cylinders
  }
  EXPECT_GT(peak, 5.0);  // it was squashed: about 9 J at the bottom
  EXPECT_LT(rec.back().totals.share("elastic"), peak / 20.0);
  EXPECT_NEAR(rec.back().totals.share("external"), before_press, 0.1 * std::fabs(before_press));
  if (world()->getRank() == 0)
    std::printf("[ info ] squash: elastic energy peak %.3g J, at the end %.3g J; potential before %.3g, after %.3g J\n", peak,
                rec.back().totals.share("elastic"), before_press, rec.back().totals.share("external"));
}
