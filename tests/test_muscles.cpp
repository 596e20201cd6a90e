// Muscles: the fibre law against finite differences and LAPACK, the muscle term's assembled energy,
// gradient and Hessian against finite differences (PSD), a fibre bar's equilibrium against the closed
// form of the energy, the contraction limit, the volume under full activation at nu = 0.49, and the
// activation schedules (keys, a line of action between bones). 1 thread, 2 threads and 2 ranks.
#include "material_test_utils.hpp"
#include "scene_test_utils.hpp"
#include "system_test_utils.hpp"

#include <sinew/algebra/terms/muscle.hpp>
#include <sinew/driver/run.hpp>
#include <sinew/materials/fiber.hpp>
#include <sinew/scenes/scene.hpp>

#include <Teuchos_CommHelpers.hpp>
#include <Tpetra_Core.hpp>
#include <Tpetra_Vector.hpp>
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <random>

using namespace sinew;
using namespace sinew::test;

namespace {

auto world() { return Tpetra::getDefaultComm(); }

std::array<double, 3> random_unit(std::mt19937_64& rng) {
  std::normal_distribution<double> n(0.0, 1.0);
  std::array<double, 3> a{n(rng), n(rng), n(rng)};
  const double l = std::sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2]);
  for (double& x : a) x /= l;
  return a;
}

FiberPoint fibre(const std::array<double, 3>& a, double k, double sigma, double limit, double activation) {
  FiberPoint p;
  p.law.stiffness = k;
  p.law.max_stress = sigma;
  p.law.limit = limit;
  p.activation = activation;
  for (int d = 0; d < 3; ++d) p.a[d] = a[d];
  return p;
}

// Deformations whose fibre stretch covers the contraction range, the rest length and beyond, away
// from the passive term's kink at lambda = 1 (where its second derivative jumps).
std::vector<Mat3> fibre_samples(std::mt19937_64& rng, const FiberPoint& p) {
  std::vector<Mat3> out;
  for (const auto& s : sample_deformations(rng, 6)) out.push_back(s.F);
  for (double lambda : {0.3, 0.62, 0.7, 0.8, 0.9, 0.97, 1.05, 1.3, 2.0}) {
    // Stretch lambda along a, plus a shear and a lateral stretch.
    const Mat3 R = random_rotation(rng);
    Mat3 F = Mat3::identity();
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) F(i, j) += (lambda - 1.0) * p.a[i] * p.a[j];
    out.push_back(R * F);
  }
  std::vector<Mat3> kept;
  for (const Mat3& F : out)
    if (std::fabs(p.stretch(F) - 1.0) > 1e-3) kept.push_back(F);
  return kept;
}

}  // namespace

// P = dPsi/dF and the Hessian d2Psi/dF2 against central differences, for passive, partly and fully
// active fibres in random directions; zero energy and stress at rest without activation.
TEST(Muscles, FibreLawDerivativesMatchFiniteDifferences) {
  std::mt19937_64 rng(2018);
  double worst_p = 0.0, worst_h = 0.0;
  int count = 0;
  for (double k : {0.0, 2.0})
    for (double alpha : {0.0, 0.3, 1.0}) {
      const FiberPoint p = fibre(random_unit(rng), k, 1.5, 0.6, alpha);
      const Mat3 I = Mat3::identity();
      EXPECT_NEAR(p.energy(I), 0.0, 1e-15);
      if (alpha == 0.0) {
        EXPECT_EQ(norm(p.pk1(I)), 0.0);
      }
      for (const Mat3& F : fibre_samples(rng, p)) {
        const double scale = std::max({k, 1.5 * alpha, 1e-3});
        const double ep = norm(p.pk1(F) - fd_pk1(p, F, 1e-6)) / scale;
        const double eh = norm_diff(p.hessian(F), fd_hessian(p, F, 1e-6)) / scale;
        worst_p = std::max(worst_p, ep);
        worst_h = std::max(worst_h, eh);
        EXPECT_LT(ep, 1e-7) << "k " << k << " activation " << alpha << " stretch " << p.stretch(F);
        EXPECT_LT(eh, 1e-5) << "k " << k << " activation " << alpha << " stretch " << p.stretch(F);
        ++count;
      }
    }
  std::printf("[ info ] fibre law: %d samples, worst PK1 error %.2e, worst Hessian error %.2e (relative)\n", count, worst_p, worst_h);
  EXPECT_GE(count, 150);
}

