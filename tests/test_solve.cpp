// Whole solves checked against independent answers and against each other: every line search, merit,
// forcing term and projection reaches the same state; the exact-Hessian fall-back and the retry rule;
// undefined (Neo-Hookean inverted) states are never accepted; uniaxial tension with rollers equals the
// material point's answer for every model; checkpoints taken inside a cut step and on another number
// of ranks restart the same run; corrupt checkpoints are named input errors.
#include "material_test_utils.hpp"
#include "scene_test_utils.hpp"
#include "system_test_utils.hpp"
#include "tpetra_test_utils.hpp"

#include <sinew/core/xml_input.hpp>
#include <sinew/driver/run.hpp>
#include <sinew/scenes/scene.hpp>
#include <sinew/solver/nonlinear_solver.hpp>

#include <Teuchos_DefaultMpiComm.hpp>
#include <Tpetra_Core.hpp>
#include <gtest/gtest.h>
#include <hdf5.h>

#include <filesystem>
#include <fstream>
#include <regex>

using namespace sinew;
using namespace sinew::test;

namespace {

auto world() { return Tpetra::getDefaultComm(); }
std::string tag() { return "_np" + std::to_string(world()->getSize()) + "_t" + std::to_string(Kokkos::DefaultExecutionSpace::concurrency()); }

// A scene, its solver, and the state at rest with the scene's full load applied (the prescribed DOFs
// at their end values): what a one-solve test starts from.
struct LoadedScene {
  explicit LoadedScene(const SceneConfig& c)
      : scene(c.scene(), world()), solver(scene.system(), c.params.solver), u(scene.system().create_vector()) {
    u->putScalar(0.0);
    scene.apply_load(1.0, *u);
  }
  Scene scene;
  NonlinearSolver solver;
  Teuchos::RCP<Vector> u;
};

// A 4^3 hex cube [-0.5, 0.5]^2 x [0, 1], bottom fixed, top rotated by `angle` about z in `steps` steps.
std::string twist_xml(double angle, int steps, const std::string& element = "hex8", const std::string& extra_solver = "",
                      const std::string& material = "") {
  return R"x(<ParameterList name="Sinew">
  <Parameter name="Scene" type="string" value="twist4"/>
  <ParameterList name="Mesh">
    <Parameter name="Element" type="string" value=")x" + element + R"x("/>
    <Parameter name="Elements" type="Array(int)" value="{4, 4, 4}"/>
    <Parameter name="Lower corner" type="Array(double)" value="{-0.5, -0.5, 0.0}"/>
    <Parameter name="Upper corner" type="Array(double)" value="{0.5, 0.5, 1.0}"/>
  </ParameterList>
  <ParameterList name="Material">
    <Parameter name="Model" type="string" value="stable-neohookean"/>
    <Parameter name="Young modulus" type="double" value="1.0"/>
    <Parameter name="Poisson ratio" type="double" value="0.45"/>)x" + material + R"x(
  </ParameterList>
  <ParameterList name="Loading">
    <Parameter name="Steps" type="int" value=")x" + std::to_string(steps) + R"x("/>
    <ParameterList name="Boundary conditions">
      <ParameterList name="bottom">
        <Parameter name="Region" type="string" value="face z-"/>
      </ParameterList>
      <ParameterList name="top">
        <Parameter name="Region" type="string" value="face z+"/>
        <Parameter name="Motion" type="string" value="rotate"/>
        <Parameter name="Center" type="Array(double)" value="{0, 0, 1}"/>
        <Parameter name="Angle" type="double" value=")x" + std::to_string(angle) + R"x("/>
      </ParameterList>
    </ParameterList>
  </ParameterList>
  <ParameterList name="Solver">
    <Parameter name="Absolute tolerance" type="double" value="1.0e-9"/>
    <Parameter name="Maximum iterations" type="int" value="80"/>)x" + extra_solver + R"x(
  </ParameterList>
  <ParameterList name="Output">
    <Parameter name="HDF5" type="bool" value="false"/>
    <Parameter name="Checkpoint every" type="int" value="0"/>
  </ParameterList>
</ParameterList>)x";
}

struct Result {
  int code;
  std::vector<double> u;
  std::vector<StepRecord> records;
};

Result run(const SceneConfig& c, Teuchos::RCP<const Teuchos::Comm<int>> comm = Teuchos::null, const std::string& restart = "",
           std::function<int()> stop = {}) {
  Simulation sim(c, RunOptions{true, restart}, comm);
  if (stop) sim.set_stop_check(stop);
  const int code = sim.run();
  return {code, gather(sim.displacement()), sim.records()};
}

}  // namespace

TEST(Solve, EveryLineSearchMeritForcingAndPreconditionerReachesTheSameState) {
  const double angle = 0.6;  // small enough that a full Newton step never overshoots
  const Result ref = run(config(twist_xml(angle, 1), "test_results/solve_ref" + tag()));
  ASSERT_EQ(ref.code, 0);
  const std::vector<std::pair<std::string, std::string>> variants = {
      {"polynomial", R"x(<Parameter name="Line search" type="string" value="polynomial"/>)x"},
      {"more-thuente", R"x(<Parameter name="Line search" type="string" value="more-thuente"/>)x"},
      {"full-step", R"x(<Parameter name="Line search" type="string" value="full-step"/>)x"},
      {"residual merit", R"x(<Parameter name="Line search merit" type="string" value="residual"/>)x"},
      {"forcing type 1", R"x(<Parameter name="Forcing term" type="string" value="type 1"/>)x"},
      {"forcing type 2", R"x(<Parameter name="Forcing term" type="string" value="type 2"/>)x"},
      {"no preconditioner", R"x(<Parameter name="Preconditioner" type="string" value="none"/>)x"},
      {"projection throughout", R"x(<Parameter name="Exact Hessian below" type="double" value="0.0"/>)x"},
      {"relative tolerance",
       R"x(<Parameter name="Relative tolerance" type="double" value="1.0e-12"/>)x"}};
  for (const auto& [name, entry] : variants) {
    const Result r = run(config(twist_xml(angle, 1, "hex8", entry), "test_results/solve_var" + tag()));
    ASSERT_EQ(r.code, 0) << name;
    EXPECT_LT(r.records.back().solve.final_residual, 1e-9) << name;
    EXPECT_LT(rel_diff(ref.u, r.u), 1e-7) << name;
  }
  // A relative tolerance alone stops earlier: |F| below 1e-3 of the first residual.
  const Result rel = run(config(twist_xml(angle, 1, "hex8",
                                          R"x(<Parameter name="Relative tolerance" type="double" value="1.0e-3"/>)x"),
                                "test_results/solve_rel" + tag()));
  ASSERT_EQ(rel.code, 0);
  const auto& s = rel.records.back().solve;
  EXPECT_LT(s.final_residual, 1e-3 * s.initial_residual);
  EXPECT_LT(s.newton_iterations, ref.records.back().solve.newton_iterations);
}

