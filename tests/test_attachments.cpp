// Attachments between bodies (two blocks meshed apart, non-matching at their interface): the term's
// energy, gradient and Hessian against finite differences with raised tractions and turned frames
// (PSD); a sliding block pulled along its interface carries no tangential force and keeps the gap
// closed; a fixed one moves with the block below to 1e-10; self contact leaves an attached interface
// alone. 1 thread, 2 threads and 2 ranks.
#include "scene_test_utils.hpp"
#include "system_test_utils.hpp"

#include <sinew/algebra/terms/attachment.hpp>
#include <sinew/algebra/terms/bone_springs.hpp>
#include <sinew/algebra/terms/contact.hpp>
#include <cmath>
#include <sinew/driver/run.hpp>
#include <sinew/scenes/scene.hpp>

#include <Teuchos_CommHelpers.hpp>
#include <Tpetra_Core.hpp>
#include <Tpetra_Vector.hpp>
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <string>

using namespace sinew;
using namespace sinew::test;

namespace {

auto world() { return Tpetra::getDefaultComm(); }

// A results folder of this run's own: the 1-thread, 2-thread and 2-rank variants run at once.
std::string results(const std::string& name) {
  return "test_results/" + name + "_np" + std::to_string(world()->getSize()) + "_t" +
         std::to_string(Kokkos::DefaultExecutionSpace::concurrency());
}

const std::string meshes = std::string(SINEW_SOURCE_DIR) + "/tests/meshes/";

// The blocks of meshes/stacked_blocks.geo: the lower one's bottom held, the upper one's top moved by
// `pull` (all three components prescribed); the upper block's bottom attached to the lower's top.
std::string stacked(const std::string& type, const std::string& pull, const std::string& extra = "", int steps = 4) {
  return file_scene_head("stacked_blocks", meshes + "stacked_blocks.msh") + R"x(
  <ParameterList name="Attachments">
    <ParameterList name="interface">
      <Parameter name="Type" type="string" value=")x" + type + R"x("/>
      <Parameter name="Region" type="string" value="group upper bottom"/>
      <Parameter name="Target" type="string" value="group lower top"/>
      <Parameter name="Distance" type="double" value="1.0e-6"/>
      <Parameter name="Tolerance" type="double" value="1.0e-11"/>
      <Parameter name="Maximum rounds" type="int" value="20"/>
    </ParameterList>
  </ParameterList>
  )x" + extra + R"x(
  <ParameterList name="Loading">
    <Parameter name="Steps" type="int" value=")x" + std::to_string(steps) + R"x("/>
    <ParameterList name="Boundary conditions">
      <ParameterList name="bottom"><Parameter name="Region" type="string" value="group bottom"/></ParameterList>
      <ParameterList name="pull">
        <Parameter name="Region" type="string" value="group top"/>
        <Parameter name="Motion" type="string" value="translate"/>
        <Parameter name="Displacement" type="Array(double)" value=")x" + pull + R"x("/>
      </ParameterList>
    </ParameterList>
  </ParameterList>
  <ParameterList name="Solver">
    <Parameter name="Absolute tolerance" type="double" value="1.0e-11"/>
  </ParameterList>
  )x" + logs_only_output() + R"x(
</ParameterList>)x";
}

// The reaction at the pulled face (the force the prescribed motion exerts there), over all ranks.
std::array<double, 3> pull_reaction(Simulation& sim) {
  const System& sys = sim.scene().system();
  auto f = sys.create_vector();
  sys.gradient(sim.displacement(), *f);
  auto X = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), sys.mesh().X);
  auto fv = f->getLocalViewHost(Tpetra::Access::ReadOnly);
  double mine[3] = {0, 0, 0}, all[3];
  for (std::size_t n = 0; n < sys.mesh().n_owned_nodes; ++n)
    if (X(n, 2) > 1.0 - 1e-12)
      for (int c = 0; c < 3; ++c) mine[c] += fv(3 * n + c, 0);
  Teuchos::reduceAll(*world(), Teuchos::REDUCE_SUM, 3, mine, all);
  return {all[0], all[1], all[2]};
}

}  // namespace