// The closed-form eigen-system (psi'' once, psi'/lambda twice, six zeros) is LAPACK's spectrum of the
// Hessian, the projections equal LAPACK's clamped and absolute-value reconstructions, and all are PSD.
TEST(Muscles, FibreEigensystemMatchesLapackAndIsPositiveSemiDefinite) {
  std::mt19937_64 rng(49);
  double worst = 0.0;
  for (double alpha : {0.0, 0.5, 1.0}) {
    const FiberPoint p = fibre(random_unit(rng), 3.0, 2.0, 0.55, alpha);
    for (const Mat3& F : fibre_samples(rng, p)) {
      const Mat9 H = p.hessian(F);
      const double scale = std::max(norm(H), 1e-12);
      double e_n = 0.0, e_t = 0.0, n[3];
      std::vector<double> ev(9, 0.0);
      if (p.eigenvalues(F, e_n, e_t, n)) ev = {e_n, e_t, e_t, 0, 0, 0, 0, 0, 0};
      std::sort(ev.begin(), ev.end());
      std::array<double, 9> w;
      std::array<double, 81> Z;
      lapack_eigen(H, w, Z);
      for (int k = 0; k < 9; ++k) {
        worst = std::max(worst, std::fabs(ev[k] - w[k]) / scale);
        EXPECT_NEAR(ev[k], w[k], 1e-12 * scale) << "activation " << alpha << " stretch " << p.stretch(F);
      }
      for (Projection q : {Projection::Clamp, Projection::Abs}) {
        const Mat9 Hp = p.projected_hessian(F, q);
        EXPECT_LT(norm_diff(Hp, lapack_projected(H, q)), 1e-12 * scale);
        lapack_eigen(Hp, w, Z);
        EXPECT_GE(w[0], -1e-12 * scale);
      }
    }
  }
  std::printf("[ info ] fibre eigenvalues vs LAPACK: worst error %.2e relative to ||H||\n", worst);
}

// The muscle term assembled over a jittered box (hex8 and tet4, a random fibre per element, part of
// the elements in the muscle): its gradient is the derivative of its energy, its Hessian the derivative
// of its gradient (directional central differences), and the Hessian is PSD. 1 and 2 ranks.
TEST(Muscles, TheMuscleTermsGradientAndHessianMatchFiniteDifferences) {
  for (auto type : {ElementType::Hex8, ElementType::Tet4}) {
    MeshSpec spec = box(2, type, 3);
    spec.jitter = 0.15;
    MaterialSpec law = all_models(1.0, 0.45)[static_cast<std::size_t>(MaterialModel::StableNeoHookean)];
    System sys(world(), build_mesh(spec, *world()), law);
    const Mesh& mesh = sys.mesh();
    MuscleBlock m;
    m.name = "m";
    m.law.stiffness = 1.3;
    m.law.max_stress = 0.9;
    m.law.limit = 0.5;
    m.activation = [](double t) { return 0.7 * t; };
    for (std::size_t e = 0; e < mesh.local_elements(); ++e) {
      if (unit_hash(mesh.element_gid[e], 0, 5) < 0.3) continue;  // the same elements on every rank
      m.elements.push_back(static_cast<int>(e));
      std::array<double, 3> a{hash_unit(mesh.element_gid[e], 0, 1), hash_unit(mesh.element_gid[e], 1, 1), hash_unit(mesh.element_gid[e], 2, 1)};
      const double l = std::sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2]);
      for (double& x : a) x /= l;
      m.fibers.push_back(a);
    }
    MuscleTerm term(sys.comm(), mesh, sys.element_data(), {m});
    term.set_load(1.0);
    EXPECT_DOUBLE_EQ(term.activation(0), 0.7);
    auto u = sys.create_vector(), d = sys.create_vector();
    set_displacement(sys, *u, [](const std::array<double, 3>& X, int i, long long gid) {
      return 0.12 * hash_unit(gid, i) + (i == 0 ? -0.25 * X[0] : 0.1 * X[2]);  // shortened along x: active range
    });
    set_displacement(sys, *d, [](const std::array<double, 3>&, int i, long long gid) { return hash_unit(gid, i, 7); });
    const auto c = check_term_derivatives(sys, term, *u, *d);
    EXPECT_NEAR(c.f_dot_d, c.dE, 1e-6 * std::max(1.0, std::fabs(c.dE))) << to_string(type);
    EXPECT_GT(c.scale, 1e-3) << to_string(type);  // the fibres were loaded
    EXPECT_LT(c.err, 1e-6 * c.scale) << to_string(type);
    EXPECT_GE(c.min_eigenvalue, -1e-12 * c.max_entry) << to_string(type);
    if (world()->getRank() == 0)
      std::printf("[ info ] %s: dE/dd %.9e vs f.d %.9e; |H d - FD| %.2e of %.2e; min eigenvalue %.2e\n", to_string(type).c_str(), c.dE,
                  c.f_dot_d, c.err, c.scale, c.min_eigenvalue);
  }
}