// A 6 x 6 x 12 hex column (1,911 DOFs: a two-level MueLu hierarchy) pulled to 1.8 times its length in
// 4 steps, bottom fixed.
std::string pull_xml(const std::string& extra_loading, const std::string& extra_solver) {
  return R"x(<ParameterList name="Sinew">
  <Parameter name="Scene" type="string" value="pull"/>
  <ParameterList name="Mesh">
    <Parameter name="Elements" type="Array(int)" value="{6, 6, 12}"/>
    <Parameter name="Upper corner" type="Array(double)" value="{0.5, 0.5, 1.0}"/>
  </ParameterList>
  <ParameterList name="Material">
    <Parameter name="Model" type="string" value="stable-neohookean"/>
    <Parameter name="Young modulus" type="double" value="1.0"/>
    <Parameter name="Poisson ratio" type="double" value="0.45"/>
  </ParameterList>
  <ParameterList name="Loading">
    <Parameter name="Steps" type="int" value="4"/>)x" + extra_loading + R"x(
    <ParameterList name="Boundary conditions">
      <ParameterList name="bottom"><Parameter name="Region" type="string" value="face z-"/></ParameterList>
      <ParameterList name="top">
        <Parameter name="Region" type="string" value="face z+"/>
        <Parameter name="Motion" type="string" value="translate"/>
        <Parameter name="Displacement" type="Array(double)" value="{0, 0, 0.8}"/>
      </ParameterList>
    </ParameterList>
  </ParameterList>
  <ParameterList name="Solver">
    <Parameter name="Absolute tolerance" type="double" value="1.0e-9"/>)x" + extra_solver + R"x(
  </ParameterList>
  <ParameterList name="Output"><Parameter name="HDF5" type="bool" value="false"/><Parameter name="Checkpoint every" type="int" value="0"/></ParameterList>
</ParameterList>)x";
}

// The step strategy (extrapolating predictor) and the preconditioner policies (hierarchy kept across
// steps, near-null space of the current state) change the path, never the end state; the predictor
// saves Newton iterations on a pull, whose displacement is nearly linear in the load.
TEST(Solve, PredictorAndPreconditionerPoliciesChangeThePathNotTheEndState) {
  auto newton = [](const Result& r) {
    int n = 0;
    for (const auto& rec : r.records) n += rec.solve.newton_iterations;
    return n;
  };
  const Result ref = run(config(pull_xml("", ""), "test_results/pull_ref" + tag()));
  ASSERT_EQ(ref.code, 0);
  const Result plain = run(config(pull_xml(R"x(<Parameter name="Predictor" type="string" value="none"/>)x", ""),
                                  "test_results/pull_plain" + tag()));
  ASSERT_EQ(plain.code, 0);
  EXPECT_LT(rel_diff(ref.u, plain.u), 1e-7);
  EXPECT_LT(newton(ref), newton(plain));
  if (world()->getRank() == 0)
    std::printf("[ info ] pull in 4 steps: %d Newton iterations with the predictor, %d without; end states %.2e apart\n",
                newton(ref), newton(plain), rel_diff(ref.u, plain.u));
  for (const std::string& entry : {std::string(R"x(<Parameter name="Preconditioner rebuild" type="string" value="every step"/>)x"),
                                   std::string(R"x(<Parameter name="Near-null space" type="string" value="current"/>)x"),
                                   std::string(R"x(<Parameter name="Rebuild factor" type="double" value="1.0"/>)x")}) {
    const Result r = run(config(pull_xml("", entry), "test_results/pull_var" + tag()));
    ASSERT_EQ(r.code, 0) << entry;
    EXPECT_LT(rel_diff(ref.u, r.u), 1e-7) << entry;
  }
}

// The tangent predictor (NonlinearSolver::tangent): from rest, the pull's first step jumps the top face
// 0.2 (a fifth of the column) and crushes the top layer; the linearised response spreads that over the
// column, leaving a fraction of the jump's residual, and keeps the prescribed values. It is taken only
// below the energy it must beat. A run with it ends where one without it does, in fewer Newton iterations.
TEST(Solve, TheTangentPredictorSpreadsAPrescribedJumpOverTheBodyAndIsTakenOnlyBelowTheEnergyToBeat) {
  SceneConfig c = config(pull_xml("", ""), "test_results/pull_tangent" + tag());
  Scene scene(c.scene(), world());
  const System& sys = scene.system();
  NonlinearSolver solver(scene.system(), c.params.solver);
  auto u0 = sys.create_vector(), jump = sys.create_vector(), f = sys.create_vector();
  u0->putScalar(0.0);
  jump->putScalar(0.0);
  scene.apply_load(0.25, *jump);
  const EvaluationTotals plain = sys.evaluate(*jump, f.get(), nullptr);
  const double f_plain = f->norm2();
  // Not taken: trial unchanged, to the bit.
  auto refused = sys.create_vector();
  refused->assign(*jump);
  EXPECT_FALSE(solver.tangent(*u0, *refused, -HUGE_VAL).converged());
  EXPECT_EQ(max_diff(gather(*refused), gather(*jump)), 0.0);
  // Taken.
  auto trial = sys.create_vector();
  trial->assign(*jump);
  const SolveReport r = solver.tangent(*u0, *trial, plain.energy);
  ASSERT_TRUE(r.converged()) << r.reason();
  EXPECT_GT(r.linear_iterations, 0);
  EXPECT_EQ(r.newton_iterations, 0);
  const EvaluationTotals predicted = sys.evaluate(*trial, f.get(), nullptr);
  EXPECT_LT(predicted.energy, plain.energy);
  const double f_predicted = f->norm2();  // collective: every rank, outside the rank-0 print below
  EXPECT_LT(f_predicted, 0.1 * f_plain) << "|F| of the jump " << f_plain;
  const auto tg = gather(*trial), jg = gather(*jump);
  // Every prescribed entry keeps its value (the top face's, and the fixed bottom's zeros).
  double moved_fixed = 0.0;
  const std::vector<char> fixed = fixed_flags(sys);
  for (std::size_t i = 0; i < tg.size(); ++i)
    if (fixed[i]) moved_fixed = std::max(moved_fixed, std::fabs(tg[i] - jg[i]));
  EXPECT_EQ(moved_fixed, 0.0);
  if (world()->getRank() == 0)
    std::printf("[ info ] pull's first step: |F| %.3e after the jump, %.3e after the tangent predictor (%d CG)\n", f_plain,
                f_predicted, r.linear_iterations);

  // Whole runs: the same end state, and the first step (from rest, where there is nothing to
  // extrapolate) in fewer Newton iterations.
  const Result ref = run(config(pull_xml(R"x(<Parameter name="Predictor" type="string" value="extrapolate"/>)x", ""),
                                "test_results/pull_extrapolate" + tag()));
  const Result tangent = run(config(pull_xml("", ""), "test_results/pull_tangent_run" + tag()));  // the default
  ASSERT_EQ(ref.code, 0);
  ASSERT_EQ(tangent.code, 0);
  EXPECT_LT(rel_diff(ref.u, tangent.u), 1e-7);
  EXPECT_LT(tangent.records.front().solve.newton_iterations, ref.records.front().solve.newton_iterations);
}