// The term's energy, gradient and Hessian at a random state, after a round has raised the tractions
// and refrozen the frames (fixed) and normals and targets (sliding) at another: the directional
// derivative equals the energy's central difference, H d the gradient's, and H is PSD.
TEST(Attachments, TheTermsGradientAndHessianMatchFiniteDifferencesAndArePositiveSemiDefinite) {
  for (const char* type : {"fixed", "sliding"}) {
    Simulation sim(config(stacked(type, "{0.1, 0, 0}"), results("attachment_fd_") + type), RunOptions{true, ""});
    System& sys = sim.scene().system();
    auto* term = sys.find_term<AttachmentTerm>();
    ASSERT_NE(term, nullptr);
    EXPECT_EQ(term->pairs().size(), 16u) << type;  // the upper block's 4 x 4 bottom nodes
    auto u0 = sys.create_vector(), u1 = sys.create_vector(), u = sys.create_vector(), d = sys.create_vector();
    u0->putScalar(0.0);
    sys.round(*u0, 0);
    // A state that turns and shifts the interface: the round raises the tractions and refreezes there.
    set_displacement(sys, *u1, [](const std::array<double, 3>& X, int i, long long gid) {
      return 0.03 * hash_unit(gid, i, 3) + (i == 0 ? 0.2 * X[2] : i == 2 ? -0.15 * X[0] : 0.0);
    });
    sys.round(*u1, 1);
    double lambda = 0.0;
    for (const auto& p : term->pairs()) lambda = std::max(lambda, std::fabs(p.lambda[0]) + std::fabs(p.lambda[2]));
    EXPECT_GT(lambda, 1.0) << type;
    set_displacement(sys, *u, [](const std::array<double, 3>&, int i, long long gid) { return 0.05 * hash_unit(gid, i); });
    set_displacement(sys, *d, [](const std::array<double, 3>&, int i, long long gid) { return hash_unit(gid, i, 7); });
    const auto c = check_term_derivatives(sys, *term, *u, *d);
    EXPECT_NEAR(c.f_dot_d, c.dE, 1e-7 * std::max(1.0, std::fabs(c.dE))) << type;
    EXPECT_GT(c.scale, 1.0) << type;
    EXPECT_LT(c.err, 1e-7 * c.scale) << type;
    EXPECT_GE(c.min_eigenvalue, -1e-12 * c.max_entry) << type;
    if (world()->getRank() == 0)
      std::printf("[ info ] %s: dE/dd %.9e vs f.d %.9e; |H d - FD| %.2e of %.2e; min eigenvalue %.2e of %.2e\n", type, c.dE,
                  c.f_dot_d, c.err, c.scale, c.min_eigenvalue, c.max_entry);
  }
}

