// Contact (algebra/terms/contact.hpp): the penalty energy's gradient and Hessian against finite
// differences (sharp and smooth onset), the smooth onset's law, node relaxation away from the springs,
// its Hessian PSD (LAPACK), colliders' signed distances against closed forms, two blocks
// pressed together in equilibrium, a half-space and a mesh collider pushing back alike, a slab folded
// onto itself by bones that does not cross itself (and does without contact), 1 thread = 2 threads =
// 2 ranks.
#include "scene_test_utils.hpp"
#include "system_test_utils.hpp"

#include <sinew/algebra/terms/contact.hpp>
#include <sinew/algebra/terms/contact_barrier.hpp>
#include <sinew/core/collective.hpp>
#include <sinew/core/parameters.hpp>
#include <sinew/solver/nonlinear_solver.hpp>
#include <sinew/driver/run.hpp>
#include <sinew/scenes/scene.hpp>

#include <Tpetra_Core.hpp>
#include <Tpetra_CrsMatrix.hpp>
#include <Tpetra_Vector.hpp>
#include <gtest/gtest.h>

#include <csignal>
#include <filesystem>
#include <fstream>
#include <map>

using namespace sinew;
using namespace sinew::test;
using geom::Vec;
using geom::operator-;
using geom::operator+;
using geom::operator*;

namespace {

auto world() { return Tpetra::getDefaultComm(); }
std::string tag() { return "_np" + std::to_string(world()->getSize()) + "_t" + std::to_string(Kokkos::DefaultExecutionSpace::concurrency()); }
const std::string meshes = std::string(SINEW_SOURCE_DIR) + "/tests/meshes/";

MaterialSpec snh(double E = 1000.0, double nu = 0.45) {
  MaterialSpec s = material_defaults(MaterialModel::StableNeoHookean, 0.0, 0.0);
  s.mu_L = E / (2 * (1 + nu));
  s.lambda_L = E * nu / ((1 + nu) * (1 - 2 * nu));
  s.projection = Projection::None;
  return s;
}

Mesh two_blocks() {
  MeshParameters p = default_section<MeshParameters>();
  p.type = MeshType::File;
  p.file = meshes + "two_blocks.msh";
  return build_scene_mesh(p, *world());
}

// The term's own gradient, unconstrained.
std::vector<double> term_force(const System& sys, const EnergyTerm& term, const Vector& u) {
  auto f = sys.create_vector();
  sys.gradient(u, *f, &term);
  return gather(*f);
}

// A contact term's forces sum to zero (each spring's weights, each barrier pair's distance is invariant
// under translation): contact pushes bodies apart, not the body as a whole.
void expect_no_net_force(const System& sys, const EnergyTerm& term, const Vector& u) {
  const auto fc = term_force(sys, term, u);
  double sum[3] = {0, 0, 0}, scale = 0.0;
  for (std::size_t k = 0; k < fc.size(); ++k) {
    sum[k % 3] += fc[k];
    scale = std::max(scale, std::fabs(fc[k]));
  }
  EXPECT_GT(scale, 0.0);
  for (double s : sum) EXPECT_LT(std::fabs(s), 1e-12 * fc.size() * scale);
}

// The springs the two-block tests use (k = 2e4, thickness 0.02) with the given margin, and the term made
// with them (no colliders) and added to the system.
ContactSettings block_springs(double margin) {
  ContactSettings cs;
  cs.stiffness = 2e4;
  cs.thickness = 0.02;
  cs.margin = margin;
  return cs;
}
std::shared_ptr<ContactTerm> add_springs(System& sys, const ContactSettings& cs) {
  auto contact = std::make_shared<ContactTerm>(sys, cs, std::vector<ColliderShape>{});
  sys.add_term(contact);
  return contact;
}

// The upper block pushed down by `push` (into the lower one when push > 0.1) with a small wiggle.
void press(const System& sys, Vector& u, double push) {
  set_displacement(sys, u, [&](const std::array<double, 3>& X, int c, long long gid) {
    return (c == 2 && X[2] > 1.05 ? -push : 0.0) + 0.004 * hash_unit(gid, c);
  });
}

// The two blocks turned into ridges that cross like an X, component c of the displacement of reference
// point X. Lower block (4 x 4 x 4 cells of 0.25): turned 45 degrees about y through its centre and moved
// to put its ridge at x = 0.625, z = 0.5 + r. Upper block: turned 45 degrees about x through its centre,
// its ridge at y = 0.625, 0.1 above the lower one. Each ridge crosses the other half-way between two of
// its nodes.
double crossed_ridges(const std::array<double, 3>& X, int c) {
  const double pi = std::acos(-1.0), r = 0.5 * std::sqrt(2.0);
  const bool upper = X[2] > 1.05;
  const double zc = upper ? 1.6 : 0.5, ca = std::cos(pi / 4), sa = std::sin(pi / 4);
  std::array<double, 3> Y = X;
  if (!upper) {  // about y: (x, z) -> the ridge from the edge x = 1, z = 1
    const double dx = X[0] - 0.5, dz = X[2] - zc;
    Y[0] = 0.5 + ca * dx - sa * dz + 0.125;
    Y[2] = zc + sa * dx + ca * dz;
  } else {  // about x: (y, z) -> the ridge from the edge y = 0, z = 1.1
    const double dy = X[1] - 0.5, dz = X[2] - zc;
    Y[1] = 0.5 + ca * dy - sa * dz + 0.125;
    Y[2] = zc + sa * dy + ca * dz;
    Y[2] += (0.5 + r + 0.1) - (1.6 - r);
  }
  return Y[c] - X[c];
}

}  // namespace

// E, dE/du and d2E/du2 of the whole system with springs in place (elastic exact, so that finite
// differences of the force see the same Hessian) along random directions, with samples both inside
// the other block and near it; the pairs cross ranks on 2 ranks.
TEST(Contact, SpringsHaveTheGradientAndHessianOfTheirEnergy) {
  // With a sharp onset and with a smooth one as wide as the thickness (both sides of it in use: the
  // samples lie from the margin down to deep inside).
  for (double onset : {0.0, 0.02}) {
  SCOPED_TRACE("onset " + std::to_string(onset));
  System sys(world(), two_blocks(), snh());
  ContactSettings cs = block_springs(0.2);
  cs.onset = onset;
  auto contact = add_springs(sys, cs);
  auto u = sys.create_vector();
  press(sys, *u, 0.13);
  const ContactDetection d = contact->detect(*u);
  sys.update_pattern();
  EXPECT_GT(d.inside, 10);
  EXPECT_GT(contact->global_pairs(), 40);
  auto f = sys.create_vector();
  auto K = sys.create_matrix();
  const auto t = sys.evaluate(*u, f.get(), K.get(), Backend::Default, Projection::None);
  EXPECT_GT(t.share("contact"), 0.0);
  EXPECT_GT(t.contacts, 10);
  EXPECT_GT(t.penetration, 0.0);
  auto dir = sys.create_vector(), up = sys.create_vector(), um = sys.create_vector(), fp = sys.create_vector(),
       fm = sys.create_vector(), Kd = sys.create_vector();
  for (int trial = 0; trial < 3; ++trial) {
    set_displacement(sys, *dir, [&](const std::array<double, 3>&, int c, long long gid) { return hash_unit(gid, c, 7 + trial); });
    const double eps = 1e-6;
    up->update(1.0, *u, eps, *dir, 0.0);
    um->update(1.0, *u, -eps, *dir, 0.0);
    const double slope = (sys.evaluate(*up, fp.get(), nullptr).energy - sys.evaluate(*um, fm.get(), nullptr).energy) / (2 * eps);
    EXPECT_NEAR(slope, f->dot(*dir), 1e-6 * std::max(1.0, std::fabs(slope)));
    K->apply(*dir, *Kd);
    fp->update(-1.0, *fm, 1.0);
    fp->scale(1.0 / (2 * eps));
    fp->update(-1.0, *Kd, 1.0);
    EXPECT_LT(fp->normInf(), 1e-5 * Kd->normInf()) << "trial " << trial;
  }
  // The springs' own Hessian is positive semi-definite, and so is the whole projected one.
  const auto H = term_hessian(sys, *contact, *u);
  EXPECT_GT(max_abs(H), 0.0);
  EXPECT_GT(min_eigenvalue(H), -1e-10 * max_abs(H));
  // Each spring's forces sum to zero (beta sums to 1): contact pushes the blocks apart, not the body.
  expect_no_net_force(sys, *contact, *u);
  }
}

// The smooth onset's law (contact_spring_law): zero off contact, value, slope and curvature continuous
// at 0 and at the onset's end (C2), its derivatives those of its value (central differences), and
// the plain k/2 s^2 from eps = 0 and beyond the onset up to a constant shift of the slope.
TEST(Contact, ASmoothOnsetIsTwiceDifferentiableAndBecomesThePlainPenalty) {
  const double eps = 0.3;
  auto law = [&](double s) { return contact_spring_law(s, eps); };
  for (double s : {-1.0, -1e-9, 0.0}) {
    EXPECT_EQ(law(s).e, 0.0);
    EXPECT_EQ(law(s).d1, 0.0);
    EXPECT_EQ(law(s).d2, 0.0);
  }
  for (double at : {0.0, eps}) {  // the joints: both sides agree to the step's order
    const double h = 1e-9;
    const auto a = law(at - h), b = law(at + h);
    EXPECT_NEAR(a.e, b.e, 1e-9) << at;  // the slope times 2h at most
    EXPECT_NEAR(a.d1, b.d1, 1e-8) << at;
    EXPECT_NEAR(a.d2, b.d2, 1e-7) << at;
  }
  for (double s : {0.01, 0.1, 0.29, 0.31, 0.7, 3.0}) {
    const double h = 1e-6;
    EXPECT_NEAR((law(s + h).e - law(s - h).e) / (2 * h), law(s).d1, 1e-8) << s;
    EXPECT_NEAR((law(s + h).d1 - law(s - h).d1) / (2 * h), law(s).d2, 1e-8) << s;
    EXPECT_GE(law(s).d2, 0.0);
    EXPECT_LE(law(s).d2, 1.0);
    const auto sharp = contact_spring_law(s, 0.0);
    EXPECT_DOUBLE_EQ(sharp.e, 0.5 * s * s);
    EXPECT_DOUBLE_EQ(sharp.d1, s);
    EXPECT_DOUBLE_EQ(sharp.d2, 1.0);
    if (s > eps) EXPECT_NEAR(law(s).d1, s - 0.5 * eps, 1e-15) << s;
    else EXPECT_NEAR(law(s).d2, s / eps, 1e-15) << s;
  }
}