// A preconditioner kept across Newton iterations and load steps (PreconditionerLag) changes the path,
// never the end state: the same state as an update for every Jacobian, in fewer updates; with the
// tightest factor kept solves fail their CG budget and are repeated, and still end there.
TEST(Solve, AKeptPreconditionerChangesThePathNotTheEndState) {
  auto sum = [](const Result& r, int SolveReport::*field) {
    int n = 0;
    for (const auto& rec : r.records) n += rec.solve.*field;
    return n;
  };
  std::string every = R"x(<Parameter name="Preconditioner update" type="string" value="every Newton iteration"/>)x";
  // Without the tangent predictor, whose solve is one more update on the first step, so that every
  // update is a Newton iteration's.
  const Result ref = run(config(pull_xml(R"x(<Parameter name="Predictor" type="string" value="extrapolate"/>)x", every),
                                "test_results/pull_every" + tag()));
  ASSERT_EQ(ref.code, 0);
  for (const auto& rec : ref.records) {
    EXPECT_EQ(rec.solve.preconditioner_updates, rec.solve.newton_iterations);
    EXPECT_EQ(rec.solve.retried_solves, 0);
  }
  const Result kept = run(config(pull_xml("", ""), "test_results/pull_kept" + tag()));
  ASSERT_EQ(kept.code, 0);
  EXPECT_LT(rel_diff(ref.u, kept.u), 1e-7);
  EXPECT_LT(sum(kept, &SolveReport::preconditioner_updates), sum(ref, &SolveReport::preconditioner_updates) / 2);
  // Kept solves that fail their CG budget (forced to 2 iterations, as a preconditioner aged past use
  // would) are repeated with an updated preconditioner, within their Newton iteration, and end in the
  // same state. (A coarse size of 60
  // makes the 375 DOFs a two-level hierarchy.)
  const std::string two_levels = R"x(<ParameterList name="Stratimikos"><ParameterList name="Preconditioner Types">
      <ParameterList name="MueLu"><Parameter name="coarse: max size" type="int" value="60"/></ParameterList>
    </ParameterList></ParameterList>)x";
  every += two_levels;
  const Result twist_ref = run(config(twist_xml(3.0, 2, "hex8", every), "test_results/twist_every" + tag()));
  setenv("SINEW_KEPT_CG_BUDGET", "2", 1);
  const Result twist = run(config(twist_xml(3.0, 2, "hex8", two_levels), "test_results/twist_tight" + tag()));
  unsetenv("SINEW_KEPT_CG_BUDGET");
  ASSERT_EQ(twist_ref.code, 0);
  ASSERT_EQ(twist.code, 0);
  EXPECT_LT(rel_diff(twist_ref.u, twist.u), 1e-7);
  EXPECT_GT(sum(twist, &SolveReport::retried_solves), 0);
  if (world()->getRank() == 0)
    std::printf("[ info ] pull: %d updates for %d Newton (every: %d); twist: %d solves retried in %d Newton, %d updates\n",
                sum(kept, &SolveReport::preconditioner_updates), sum(kept, &SolveReport::newton_iterations),
                sum(ref, &SolveReport::preconditioner_updates), sum(twist, &SolveReport::retried_solves),
                sum(twist, &SolveReport::newton_iterations), sum(twist, &SolveReport::preconditioner_updates));
}

TEST(Solve, EveryProjectionOnHexAndTetReachesTheSameState) {
  for (const std::string element : {"hex8", "tet4"}) {
    std::vector<double> first;
    for (const std::string projection : {"clamp", "abs", "none"}) {
      const Result r = run(config(twist_xml(1.2, 2, element, "",
                                            R"x(<Parameter name="Projection" type="string" value=")x" + projection + R"x("/>)x"),
                                  "test_results/solve_proj" + tag()));
      ASSERT_EQ(r.code, 0) << element << " " << projection;
      for (const auto& rec : r.records) EXPECT_EQ(rec.totals.inverted, 0) << element << " " << projection;
      if (first.empty())
        first = r.u;
      else
        EXPECT_LT(rel_diff(first, r.u), 1e-7) << element << " " << projection;
    }
  }
}

// twist_xml's cube at nu = 0.49 (nearly incompressible), twisted by `angle` in one step.
static std::string nu49_twist_xml(double angle, const std::string& extra_solver) {
  const std::string nu49 = R"x(<Parameter name="Poisson ratio" type="double" value="0.49"/>)x";
  return std::regex_replace(twist_xml(angle, 1, "hex8", extra_solver),
                            std::regex(R"x(<Parameter name="Poisson ratio" type="double" value="0.45"/>)x"), nu49);
}

// A 4.5 rad twist in one step at nu = 0.49 with 'Exact Hessian below' = `below`, and an update of the
// preconditioner per Jacobian, so that the measured path is the Hessian policy's alone.
static std::string eager_twist_xml(const char* below) {
  return nu49_twist_xml(4.5, std::string(R"x(<Parameter name="Exact Hessian below" type="double" value=")x") + below +
                                 "\"/><Parameter name=\"Preconditioner update\" type=\"string\" value=\"every Newton iteration\"/>");
}