namespace {

// A bar [0, 2] x [0, 1] x [0, 1] of 6 x 3 x 3 hex8 cells on rollers (x fixed on x-, y on y-, z on z-)
// with fibres along x over the whole bar: a homogeneous deformation F = diag(lambda, mu, mu).
std::string fibre_bar(const std::string& model, double nu, const std::string& muscle, int steps) {
  return R"x(<ParameterList name="Sinew">
  <Parameter name="Scene" type="string" value="fibre_bar"/>
  <ParameterList name="Mesh">
    <Parameter name="Type" type="string" value="box"/>
    <Parameter name="Elements" type="Array(int)" value="{6, 3, 3}"/>
    <Parameter name="Upper corner" type="Array(double)" value="{2.0, 1.0, 1.0}"/>
  </ParameterList>
  <ParameterList name="Material">
    <Parameter name="Model" type="string" value=")x" + model + R"x("/>
    <Parameter name="Young modulus" type="double" value="1000.0"/>
    <Parameter name="Poisson ratio" type="double" value=")x" + std::to_string(nu) + R"x("/>
  </ParameterList>
  <ParameterList name="Loading">
    <Parameter name="Steps" type="int" value=")x" + std::to_string(steps) + R"x("/>
    <ParameterList name="Boundary conditions">
      <ParameterList name="x"><Parameter name="Region" type="string" value="face x-"/><Parameter name="Components" type="string" value="x"/></ParameterList>
      <ParameterList name="y"><Parameter name="Region" type="string" value="face y-"/><Parameter name="Components" type="string" value="y"/></ParameterList>
      <ParameterList name="z"><Parameter name="Region" type="string" value="face z-"/><Parameter name="Components" type="string" value="z"/></ParameterList>
    </ParameterList>
  </ParameterList>
  <ParameterList name="Muscles"><ParameterList name="bar">
    <Parameter name="Region" type="string" value="all"/>
    <Parameter name="Fiber direction" type="Array(double)" value="{2.0, 0.0, 0.0}"/>
    )x" + muscle + R"x(
  </ParameterList></ParameterList>
  <ParameterList name="Solver">
    <Parameter name="Absolute tolerance" type="double" value="1.0e-11"/>
  </ParameterList>
  )x" + logs_only_output() + R"x(
</ParameterList>)x";
}

// The bar's end stretch lambda (x+ face) and lateral stretch mu (y+ face), from the converged run.
std::array<double, 2> bar_stretches(Simulation& sim) {
  const System& sys = sim.scene().system();
  const auto u = gather(sim.displacement());
  auto X = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), sys.mesh().X);
  double mine[4] = {0, 0, 0, 0}, all[4];
  for (std::size_t n = 0; n < sys.mesh().n_owned_nodes; ++n) {
    const auto gid = static_cast<std::size_t>(sys.mesh().node_gid[n]);
    if (X(n, 0) > 2.0 - 1e-12) {
      mine[0] += u[3 * gid];
      mine[1] += 1.0;
    }
    if (X(n, 1) > 1.0 - 1e-12) {
      mine[2] += u[3 * gid + 1];
      mine[3] += 1.0;
    }
  }
  Teuchos::reduceAll(*world(), Teuchos::REDUCE_SUM, 4, mine, all);
  return {1.0 + all[0] / all[1] / 2.0, 1.0 + all[2] / all[3]};
}