// Node relaxation with contact on moves no node of a spring (its energy is not linear there) and
// relaxes others: the pressed blocks' springs keep their nodes exactly, some other node moves, the
// total energy falls. Without the contact term the same call moves spring nodes too (the test can fail).
TEST(Contact, NodeRelaxationLeavesTheSpringsNodesWhereTheyAre) {
  for (bool with_contact : {true, false}) {
    SCOPED_TRACE(with_contact ? "contact" : "no contact");
    System sys(world(), two_blocks(), snh());
    ContactSettings cs = block_springs(0.2);
    cs.onset = 0.02;
    auto contact = std::make_shared<ContactTerm>(sys, cs, std::vector<ColliderShape>{});
    if (with_contact) sys.add_term(contact);
    auto u = sys.create_vector();
    press(sys, *u, 0.13);
    contact->detect(*u);
    if (with_contact) sys.update_pattern();
    // Every rank's spring nodes (global ids), gathered.
    std::vector<long long> mine;
    for (const auto& p : contact->pairs())
      for (auto g : p.node) mine.push_back(static_cast<long long>(g));
    const std::vector<long long> spring_nodes = allgatherv(raw_comm(*world()), mine);
    ASSERT_FALSE(spring_nodes.empty());
    auto f = sys.create_vector();
    const double E0 = sys.evaluate(*u, f.get(), nullptr).energy;
    const auto before = gather(*u);
    NodeRelaxationSettings settings;
    const NodeRelaxationTotals t = sys.relax_nodes(*u, *f, 1e-4, 1, settings);
    EXPECT_GT(t.nodes, 0);
    const auto after = gather(*u);
    int spring_moved = 0, other_moved = 0;
    std::vector<char> is_spring(before.size() / 3, 0);
    for (long long g : spring_nodes) is_spring[static_cast<std::size_t>(g)] = 1;
    for (std::size_t n = 0; n < is_spring.size(); ++n) {
      const bool moved = after[3 * n] != before[3 * n] || after[3 * n + 1] != before[3 * n + 1] || after[3 * n + 2] != before[3 * n + 2];
      (is_spring[n] ? spring_moved : other_moved) += moved;
    }
    EXPECT_GT(other_moved, 0);
    if (with_contact) {
      EXPECT_EQ(spring_moved, 0);
      EXPECT_LT(sys.evaluate(*u, nullptr, nullptr).energy, E0);
    } else {
      EXPECT_GT(spring_moved, 0);
    }
  }
}

// Every spring on every rank, by its four nodes (global ids), with its traction.
std::map<std::array<long long, 4>, double> all_springs(const ContactTerm& contact) {
  std::vector<double> mine;
  for (const auto& p : contact.pairs())
    mine.insert(mine.end(), {double(p.node[0]), double(p.node[1]), double(p.node[2]), double(p.node[3]), p.lambda});
  const std::vector<double> all = allgatherv(raw_comm(*world()), mine);
  std::map<std::array<long long, 4>, double> out;
  for (std::size_t k = 0; k + 4 < all.size(); k += 5)
    out[{(long long)all[k], (long long)all[k + 1], (long long)all[k + 2], (long long)all[k + 3]}] = all[k + 4];
  return out;
}

// A regroup (inside a solve that has not converged) pairs the samples that went in since the last
// detection, keeps every existing spring with the traction it had (Uzawa's update waits for a
// converged state; a detection between solves would raise them at the same state), and reports
// nothing when nothing changed.
TEST(Contact, ARegroupAddsTheSamplesThatWentInAndKeepsTheTractions) {
  System sys(world(), two_blocks(), snh());
  auto contact = add_springs(sys, block_springs(0.03));
  auto u = sys.create_vector();
  // The upper block tilted down towards x = 1 by `push` there and by push - 0.1 at x = 0 (the blocks
  // are 0.1 apart): the side at x = 1 goes in first.
  auto tilt = [&](double push) {
    set_displacement(sys, *u, [&](const std::array<double, 3>& X, int c, long long gid) {
      return (c == 2 && X[2] > 1.05 ? -(push - 0.1 * (1.0 - X[0])) : 0.0) + 0.004 * hash_unit(gid, c);
    });
  };
  tilt(0.12);
  contact->detect(*u);
  tilt(0.14);
  contact->detect(*u, true);  // between solves: tractions raised for samples behind their targets
  sys.update_pattern();
  const auto before = all_springs(*contact);
  int traction = 0;
  for (const auto& [nodes, lambda] : before) traction += lambda > 0.0;
  ASSERT_GT(traction, 0);
  tilt(0.25);  // further in: the whole face inside, the first samples deeper
  const System::Round r = sys.regroup(*u);
  EXPECT_TRUE(r.again);
  ASSERT_EQ(r.lines.size(), 1u);
  EXPECT_NE(r.lines[0].find("contact regroup"), std::string::npos);
  const auto after = all_springs(*contact);
  EXPECT_GT(after.size(), before.size());
  int kept = 0;
  for (const auto& [nodes, lambda] : before) {
    auto it = after.find(nodes);
    if (it == after.end()) continue;
    ++kept;
    EXPECT_EQ(it->second, lambda);
  }
  EXPECT_GT(kept, 0);
  // At the same state again: nothing new, no line, and the evaluation has every spring's columns.
  const System::Round again = sys.regroup(*u);
  EXPECT_FALSE(again.again);
  EXPECT_TRUE(again.lines.empty());
  EXPECT_TRUE(std::isfinite(sys.evaluate(*u, nullptr, nullptr).energy));
  // A detection between solves at this state would have raised them: the test above can fail.
  contact->detect(*u, true);
  int raised = 0;
  for (const auto& [nodes, lambda] : all_springs(*contact)) {
    auto it = before.find(nodes);
    raised += it != before.end() && lambda > it->second;
  }
  EXPECT_GT(raised, 0);
}

// 'Keep springs across steps': a step's first round starts from the springs the last step converged
// with (all kept, reported as such); without it, or after a failed attempt, it pairs afresh.
TEST(Contact, AStepKeepsItsLastStatesSpringsOnlyWhenAskedAndNotAfterAFailure) {
  for (bool keep : {true, false}) {
    SCOPED_TRACE(keep ? "keep" : "fresh");
    System sys(world(), two_blocks(), snh());
    ContactSettings cs = block_springs(0.05);
    cs.keep = keep;
    auto contact = add_springs(sys, cs);
    auto u = sys.create_vector();
    press(sys, *u, 0.13);
    sys.round(*u, 0);
    sys.end_step(*u);
    const long long pairs = contact->global_pairs();
    ASSERT_GT(pairs, 10);
    const std::string kept = "(" + std::to_string(pairs) + " kept";
    const System::Round next = sys.round(*u, 0);  // the next step, from the same state
    ASSERT_EQ(next.lines.size(), 1u);
    EXPECT_EQ(next.lines[0].find(kept) != std::string::npos, keep) << next.lines[0];
    EXPECT_EQ(next.lines[0].find("(0 kept") != std::string::npos, !keep) << next.lines[0];
    sys.abandon_step();  // that attempt failed: the cut one pairs afresh
    const System::Round cut = sys.round(*u, 0);
    EXPECT_NE(cut.lines[0].find("(0 kept"), std::string::npos) << cut.lines[0];
  }
}