TEST(Solve, ExactHessianFallsBackToProjectionAndConverges) {
  // Exact Hessian as soon as the residual drops at all: far from the solution it gives directions that
  // do not descend or need short steps, so the policy must fall back, and the solve still converge to
  // the state projection alone reaches.
  // A 4.5 rad twist in one step at nu = 0.49 (measured: exact from iteration 3, a step of 1/4 at
  // iteration 5, projected from then on).
  const auto xml = eager_twist_xml;
  const Result projected = run(config(xml("0.0"), "test_results/solve_fb0" + tag()));
  const Result eager = run(config(xml("0.999"), "test_results/solve_fb1" + tag()));
  ASSERT_EQ(projected.code, 0);
  ASSERT_EQ(eager.code, 0);
  EXPECT_TRUE(eager.records.back().solve.exact_hessian_used);
  EXPECT_TRUE(eager.records.back().solve.exact_hessian_fell_back);
  EXPECT_FALSE(projected.records.back().solve.exact_hessian_used);
  EXPECT_LT(rel_diff(projected.u, eager.u), 1e-7);
}

TEST(Solve, AnExactSolveOverItsCGBudgetIsRedoneWithProjectionAndTheSolveConverges) {
  // The eager switch of the test above, with every exact solve forced over its CG budget (none):
  // each is solved again with the projected Hessian, assembled at the same state within its Newton
  // iteration (RetryingSolve), and the solve ends where projection alone does. Without that the
  // truncated exact directions would be stepped along.
  const auto xml = eager_twist_xml;
  const Result projected = run(config(xml("0.0"), "test_results/solve_ob0" + tag()));
  const Result free = run(config(xml("0.999"), "test_results/solve_ob1" + tag()));
  setenv("SINEW_EXACT_CG_BUDGET", "0", 1);
  const Result capped = run(config(xml("0.999"), "test_results/solve_ob2" + tag()));
  unsetenv("SINEW_EXACT_CG_BUDGET");
  ASSERT_EQ(projected.code, 0);
  ASSERT_EQ(free.code, 0);
  ASSERT_EQ(capped.code, 0);
  const SolveReport& c = capped.records.back().solve;
  EXPECT_GT(c.exact_over_budget, 0);
  EXPECT_TRUE(c.exact_hessian_fell_back);
  EXPECT_EQ(free.records.back().solve.exact_over_budget, 0);  // the measured budget leaves this twist alone
  EXPECT_EQ(projected.records.back().solve.exact_over_budget, 0);
  EXPECT_LT(rel_diff(projected.u, capped.u), 1e-7);
  if (world()->getRank() == 0)
    std::printf("[ info ] exact solves over budget: %d in %d Newton iterations, each solved again projected (free: %d Newton)\n", c.exact_over_budget,
                c.newton_iterations, free.records.back().solve.newton_iterations);
}

namespace {
// No energy, but a step limit that holds every other Newton step at 0.6 of the Newton step (as a
// contact barrier's collision test holds steps where surface points close on faces).
class HoldEveryOtherStep : public EnergyTerm {
 public:
  const char* name() const override { return "hold every other step"; }
  void add(const TermInput&, TermOutput&) const override {}
  bool limits_steps() const override { return true; }
  double step_limit(const Vector&, const Vector&, double t_max) const override { return ++calls_ % 2 ? 0.6 : t_max; }

 private:
  mutable long calls_ = 0;
};
}  // namespace

// HessianPolicy: after a step a term's limit held short of 1, the next Jacobian is the projected one,
// even where the residual has fallen far enough for the exact one; after a step it did not hold, the
// exact Hessian comes back at once. The solve converges to the state the plain twist reaches.
TEST(Solve, AfterAStepATermHeldShortTheNextJacobianIsProjected) {
  const std::string xml = twist_xml(1.0, 1);
  LoadedScene plain(config(xml, "test_results/solve_held0" + tag()));
  ASSERT_TRUE(plain.solver.solve(*plain.u).converged());
  LoadedScene held(config(xml, "test_results/solve_held1" + tag()));
  held.scene.system().add_term(std::make_shared<HoldEveryOtherStep>());
  std::vector<NewtonIterate> its;
  const SolveReport r = held.solver.solve(*held.u, [&](const NewtonIterate& it) { its.push_back(it); });
  ASSERT_TRUE(r.converged()) << r.reason();
  int after_held = 0, exact_after_free = 0;
  for (std::size_t i = 1; i < its.size(); ++i) {
    if (its[i - 1].step_bound < 1.0) {
      EXPECT_FALSE(its[i].exact_hessian) << "iteration " << its[i].iteration << " follows a held step";
      ++after_held;
    } else {
      exact_after_free += its[i].exact_hessian;
    }
  }
  EXPECT_GT(after_held, 2);
  EXPECT_GT(exact_after_free, 0);
  EXPECT_LT(rel_diff(gather(*plain.u), gather(*held.u)), 1e-6);
}

// 'Exact Hessian within': with the relative rule all but off ('Exact Hessian below' 1e-12), the exact
// Hessian comes once |F| is below 'within' times the absolute tolerance (here 1e6 x 1e-9), at the first
// iteration after that and from then on (nothing inverts in a 1 rad twist); with 0 Newton projects
// throughout, converging linearly, so the floor saves iterations. Both reach the same state.
TEST(Solve, TheExactHessianAlsoComesBelowAFloorNearTheConvergenceThreshold) {
  const auto xml = [](const char* within) {
    return twist_xml(1.0, 1, "hex8",
                     std::string(R"x(<Parameter name="Exact Hessian below" type="double" value="1e-12"/><Parameter name="Exact Hessian within" type="double" value=")x") +
                         within + "\"/>");
  };
  const double floor = 1e6 * 1e-9;
  std::vector<NewtonIterate> off_its, on_its;
  LoadedScene off(config(xml("0"), "test_results/solve_within0" + tag()));
  const SolveReport r0 = off.solver.solve(*off.u, [&](const NewtonIterate& it) { off_its.push_back(it); });
  LoadedScene on(config(xml("1e6"), "test_results/solve_within1" + tag()));
  const SolveReport r1 = on.solver.solve(*on.u, [&](const NewtonIterate& it) { on_its.push_back(it); });
  ASSERT_TRUE(r0.converged()) << r0.reason();
  ASSERT_TRUE(r1.converged()) << r1.reason();
  for (const auto& it : off_its) EXPECT_FALSE(it.exact_hessian) << "iteration " << it.iteration;
  int exact = 0;
  for (std::size_t i = 1; i < on_its.size(); ++i) {
    EXPECT_EQ(on_its[i].exact_hessian, on_its[i - 1].residual < floor) << "iteration " << on_its[i].iteration;
    exact += on_its[i].exact_hessian;
  }
  EXPECT_GT(exact, 0);
  EXPECT_LT(r1.newton_iterations, r0.newton_iterations);
  EXPECT_LT(rel_diff(gather(*off.u), gather(*on.u)), 1e-6);
  if (world()->getRank() == 0)
    std::printf("[ info ] Newton iterations: %d projected throughout, %d with the floor (%d exact)\n", r0.newton_iterations,
                r1.newton_iterations, exact);
}