// The upper block's top pulled along the interface: sliding, the block slides and the pull meets no
// tangential force (below 1e-8 of the fixed attachment's, which shears both blocks); the normal gap
// stays closed; fixed, the upper block's bottom moves with the lower block's top to 1e-10.
TEST(Attachments, ASlidingBlockCarriesNoTangentialForceAndAFixedOneMovesWithItsBase) {
  Simulation fixed(config(stacked("fixed", "{0.1, 0.05, 0}"), results("attachment_fixed")), RunOptions{true, ""});
  ASSERT_EQ(fixed.run(), 0);
  Simulation sliding(config(stacked("sliding", "{0.1, 0.05, 0}"), results("attachment_sliding")), RunOptions{true, ""});
  ASSERT_EQ(sliding.run(), 0);
  const auto rf = pull_reaction(fixed), rs = pull_reaction(sliding);
  const double pull = std::hypot(rf[0], rf[1]), tangential = std::hypot(rs[0], rs[1]);
  const double gap_fixed = fixed.scene().system().find_term<AttachmentTerm>()->largest_gaps(fixed.displacement())[0];
  const double gap_sliding = sliding.scene().system().find_term<AttachmentTerm>()->largest_gaps(sliding.displacement())[0];
  if (world()->getRank() == 0)
    std::printf("[ info ] pull (0.1, 0.05, 0): tangential reaction fixed %.6e, sliding %.3e (ratio %.2e); largest gap fixed %.2e, "
                "sliding (normal) %.2e\n",
                pull, tangential, tangential / pull, gap_fixed, gap_sliding);
  EXPECT_GT(pull, 1.0);  // the fixed attachment shears the blocks
  EXPECT_LT(tangential, 1e-8 * pull);
  EXPECT_LT(gap_fixed, 1e-10);
  EXPECT_LT(gap_sliding, 1e-10);
  // Fixed: every sample's displacement is its target point's (the surfaces touch at rest).
  const System& sys = fixed.scene().system();
  const auto* term = sys.find_term<AttachmentTerm>();
  const auto u = gather(fixed.displacement());
  double worst = 0.0, moved = 0.0;
  for (const auto& p : term->pairs()) {
    const auto& t = term->surface().triangles[p.triangle];
    for (int c = 0; c < 3; ++c) {
      double q = 0.0;
      for (int j = 0; j < 3; ++j) q += p.beta[j] * u[3 * term->surface().gid[t[j]] + c];
      worst = std::max(worst, std::fabs(u[3 * term->surface().gid[p.vertex] + c] - q));
      moved = std::max(moved, std::fabs(q));
    }
  }
  EXPECT_GT(moved, 1e-3);
  EXPECT_LT(worst, 1e-10);
  // Sliding: the upper block slid rigidly (its bottom moved by the pull).
  const auto us = gather(sliding.displacement());
  const auto* ts = sliding.scene().system().find_term<AttachmentTerm>();
  for (const auto& p : ts->pairs()) {
    EXPECT_NEAR(us[3 * ts->surface().gid[p.vertex]], 0.1, 1e-9);
    EXPECT_NEAR(us[3 * ts->surface().gid[p.vertex] + 1], 0.05, 1e-9);
  }
}

// Self contact on: the attached interface touches at rest, yet contact pairs none of its nodes (the
// attachment holds them), and the sliding run gives the same state as without contact.
TEST(Attachments, SelfContactLeavesAnAttachedInterfaceAlone) {
  const std::string contact = R"x(<ParameterList name="Contact"><Parameter name="Self contact" type="bool" value="true"/><Parameter name="Self contact model" type="string" value="springs"/></ParameterList>)x";
  Simulation with(config(stacked("sliding", "{0.1, 0.05, 0}", contact, 2), results("attachment_contact")), RunOptions{true, ""});
  ASSERT_EQ(with.run(), 0);
  Simulation without(config(stacked("sliding", "{0.1, 0.05, 0}", "", 2), results("attachment_no_contact")), RunOptions{true, ""});
  ASSERT_EQ(without.run(), 0);
  const auto* c = with.scene().system().find_term<ContactTerm>();
  ASSERT_NE(c, nullptr);
  EXPECT_EQ(c->global_pairs(), 0);
  EXPECT_LT(rel_diff(gather(with.displacement()), gather(without.displacement())), 1e-9);
}