// A surface point can lie inside an element that has folded over itself (tets of it turned inside
// out, its sound tets bulging past the surface) without going through any face; the detection tells it
// apart from one pressed through a face, which is penetration. Here the top corner of a cell of the
// lower block (at (0.75, 0.5, 1)) is pulled back over the cell's other top corner and a little up:
// two of its six tets turn inside out and two bulge above the top face. The upper block is moved so
// that a corner of its bottom sits in that bulge, in no sound element: one point inside, folded, no
// penetration. The blocks pressed into each other (the upper's bottom through the lower's top face):
// penetration, none folded. And a point dragged deep into its own body (the lower block's top centre
// pushed down 2.5 cells, its own cells turned inside out): it lies in a sound cell of the third layer,
// outside its ring, yet went through no face, since its own triangles follow it down a funnel (the
// surface does not enclose it: winding number near 0.96); folded, no penetration. (The test before the
// winding number, a point in a cell with no tet turned inside out, called that penetration: BCN's
// frame 39 with inertia, 10.6 mm.) Springs and barrier alike (the report does not depend on the model).
TEST(Contact, APointInsideElementsWhereTheMeshFoldsIsNotPenetration) {
  const double h = 0.25;  // two_blocks' cells
  const Vec cell{0.5, 0.25, 0.75}, corner = cell + Vec{h, h, h}, pulled = cell + Vec{-0.5 * h, h, 1.2 * h};
  const Vec shift = (cell + Vec{-0.45 * h, 0.95 * h, 1.15 * h}) - Vec{0.0, 0.5, 1.1};  // the upper's (0, 0.5, 1.1) into the bulge
  for (bool barrier : {false, true}) {
    SCOPED_TRACE(barrier ? "barrier" : "springs");
    System sys(world(), two_blocks(), snh());
    ContactSettings cs = block_springs(0.2);
    cs.barrier = barrier;
    auto contact = add_springs(sys, cs);
    auto u = sys.create_vector();
    set_displacement(sys, *u, [&](const std::array<double, 3>& X, int c, long long) {
      if (std::fabs(X[0] - corner[0]) + std::fabs(X[1] - corner[1]) + std::fabs(X[2] - corner[2]) < 1e-9) return (pulled - corner)[c];
      return X[2] > 1.05 ? shift[c] : 0.0;
    });
    auto one_point_in_a_fold = [](const ContactDetection& d, double deeper_than) {
      EXPECT_EQ(d.inside, 1);
      EXPECT_EQ(d.folded, 1);
      EXPECT_GT(d.deepest, deeper_than);
      EXPECT_EQ(d.crossed, 0);
      EXPECT_EQ(d.crossed_deepest, 0.0);
    };
    one_point_in_a_fold(contact->detect(*u), 0.0);
    press(sys, *u, 0.13);
    const ContactDetection pressed = contact->detect(*u);
    EXPECT_GT(pressed.inside, 10);
    EXPECT_EQ(pressed.folded, 0);
    EXPECT_EQ(pressed.crossed, pressed.inside);
    EXPECT_GT(pressed.crossed_deepest, 0.02);
    EXPECT_EQ(pressed.crossed_deepest, pressed.deepest);
    const Vec top{0.5, 0.5, 1.0}, dragged{0.52, 0.53, 0.375};
    set_displacement(sys, *u, [&](const std::array<double, 3>& X, int c, long long) {
      return std::fabs(X[0] - top[0]) + std::fabs(X[1] - top[1]) + std::fabs(X[2] - top[2]) < 1e-9 ? (dragged - top)[c] : 0.0;
    });
    one_point_in_a_fold(contact->detect(*u), 0.1);
  }
}

// The winding number that tells a point through a face from one in a fold: the solid angles of a closed
// surface's triangles sum to 4 pi from inside, 0 from outside, and a vertex (its own triangles subtend
// nothing) sees the share of the sphere that the body fills around it: 1/8 at a cube's corner, 1/2 at a
// point of a face. Passing through a face adds one.
TEST(Contact, TheWindingNumberIsOneInsideZeroOutsideAndTheBodysShareAtAVertex) {
  // The unit cube [0, 1]^3, 12 triangles with outward normals, and a vertex at the centre of its top.
  std::vector<Vec> x;
  for (int k = 0; k < 8; ++k) x.push_back({double(k & 1), double((k >> 1) & 1), double((k >> 2) & 1)});
  const std::vector<std::array<int, 3>> T = {{0, 2, 1}, {1, 2, 3}, {0, 1, 4}, {1, 5, 4}, {0, 4, 2}, {2, 4, 6},
                                             {1, 3, 5}, {3, 7, 5}, {2, 6, 3}, {3, 6, 7}};
  std::vector<std::array<int, 3>> tris = T;
  x.push_back({0.5, 0.5, 1.0});  // 8: the top face (4, 5, 6, 7) as four triangles around it
  for (const auto& e : std::vector<std::array<int, 2>>{{4, 5}, {5, 7}, {7, 6}, {6, 4}}) tris.push_back({e[0], e[1], 8});
  auto winding = [&](const Vec& p, int skip) {
    double w = 0.0;
    for (const auto& t : tris)
      if (t[0] != skip && t[1] != skip && t[2] != skip) w += geom::solid_angle(p, x[t[0]], x[t[1]], x[t[2]]);
    return w / (4.0 * M_PI);
  };
  EXPECT_NEAR(winding({0.3, 0.6, 0.2}, -1), 1.0, 1e-12);
  EXPECT_NEAR(winding({1.3, 0.6, 0.2}, -1), 0.0, 1e-12);
  EXPECT_NEAR(winding({0.5, 0.5, -1e-6}, -1), 0.0, 1e-5);  // just below the bottom face, and just above
  EXPECT_NEAR(winding({0.5, 0.5, 1e-6}, -1), 1.0, 1e-5);
  EXPECT_NEAR(winding(x[0], 0), 0.125, 1e-12);  // a corner
  EXPECT_NEAR(winding(x[8], 8), 0.5, 1e-12);    // a point of a flat face
  EXPECT_EQ(geom::solid_angle(x[0], x[0], x[1], x[2]), 0.0);
}

// A segment crosses a triangle only through its interior, from one side of its plane to the other:
// an end point on the plane, a line through an edge or a corner, a segment in the plane or beside the
// triangle is no crossing; the triangle's orientation does not matter.
TEST(Contact, ASegmentCrossesATriangleOnlyThroughItsInterior) {
  const Vec a{0, 0, 0}, b{1, 0, 0}, c{0, 1, 0};
  EXPECT_TRUE(geom::segment_crosses_triangle({0.2, 0.2, -1}, {0.2, 0.3, 1}, a, b, c));
  EXPECT_TRUE(geom::segment_crosses_triangle({0.2, 0.2, 1}, {0.2, 0.3, -1}, a, c, b));
  EXPECT_FALSE(geom::segment_crosses_triangle({0.6, 0.6, -1}, {0.6, 0.6, 1}, a, b, c));   // beside it
  EXPECT_FALSE(geom::segment_crosses_triangle({0.2, 0.2, 0.1}, {0.2, 0.3, 1}, a, b, c));  // above it
  EXPECT_FALSE(geom::segment_crosses_triangle({0.2, 0.2, 0}, {0.2, 0.3, 1}, a, b, c));    // from its face
  EXPECT_FALSE(geom::segment_crosses_triangle({0.5, 0, -1}, {0.5, 0, 1}, a, b, c));       // through an edge
  EXPECT_FALSE(geom::segment_crosses_triangle({0, 0, -1}, {0, 0, 1}, a, b, c));           // through a corner
  EXPECT_FALSE(geom::segment_crosses_triangle({0.1, 0.1, 0}, {0.3, 0.1, 0}, a, b, c));    // in its plane
}

// Signed distances and their gradients against closed forms: outside and inside, near edges and
// corners of a mesh box (the pseudo-normals' business), moved by a pose.
TEST(Contact, CollidersKnowTheirSignedDistance) {
  ColliderShape sphere;
  sphere.kind = ColliderShape::Kind::Sphere;
  sphere.center = {1, 2, 3};
  sphere.radius = 0.5;
  ColliderShape capsule;
  capsule.kind = ColliderShape::Kind::Capsule;
  capsule.a = {0, 0, 0};
  capsule.b = {0, 0, 2};
  capsule.radius = 0.25;
  ColliderShape cylinder = capsule;
  cylinder.kind = ColliderShape::Kind::Cylinder;
  // A closed box [0, 1]^3 as twelve outward triangles.
  auto box = std::make_shared<TriangleSurface>();
  for (int k = 0; k < 8; ++k) box->vertices.push_back({double(k & 1), double((k >> 1) & 1), double((k >> 2) & 1)});
  box->triangles = {{0, 2, 1}, {1, 2, 3}, {4, 5, 6}, {5, 7, 6}, {0, 1, 4}, {1, 5, 4},
                    {2, 6, 3}, {3, 6, 7}, {0, 4, 2}, {2, 4, 6}, {1, 3, 5}, {3, 7, 5}};
  box->lower = {0, 0, 0};
  box->upper = {1, 1, 1};
  ColliderShape mesh;
  mesh.kind = ColliderShape::Kind::Mesh;
  mesh.surface = box;
  for (auto* c : {&sphere, &capsule, &cylinder, &mesh}) c->prepare();
  auto box_distance = [](const Vec& p) {
    Vec q;
    double inside = HUGE_VAL;
    for (int i = 0; i < 3; ++i) {
      q[i] = std::clamp(p[i], 0.0, 1.0);
      inside = std::min({inside, p[i], 1.0 - p[i]});
    }
    const double out = geom::norm(p - q);
    return out > 0.0 ? out : -inside;
  };
  for (int k = 0; k < 400; ++k) {
    const Vec p{3 * hash_unit(k, 0, 3), 3 * hash_unit(k, 1, 3), 3 * hash_unit(k, 2, 3)};
    Vec g;
    EXPECT_NEAR(sphere.distance(p, g), geom::norm(p - sphere.center) - 0.5, 1e-14);
    const double zc = std::clamp(p[2], 0.0, 2.0);
    EXPECT_NEAR(capsule.distance(p, g), std::hypot(p[0], p[1], p[2] - zc) - 0.25, 1e-14);
    EXPECT_NEAR(cylinder.distance(p, g), std::hypot(p[0], p[1]) - 0.25, 1e-14);
    const Vec pb{0.5 + 0.8 * hash_unit(k, 0, 5), 0.5 + 0.8 * hash_unit(k, 1, 5), 0.5 + 0.8 * hash_unit(k, 2, 5)};
    const double phi = mesh.distance(pb, g);
    EXPECT_NEAR(phi, box_distance(pb), 1e-12) << pb[0] << " " << pb[1] << " " << pb[2];
    // The gradient is the derivative of the distance (away from the box's medial surfaces).
    const double h = 1e-7;
    for (int i = 0; i < 3; ++i) {
      Vec a = pb, b = pb, ga;
      a[i] += h;
      b[i] -= h;
      const double fd = (mesh.distance(a, ga) - mesh.distance(b, ga)) / (2 * h);
      if (std::fabs(box_distance(a) - box_distance(b) - 2 * h * g[i]) < 1e-9) EXPECT_NEAR(fd, g[i], 1e-5);
    }
  }
  // Points just off an edge and a corner of the box: outside, whatever face is nearest.
  Vec g;
  EXPECT_NEAR(mesh.distance({1.001, 1.001, 0.5}, g), std::sqrt(2e-6), 1e-12);
  EXPECT_NEAR(mesh.distance({-0.001, -0.001, -0.001}, g), std::sqrt(3e-6), 1e-12);
  EXPECT_NEAR(mesh.distance({0.999, 0.999, 0.5}, g), -0.001, 1e-12);
}