TEST(Solve, AFailedSolveIsRetriedWithProjectionOnlyWhenTheExactHessianWasUsed) {
  // Three Newton iterations cannot converge a pi/2 twist. With the default switch (1% of the first
  // residual) the exact Hessian is never reached: no retry, 3 iterations. With an eager switch it is
  // used at the third, and the retry with projection adds 3 more.
  for (const auto& [below, expected] : std::vector<std::pair<std::string, int>>{{"0.01", 3}, {"0.999", 6}}) {
    SceneConfig c = config(twist_xml(1.5708, 1, "hex8", R"x(<Parameter name="Exact Hessian below" type="double" value=")x" + below + R"x("/>)x"),
                           "test_results/solve_retry" + tag());
    c.params.solver.max_iterations = 3;
    c.params.loading.max_cuts = 0;
    // The counts are the Hessian policy's: no iteration redone for a kept preconditioner (on 2 ranks one
    // is, and the exact Hessian comes an iteration later).
    c.params.solver.update = SolverParameters::Update::EveryNewtonIteration;
    LoadedScene s(c);
    const SolveReport r = s.solver.solve(*s.u);
    EXPECT_FALSE(r.converged()) << below;
    EXPECT_EQ(r.status, SolveStatus::MaxIterations) << below;
    EXPECT_EQ(r.newton_iterations, expected) << "Exact Hessian below " << below;
  }
}

TEST(Solve, AnUndefinedNeoHookeanStateIsNeverAccepted) {
  // A scrambled start inverts elements, where Neo-Hookean's energy is +inf. Even with a tolerance that
  // the first residual meets, the solve must not report convergence there.
  std::string xml = twist_xml(0.0, 1, "hex8", "", "");
  xml = std::regex_replace(xml, std::regex("stable-neohookean"), "neohookean");
  xml = std::regex_replace(xml, std::regex(R"x(<Parameter name="Steps" type="int" value="1"/>)x"),
                           R"x(<Parameter name="Steps" type="int" value="1"/>
    <Parameter name="Initial state" type="string" value="scramble"/>)x");
  SceneConfig c = config(xml, "test_results/solve_nh" + tag());
  c.params.solver.absolute_tolerance = 1e300;
  Scene scene(c.scene(), world());
  NonlinearSolver solver(scene.system(), c.params.solver);
  auto u = scene.system().create_vector();
  scene.initial_state(*u);
  scene.apply_load(1.0, *u);
  const auto totals = scene.system().evaluate(*u, nullptr, nullptr);
  ASSERT_GT(totals.undefined, 0);
  EXPECT_TRUE(std::isinf(totals.energy) && totals.energy > 0.0);  // +inf, not a finite (too low) energy
  const SolveReport r = solver.solve(*u);
  EXPECT_EQ(r.status, SolveStatus::UndefinedEnergy) << r.reason();
  EXPECT_FALSE(r.converged());
}

namespace {

// The lateral stretch t of uniaxial stress diag(s, t, t) (P_yy = P_zz = 0) from the material law alone:
// Newton on P_yy(t) with a finite-difference slope, started at 1. Independent of meshes and solvers.
template <class Model>
double lateral_stretch(const Model& m, double s) {
  double t = 1.0;
  for (int it = 0; it < 100; ++it) {
    const double f = m.pk1(Mat3::diag(s, t, t))(1, 1), h = 1e-7;
    const double df = (m.pk1(Mat3::diag(s, t + h, t + h))(1, 1) - m.pk1(Mat3::diag(s, t - h, t - h))(1, 1)) / (2 * h);
    const double dt = f / df;
    t -= dt;
    if (std::fabs(dt) < 1e-15) break;
  }
  return t;
}

std::string uniaxial_xml(const std::string& model, const std::string& element, double nu, double stretch) {
  // Rollers on x-, y-, z- (one component each), the x+ face pulled along x only: homogeneous uniaxial
  // stress, whose discrete solution is the affine one for hex8 and tet4 alike.
  return R"x(<ParameterList name="Sinew">
  <Parameter name="Scene" type="string" value="uniaxial"/>
  <ParameterList name="Mesh">
    <Parameter name="Element" type="string" value=")x" + element + R"x("/>
    <Parameter name="Elements" type="Array(int)" value="{2, 2, 2}"/>
  </ParameterList>
  <ParameterList name="Material">
    <Parameter name="Model" type="string" value=")x" + model + R"x("/>
    <Parameter name="Young modulus" type="double" value="1.0"/>
    <Parameter name="Poisson ratio" type="double" value=")x" + std::to_string(nu) + R"x("/>
  </ParameterList>
  <ParameterList name="Loading">
    <Parameter name="Steps" type="int" value="4"/>
    <ParameterList name="Boundary conditions">
      <ParameterList name="symmetry x"><Parameter name="Region" type="string" value="face x-"/><Parameter name="Components" type="string" value="x"/></ParameterList>
      <ParameterList name="symmetry y"><Parameter name="Region" type="string" value="face y-"/><Parameter name="Components" type="string" value="y"/></ParameterList>
      <ParameterList name="symmetry z"><Parameter name="Region" type="string" value="face z-"/><Parameter name="Components" type="string" value="z"/></ParameterList>
      <ParameterList name="pull">
        <Parameter name="Region" type="string" value="face x+"/>
        <Parameter name="Motion" type="string" value="translate"/>
        <Parameter name="Components" type="string" value="x"/>
        <Parameter name="Displacement" type="Array(double)" value="{)x" + std::to_string(stretch - 1.0) + R"x(, 0, 0}"/>
      </ParameterList>
    </ParameterList>
  </ParameterList>
  <ParameterList name="Solver">
    <Parameter name="Absolute tolerance" type="double" value="1.0e-12"/>
    <Parameter name="Maximum iterations" type="int" value="80"/>
  </ParameterList>
  <ParameterList name="Output"><Parameter name="HDF5" type="bool" value="false"/><Parameter name="Checkpoint every" type="int" value="0"/></ParameterList>
</ParameterList>)x";
}

}  // namespace