// Two blocks 0.1 apart (meshes/two_blocks.msh), the upper one free and held by a fixed attachment
// across the gap, the lower one's bottom turned by 40 degrees about x: the upper block turns with it
// rigidly (its offset across the gap turns with the target's frame), to 1e-8 of the motion.
TEST(Attachments, AFixedAttachmentAcrossAGapTurnsItsOffsetWithTheTarget) {
  const double angle = 0.698132;  // 40 degrees, as the XML spells it
  const std::string xml = file_scene_head("turned_blocks", meshes + "two_blocks.msh") + R"x(
  <ParameterList name="Attachments">
    <ParameterList name="across">
      <Parameter name="Region" type="string" value="group upper"/>
      <Parameter name="Target" type="string" value="group lower"/>
      <Parameter name="Distance" type="double" value="0.15"/>
      <Parameter name="Tolerance" type="double" value="1.0e-11"/>
      <Parameter name="Maximum rounds" type="int" value="30"/>
    </ParameterList>
  </ParameterList>
  <ParameterList name="Loading">
    <Parameter name="Steps" type="int" value="4"/>
    <ParameterList name="Boundary conditions">
      <ParameterList name="bottom">
        <Parameter name="Region" type="string" value="group bottom"/>
        <Parameter name="Motion" type="string" value="rotate"/>
        <Parameter name="Axis" type="Array(double)" value="{1, 0, 0}"/>
        <Parameter name="Center" type="Array(double)" value="{0.5, 0.5, 0}"/>
        <Parameter name="Angle" type="double" value=")x" + std::to_string(angle) + R"x("/>
      </ParameterList>
    </ParameterList>
  </ParameterList>
  <ParameterList name="Solver">
    <Parameter name="Absolute tolerance" type="double" value="1.0e-10"/>
  </ParameterList>
  )x" + logs_only_output() + R"x(
</ParameterList>)x";
  Simulation sim(config(xml, results("attachment_turned")), RunOptions{true, ""});
  ASSERT_EQ(sim.run(), 0);
  const System& sys = sim.scene().system();
  const auto* term = sys.find_term<AttachmentTerm>();
  ASSERT_NE(term, nullptr);
  EXPECT_EQ(term->pairs().size(), 25u);  // the upper block's bottom face, 5 x 5 nodes, 0.1 above the lower's top
  const auto u = gather(sim.displacement());
  auto X = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), sys.mesh().X);
  // The rigid motion of every node: x = c + R (X - c), R about x through c = (0.5, 0.5, 0).
  const double c = std::cos(angle), s = std::sin(angle);
  double mine = 0.0, worst = 0.0;
  for (std::size_t n = 0; n < sys.mesh().n_owned_nodes; ++n) {
    const double y = X(n, 1) - 0.5, z = X(n, 2);
    const double rigid[3] = {0.0, c * y - s * z - y, s * y + c * z - z};
    const auto g = static_cast<std::size_t>(sys.mesh().node_gid[n]);
    for (int k = 0; k < 3; ++k) mine = std::max(mine, std::fabs(u[3 * g + k] - rigid[k]));
  }
  Teuchos::reduceAll(*world(), Teuchos::REDUCE_MAX, mine, Teuchos::outArg(worst));
  if (world()->getRank() == 0) std::printf("[ info ] turned 40 degrees: largest distance from the rigid motion %.2e\n", worst);
  EXPECT_LT(worst, 1e-8 * 2.1);  // 2.1: the reach of the upper block's top from the axis
}

// A run stopped after two of four steps and restarted from its checkpoint continues with the
// attachment's pairs and tractions as they were, and ends in the uninterrupted run's state with its
// tractions.
TEST(Attachments, ARestartContinuesWithTheTractions) {
  auto make = [&](const std::string& out) {
    SceneConfig c = config(stacked("fixed", "{0.1, 0.05, -0.05}"), out);
    c.params.output.checkpoint_every = 1;
    return c;
  };
  const std::string whole_dir = results("attachment_whole"), dir = results("attachment_stopped");
  Simulation whole(make(whole_dir), RunOptions{true, ""});
  ASSERT_EQ(whole.run(), 0);
  std::vector<AttachmentTerm::Pair> stopped;
  {
    setenv("SINEW_STOP_AFTER_STEP", "2", 1);  // as SIGTERM after step 2 of 4 (read by the constructor)
    Simulation first(make(dir), RunOptions{true, ""});
    unsetenv("SINEW_STOP_AFTER_STEP");
    EXPECT_EQ(first.run(), 128 + 15);
    stopped = first.scene().system().find_term<AttachmentTerm>()->pairs();
  }
  Simulation rest(make(dir), RunOptions{true, dir + "/checkpoint.h5"});
  // The restarted term holds the stopped one's pairs: targets, frozen offsets, tractions.
  const auto& loaded = rest.scene().system().find_term<AttachmentTerm>()->pairs();
  ASSERT_EQ(loaded.size(), stopped.size());
  double lambda = 0.0;
  for (std::size_t i = 0; i < loaded.size(); ++i) {
    EXPECT_EQ(loaded[i].triangle, stopped[i].triangle);
    for (int d = 0; d < 3; ++d) {
      EXPECT_EQ(loaded[i].lambda[d], stopped[i].lambda[d]);
      EXPECT_EQ(loaded[i].frozen[d], stopped[i].frozen[d]);
      EXPECT_EQ(loaded[i].beta[d], stopped[i].beta[d]);
      lambda = std::max(lambda, std::fabs(stopped[i].lambda[d]));
    }
  }
  EXPECT_GT(lambda, 1.0);
  ASSERT_EQ(rest.run(), 0);
  const double du = rel_diff(gather(whole.displacement()), gather(rest.displacement()));
  EXPECT_LT(du, 1e-9);
  const auto* a = whole.scene().system().find_term<AttachmentTerm>();
  const auto* b = rest.scene().system().find_term<AttachmentTerm>();
  double dl = 0.0, scale = 0.0;
  for (std::size_t i = 0; i < a->pairs().size(); ++i)
    for (int d = 0; d < 3; ++d) {
      dl = std::max(dl, std::fabs(a->pairs()[i].lambda[d] - b->pairs()[i].lambda[d]));
      scale = std::max(scale, std::fabs(a->pairs()[i].lambda[d]));
    }
  EXPECT_GT(scale, 1.0);
  EXPECT_LT(dl, 1e-6 * scale);
  if (world()->getRank() == 0) {
    // Step 3's residual at its first guess holds the attachment's forces there: one the tractions are
    // missing from (a restart that lost them) is off by the tractions times the areas (~4 here).
    const auto rw = csv_column(whole_dir + "/log.csv", "initial_residual"), rr = csv_column(dir + "/log.csv", "initial_residual");
    ASSERT_EQ(rw.size(), 4u);
    ASSERT_EQ(rr.size(), 4u);
    const double a3 = std::stod(rw[2]), b3 = std::stod(rr[2]);
    EXPECT_NEAR(a3, b3, 1e-3 * a3);
    std::printf("[ info ] restarted after step 2: displacement %.2e, tractions %.2e of %.2e from the uninterrupted run; step 3's "
                "first residual %.6e (uninterrupted %.6e)\n",
                du, dl, scale, b3, a3);
  }
}