namespace {

// A 4 x 4 x 4 hex cube [0, 1]^3 whose top is pushed down by 0.3 onto a collider below it.
std::string pushed_block(const std::string& collider, double tol = 1e-9) {
  return R"x(<ParameterList name="Sinew">
  <Parameter name="Scene" type="string" value="pushed"/>
  <ParameterList name="Mesh">
    <Parameter name="Elements" type="Array(int)" value="{4, 4, 4}"/>
  </ParameterList>
  <ParameterList name="Material">
    <Parameter name="Model" type="string" value="stable-neohookean"/>
    <Parameter name="Young modulus" type="double" value="1000.0"/>
    <Parameter name="Poisson ratio" type="double" value="0.4"/>
  </ParameterList>
  <ParameterList name="Loading">
    <Parameter name="Steps" type="int" value="3"/>
    <ParameterList name="Boundary conditions">
      <ParameterList name="top">
        <Parameter name="Region" type="string" value="face z+"/>
        <Parameter name="Motion" type="string" value="translate"/>
        <Parameter name="Displacement" type="Array(double)" value="{0, 0, -0.3}"/>
      </ParameterList>
    </ParameterList>
  </ParameterList>
  <ParameterList name="Contact">
    <ParameterList name="Colliders">
      <ParameterList name="below">)x" + collider + R"x(</ParameterList>
    </ParameterList>
  </ParameterList>
  <ParameterList name="Solver">
    <Parameter name="Absolute tolerance" type="double" value=")x" + format_number(tol) + R"x("/>
  </ParameterList>
  )x" + logs_only_output() + R"x(
</ParameterList>)x";
}

// The sum over the nodes of a boundary condition of the unconstrained gradient's component c: minus
// the force the condition exerts on the body (the reaction is -this).
double condition_force(Simulation& sim, const std::string& name, int c, const EnergyTerm* only = nullptr) {
  const System& sys = sim.scene().system();
  auto f = sys.create_vector();
  sys.gradient(sim.displacement(), *f, only);
  auto v = f->getLocalViewHost(Tpetra::Access::ReadOnly);
  double local = 0.0, global = 0.0;
  for (const auto& bc : sim.scene().boundary_conditions())
    if (bc.name == name)
      for (int n : bc.nodes)
        if (static_cast<std::size_t>(n) < sys.mesh().n_owned_nodes) local += v(3 * n + c, 0);
  Teuchos::reduceAll(*sys.comm(), Teuchos::REDUCE_SUM, local, Teuchos::outArg(global));
  return global;
}

double term_total(Simulation& sim, const EnergyTerm& term, int c) {
  const auto f = term_force(sim.scene().system(), term, sim.displacement());
  double s = 0.0;
  for (std::size_t k = c; k < f.size(); k += 3) s += f[k];
  return s;
}

}  // namespace

// A block pushed onto a half-space and onto a closed mesh box whose top is the same plane: the same
// state, the same reaction, and it equals the collider's push on the block.
TEST(Contact, AHalfSpaceAndAMeshColliderPushBackAlike) {
  const std::string dir = "test_results/contact_colliders" + tag();
  std::filesystem::create_directories(dir);
  {
    std::ofstream obj(dir + "/slab.obj");
    for (int k = 0; k < 8; ++k) obj << "v " << (k & 1 ? 3 : -2) << " " << ((k >> 1) & 1 ? 3 : -2) << " " << ((k >> 2) & 1 ? -0.1 : -1.1) << "\n";
    obj << "f 1 3 2\nf 2 3 4\nf 5 6 7\nf 6 8 7\nf 1 2 5\nf 2 6 5\nf 3 7 4\nf 4 7 8\nf 1 5 3\nf 3 5 7\nf 2 4 6\nf 4 8 6\n";
  }
  const std::string half = R"x(<Parameter name="Shape" type="string" value="half-space"/>
        <Parameter name="Point" type="Array(double)" value="{0, 0, -0.1}"/>)x";
  const std::string mesh = R"x(<Parameter name="Shape" type="string" value="mesh"/>
        <Parameter name="Surface" type="string" value=")x" + dir + "/slab.obj" + R"x("/>)x";
  Simulation a(config(pushed_block(half), dir + "/half"), RunOptions{true, ""});
  Simulation b(config(pushed_block(mesh), dir + "/mesh"), RunOptions{true, ""});
  ASSERT_EQ(a.run(), 0);
  ASSERT_EQ(b.run(), 0);
  const double ra = condition_force(a, "top", 2), rb = condition_force(b, "top", 2);
  // The body is pressed: the top pushes down with about E x strain over the area (0.2 after the 0.1 gap).
  EXPECT_GT(-ra, 100.0);
  EXPECT_NEAR(ra, rb, 1e-9 * std::fabs(ra));
  EXPECT_LT(rel_diff(gather(a.displacement()), gather(b.displacement())), 1e-9);
  // Equilibrium: the collider pushes the body up as hard as the top pushes it down (1e-6 relative).
  // In gradients: the body's elastic gradient sums to zero, so the contact term's equals the top's.
  for (Simulation* s : {&a, &b}) {
    const double contact = term_total(*s, *s->scene().contact(), 2);
    EXPECT_NEAR(contact, ra, 1e-6 * std::fabs(ra));
    EXPECT_LT(s->records().back().totals.penetration, s->scene().contact()->settings().thickness);
  }
}

namespace {

// The two blocks pressed together; the springs unless contact_extra names the model (the default is the
// barrier, whose tests say so).
std::string blocks_xml(double push, bool self, int steps = 4, std::string contact_extra = "",
                       const std::string& output_extra = R"x(<Parameter name="Checkpoint every" type="int" value="0"/>)x",
                       const std::string& loading_extra = "") {
  if (contact_extra.find("Self contact model") == std::string::npos)
    contact_extra += R"x(<Parameter name="Self contact model" type="string" value="springs"/>)x";
  return file_scene_head("blocks", meshes + "two_blocks.msh") + R"x(
  <ParameterList name="Loading">
    <Parameter name="Steps" type="int" value=")x" + std::to_string(steps) + R"x("/>
    )x" + loading_extra + R"x(
    <ParameterList name="Boundary conditions">
      <ParameterList name="bottom">
        <Parameter name="Region" type="string" value="group bottom"/>
      </ParameterList>
      <ParameterList name="top">
        <Parameter name="Region" type="string" value="group top"/>
        <Parameter name="Motion" type="string" value="translate"/>
        <Parameter name="Displacement" type="Array(double)" value="{0.02, 0.01, -)x" + std::to_string(push) + R"x(}"/>
      </ParameterList>
    </ParameterList>
  </ParameterList>
  <ParameterList name="Contact">
    <Parameter name="Self contact" type="bool" value=")x" + (self ? "true" : "false") + R"x("/>
    )x" + contact_extra + R"x(
  </ParameterList>
  <ParameterList name="Solver">
    <Parameter name="Absolute tolerance" type="double" value="1.0e-9"/>
  </ParameterList>
  )x" + logs_only_output(output_extra) + R"x(
</ParameterList>)x";
}

// The tractions of this rank's springs, in their order.
std::vector<double> tractions(const ContactTerm& contact) {
  std::vector<double> out;
  for (const auto& p : contact.pairs()) out.push_back(p.lambda);
  return out;
}

}  // namespace

// Two cubes 0.1 apart, the upper pushed down by 0.4 (and a little sideways): they meet and do not pass
// through each other; the force the top exerts reaches the bottom through the springs only (1e-6);
// the same end state on 1 thread, 2 threads and 2 ranks.
TEST(Contact, TwoBlocksPressedTogetherPushEachOtherBack) {
  Simulation sim(config(blocks_xml(0.4, true), "test_results/contact_blocks" + tag()), RunOptions{true, ""});
  ASSERT_EQ(sim.run(), 0);
  const auto& last = sim.records().back();
  const ContactTerm& contact = *sim.scene().contact();
  EXPECT_GT(last.totals.contacts, 20);
  EXPECT_LT(last.totals.penetration, contact.settings().thickness);
  const double top = condition_force(sim, "top", 2), bottom = condition_force(sim, "bottom", 2);
  // Gradients at the prescribed faces (the reactions are their negatives): the top pushes down, the
  // bottom holds up as much.
  EXPECT_LT(top, -100.0);
  EXPECT_NEAR(bottom, -top, 1e-6 * std::fabs(top));
  // The springs push the upper block (its nodes: reference z > 1.05) up as hard as its top pushes it
  // down: the contact term's gradient over the block equals the top's (the elastic one sums to zero).
  const System& sys = sim.scene().system();
  const auto fc = term_force(sys, contact, sim.displacement());
  auto X = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), sys.mesh().X);
  double upper_local = 0.0, upper = 0.0;
  for (std::size_t n = 0; n < sys.mesh().n_owned_nodes; ++n)
    if (X(n, 2) > 1.05) {
      auto v = sim.displacement().getMap()->getGlobalElement(static_cast<LO>(3 * n + 2));
      upper_local += fc[static_cast<std::size_t>(v)];
    }
  Teuchos::reduceAll(*world(), Teuchos::REDUCE_SUM, upper_local, Teuchos::outArg(upper));
  EXPECT_NEAR(upper, top, 1e-6 * std::fabs(top));
  // The pressure the output writes: the springs' traction, which over the contact face carries the push
  // (sum of pressure x area ~ the force, within the spread of the nodal areas).
  sys.evaluate(sim.displacement(), nullptr, nullptr);
  double carried_local = 0.0, carried = 0.0;
  for (std::size_t n = 0; n < sys.mesh().n_owned_nodes; ++n) {
    const int v = contact.surface().vertex_of(sys.mesh().node_gid[n]);
    if (v >= 0) carried_local += contact.pressure()[n] * contact.surface().area[v];
  }
  Teuchos::reduceAll(*world(), Teuchos::REDUCE_SUM, carried_local, Teuchos::outArg(carried));
  EXPECT_GT(carried, 0.5 * std::fabs(top));
  EXPECT_LT(carried, 2.0 * std::fabs(top));
  agree_with_reference(gather(sim.displacement()), world()->getRank(), 1e-6);
}