TEST(Solve, UniaxialTensionWithRollersEqualsTheMaterialPointForEveryModel) {
  // Every model at stretch 1.3 (nu = 0.3), and SNH at the paper's 3.4 (nu = 0.49), on hex8 and tet4.
  struct Case {
    std::string model;
    double nu, stretch;
  };
  std::vector<Case> cases;
  for (const auto& m : material_model_names()) cases.push_back({m, 0.3, 1.3});
  cases.push_back({"stable-neohookean", 0.49, 3.4});
  double worst = 0.0;
  for (const std::string element : {"hex8", "tet4"}) {
    for (const auto& c : cases) {
      const SceneConfig cfg = config(uniaxial_xml(c.model, element, c.nu, c.stretch), "test_results/uniaxial" + tag());
      Simulation sim(cfg, RunOptions{true, ""});
      ASSERT_EQ(sim.run(), 0) << c.model << " " << element;
      const double t = with_material(sim.scene().system().material(), [&](const auto& m) { return lateral_stretch(m, c.stretch); });
      const auto u = gather(sim.displacement());
      // Nodes in global order: the box [0, 1]^3 on a 3 x 3 x 3 lattice, x fastest.
      double err = 0.0;
      for (int k = 0; k <= 2; ++k)
        for (int j = 0; j <= 2; ++j)
          for (int i = 0; i <= 2; ++i) {
            const std::size_t n = static_cast<std::size_t>(i + 3 * (j + 3 * k));
            const double X[3] = {0.5 * i, 0.5 * j, 0.5 * k};
            const double expect[3] = {(c.stretch - 1.0) * X[0], (t - 1.0) * X[1], (t - 1.0) * X[2]};
            for (int d = 0; d < 3; ++d) err = std::max(err, std::fabs(u[3 * n + d] - expect[d]));
          }
      EXPECT_LT(err, 1e-8 * c.stretch) << c.model << " " << element << " nu " << c.nu << " stretch " << c.stretch << " (t = " << t << ")";
      worst = std::max(worst, err);
    }
  }
  if (world()->getRank() == 0) std::printf("[ info ] uniaxial tension, every model, hex8 and tet4: max |u - u_affine| = %.2e\n", worst);
}