// The closed form: F = diag(lambda, mu, mu) with P_xx(F) + psi_f'(lambda) = 0 (the free end) and
// P_yy(F) = 0 (the free sides), solved by Newton on the two stretches (central-difference Jacobian).
std::array<double, 2> bar_equilibrium(const MaterialSpec& spec, const FiberLaw& fl, double alpha) {
  auto residual = [&](double l, double m, double r[2]) {
    const Mat3 P = with_material(spec, [&](const auto& law) { return law.pk1(Mat3::diag(l, m, m)); });
    double psi, d1, d2;
    fl.curve(l, alpha, psi, d1, d2);
    r[0] = P(0, 0) + d1;
    r[1] = P(1, 1);
  };
  double l = 1.0, m = 1.0;
  for (int it = 0; it < 100; ++it) {
    double r[2], rl[2], rm[2];
    const double h = 1e-7;
    residual(l, m, r);
    residual(l + h, m, rl);
    residual(l, m + h, rm);
    const double a = (rl[0] - r[0]) / h, b = (rm[0] - r[0]) / h, c = (rl[1] - r[1]) / h, d = (rm[1] - r[1]) / h;
    const double det = a * d - b * c;
    double dl = -(d * r[0] - b * r[1]) / det, dm = -(-c * r[0] + a * r[1]) / det;
    const double s = std::min(1.0, 0.05 / std::max(std::fabs(dl), std::fabs(dm)));  // damped far from it
    l += s * dl;
    m += s * dm;
    if (std::fabs(dl) + std::fabs(dm) < 1e-15) break;
  }
  return {l, m};
}

}  // namespace

// A fibre bar, activation 1: its length at equilibrium is the closed form's to 1e-6 (the same in 2 and
// 4 load steps), and the fibres shortened.
TEST(Muscles, AnActivatedFibreBarShortensToTheClosedFormLength) {
  const double sigma = 150.0;
  std::vector<double> ends;
  for (int steps : {2, 4}) {
    const std::string muscle = R"x(<Parameter name="Maximum stress" type="double" value="150.0"/>
      <Parameter name="Fiber stiffness" type="double" value="400.0"/>
      <Parameter name="Activation" type="double" value="1.0"/>)x";
    Simulation sim(config(fibre_bar("stable-neohookean", 0.45, muscle, steps), "test_results/fibre_bar"), RunOptions{true, ""});
    ASSERT_EQ(sim.run(), 0);
    const auto s = bar_stretches(sim);
    FiberLaw fl;
    fl.stiffness = 400.0;
    fl.max_stress = sigma;
    fl.limit = 0.6;
    const auto exact = bar_equilibrium(sim.scene().system().material(), fl, 1.0);
    if (world()->getRank() == 0)
      std::printf("[ info ] %d steps: lambda %.10f (closed form %.10f), mu %.10f (%.10f)\n", steps, s[0], exact[0], s[1], exact[1]);
    EXPECT_NEAR(s[0], exact[0], 1e-6 * exact[0]);
    EXPECT_NEAR(s[1], exact[1], 1e-6 * exact[1]);
    EXPECT_LT(s[0], 0.95);  // it did contract
    const auto* term = sim.scene().system().find_term<MuscleTerm>();
    ASSERT_NE(term, nullptr);
    EXPECT_DOUBLE_EQ(term->activation(0), 1.0);
    const auto r = term->stretch_range(0);
    EXPECT_NEAR(r[0], s[0], 1e-6);
    EXPECT_NEAR(r[1], s[0], 1e-6);
    ends.push_back(s[0]);
  }
  EXPECT_NEAR(ends[0], ends[1], 1e-8);
}

// A maximum stress thirty times the Young modulus drives the fibres to their contraction limit and
// not past it; at nu = 0.49 the stable Neo-Hookean muscle keeps its volume to 1% (corotational's volume
// change on the same bar is printed). (A hundred times E in 6 steps stalls Newton with the backtracking
// line search: the first step's direction, from the rest state whose fibres have no stiffness along
// themselves, overshoots past the limit; 40 steps or 'Line search' more-thuente converge.)
TEST(Muscles, AFullyActiveMuscleStopsAtItsContractionLimitAndKeepsItsVolume) {
  const std::string muscle = R"x(<Parameter name="Maximum stress" type="double" value="3.0e4"/>
      <Parameter name="Contraction limit" type="double" value="0.7"/>
      <Parameter name="Activation" type="double" value="1.0"/>)x";
  for (const char* model : {"stable-neohookean", "corotational"}) {
    Simulation sim(config(fibre_bar(model, 0.49, muscle, 6), "test_results/fibre_bar_limit"), RunOptions{true, ""});
    ASSERT_EQ(sim.run(), 0);
    const auto s = bar_stretches(sim);
    const double J = s[0] * s[1] * s[1];
    if (world()->getRank() == 0)
      std::printf("[ info ] %s, nu 0.49, sigma = 30 E: fibre stretch %.6f (limit 0.7), lateral %.6f, volume change %.3f%%\n", model,
                  s[0], s[1], 100.0 * (J - 1.0));
    EXPECT_GE(s[0], 0.7 - 1e-9) << model;
    EXPECT_LT(s[0], 0.73) << model;
    if (std::string(model) == "stable-neohookean") {
      EXPECT_LT(std::fabs(J - 1.0), 0.01);
    }
  }
}