// Without contact the same push drives the upper block through the lower one: the test above can fail.
TEST(Contact, WithoutContactTheBlocksPassThroughEachOther) {
  Simulation sim(config(blocks_xml(0.4, false, 2), "test_results/contact_blocks_off" + tag()), RunOptions{true, ""});
  ASSERT_EQ(sim.run(), 0);
  const auto u = gather(sim.displacement());
  const Mesh& m = sim.scene().system().mesh();
  // The lowest point of the upper block ends below the highest point of the lower one.
  auto X = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), m.X);
  double low = HUGE_VAL, high = -HUGE_VAL;
  for (std::size_t n = 0; n < m.n_owned_nodes; ++n) {
    const double z = X(n, 2) + u[3 * static_cast<std::size_t>(m.node_gid[n]) + 2];
    if (X(n, 2) > 1.05)
      low = std::min(low, z);
    else
      high = std::max(high, z);
  }
  double glow = 0.0, ghigh = 0.0;
  Teuchos::reduceAll(*world(), Teuchos::REDUCE_MIN, low, Teuchos::outArg(glow));
  Teuchos::reduceAll(*world(), Teuchos::REDUCE_MAX, high, Teuchos::outArg(ghigh));
  EXPECT_LT(glow, ghigh - 0.2);
}

// A run stopped by a signal inside a contact step (between its augmented-Lagrangian rounds) and restarted
// from its checkpoint continues with the springs and tractions the uninterrupted run had at the step's
// start (the contact term's state in the checkpoint), and ends where it ends. A soft penalty (3000,
// a fiftieth of the automatic one) makes the rounds raise tractions; the preconditioner is set up
// afresh each step as the restarted run does.
TEST(Contact, ARestartInsideAContactStepContinuesWithTheSameTractions) {
  const std::string xml = blocks_xml(0.4, true, 4, R"x(<Parameter name="Stiffness" type="double" value="3000"/>)x",
                                     R"x(<Parameter name="Checkpoint every" type="int" value="1"/>)x");
  const std::string dir = "test_results/contact_restart" + tag();
  SceneConfig c = config(xml, dir + "_full");
  c.params.solver.rebuild = SolverParameters::Rebuild::EveryStep;
  Simulation full(c, RunOptions{true, ""});
  std::vector<double> at_step_2;
  full.set_step_observer([&](const StepRecord& r, const Vector&) {
    if (r.step == 2) at_step_2 = tractions(*full.scene().contact());
  });
  ASSERT_EQ(full.run(), 0);
  double largest = 0.0;
  for (double l : at_step_2) largest = std::max(largest, l);
  double largest_all = 0.0;
  Teuchos::reduceAll(*world(), Teuchos::REDUCE_MAX, largest, Teuchos::outArg(largest_all));
  EXPECT_GT(largest_all, 0.0) << "the scene must carry tractions into step 3 for this test to mean anything";

  c.params.output.directory = dir + "_cut";
  Simulation cut(c, RunOptions{true, ""});
  int calls = 0;  // Newton iterations of step 3: stop in its later rounds
  cut.set_stop_check([&] { return cut.records().size() == 2 && ++calls > 12 ? SIGTERM : 0; });
  ASSERT_NE(cut.run(), 0);
  ASSERT_EQ(cut.records().size(), 2u);

  Simulation again(c, RunOptions{true, dir + "_cut/checkpoint.h5"});
  EXPECT_EQ(tractions(*again.scene().contact()), at_step_2);
  ASSERT_EQ(again.run(), 0);
  const double d = rel_diff(gather(full.displacement()), gather(again.displacement()));
  EXPECT_LT(d, 1e-8);
  if (world()->getRank() == 0) std::printf("restarted inside step 3: final displacement %.2e (relative) from the uninterrupted run's\n", d);
}

// ---- barrier self contact (terms/contact_barrier.hpp) ----------------------------------------------

// The squared distance from a point to a triangle's face, edge and corner, with the gradient and
// Hessian the barrier uses, against central differences of the distance itself (each point placed where
// that feature is the closest); and the feature test agrees with the closest point.
TEST(BarrierContact, TheDistanceHasTheGradientAndHessianOfTheDistanceItself) {
  const Vec a{0.1, -0.2, 0.05}, b{1.1, 0.1, -0.1}, c{0.3, 0.9, 0.2};
  struct Case {
    Vec p;
    barrier::Feature::Kind kind;
  };
  const Case cases[] = {{{0.45, 0.25, 0.6}, barrier::Feature::Face},
                        {{0.7, -0.6, 0.3}, barrier::Feature::Edge},
                        {{-0.5, -0.7, 0.2}, barrier::Feature::Vertex}};
  for (const Case& k : cases) {
    const barrier::Feature f = barrier::closest_feature(k.p, a, b, c);
    ASSERT_EQ(f.kind, k.kind);
    const barrier::Distance2 D = barrier::distance2(k.p, a, b, c, f);
    Vec x[4] = {k.p, a, b, c};
    auto d2 = [&](const Vec* y) {
      const double d = barrier::point_triangle_distance(y[0], y[1], y[2], y[3]);
      return d * d;
    };
    EXPECT_NEAR(D.value, d2(x), 1e-14);
    const double h = 1e-5;
    double gmax = 0.0, herr = 0.0, hmax = 0.0, gerr = 0.0;
    for (int i = 0; i < 12; ++i) {
      Vec xp[4] = {x[0], x[1], x[2], x[3]}, xm[4] = {x[0], x[1], x[2], x[3]};
      xp[i / 3][i % 3] += h;
      xm[i / 3][i % 3] -= h;
      gerr = std::max(gerr, std::fabs((d2(xp) - d2(xm)) / (2 * h) - D.grad[i]));
      gmax = std::max(gmax, std::fabs(D.grad[i]));
      // Column i of the Hessian: central differences of the formula's gradient.
      const barrier::Distance2 Dp = barrier::distance2(xp[0], xp[1], xp[2], xp[3], f), Dm = barrier::distance2(xm[0], xm[1], xm[2], xm[3], f);
      for (int j = 0; j < 12; ++j) {
        herr = std::max(herr, std::fabs((Dp.grad[j] - Dm.grad[j]) / (2 * h) - D.hess[j * 12 + i]));
        hmax = std::max(hmax, std::fabs(D.hess[j * 12 + i]));
      }
    }
    EXPECT_GT(gmax, 0.1);
    EXPECT_LT(gerr, 1e-8 * gmax) << "feature " << k.kind;
    EXPECT_LT(herr, 1e-6 * hmax) << "feature " << k.kind;
    // Translating everything changes nothing: the gradient's four blocks sum to zero.
    for (int c3 = 0; c3 < 3; ++c3) EXPECT_NEAR(D.grad[c3] + D.grad[3 + c3] + D.grad[6 + c3] + D.grad[9 + c3], 0.0, 1e-12);
  }
}

// b(D) = -(D - D^)^2 ln(D / D^): zero with its slope and curvature at D^ (the barrier switches on
// smoothly), its derivatives those of its value, and unbounded as D -> 0; the projection leaves a
// 12 x 12 Hessian PSD and a PSD one alone.
TEST(BarrierContact, TheBarrierSwitchesOnSmoothlyAndGrowsWithoutBound) {
  const double Dhat = 4e-4;
  for (double D : {1e-6, 3e-5, 1e-4, 3.9e-4}) {
    const barrier::Law l = barrier::law(D, Dhat), lp = barrier::law(D * (1 + 1e-6), Dhat), lm = barrier::law(D * (1 - 1e-6), Dhat);
    EXPECT_GT(l.e, 0.0);
    EXPECT_LT(l.d1, 0.0);
    EXPECT_GT(l.d2, 0.0);
    EXPECT_NEAR((lp.e - lm.e) / (2e-6 * D), l.d1, 1e-6 * std::fabs(l.d1));
    EXPECT_NEAR((lp.d1 - lm.d1) / (2e-6 * D), l.d2, 1e-6 * std::fabs(l.d2));
  }
  const barrier::Law at = barrier::law(Dhat * (1 - 1e-6), Dhat);
  EXPECT_LT(at.e, 1e-15);
  EXPECT_LT(std::fabs(at.d1), 1e-9);
  EXPECT_LT(at.d2, 1e-4);
  EXPECT_EQ(barrier::law(Dhat, Dhat).e, 0.0);
  EXPECT_GT(barrier::law(1e-30, Dhat).e, 3.5 * barrier::law(1e-10, Dhat).e);  // -ln D: 62 against 15
  EXPECT_FALSE(std::isfinite(barrier::law(0.0, Dhat).e));

  const Vec a{0.1, -0.2, 0.05}, b{1.1, 0.1, -0.1}, c{0.3, 0.9, 0.2}, p{-0.3, -0.4, 0.05};  // nearest a
  const barrier::Distance2 D = barrier::distance2(p, a, b, c, barrier::closest_feature(p, a, b, c));
  const barrier::Law l = barrier::law(D.value, 1.5 * D.value);
  std::vector<std::vector<double>> H(12, std::vector<double>(12));
  double Hp[144];
  for (int i = 0; i < 12; ++i)
    for (int j = 0; j < 12; ++j) Hp[i * 12 + j] = H[i][j] = l.d2 * D.grad[i] * D.grad[j] + l.d1 * D.hess[i * 12 + j];
  EXPECT_LT(min_eigenvalue(H), -1e-3) << "the unprojected Hessian is indefinite here, or the test proves nothing";
  barrier::project_psd(Hp);
  for (int i = 0; i < 12; ++i)
    for (int j = 0; j < 12; ++j) H[i][j] = Hp[i * 12 + j];
  EXPECT_GT(min_eigenvalue(H), -1e-12 * max_abs(H));
  double before[144];
  std::copy(Hp, Hp + 144, before);
  barrier::project_psd(Hp);
  for (int k = 0; k < 144; ++k) EXPECT_NEAR(Hp[k], before[k], 1e-12 * max_abs(H));
}