TEST(Solve, ACheckpointInsideACutStepRestartsTheSameRun) {
  // One step of 1.5 rad with 6 Newton iterations allowed: the full increment fails and is cut (measured:
  // fail, then load 0.5, then 1; 24 Newton iterations with the retries). Stop the
  // run at various Newton iterations (as a SIGTERM would), restart from its checkpoint, and compare with
  // the uninterrupted run; at least one stop must land inside the cut step. The preconditioner is updated
  // for every Jacobian: a kept one is state that no checkpoint holds (the restarted run would set up
  // afresh where the uninterrupted one keeps its own, and the two agree to the solver's tolerance only,
  // 3e-9 measured).
  auto make = [](const std::string& dir) {
    SceneConfig c = config(twist_xml(1.5, 1, "hex8"), dir);
    c.params.solver.update = SolverParameters::Update::EveryNewtonIteration;
    c.params.solver.max_iterations = 6;
    c.params.solver.absolute_tolerance = 1e-8;
    // The path measured above; with the node relaxation the full increment converges in 6 (no cut).
    c.params.solver.node_relaxation = 0.0;
    c.params.output.checkpoint_every = 1;
    return c;
  };
  const Result full = run(make("test_results/cut_full" + tag()));
  ASSERT_EQ(full.code, 0);
  ASSERT_GE(full.records.back().cuts, 1) << "the scene must need a cut for this test to mean anything";
  int inside = 0;
  for (int stop_at : {3, 8, 13, 16, 19, 22}) {
    const std::string dir = "test_results/cut_stop" + std::to_string(stop_at) + tag();
    int calls = 0;
    const Result stopped = run(make(dir), Teuchos::null, "", [&] { return ++calls == stop_at ? 15 : 0; });
    if (stopped.code == 0) continue;  // finished before the stop
    ASSERT_EQ(stopped.code, 128 + 15);
    // Where did it stop? Read the checkpoint's load.
    hid_t f = H5Fopen((dir + "/checkpoint.h5").c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
    ASSERT_GE(f, 0);
    double load = -1.0;
    hid_t a = H5Aopen(f, "load", H5P_DEFAULT);
    H5Aread(a, H5T_NATIVE_DOUBLE, &load);
    H5Aclose(a);
    H5Fclose(f);
    if (load > 1e-12 && load < 1.0 - 1e-12) ++inside;
    world()->barrier();
    const Result resumed = run(make(dir), Teuchos::null, dir + "/checkpoint.h5");
    ASSERT_EQ(resumed.code, 0) << "stop at " << stop_at;
    EXPECT_LT(rel_diff(full.u, resumed.u), 1e-10) << "stop at " << stop_at << ", checkpoint load " << load;
  }
  EXPECT_GE(inside, 1);
}

TEST(Solve, ACheckpointFromTwoRanksRestartsOnOne) {
  if (world()->getSize() != 2) GTEST_SKIP() << "needs 2 MPI ranks";
  SceneConfig c = config(twist_xml(1.2, 3, "hex8"), "test_results/ranks_full");
  c.params.output.checkpoint_every = 1;
  c.params.output.hdf5 = true;
  const Result full = run(c);
  ASSERT_EQ(full.code, 0);
  SceneConfig stop = c;
  stop.params.output.directory = "test_results/ranks_stop";
  int steps_done = 0;
  // Stop after step 1 (the check after each step is the one that counts whole steps here).
  const Result stopped = run(stop, Teuchos::null, "", [&] { return ++steps_done > 6 ? 15 : 0; });
  ASSERT_EQ(stopped.code, 128 + 15);
  world()->barrier();
  // Each rank alone restarts the 2-rank checkpoint on one rank.
  SceneConfig one = stop;
  one.params.output.directory = "test_results/ranks_one_" + std::to_string(world()->getRank());
  std::filesystem::create_directories(one.params.output.directory);
  auto self = Teuchos::rcp(new Teuchos::MpiComm<int>(MPI_COMM_SELF));
  const Result resumed = run(one, self, "test_results/ranks_stop/checkpoint.h5");
  ASSERT_EQ(resumed.code, 0);
  EXPECT_LT(rel_diff(full.u, resumed.u), 1e-8);
}

TEST(Solve, CorruptOrMismatchedCheckpointsAreNamedInputErrors) {
  const std::string dir = "test_results/bad_ckpt" + tag();
  SceneConfig c = config(twist_xml(0.5, 2, "hex8"), dir);
  c.params.output.checkpoint_every = 1;
  c.params.output.hdf5 = true;
  ASSERT_EQ(run(c).code, 0);
  world()->barrier();
  const std::string good = dir + "/checkpoint.h5";
  auto error = [&](const std::string& path, const SceneConfig& cfg) {
    try {
      Simulation sim(cfg, RunOptions{true, path});
    } catch (const InputError& e) {
      EXPECT_EQ(e.kind, InputErrorKind::File) << e.what();
      return std::string(e.what());
    }
    return std::string("no error");
  };
  const bool root = world()->getRank() == 0;
  // Copies of the good file with one thing wrong, written by rank 0.
  auto variant = [&](const std::string& name, const std::function<void(hid_t)>& edit) {
    const std::string p = dir + "/" + name + ".h5";
    if (root) {
      std::filesystem::copy_file(good, p, std::filesystem::copy_options::overwrite_existing);
      hid_t f = H5Fopen(p.c_str(), H5F_ACC_RDWR, H5P_DEFAULT);
      edit(f);
      H5Fclose(f);
    }
    world()->barrier();
    return p;
  };
  auto set_attr = [](hid_t f, const char* name, double v) {
    hid_t a = H5Aopen(f, name, H5P_DEFAULT);
    H5Awrite(a, H5T_NATIVE_DOUBLE, &v);
    H5Aclose(a);
  };
  EXPECT_NE(error(dir + "/missing.h5", c).find("does not exist"), std::string::npos);
  if (root) std::ofstream(dir + "/text.h5") << "not hdf5\n";
  world()->barrier();
  EXPECT_NE(error(dir + "/text.h5", c).find("is not an HDF5 file"), std::string::npos);
  EXPECT_NE(error(variant("nostep", [](hid_t f) { H5Adelete(f, "step"); }), c).find("has no 'step' attribute"), std::string::npos);
  EXPECT_NE(error(variant("nanload", [&](hid_t f) { set_attr(f, "load", NAN); }), c).find("'load'"), std::string::npos);
  EXPECT_NE(error(variant("farstep", [&](hid_t f) { set_attr(f, "step", 99); }), c).find("'step'"), std::string::npos);
  EXPECT_NE(error(variant("nodisp", [](hid_t f) { H5Ldelete(f, "/displacement", H5P_DEFAULT); }), c).find("has no /displacement"),
            std::string::npos);
  EXPECT_NE(error(variant("naninside", [](hid_t f) {
                    hid_t d = H5Dopen2(f, "/displacement", H5P_DEFAULT);
                    hid_t s = H5Dget_space(d);
                    hsize_t dims[2];
                    H5Sget_simple_extent_dims(s, dims, nullptr);
                    std::vector<double> v(dims[0] * dims[1], NAN);
                    H5Dwrite(d, H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, v.data());
                    H5Sclose(s);
                    H5Dclose(d);
                  }),
                  c)
                .find("non-finite"),
            std::string::npos);
  // Corrupt in one row only (the last: on 2 ranks, only the last rank's block): every rank must end
  // with the error, none may wait for the others (this hung before the reads and checks were split
  // from the collective import).
  auto edit_last_row = [](hid_t f, const char* name, hid_t type, const void* value) {
    hid_t d = H5Dopen2(f, name, H5P_DEFAULT);
    hid_t sp = H5Dget_space(d);
    hsize_t dims[2] = {0, 0};
    const int nd = H5Sget_simple_extent_dims(sp, dims, nullptr);
    hsize_t start[2] = {dims[0] - 1, 0}, count[2] = {1, 1};
    H5Sselect_hyperslab(sp, H5S_SELECT_SET, start, nullptr, count, nullptr);
    hid_t mem = H5Screate_simple(nd, count, nullptr);
    H5Dwrite(d, type, mem, sp, H5P_DEFAULT, value);
    H5Sclose(mem);
    H5Sclose(sp);
    H5Dclose(d);
  };
  const double nan = NAN;
  const long long far = 1000000, twin = 0;
  EXPECT_NE(error(variant("nanlast", [&](hid_t f) { edit_last_row(f, "/displacement", H5T_NATIVE_DOUBLE, &nan); }), c)
                .find("holds a non-finite value"),
            std::string::npos);
  EXPECT_NE(error(variant("gidlast", [&](hid_t f) { edit_last_row(f, "/node_gid", H5T_NATIVE_LLONG, &far); }), c)
                .find("holds 1000000, not a node of this mesh"),
            std::string::npos);
  EXPECT_NE(error(variant("gidtwin", [&](hid_t f) { edit_last_row(f, "/node_gid", H5T_NATIVE_LLONG, &twin); }), c)
                .find("does not cover node"),
            std::string::npos);
  SceneConfig other_steps = c;
  other_steps.params.loading.steps = 5;
  EXPECT_NE(error(good, other_steps).find("was written for 2 load steps; this scene has 5"), std::string::npos);
  SceneConfig other_mesh = c;
  other_mesh.params.mesh.cells = {4, 4, 5};
  EXPECT_NE(error(good, other_mesh).find("was written for a mesh of 125 nodes"), std::string::npos);
  // A truncated file (a copy cut in half).
  if (root) {
    std::filesystem::copy_file(good, dir + "/half.h5", std::filesystem::copy_options::overwrite_existing);
    std::filesystem::resize_file(dir + "/half.h5", std::filesystem::file_size(good) / 2);
  }
  world()->barrier();
  EXPECT_NE(error(dir + "/half.h5", c), "no error");
  // Reading bad files silenced HDF5's own error printing only while it read them.
  H5E_auto2_t func = nullptr;
  void* data = nullptr;
  H5Eget_auto2(H5E_DEFAULT, &func, &data);
  EXPECT_NE(func, nullptr) << "HDF5 error reporting was left switched off";
}

TEST(Solve, TheLineSearchStepsBeyondNewtonWhereTheFullStepLowersTheEnergyAlmostLinearly) {
  // Projection throughout on a pi/2 twist at nu = 0.49: the clamped Hessian is stiffer than the energy
  // along its directions, so full steps lower the energy by more than a quadratic's half of the slope
  // and Newton converges linearly. 'Maximum step' lets the line search go on to the energy's minimum
  // along the direction, up to that many Newton steps: fewer iterations, the same end state, and never
  // a step beyond the cap (1: never beyond the Newton step).
  struct Path {
    int newton = 0;
    double longest = 0.0;
    std::vector<double> u;
  };
  auto solve = [&](double max_step) {
    const std::string entries = R"x(<Parameter name="Exact Hessian below" type="double" value="0.0"/>
        <Parameter name="Preconditioner update" type="string" value="every Newton iteration"/>
        <Parameter name="Maximum step" type="double" value=")x" + std::to_string(max_step) + "\"/>";
    SceneConfig c = config(nu49_twist_xml(1.5708, entries), "test_results/solve_extend" + tag());
    LoadedScene s(c);
    Path p;
    const SolveReport r = s.solver.solve(*s.u, [&](const NewtonIterate& it) { p.longest = std::max(p.longest, it.step); });
    EXPECT_TRUE(r.converged()) << "Maximum step " << max_step << ": " << r.reason();
    p.newton = r.newton_iterations;
    p.u = gather(*s.u);
    return p;
  };
  // The minimum along these directions lies near 1.45 Newton steps: a cap of 1.3 binds, 4 does not.
  const Path newton = solve(1.0), capped = solve(1.3), free = solve(4.0);
  EXPECT_EQ(newton.longest, 1.0);
  EXPECT_GT(capped.longest, 1.0);
  EXPECT_LE(capped.longest, 1.3);
  EXPECT_GT(free.longest, 1.3);
  EXPECT_LE(free.longest, 4.0);
  EXPECT_LT(free.newton, newton.newton);
  EXPECT_LT(capped.newton, newton.newton);
  EXPECT_LT(rel_diff(newton.u, capped.u), 1e-7);
  EXPECT_LT(rel_diff(newton.u, free.u), 1e-7);
  std::printf("Newton iterations with Maximum step 1 / 1.3 / 4: %d / %d / %d (longest steps %.3g, %.3g)\n", newton.newton,
              capped.newton, free.newton, capped.longest, free.longest);
}

TEST(Solve, WhereTheEnergyCannotTellAStepFromNoneTheSlopesAlongItStillLengthenIt) {
  // The same projected twist solved far below where its energy changes by more than roundoff: near
  // convergence a step changes the energy by about |F|^2 / k, below 1e-11 of the energy, so the energy
  // cannot say whether a longer step would be better, and steps of exactly 1 used to follow (linear
  // convergence at the projection's rate). The slopes along the direction, F(x + t d) . d, still can.
  std::vector<NewtonIterate> its;
  const std::string entries = R"x(<Parameter name="Exact Hessian below" type="double" value="0.0"/>
      <Parameter name="Preconditioner update" type="string" value="every Newton iteration"/>)x";
  SceneConfig c = config(nu49_twist_xml(1.5708, entries), "test_results/solve_blind" + tag());
  c.params.solver.absolute_tolerance = 1e-13;
  LoadedScene s(c);
  const SolveReport r = s.solver.solve(*s.u, [&](const NewtonIterate& it) { its.push_back(it); });
  EXPECT_TRUE(r.converged()) << r.reason();
  // Below |F| 1e-7 every step was exactly 1 without the slopes (20 iterations, |F| 0.3 of the last
  // each); with them 16, several of them longer.
  int lengthened = 0;
  for (std::size_t i = 1; i < its.size(); ++i) {
    if (!(its[i - 1].residual < 1e-7)) continue;
    EXPECT_LE(its[i].step, 2.0) << "beyond 'Maximum step' at iteration " << its[i].iteration;
    if (its[i].step > 1.25) {
      ++lengthened;
      EXPECT_LT(its[i].residual, its[i - 1].residual) << "a lengthened step raised |F| at iteration " << its[i].iteration;
    }
  }
  EXPECT_GE(lengthened, 2);
  std::printf("Newton iterations %d, steps lengthened below |F| 1e-7: %d\n", r.newton_iterations, lengthened);
}