// Keys are linear between them and held beyond; a constant activation is ramped with the load.
TEST(Muscles, ActivationFollowsItsKeysOverTheLoad) {
  const std::string keys = R"x(<Parameter name="Activation times" type="Array(double)" value="{0.2, 0.5, 1.0}"/>
      <Parameter name="Activation values" type="Array(double)" value="{0.0, 1.0, 0.5}"/>)x";
  Simulation sim(config(fibre_bar("stable-neohookean", 0.45, keys, 2), "test_results/fibre_bar_keys"), RunOptions{true, ""});
  auto* term = sim.scene().system().find_term<MuscleTerm>();
  ASSERT_NE(term, nullptr);
  const double expected[][2] = {{0.0, 0.0}, {0.2, 0.0}, {0.35, 0.5}, {0.5, 1.0}, {0.75, 0.75}, {1.0, 0.5}};
  for (const auto& [t, a] : expected) {
    term->set_load(t);
    EXPECT_NEAR(term->activation(0), a, 1e-12) << "t " << t;
  }
  Simulation ramp(config(fibre_bar("stable-neohookean", 0.45, R"x(<Parameter name="Activation" type="double" value="0.8"/>)x", 2),
                         "test_results/fibre_bar_ramp"),
                  RunOptions{true, ""});
  auto* r = ramp.scene().system().find_term<MuscleTerm>();
  r->set_load(0.25);
  EXPECT_NEAR(r->activation(0), 0.2, 1e-15);
}

// A line of action from a fixed origin to a point on a bone that swings towards it: the activation
// rises as the line shortens, (L0 - L) / (s L0), clamped to [0, 1].
TEST(Muscles, ALineOfActionFiresTheMuscleAsItShortens) {
  const std::string line = R"x(<ParameterList name="Line of action">
        <Parameter name="Origin" type="Array(double)" value="{0.0, 0.5, 2.0}"/>
        <Parameter name="Insertion bone" type="string" value="hand"/>
        <Parameter name="Insertion" type="Array(double)" value="{2.0, 0.5, 0.5}"/>
        <Parameter name="Shortening" type="double" value="0.25"/>
      </ParameterList>)x";
  std::string xml = fibre_bar("stable-neohookean", 0.45, line, 2);
  // A bone at the bar's far end, rotating by 90 degrees about the y axis through (1, 0.5, 0.5).
  const std::string skeleton = R"x(<ParameterList name="Skeleton"><ParameterList name="Bones"><ParameterList name="hand">
      <Parameter name="Region" type="string" value="face x+"/>
      <Parameter name="Pivot" type="Array(double)" value="{1.0, 0.5, 0.5}"/>
      <ParameterList name="Keyframes"><ParameterList name="up">
        <Parameter name="Time" type="double" value="1.0"/>
        <Parameter name="Axis" type="Array(double)" value="{0.0, -1.0, 0.0}"/>
        <Parameter name="Angle" type="double" value="1.5707963267948966"/>
      </ParameterList></ParameterList>
    </ParameterList></ParameterList></ParameterList>
  <ParameterList name="Solver">)x";
  xml.replace(xml.find("<ParameterList name=\"Solver\">"), std::string("<ParameterList name=\"Solver\">").size(), skeleton);
  // The rollers would share nodes with the bone on face x+: the bone alone holds the bar.
  for (const char* c : {"x", "y", "z"}) {
    const std::string roller = std::string(R"x(<ParameterList name=")x") + c + R"x("><Parameter name="Region" type="string" value="face )x" +
                               c + R"x(-"/><Parameter name="Components" type="string" value=")x" + c + R"x("/></ParameterList>)x";
    xml.erase(xml.find(roller), roller.size());
  }
  Simulation sim(config(xml, "test_results/fibre_bar_line"), RunOptions{true, ""});
  auto* term = sim.scene().system().find_term<MuscleTerm>();
  ASSERT_NE(term, nullptr);
  const Skeleton& sk = sim.scene().skeleton();
  const double L0 = std::sqrt(4.0 + 2.25);
  for (double t : {0.0, 0.3, 0.6, 1.0}) {
    const auto p = sk.transform(0, t).apply({2.0, 0.5, 0.5});
    const double L = std::sqrt(p[0] * p[0] + (p[2] - 2.0) * (p[2] - 2.0) + (p[1] - 0.5) * (p[1] - 0.5));
    term->set_load(t);
    EXPECT_NEAR(term->activation(0), std::clamp((L0 - L) / (0.25 * L0), 0.0, 1.0), 1e-12) << "t " << t;
  }
  term->set_load(1.0);
  EXPECT_GT(term->activation(0), 0.9);  // the insertion swung up to (1, 0.5, 1.5): L = 1.118, 0.56 shorter
}