// Additive CCD: a point moving straight through a triangle stops short of it (and still apart by at
// least a tenth of where it started); one sliding past it above its plane, or moving away, is not
// stopped; a triangle moving onto a still point is stopped as well.
TEST(BarrierContact, ContinuousCollisionStopsAPointShortOfATriangle) {
  const Vec a{0, 0, 0}, b{1, 0, 0}, c{0, 1, 0}, zero{0, 0, 0};
  const Vec p{0.2, 0.2, 0.1}, through{0.05, 0.02, -0.3};  // crosses the plane at t = 1/3, inside the triangle
  const double t = barrier::vertex_triangle_toi(p, a, b, c, through, zero, zero, zero, 1.0);
  EXPECT_LT(t, 1.0 / 3.0);
  EXPECT_GT(t, 0.25);  // not needlessly short: the crossing is at 1/3
  const Vec at{p[0] + t * through[0], p[1] + t * through[1], p[2] + t * through[2]};
  EXPECT_GE(barrier::point_triangle_distance(at, a, b, c), 0.1 * 0.1 * (1 - 1e-12));
  EXPECT_EQ(barrier::vertex_triangle_toi(p, a, b, c, Vec{2.0, 1.0, 0.0}, zero, zero, zero, 1.0), 1.0);   // slides above
  EXPECT_EQ(barrier::vertex_triangle_toi(p, a, b, c, Vec{0.0, 0.0, 1.0}, zero, zero, zero, 1.0), 1.0);   // leaves
  const Vec up{0, 0, 0.5};  // the triangle rises through the point at t = 0.2
  EXPECT_LT(barrier::vertex_triangle_toi(p, a, b, c, zero, up, up, up, 1.0), 0.2);
  // Over a longer interval, the same crossing bounds it.
  EXPECT_LT(barrier::vertex_triangle_toi(p, a, b, c, through, zero, zero, zero, 2.0), 1.0 / 3.0);
}

// The edge-edge pieces: the closest-feature test agrees with a dense search over both segments; the
// mollified barrier m(c) b(D) has the gradient of its value and the Hessian of its gradient (central
// differences) where the lines', a point-edge and a point-point distance are the closest, and where the
// edges are nearly parallel (the mollifier below 1); and it fades to nothing as they turn parallel.
TEST(BarrierContact, TheEdgeEdgeBarrierHasTheDerivativesOfItsValueAndFadesAsTheEdgesTurnParallel) {
  struct Case {
    Vec a0, a1, b0, b1;
    barrier::EdgeFeature::Kind kind;
    bool mollified;
  };
  const Case cases[] = {
      {{0.0, 0.1, 0.05}, {1.0, -0.1, 0.0}, {0.4, -0.5, 0.12}, {0.5, 0.6, 0.1}, barrier::EdgeFeature::Lines, false},
      {{0.0, 0.1, 0.05}, {1.0, -0.1, 0.0}, {1.06, -0.5, 0.12}, {1.2, 0.6, 0.1}, barrier::EdgeFeature::PointEdge, false},
      {{0.0, 0.1, 0.05}, {1.0, -0.1, 0.0}, {1.05, 0.03, 0.08}, {1.4, 0.6, 0.1}, barrier::EdgeFeature::Points, false},
      {{0.0, 0.0, 0.0}, {1.0, 0.0, 0.0}, {0.2, -0.01, 0.1}, {0.9, 0.005, 0.105}, barrier::EdgeFeature::PointEdge, true}};
  const double Dhat = 0.2 * 0.2;
  for (const Case& k : cases) {
    const Vec x[4] = {k.a0, k.a1, k.b0, k.b1};
    const barrier::EdgeFeature f = barrier::closest_edge_feature(x[0], x[1], x[2], x[3]);
    ASSERT_EQ(f.kind, k.kind);
    // The distance against the closest of 1001 x 1001 point pairs.
    double dense = HUGE_VAL;
    for (int i = 0; i <= 1000; ++i)
      for (int j = 0; j <= 1000; ++j) {
        const double s = i / 1000.0, t = j / 1000.0;
        dense = std::min(dense, geom::norm((x[0] + s * (x[1] - x[0])) - (x[2] + t * (x[3] - x[2]))));
      }
    const double d = barrier::segment_distance(x[0], x[1], x[2], x[3]);
    EXPECT_LE(d, dense + 1e-14);
    EXPECT_GT(d, dense - 2e-3);
    ASSERT_LT(d * d, Dhat);
    const Vec ea = x[1] - x[0], eb = x[3] - x[2];
    const double eps = 1e-3 * geom::dot(ea, ea) * geom::dot(eb, eb), c = geom::dot(geom::cross(ea, eb), geom::cross(ea, eb));
    EXPECT_EQ(c < eps, k.mollified);
    const barrier::Distance2 E = barrier::edge_edge_barrier(x[0], x[1], x[2], x[3], f, Dhat, eps);
    const double m = c < eps ? (2.0 - c / eps) * c / eps : 1.0;
    EXPECT_NEAR(E.value, m * barrier::law(d * d, Dhat).e, 1e-12 * E.value);
    auto value = [&](const Vec* y) {
      return barrier::edge_edge_barrier(y[0], y[1], y[2], y[3], barrier::closest_edge_feature(y[0], y[1], y[2], y[3]), Dhat, eps).value;
    };
    const double h = 1e-6;
    double gmax = 0.0, gerr = 0.0, hmax = 0.0, herr = 0.0;
    for (int i = 0; i < 12; ++i) {
      Vec xp[4] = {x[0], x[1], x[2], x[3]}, xm[4] = {x[0], x[1], x[2], x[3]};
      xp[i / 3][i % 3] += h;
      xm[i / 3][i % 3] -= h;
      gerr = std::max(gerr, std::fabs((value(xp) - value(xm)) / (2 * h) - E.grad[i]));
      gmax = std::max(gmax, std::fabs(E.grad[i]));
      const barrier::Distance2 Ep = barrier::edge_edge_barrier(xp[0], xp[1], xp[2], xp[3], f, Dhat, eps),
                               Em = barrier::edge_edge_barrier(xm[0], xm[1], xm[2], xm[3], f, Dhat, eps);
      for (int j = 0; j < 12; ++j) {
        herr = std::max(herr, std::fabs((Ep.grad[j] - Em.grad[j]) / (2 * h) - E.hess[j * 12 + i]));
        hmax = std::max(hmax, std::fabs(E.hess[j * 12 + i]));
      }
    }
    EXPECT_GT(gmax, 0.0);
    EXPECT_LT(gerr, 1e-6 * gmax) << "feature " << k.kind;
    EXPECT_LT(herr, 1e-5 * hmax) << "feature " << k.kind;
    for (int c3 = 0; c3 < 3; ++c3) EXPECT_NEAR(E.grad[c3] + E.grad[3 + c3] + E.grad[6 + c3] + E.grad[9 + c3], 0.0, 1e-9 * gmax);
  }
  // Turning edge b parallel to a at a fixed distance: the energy falls to zero with the mollifier.
  const Vec a0{0, 0, 0}, a1{1, 0, 0};
  double last = HUGE_VAL;
  for (double tilt : {0.05, 0.02, 0.01, 0.001, 0.0}) {
    const Vec b0{0.3, -tilt, 0.1}, b1{0.7, tilt, 0.1};
    const double eps = 1e-3 * 1.0 * geom::dot(b1 - b0, b1 - b0);
    const double e = barrier::edge_edge_barrier(a0, a1, b0, b1, barrier::closest_edge_feature(a0, a1, b0, b1), Dhat, eps).value;
    EXPECT_LE(e, last * (1.0 + 1e-12));
    last = e;
  }
  EXPECT_EQ(last, 0.0);
}

// Edge CCD: an edge moving down through another that crosses below it stops short of it (still apart by
// at least a tenth of where it started); sliding along it, or crossing above it, is not stopped.
TEST(BarrierContact, ContinuousCollisionStopsAnEdgeShortOfAnotherEdge) {
  const Vec a0{0, 0.5, 0}, a1{1, 0.5, 0}, b0{0.5, 0, 0.1}, b1{0.5, 1, 0.1}, zero{0, 0, 0}, down{0, 0, -0.3};
  const double t = barrier::edge_edge_toi(a0, a1, b0, b1, zero, zero, down, down, 1.0);  // crosses at t = 1/3
  EXPECT_LT(t, 1.0 / 3.0);
  EXPECT_GT(t, 0.25);
  const Vec c0 = b0 + t * down, c1 = b1 + t * down;
  EXPECT_GE(barrier::segment_distance(a0, a1, c0, c1), 0.1 * 0.1 * (1 - 1e-12));
  EXPECT_EQ(barrier::edge_edge_toi(a0, a1, b0, b1, zero, zero, Vec{0.0, 2.0, 0.0}, Vec{0.0, 2.0, 0.0}, 1.0), 1.0);  // slides along
  EXPECT_EQ(barrier::edge_edge_toi(a0, a1, b0, b1, zero, zero, Vec{2.0, 0.0, 0.0}, Vec{2.0, 0.0, 0.0}, 1.0), 1.0);  // passes above
}