namespace {

// A 3 x 3 x 4 box twisted by a bone: its bottom held by a root bone, its top turned 60 degrees about z
// by a child bone; the bones' attachment fixed or soft (with a stiffness per volume per length).
std::string twisted_box(const std::string& attachment) {
  return R"x(<ParameterList name="Sinew">
  <Parameter name="Scene" type="string" value="bone_twist"/>
  <ParameterList name="Mesh">
    <Parameter name="Type" type="string" value="box"/>
    <Parameter name="Elements" type="Array(int)" value="{3, 3, 4}"/>
    <Parameter name="Upper corner" type="Array(double)" value="{1.0, 1.0, 1.5}"/>
  </ParameterList>
  <ParameterList name="Material">
    <Parameter name="Model" type="string" value="stable-neohookean"/>
    <Parameter name="Young modulus" type="double" value="1000"/>
    <Parameter name="Poisson ratio" type="double" value="0.45"/>
  </ParameterList>
  <ParameterList name="Skeleton">
    )x" + attachment + R"x(
    <ParameterList name="Bones">
      <ParameterList name="root"><Parameter name="Region" type="string" value="face z-"/></ParameterList>
      <ParameterList name="top">
        <Parameter name="Parent" type="string" value="root"/>
        <Parameter name="Region" type="string" value="face z+"/>
        <Parameter name="Pivot" type="Array(double)" value="{0.5, 0.5, 1.5}"/>
        <ParameterList name="Keyframes"><ParameterList name="turned">
          <Parameter name="Time" type="double" value="1.0"/>
          <Parameter name="Axis" type="Array(double)" value="{0, 0, 1}"/>
          <Parameter name="Angle" type="double" value="1.0471975512"/>
        </ParameterList></ParameterList>
      </ParameterList>
    </ParameterList>
  </ParameterList>
  <ParameterList name="Loading"><Parameter name="Steps" type="int" value="3"/></ParameterList>
  <ParameterList name="Solver"><Parameter name="Absolute tolerance" type="double" value="1.0e-10"/></ParameterList>
  )x" + logs_only_output() + R"x(
</ParameterList>)x";
}

}  // namespace