// Fibres and activation from CSV files: a header line is skipped, every element of the region takes its
// row (normalized), the activation is linear between the file's rows; a row that is not plain finite
// numbers, or an element the file leaves out, is an input error naming the file, line and culprit.
TEST(Muscles, FibresAndActivationComeFromCsvFiles) {
  namespace fs = std::filesystem;
  const fs::path dir = fs::absolute("test_results/muscle_csv");
  fs::create_directories(dir);
  const std::string fibres = (dir / "fibres.csv").string(), activation = (dir / "activation.csv").string();
  auto write = [](const std::string& path, const std::string& text) {
    if (world()->getRank() == 0) std::ofstream(path) << text;
    world()->barrier();
  };
  std::string rows = "element, x, y, z\n";
  for (int e = 0; e < 54; ++e) rows += std::to_string(e) + ", 0, " + std::to_string(1 + e % 3) + ", 0\n";
  write(fibres, rows);
  write(activation, "t, activation\n0.0, 0.0\n0.5, 0.6\n1.0, 0.2\n");
  const std::string muscle = "<Parameter name=\"Fiber file\" type=\"string\" value=\"" + fibres + "\"/>" +
                             "<Parameter name=\"Activation file\" type=\"string\" value=\"" + activation + "\"/>";
  std::string xml = fibre_bar("stable-neohookean", 0.45, muscle, 2);
  const std::string direction = R"x(<Parameter name="Fiber direction" type="Array(double)" value="{2.0, 0.0, 0.0}"/>)x";
  xml.erase(xml.find(direction), direction.size());
  {
    Simulation sim(config(xml, "test_results/muscle_csv/run"), RunOptions{true, ""});
    auto* term = sim.scene().system().find_term<MuscleTerm>();
    ASSERT_NE(term, nullptr);
    term->set_load(0.25);
    EXPECT_NEAR(term->activation(0), 0.3, 1e-12);
    term->set_load(0.75);
    EXPECT_NEAR(term->activation(0), 0.4, 1e-12);
    std::vector<TermState::Nodal> fields;
    term->element_fields(fields);
    ASSERT_EQ(fields.size(), 2u);
    const Mesh& mesh = sim.scene().system().mesh();
    for (std::size_t e = 0; e < mesh.n_owned_elements; ++e) {
      EXPECT_EQ(fields[0].values[3 * e + 0], 0.0);
      EXPECT_EQ(fields[0].values[3 * e + 1], 1.0);  // (0, 1 + e % 3, 0) normalized
      EXPECT_EQ(fields[0].values[3 * e + 2], 0.0);
      EXPECT_NEAR(fields[1].values[e], 0.4, 1e-12);
    }
  }
  auto fails_with = [&](const std::string& message) {
    try {
      Simulation sim(config(xml, "test_results/muscle_csv/bad"), RunOptions{true, ""});
      ADD_FAILURE() << "no error; expected " << message;
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find(message), std::string::npos) << e.what();
    }
  };
  write(activation, "t, activation\n0.0, 0.0\n0.5, nan\n");
  fails_with("activation.csv' line 3: 'nan' is not a finite number");
  write(activation, "0.0, 0.0\n1.0, 1.0\n");
  write(fibres, rows.substr(0, rows.find("\n7, ")) + "\n");  // elements 7 and on left out
  fails_with("fibres.csv' gives no fibre for element 7 of the region");
}