// The barrier term in a system: its gradient is that of its energy (central differences along random
// directions, samples between the blocks closer than dhat), its Hessian PSD, its forces sum to zero;
// and the step limit stops a step that would push the upper block's samples through the lower one.
TEST(BarrierContact, TheTermHasTheGradientOfItsEnergyAndLimitsSteps) {
  System sys(world(), two_blocks(), snh());
  ContactSettings cs = block_springs(0.2);
  cs.barrier = true;
  cs.edge_pairs = true;
  cs.thickness = 0.15;  // the blocks are 0.1 apart at rest
  auto contact = add_springs(sys, cs);
  auto u = sys.create_vector();
  press(sys, *u, 0.05);  // 0.05 apart, a wiggle of 0.004
  contact->detect(*u);
  sys.update_pattern();
  EXPECT_GT(contact->global_pairs(), 20);
  std::size_t edge_pairs = 0;  // (edge-edge pairs, some crossing, some parallel: mollified)
  for (const auto& p : contact->pairs()) edge_pairs += p.edges;
  EXPECT_GT(edge_pairs, 10u);
  {  // A checkpoint keeps them: a term loaded from the state has the same pairs, edge pairs included.
    contact->end_step(*u);
    TermState state;
    contact->save_state(state);
    ASSERT_NE(state.find_shared("edge pairs"), nullptr);
    System again(world(), two_blocks(), snh());
    auto loaded = add_springs(again, cs);
    loaded->load_state(state);
    std::size_t loaded_edges = 0;
    for (const auto& p : loaded->pairs()) loaded_edges += p.edges;
    EXPECT_EQ(loaded_edges, edge_pairs);
    EXPECT_EQ(loaded->global_pairs(), contact->global_pairs());
  }
  auto f = sys.create_vector();
  const auto t = sys.evaluate(*u, f.get(), nullptr);
  EXPECT_GT(t.share("contact"), 0.0);
  EXPECT_GT(t.contacts, 10);
  auto dir = sys.create_vector(), up = sys.create_vector(), um = sys.create_vector();
  for (int trial = 0; trial < 3; ++trial) {
    set_displacement(sys, *dir, [&](const std::array<double, 3>&, int c, long long gid) { return hash_unit(gid, c, 7 + trial); });
    const double eps = 1e-6;
    up->update(1.0, *u, eps, *dir, 0.0);
    um->update(1.0, *u, -eps, *dir, 0.0);
    const double slope = (sys.evaluate(*up, nullptr, nullptr).energy - sys.evaluate(*um, nullptr, nullptr).energy) / (2 * eps);
    EXPECT_NEAR(slope, f->dot(*dir), 1e-6 * std::max(1.0, std::fabs(slope)));
  }
  const auto H = term_hessian(sys, *contact, *u);
  EXPECT_GT(max_abs(H), 0.0);
  EXPECT_GT(min_eigenvalue(H), -1e-10 * max_abs(H));
  expect_no_net_force(sys, *contact, *u);
  // A step moving the upper block down by 0.1 more would cross at 1/2: it is limited short of that;
  // one moving it up is not limited.
  auto down = sys.create_vector();
  set_displacement(sys, *down, [&](const std::array<double, 3>& X, int c, long long) { return c == 2 && X[2] > 1.05 ? -0.1 : 0.0; });
  const double limit = sys.step_limit(*u, *down, 2.0);
  EXPECT_LT(limit, 0.5);
  EXPECT_GT(limit, 0.2);
  down->scale(-1.0);
  EXPECT_EQ(sys.step_limit(*u, *down, 2.0), 2.0);
  // A first guess that takes the upper block 0.1 down (through the lower one's top) is pulled back
  // where it crosses: the path to what is left is admitted, the lower block's samples away from the
  // contact keep their guess, and the upper block's top (no surface point of the contact) too.
  set_displacement(sys, *down, [&](const std::array<double, 3>& X, int c, long long) { return c == 2 && X[2] > 1.05 ? -0.1 : 0.0; });
  auto guess = sys.create_vector();
  guess->update(1.0, *u, 1.0, *down, 0.0);
  const auto wanted = gather(*guess);
  EXPECT_EQ(sys.admit_guess(*u, *guess), 1.0);  // the pull-back was local
  auto path = sys.create_vector();
  path->update(1.0, *guess, -1.0, *u, 0.0);
  EXPECT_EQ(sys.step_limit(*u, *path, 1.0), 1.0);
  const auto got = gather(*guess);
  std::size_t kept = 0, pulled = 0;
  for (std::size_t i = 2; i < got.size(); i += 3) (std::fabs(got[i] - wanted[i]) < 1e-15 ? kept : pulled) += 1;
  EXPECT_GT(pulled, 10u);
  EXPECT_GT(kept, pulled);
}

// Two blocks turned into ridges that cross like an X (the lower one's along y, the upper one's along x,
// each crossing the other in the middle of a lattice edge), the upper one moved down through the lower
// one: no vertex comes near a face before the ridges' edges meet, so the vertex-face collision test
// alone lets the whole step through; with edge pairs it stops the step short of the crossing.
TEST(BarrierContact, TheCollisionTestStopsTwoEdgesCrossingWhereNoPointMeetsAFace) {
  auto limit = [&](bool edges) {
    System sys(world(), two_blocks(), snh());
    ContactSettings cs = block_springs(0.2);
    cs.barrier = true;
    cs.thickness = 0.02;
    cs.edge_pairs = edges;
    auto contact = add_springs(sys, cs);
    auto u = sys.create_vector(), down = sys.create_vector();
    set_displacement(sys, *u, [&](const std::array<double, 3>& X, int c, long long) { return crossed_ridges(X, c); });
    set_displacement(sys, *down, [&](const std::array<double, 3>& X, int c, long long) { return c == 2 && X[2] > 1.05 ? -0.15 : 0.0; });
    contact->detect(*u);
    sys.update_pattern();
    return sys.step_limit(*u, *down, 1.0);
  };
  // The ridges meet at 2/3 of the step (0.1 of 0.15). A ridge's node 0.125 from the crossing would come
  // to a tenth of its distance to the other's faces (the collision test's floor) after 0.2025.
  const double with = limit(true), without = limit(false);
  EXPECT_EQ(without, 1.0);
  EXPECT_LT(with, 2.0 / 3.0);
  EXPECT_GT(with, 0.55);
}

// What a step's end reports of a surface through itself: the crossed ridges of the test above, stepped
// the whole way (the ridges 0.05 through each other, no node through a face), have surface edges
// through faces where the samples' winding numbers see nothing; before the step, none.
TEST(BarrierContact, TheDetectionCountsSurfaceEdgesThroughAFaceWhereNoPointCrossedOne) {
  for (bool barrier : {false, true}) {  // (the count is the detection's, whatever the model)
    System sys(world(), two_blocks(), snh());
    ContactSettings cs = block_springs(0.2);
    cs.barrier = barrier;
    cs.thickness = 0.02;
    auto contact = add_springs(sys, cs);
    auto u = sys.create_vector(), crossed = sys.create_vector();
    set_displacement(sys, *u, [&](const std::array<double, 3>& X, int c, long long) { return crossed_ridges(X, c); });
    set_displacement(sys, *crossed, [&](const std::array<double, 3>& X, int c, long long) {
      return crossed_ridges(X, c) + (c == 2 && X[2] > 1.05 ? -0.15 : 0.0);
    });
    contact->end_step(*u);
    EXPECT_EQ(contact->step_counts().edges_through_faces, 0) << "barrier " << barrier;
    const ContactDetection after = contact->detect(*crossed);
    contact->end_step(*crossed);
    EXPECT_GT(contact->step_counts().edges_through_faces, 0) << "barrier " << barrier;
    EXPECT_EQ(after.crossed, 0) << "barrier " << barrier;
  }
}

// The barrier's pair Hessians are PSD projections, except where the solver asks for every term's exact
// Hessian (TermInput::exact_terms, HessianPolicy's exact-terms tier): then the term's Hessian is the
// derivative of its gradient, and indefinite (b' < 0 times the curvature of the distance), where the
// projected one is PSD and differs from those differences.
TEST(BarrierContact, AskedForTheExactHessianTheBarrierGivesTheDerivativeOfItsGradientUnprojected) {
  System sys(world(), two_blocks(), snh());
  ContactSettings cs = block_springs(0.2);
  cs.barrier = true;
  cs.edge_pairs = true;
  cs.thickness = 0.15;
  auto contact = add_springs(sys, cs);
  EXPECT_TRUE(sys.projects_hessians());
  auto u = sys.create_vector();
  press(sys, *u, 0.05);
  contact->detect(*u);
  sys.update_pattern();
  auto d = sys.create_vector();
  set_displacement(sys, *d, [&](const std::array<double, 3>&, int c, long long gid) { return hash_unit(gid, c, 11); });
  const auto exact = check_term_derivatives(sys, *contact, *u, *d, 1e-7, true);
  const auto projected = check_term_derivatives(sys, *contact, *u, *d, 1e-7, false);
  EXPECT_GT(exact.scale, 0.0);
  EXPECT_LT(exact.err, 1e-5 * exact.scale);
  EXPECT_LT(exact.min_eigenvalue, -1e-6 * exact.max_entry);
  EXPECT_GT(projected.min_eigenvalue, -1e-10 * projected.max_entry);
  EXPECT_GT(projected.err, 1e-3 * projected.scale);
  // Terms that project nothing do not offer the tier.
  System plain(world(), two_blocks(), snh());
  EXPECT_FALSE(plain.projects_hessians());
}