// 'Bone attachment' auto (the default): soft bones where the barrier holds self contact (its collision test
// bounds free nodes only, and a prescribed bone node would carry the surface through a face), fixed bones
// otherwise; a 'Bone stiffness' for bones that end up fixed is an input error, and an explicit choice wins.
TEST(Attachments, BonesAreSoftByDefaultWhereTheBarrierHoldsSelfContactAndFixedOtherwise) {
  using A = SkeletonParameters::Attachment;
  auto with = [](const std::string& skeleton, const std::string& contact) {
    std::string xml = twisted_box(skeleton);
    if (!contact.empty())
      xml.insert(xml.find("<ParameterList name=\"Loading\">"), "<ParameterList name=\"Contact\">" + contact + "</ParameterList>\n  ");
    return config(xml, results("bones_auto"));
  };
  const std::string self = R"x(<Parameter name="Self contact" type="bool" value="true"/>)x";
  const std::string springs = R"x(<Parameter name="Self contact model" type="string" value="springs"/>)x";
  EXPECT_EQ(with("", "").params.skeleton.attachment, A::Fixed);
  const SceneConfig barrier = with("", self);
  EXPECT_EQ(barrier.params.terms.of<Contact>().model, ContactParameters::Model::Barrier);  // the default model
  EXPECT_EQ(barrier.params.skeleton.attachment, A::Soft);
  EXPECT_EQ(with("", self + springs).params.skeleton.attachment, A::Fixed);
  EXPECT_EQ(with(R"x(<Parameter name="Bone attachment" type="string" value="fixed"/>)x", self).params.skeleton.attachment, A::Fixed);
  EXPECT_EQ(with(R"x(<Parameter name="Bone attachment" type="string" value="soft"/>)x", "").params.skeleton.attachment, A::Soft);
  const std::string stiffness = R"x(<Parameter name="Bone stiffness" type="double" value="1.0e6"/>)x";
  EXPECT_EQ(with(stiffness, self).params.skeleton.attachment, A::Soft);
  try {
    with(stiffness, self + springs);
    ADD_FAILURE() << "a bone stiffness for fixed bones was accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("'Bone stiffness' applies to soft bones"), std::string::npos) << e.what();
  }
  // The run holds the box by the bone springs' term, with nothing prescribed.
  Simulation run(with("", self), RunOptions{true, ""});
  ASSERT_EQ(run.run(), 0);
  EXPECT_NE(run.scene().system().find_term<BoneSpringTerm>(), nullptr);
  EXPECT_TRUE(run.scene().system().fixed_owned_dofs().empty());
}

// Soft bones: springs to the bones' motion (an energy term, PSD: k_n I per node) instead of prescribed
// nodes. The twisted box they hold differs from the fixed bones' by an offset that falls as 1/stiffness
// (ten times stiffer: ten times closer, to 20%); the term's gradient and Hessian match finite differences.
TEST(Attachments, SoftBonesHoldTheirNodesBySpringsThatTendToFixedBonesAsTheyStiffen) {
  Simulation fixed(config(twisted_box(""), results("bones_fixed")), RunOptions{true, ""});
  ASSERT_EQ(fixed.run(), 0);
  const auto uf = gather(fixed.displacement());
  std::vector<double> diffs;
  for (const char* kappa : {"1.0e6", "1.0e7"}) {
    Simulation soft(config(twisted_box(std::string(R"x(<Parameter name="Bone attachment" type="string" value="soft"/>
    <Parameter name="Bone stiffness" type="double" value=")x") + kappa + R"x("/>)x"),
                           results("bones_soft_") + kappa),
                    RunOptions{true, ""});
    ASSERT_EQ(soft.run(), 0);
    const System& sys = soft.scene().system();
    EXPECT_TRUE(sys.fixed_owned_dofs().empty());  // nothing prescribed: the springs hold the box
    const auto* term = sys.find_term<BoneSpringTerm>();
    ASSERT_NE(term, nullptr);
    const double offset = term->largest_offset(soft.displacement());
    diffs.push_back(max_diff(uf, gather(soft.displacement())));
    if (world()->getRank() == 0)
      std::printf("[ info ] bone stiffness %s: largest offset of a held node %.3e, largest difference from fixed bones %.3e\n", kappa,
                  offset, diffs.back());
    EXPECT_GT(offset, 0.0);
    EXPECT_LT(diffs.back(), 0.05);  // the twist moved the top corners by 0.35
    if (diffs.size() == 2) {
      // Gradient and Hessian of the term at a random state, against central differences.
      auto u = sys.create_vector(), d = sys.create_vector();
      set_displacement(sys, *u, [](const std::array<double, 3>&, int i, long long gid) { return 0.05 * hash_unit(gid, i); });
      set_displacement(sys, *d, [](const std::array<double, 3>&, int i, long long gid) { return hash_unit(gid, i, 7); });
      const auto c = check_term_derivatives(sys, *term, *u, *d);
      EXPECT_NEAR(c.f_dot_d, c.dE, 1e-7 * std::fabs(c.dE));
      EXPECT_LT(c.err, 1e-7 * c.scale);
      EXPECT_GE(c.min_eigenvalue, -1e-12 * c.max_entry);
    }
  }
  EXPECT_NEAR(diffs[1] / diffs[0], 0.1, 0.02);
}