// Each Newton iteration reports its direction's largest entry (NewtonIterate::direction_max, the log's
// |du|): on a small twist, nearly linear, the first direction is nearly the whole way (its largest entry
// within 5% of the largest displacement solved for), and the steps times the reported entries bound the
// displacement from above, as the max norm of a sum must (no node relaxation, which moves nodes off the
// directions).
TEST(Solve, EachIterationReportsHowFarItsNewtonDirectionGoes) {
  SceneConfig c = config(twist_xml(0.05, 1, "hex8", R"x(<Parameter name="Node relaxation" type="double" value="0"/>)x"),
                         "test_results/solve_du" + tag());
  LoadedScene s(c);
  const std::vector<double> start = gather(*s.u);
  std::vector<NewtonIterate> its;
  const SolveReport r = s.solver.solve(*s.u, [&](const NewtonIterate& it) { its.push_back(it); });
  ASSERT_TRUE(r.converged()) << r.reason();
  ASSERT_GE(its.size(), 2u);
  ASSERT_EQ(r.relaxed_nodes, 0);
  const std::vector<double> end = gather(*s.u);
  double moved = 0.0;
  for (std::size_t i = 0; i < end.size(); ++i) moved = std::max(moved, std::fabs(end[i] - start[i]));
  double bound = 0.0;
  for (const NewtonIterate& it : its) {
    ASSERT_TRUE(std::isfinite(it.direction_max));
    bound += it.step * it.direction_max;
  }
  EXPECT_GT(moved, 0.0);
  EXPECT_NEAR(its[0].direction_max, moved, 0.05 * moved);
  EXPECT_GE(bound, moved * (1.0 - 1e-12));
  EXPECT_LT(its.back().direction_max, 1e-3 * its[0].direction_max);  // converged: the last direction is short
}

TEST(Solve, NoxBacktrackSettingsGovernTheEnergyLineSearch) {
  // A 3.14 rad twist at nu = 0.49 needs a half step in its first Newton iteration (measured). With
  // NOX's own "Backtrack" list allowing one trial only, the energy line search must fail there.
  const std::string one_try = R"x(<ParameterList name="NOX"><ParameterList name="Line Search"><ParameterList name="Backtrack">
      <Parameter name="Max Iters" type="int" value="1"/></ParameterList></ParameterList></ParameterList>)x";
  for (const bool limited : {false, true}) {
    SceneConfig c = config(nu49_twist_xml(3.14, limited ? one_try : ""), "test_results/solve_bt" + tag());
    LoadedScene s(c);
    const SolveReport r = s.solver.solve(*s.u);
    if (limited)
      EXPECT_EQ(r.status, SolveStatus::LineSearchFailed) << r.reason();
    else
      EXPECT_TRUE(r.converged()) << r.reason();
  }
}