// Each Newton iteration's row of newton.csv reports the longest step the barrier's collision test
// allowed along its direction (step_bound, +inf where it allowed the line search's longest): pressing
// two blocks together, some directions would carry the top's faces through the bottom's, and their
// steps stop at or before that bound; no step goes past one. The iteration after a step held short of
// 1 by the bound assembles the projected Hessian (HessianPolicy: the exact one waits for a step that
// was not held), also across the regroups of a load step. (Here the residuals after the held steps are
// above the exact Hessian's threshold anyway; Solve.AfterAStepATermHeldShortTheNextJacobianIsProjected
// is the test that fails without the rule.) Without edge pairs (on by default) and at the springs'
// thickness 0.05 h (the barrier's default is 0.15 h): with either default this scene's held steps
// backtrack past their bounds, and no row would show a step taken to its bound.
TEST(BarrierContact, EachIterationReportsTheStepItsCollisionTestAllowsAndAHeldStepIsFollowedByAProjectedOne) {
  const std::string dir = "test_results/contact_blocks_bound" + tag();
  Simulation sim(config(blocks_xml(0.4, true, 4,
                                   R"x(<Parameter name="Self contact model" type="string" value="barrier"/>
                                       <Parameter name="Edge pairs" type="bool" value="false"/>
                                       <Parameter name="Thickness" type="double" value="0.0125"/>)x"),
                        dir),
                 RunOptions{true, ""});
  ASSERT_EQ(sim.run(), 0);
  const std::vector<std::string> steps = csv_column(dir + "/newton.csv", "step_length"),
                                 bounds = csv_column(dir + "/newton.csv", "step_bound"),
                                 exact = csv_column(dir + "/newton.csv", "exact_hessian"),
                                 load_step = csv_column(dir + "/newton.csv", "step");
  ASSERT_EQ(steps.size(), bounds.size());
  ASSERT_EQ(steps.size(), exact.size());
  ASSERT_EQ(steps.size(), load_step.size());
  int bounded = 0, at_bound = 0, after_held = 0, exact_rows = 0;
  for (std::size_t i = 0; i < steps.size(); ++i) {
    const double step = std::stod(steps[i]), bound = std::stod(bounds[i]);
    exact_rows += exact[i] == "1";
    if (i > 0 && load_step[i] == load_step[i - 1] && std::stod(bounds[i - 1]) < 1.0) {
      ++after_held;
      EXPECT_EQ(exact[i], "0") << "row " << i + 1 << " follows a step held at " << bounds[i - 1];
    }
    if (std::isinf(bound)) continue;
    ++bounded;
    EXPECT_GT(bound, 0.0);
    EXPECT_LE(step, bound * (1.0 + 1e-12)) << "row " << i + 1;
    at_bound += step == bound;
  }
  EXPECT_GT(steps.size(), 4u);
  EXPECT_GT(bounded, 0);
  EXPECT_GT(at_bound, 0);
  EXPECT_GT(after_held, 0);
  EXPECT_GT(exact_rows, 0);
  std::printf("  %zu Newton iterations, %d bounded by the collision test, %d of them stepped to the bound; %d after a held step, "
              "%d exact\n", steps.size(), bounded, at_bound, after_held, exact_rows);
}

// With the barrier, every step starts from the tangent predictor (the linearised step from the last
// state, NonlinearSolver::tangent), not only the first: its guess passes the collision test as any
// other. The blocks pressed together end where they end from the extrapolated guesses, and the
// predictor's CG solves are the difference between each step's CG count and its Newton iterations'.
// At the springs' thickness 0.05 h: at the barrier's default 0.15 h, on two ranks, the two runs came to
// rest 2.8% apart (79 and 67 Newton iterations), two equilibria of the blocks' frictionless contact
// under the sideways push, which a comparison of end states cannot tell from a wrong predictor.
TEST(BarrierContact, EveryStepStartsFromTheLinearisedStepAndEndsWhereExtrapolatingDoes) {
  const std::string barrier = R"x(<Parameter name="Self contact model" type="string" value="barrier"/>
                                  <Parameter name="Thickness" type="double" value="0.0125"/>)x";
  const std::string no_checkpoints = R"x(<Parameter name="Checkpoint every" type="int" value="0"/>)x";
  const std::string tangent_dir = "test_results/contact_blocks_tangent" + tag(),
                    extrapolated_dir = "test_results/contact_blocks_extrapolated" + tag();
  auto run = [&](const std::string& loading, const std::string& dir) {
    auto sim = std::make_unique<Simulation>(config(blocks_xml(0.4, true, 4, barrier, no_checkpoints, loading), dir), RunOptions{true, ""});
    EXPECT_EQ(sim->run(), 0);
    return sim;
  };
  const auto tangent = run("", tangent_dir);
  const auto extrapolated = run(R"x(<Parameter name="Predictor" type="string" value="extrapolate"/>)x", extrapolated_dir);
  EXPECT_LT(rel_diff(gather(tangent->displacement()), gather(extrapolated->displacement())), 1e-6);
  // Per step: the CG iterations outside its Newton iterations (log.csv's count less newton.csv's).
  auto predictor_cg = [](const std::string& dir) {
    const auto step = csv_column(dir + "/newton.csv", "step"), cg = csv_column(dir + "/newton.csv", "cg_iterations");
    const auto steps = csv_column(dir + "/log.csv", "step"), total = csv_column(dir + "/log.csv", "cg_iterations");
    std::vector<int> out;
    for (std::size_t k = 0; k < steps.size(); ++k) {
      int n = std::stoi(total[k]);
      for (std::size_t i = 0; i < step.size(); ++i) n -= step[i] == steps[k] ? std::stoi(cg[i]) : 0;
      out.push_back(n);
    }
    return out;
  };
  const std::vector<int> with = predictor_cg(tangent_dir), without = predictor_cg(extrapolated_dir);
  ASSERT_EQ(with.size(), 4u);
  ASSERT_EQ(without.size(), 4u);
  for (std::size_t k = 0; k < with.size(); ++k) {
    EXPECT_GT(with[k], 0) << "step " << k + 1;
    EXPECT_EQ(without[k], 0) << "step " << k + 1;
  }
  int tn = 0, en = 0;
  for (const auto& r : tangent->records()) tn += r.solve.newton_iterations;
  for (const auto& r : extrapolated->records()) en += r.solve.newton_iterations;
  if (world()->getRank() == 0) std::printf("  Newton iterations: %d from the tangent, %d extrapolated\n", tn, en);
}

// The barrier's default k is a tenth of the springs' ((mu_L + lambda_L) / h against ten times that: at the
// springs' k the barrier's energy rose so steeply within its thickness that Newton steps closing surfaces
// were cut to a few percent, docs/performance.md "A softer barrier"); a given 'Stiffness' is both's.
TEST(BarrierContact, DefaultsToATenthOfTheSpringsStiffnessAndTakesAGivenOneAsIs) {
  for (const std::string given : {"", R"x(<Parameter name="Stiffness" type="double" value="3.0e5"/>)x"}) {
    SCOPED_TRACE(given.empty() ? "default" : "given");
    Simulation sim(config(blocks_xml(0.0, true, 1, R"x(<Parameter name="Self contact model" type="string" value="barrier"/>)x" + given),
                          "test_results/contact_blocks_barrier_stiffness" + tag()),
                   RunOptions{true, ""});
    const ContactTerm& contact = *sim.scene().contact();
    const System& sys = sim.scene().system();
    const double springs = given.empty() ? 10.0 * sys.stiffness_scale() / sys.cell_size() : 3.0e5;
    EXPECT_NEAR(contact.settings().stiffness, springs, 1e-12 * springs);
    EXPECT_NEAR(contact.barrier_stiffness(), given.empty() ? springs / 10.0 : springs, 1e-12 * springs);
  }
}

// The blocks pressed 0.3 into each other's place with the barrier and its edge pairs: the run ends with
// no surface point inside the other block and no pair (point-face or edge-edge) closer than a hundredth
// of its dhat, the top's push carried to the bottom.
TEST(BarrierContact, TwoBlocksPressedTogetherNeverTouch) {
  Simulation sim(config(blocks_xml(0.4, true, 4,
                                   R"x(<Parameter name="Self contact model" type="string" value="barrier"/>
                                       <Parameter name="Edge pairs" type="bool" value="true"/>)x"),
                        "test_results/contact_blocks_barrier" + tag()),
                 RunOptions{true, ""});
  ASSERT_EQ(sim.run(), 0);
  const auto& last = sim.records().back();
  const ContactTerm& contact = *sim.scene().contact();
  EXPECT_GT(last.totals.contacts, 20);
  EXPECT_EQ(contact.step_counts().inside_depth, 0.0);
  const double top = condition_force(sim, "top", 2), bottom = condition_force(sim, "bottom", 2);
  EXPECT_LT(top, -100.0);
  EXPECT_NEAR(bottom, -top, 1e-6 * std::fabs(top));
  // Every pair's sample keeps its distance (the barrier's pairs on this rank).
  const System& sys = sim.scene().system();
  auto X = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), sys.mesh().X);
  (void)X;
  double closest = HUGE_VAL;
  std::size_t edge_pairs = 0;
  const auto& s = contact.surface();
  const auto all = gather(sim.displacement());
  for (const auto& p : contact.pairs()) {
    Vec x[4];
    for (int j = 0; j < 4; ++j) {
      const int v = s.vertex_of(p.node[j]);
      for (int k = 0; k < 3; ++k) x[j][k] = s.X[v][k] + all[3 * static_cast<std::size_t>(p.node[j]) + k];
    }
    const double d = p.edges ? barrier::segment_distance(x[0], x[1], x[2], x[3]) : barrier::point_triangle_distance(x[0], x[1], x[2], x[3]);
    closest = std::min(closest, d / p.delta);
    edge_pairs += p.edges;
  }
  EXPECT_GT(edge_pairs, 0u);
  EXPECT_GT(closest, 0.01);
  EXPECT_LT(closest, 1.0);  // and some pair pushes
}