namespace {

// The stacked blocks with no attachment, self contact on, the upper block's top moved by `press`.
std::string touching(const std::string& press) {
  std::string xml = stacked("fixed", press, R"x(<ParameterList name="Contact"><Parameter name="Self contact" type="bool" value="true"/><Parameter name="Self contact model" type="string" value="springs"/></ParameterList>)x", 2);
  const auto a = xml.find("<ParameterList name=\"Attachments\">");
  const auto b = xml.find("</ParameterList>\n  </ParameterList>", a) + std::string("</ParameterList>\n  </ParameterList>").size();
  return xml.erase(a, b - a);
}

}  // namespace

// Two bodies meshed touching (no attachment): self contact finds their interface closer than its
// thickness at rest and notes it, and does not push the bodies apart there (held in place, nothing
// moves), yet resists their pressing into each other (the press reaches the lower block; the deepest
// penetration stays within the rounds' tolerance, a tenth of the thickness, as anywhere else).
TEST(Attachments, SelfContactDoesNotPushApartBodiesThatTouchAtRestYetResistsPressing) {
  Simulation held(config(touching("{0, 0, 0}"), results("touching_held")), RunOptions{true, ""});
  ASSERT_EQ(held.run(), 0);
  const auto* c = held.scene().system().find_term<ContactTerm>();
  ASSERT_NE(c, nullptr);
  const auto notes = c->notes();
  ASSERT_EQ(notes.size(), 1u);
  EXPECT_NE(notes[0].find("25 surface points"), std::string::npos) << notes[0];  // 4 x 4 above, 3 x 3 below
  EXPECT_LT(max_abs(gather(held.displacement())), 1e-12);
  Simulation pressed(config(touching("{0, 0, -0.1}"), results("touching_pressed")), RunOptions{true, ""});
  ASSERT_EQ(pressed.run(), 0);
  // The press reaches the lower block through contact (its top's middle goes down), and the springs'
  // deepest penetration stays small.
  const System& sys = pressed.scene().system();
  const auto u = gather(pressed.displacement());
  const auto* ct = sys.find_term<ContactTerm>();
  double sink = 0.0;
  for (std::size_t v = 0; v < ct->surface().vertices(); ++v) {
    const auto& P = ct->surface().X[v];
    if (std::fabs(P[0] - 0.5) + std::fabs(P[1] - 0.5) + std::fabs(P[2] - 0.5) < 1e-12)  // the lower top's middle
      sink = -u[3 * static_cast<std::size_t>(ct->surface().gid[v]) + 2];
  }
  const double penetration = sys.evaluate(pressed.displacement(), nullptr, nullptr).penetration;
  if (world()->getRank() == 0)
    std::printf("[ info ] touching at rest: %s; held: nothing moves; pressed by 0.1: the lower top's middle sinks %.4f, "
                "deepest penetration %.2e\n",
                notes[0].c_str(), sink, penetration);
  EXPECT_GT(sink, 0.02);
  EXPECT_LT(penetration, 0.11 * ct->settings().thickness);  // the rounds' tolerance, a tenth of it, as elsewhere
  EXPECT_GT(pressed.scene().system().find_term<ContactTerm>()->global_pairs(), 0);
}
