// Rigged characters read with Assimp (discretization/rig_file.hpp): a production file's joints,
// weights and clip; the bind pose skins back to the mesh as placed; clips are sampled between keys by
// slerp and composed down the hierarchy (a glTF file written here, checked against hand-computed
// transforms); broken files are named.
#include "scene_test_utils.hpp"

#include <sinew/core/errors.hpp>
#include <sinew/core/sym_eigen.hpp>
#include <sinew/discretization/rig_file.hpp>
#include <sinew/driver/run.hpp>
#include <sinew/scenes/region.hpp>
#include <sinew/scenes/scene.hpp>

#include <Kokkos_Core.hpp>
#include <Tpetra_Core.hpp>
#include <Tpetra_Vector.hpp>

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

using namespace sinew;

namespace {

const char* kEpileptic = "/usr/share/assimp/models/X/BCN_Epileptic.X";  // Debian's assimp-testmodels (BSD-3)

std::string write_file(const std::string& name, const std::string& text) {
  std::filesystem::create_directories("test_results/rig");
  const std::string path = "test_results/rig/" + name;
  std::ofstream(path, std::ios::binary) << text;
  return path;
}

std::string base64(const std::string& bytes) {
  static const char* A = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  std::size_t i = 0;
  for (; i + 2 < bytes.size(); i += 3) {
    const std::uint32_t v = (std::uint8_t(bytes[i]) << 16) | (std::uint8_t(bytes[i + 1]) << 8) | std::uint8_t(bytes[i + 2]);
    out += {A[v >> 18], A[(v >> 12) & 63], A[(v >> 6) & 63], A[v & 63]};
  }
  if (i + 1 == bytes.size()) {
    const std::uint32_t v = std::uint8_t(bytes[i]) << 16;
    out += {A[v >> 18], A[(v >> 12) & 63], '=', '='};
  } else if (i + 2 == bytes.size()) {
    const std::uint32_t v = (std::uint8_t(bytes[i]) << 16) | (std::uint8_t(bytes[i + 1]) << 8);
    out += {A[v >> 18], A[(v >> 12) & 63], A[(v >> 6) & 63], '='};
  }
  return out;
}

// root -> child (at x = 1) -> tip (at x = 1 from the child); the clip turns the child about z from 0
// at t = 0 to `degrees` at t = 1 s (glTF quaternions are x, y, z, w).
std::string two_joint_gltf(double degrees, float poison = 0.0f) {
  const float h = static_cast<float>(0.5 * degrees * M_PI / 180.0);
  const float data[10] = {0.0f, 1.0f, 0, 0, 0, 1, 0, 0, std::sin(h) + poison, std::cos(h)};
  const std::string bytes(reinterpret_cast<const char*>(data), sizeof data);
  return R"({"asset": {"version": "2.0"}, "scene": 0, "scenes": [{"nodes": [0]}],
 "nodes": [{"name": "root", "children": [1]}, {"name": "child", "translation": [1, 0, 0], "children": [2]},
           {"name": "tip", "translation": [1, 0, 0]}],
 "buffers": [{"byteLength": 40, "uri": "data:application/octet-stream;base64,)" + base64(bytes) + R"("}],
 "bufferViews": [{"buffer": 0, "byteOffset": 0, "byteLength": 8}, {"buffer": 0, "byteOffset": 8, "byteLength": 32}],
 "accessors": [{"bufferView": 0, "componentType": 5126, "count": 2, "type": "SCALAR", "min": [0], "max": [1]},
               {"bufferView": 1, "componentType": 5126, "count": 2, "type": "VEC4"}],
 "animations": [{"name": "bend", "samplers": [{"input": 0, "output": 1, "interpolation": "LINEAR"}],
                 "channels": [{"sampler": 0, "target": {"node": 1, "path": "rotation"}}]}]}
)";
}

double distance(const Affine& a, const Affine& b) {
  double d = 0.0;
  for (int k = 0; k < 9; ++k) d = std::max(d, std::fabs(a.A[k] - b.A[k]));
  for (int i = 0; i < 3; ++i) d = std::max(d, std::fabs(a.t[i] - b.t[i]));
  return d;
}

Affine turn_z(double degrees, std::array<double, 3> t) {
  Affine a;
  const double c = std::cos(degrees * M_PI / 180.0), s = std::sin(degrees * M_PI / 180.0);
  a.A(0, 0) = c;
  a.A(0, 1) = -s;
  a.A(1, 0) = s;
  a.A(1, 1) = c;
  a.t = t;
  return a;
}

}  // namespace

TEST(RigFile, AClipIsSampledBetweenKeysBySlerpAndComposedDownTheHierarchy) {
  const RigFile rig = read_rig_file(write_file("bend.gltf", two_joint_gltf(90.0)));
  const int child = rig.node_index("child"), tip = rig.node_index("tip");
  ASSERT_GE(child, 0);
  ASSERT_GE(tip, 0);
  ASSERT_EQ(rig.clips.size(), 1u);
  const RigClip& clip = rig.clips[0];
  EXPECT_NEAR(clip.duration, 1.0, 1e-9);
  // Slerp turns at a constant rate: 22.5 degrees at a quarter (normalized linear interpolation of the
  // quaternions would give 22.2), 45 at half; held after the last key. Keys are floats: 1e-6.
  for (const auto& [t, deg] : std::vector<std::pair<double, double>>{{0.0, 0.0}, {0.25, 22.5}, {0.5, 45.0}, {1.0, 90.0}, {2.0, 90.0}}) {
    EXPECT_LT(distance(rig.world(child, &clip, t), turn_z(deg, {1, 0, 0})), 1e-6) << "child at t = " << t;
    // The tip moves with its parent: its origin at (1, 0, 0) + R (1, 0, 0).
    const double r = deg * M_PI / 180.0;
    EXPECT_LT(distance(rig.world(tip, &clip, t), turn_z(deg, {1 + std::cos(r), std::sin(r), 0})), 1e-6) << "tip at t = " << t;
  }
  // The rest pose: no turn.
  EXPECT_LT(distance(rig.world(tip, nullptr, 0.0), turn_z(0.0, {2, 0, 0})), 1e-12);
}

TEST(RigFile, AProductionCharacterIsReadWithItsJointsWeightsAndClip) {
  ASSERT_TRUE(std::filesystem::exists(kEpileptic)) << kEpileptic << " is missing: scripts/deps.sh installs assimp-testmodels";
  const RigFile rig = read_rig_file(kEpileptic);
  ASSERT_EQ(rig.meshes.size(), 3u);
  long long joints = 0;
  for (const auto& n : rig.nodes) joints += n.joint;
  EXPECT_EQ(joints, 54);
  ASSERT_EQ(rig.clips.size(), 1u);
  EXPECT_NEAR(rig.clips[0].duration, 3.3, 1e-9);
  std::printf("[ info ] %s", describe(rig).substr(0, describe(rig).find('\n') + 1).c_str());
  for (std::size_t m = 0; m < rig.meshes.size(); ++m) {
    const RigMesh& mesh = rig.meshes[m];
    // Every vertex held by bones whose weights sum to 1.
    std::vector<double> total(mesh.vertices.size(), 0.0);
    for (const auto& b : mesh.bones)
      for (const auto& [v, w] : b.weights) total[v] += w;
    for (std::size_t v = 0; v < total.size(); ++v) ASSERT_NEAR(total[v], 1.0, 1e-12) << mesh.name << " vertex " << v;
    // The bind pose skins back to the vertices as stored: every bone's world transform at rest times
    // its inverse bind matrix is the identity (a wrong row/column order, a parent missed in the
    // composition or a wrong offset matrix would not give this back). The node holding a skinned mesh
    // does not move it (glTF says so; Assimp's importers follow).
    const auto bound = rig.skin(static_cast<int>(m), nullptr, 0.0);
    double err = 0.0, size = 0.0;
    for (std::size_t v = 0; v < bound.size(); ++v)
      for (int i = 0; i < 3; ++i) {
        err = std::max(err, std::fabs(bound[v][i] - mesh.vertices[v][i]));
        size = std::max(size, std::fabs(mesh.vertices[v][i]));
      }
    EXPECT_LT(err, 1e-5 * size) << mesh.name;
    // The clip moves the skin, and by no more than the body's size.
    const auto moved = rig.skin(static_cast<int>(m), &rig.clips[0], 1.65);
    double most = 0.0;
    for (std::size_t v = 0; v < moved.size(); ++v)
      for (int i = 0; i < 3; ++i) most = std::max(most, std::fabs(moved[v][i] - bound[v][i]));
    EXPECT_GT(most, 1e-3 * size) << mesh.name;
    EXPECT_LT(most, 2.0 * size) << mesh.name;
    std::printf("[ info ] %s: bind pose skinned back to %.1e of its size %.3g; at 1.65 s vertices moved up to %.3g\n",
                mesh.name.c_str(), err / size, size, most);
  }
  // At a key's time an animated node's local transform (its world transform relative to its parent's)
  // carries the key's translation.
  const RigClip& clip = rig.clips[0];
  int checked = 0;
  for (const auto& ch : clip.channels) {
    if (ch.translation.empty() || rig.nodes[ch.node].parent < 0) continue;
    const auto& [t, v] = ch.translation.back();
    const Affine W = rig.world(ch.node, &clip, t), P = rig.world(rig.nodes[ch.node].parent, &clip, t);
    // local translation = P^-1 (W.t - P.t)
    const Mat3& A = P.A;
    const double d = det(A);
    ASSERT_GT(std::fabs(d), 1e-12);
    const std::array<double, 3> r{W.t[0] - P.t[0], W.t[1] - P.t[1], W.t[2] - P.t[2]};
    for (int i = 0; i < 3; ++i) {
      Mat3 Ai = A;  // Cramer's rule
      for (int k = 0; k < 3; ++k) Ai(k, i) = r[k];
      EXPECT_NEAR(det(Ai) / d, v[i], 1e-6 * (1 + std::fabs(v[i]))) << rig.nodes[ch.node].name;
    }
    if (++checked == 10) break;
  }
  EXPECT_EQ(checked, 10);
}

TEST(RigFile, BrokenFilesAreNamed) {
  auto message = [](const std::string& path) {
    try {
      read_rig_file(path);
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string("(accepted)");
  };
  EXPECT_NE(message("test_results/rig/none.gltf").find("cannot open the rig file"), std::string::npos);
  EXPECT_NE(message(write_file("garbage.gltf", "{ this is not json")).find("Assimp cannot read it"), std::string::npos);
  const std::string nan = message(write_file("nan.gltf", two_joint_gltf(90.0, std::nanf(""))));
  EXPECT_NE(nan.find("clip 'bend', node 'child': rotation key 1 is not a rotation"), std::string::npos) << nan;
}

TEST(RigFile, AMotionCaptureIsRetargetedByJointNames) {
  // A BVH written here, ten times the rig's size and with other joint names: 'hip' slides 2 along x and
  // 'knee' turns 90 degrees about z over 1 s. Carried onto the glTF rig (root, child, tip) by
  // "hip:root, knee:child" from the rig's pose at 0.5 s of its own clip (the child already turned 45
  // degrees): the child turns in the world by the knee's turn on top of its reference, the root slides
  // by the knee's slide times the ratio of heights (1/10), and the unmapped tip follows its parent.
  const std::string bvh = write_file("slide_bend.bvh", R"(HIERARCHY
ROOT hip
{
  OFFSET 0 0 0
  CHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation
  JOINT knee
  {
    OFFSET 10 0 0
    CHANNELS 3 Zrotation Xrotation Yrotation
    End Site
    {
      OFFSET 10 0 0
    }
  }
}
MOTION
Frames: 2
Frame Time: 1.0
0 0 0 0 0 0 0 0 0
2 0 0 0 0 0 90 0 0
)");
  const RigFile source = read_rig_file(bvh), rig = read_rig_file(write_file("bend_target.gltf", two_joint_gltf(90.0)));
  ASSERT_EQ(source.clips.size(), 1u);
  EXPECT_NEAR(source.clips[0].duration, 1.0, 1e-9);
  const std::vector<Affine> reference = rig.pose(&rig.clips[0], 0.5);
  const Retarget retarget(rig, reference, source, source.clips[0], 0.0, Retarget::parse_map(" hip : root,knee:child "), 0.0);
  EXPECT_NEAR(retarget.scale(), 0.1, 1e-12);
  const int root = rig.node_index("root"), child = rig.node_index("child"), tip = rig.node_index("tip");
  for (double t : {0.0, 0.5, 1.0}) {
    const std::vector<Affine> W = retarget.pose(t);
    const double deg = 45.0 + 90.0 * t, r = deg * M_PI / 180.0, slide = 0.2 * t;
    EXPECT_LT(distance(W[root], turn_z(0.0, {slide, 0, 0})), 1e-6) << "root at t = " << t;
    EXPECT_LT(distance(W[child], turn_z(deg, {slide + 1, 0, 0})), 1e-6) << "child at t = " << t;
    EXPECT_LT(distance(W[tip], turn_z(deg, {slide + 1 + std::cos(r), std::sin(r), 0})), 1e-6) << "tip at t = " << t;
  }
  // At the source's reference time the rig stands exactly in its reference pose.
  const std::vector<Affine> W0 = retarget.pose(0.0);
  for (std::size_t n = 0; n < rig.nodes.size(); ++n) EXPECT_LT(distance(W0[n], reference[n]), 1e-12) << rig.nodes[n].name;
  // A given scale replaces the ratio of heights.
  EXPECT_LT(distance(Retarget(rig, reference, source, source.clips[0], 0.0, {{"hip", "root"}}, 0.5).pose(1.0)[root], turn_z(0.0, {1.0, 0, 0})), 1e-6);
  // Names the files do not have, a joint mapped twice, a malformed pair: named.
  auto message = [&](const std::string& map) {
    try {
      Retarget(rig, reference, source, source.clips[0], 0.0, Retarget::parse_map(map), 0.0);
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string("(accepted)");
  };
  EXPECT_NE(message("Hips:root").find("has no joint 'Hips' (it has 'hip'"), std::string::npos) << message("Hips:root");
  EXPECT_NE(message("hip:Root").find("has no joint 'Root' (it has"), std::string::npos) << message("hip:Root");
  EXPECT_NE(message("hip:root, knee:root").find("the rig's joint 'root' is mapped twice"), std::string::npos);
  EXPECT_NE(message("hip root").find("'hip root' is not 'source joint:rig joint'"), std::string::npos) << message("hip root");
  EXPECT_NE(message(" , ").find("maps no joint"), std::string::npos);
}

TEST(RigFile, TheFastWindingNumberAgreesWithTheExactSumOnAnOpenSkin) {
  // BCN's skin (three open pieces, 46 open edges): the hierarchical winding number against the sum of
  // every triangle's solid angle at the centres of a 4 cm lattice around the body and at points 3 mm
  // off the skin on both sides of every 7th triangle (where near subtrees must be summed exactly).
  const TriangleSurface skin = rig_surface(read_rig_file(kEpileptic), "");
  const FastWindingNumber fast(skin);
  std::vector<std::array<double, 3>> points;
  const double h = 0.04;
  for (double x = skin.lower[0] - h; x < skin.upper[0] + h; x += h)
    for (double y = skin.lower[1] - h; y < skin.upper[1] + h; y += h)
      for (double z = skin.lower[2] - h; z < skin.upper[2] + h; z += h) points.push_back({x, y, z});
  const std::size_t lattice = points.size();
  for (std::size_t t = 0; t < skin.triangles.size(); t += 7) {
    const auto &a = skin.vertices[skin.triangles[t][0]], &b = skin.vertices[skin.triangles[t][1]], &c = skin.vertices[skin.triangles[t][2]];
    std::array<double, 3> n{(b[1] - a[1]) * (c[2] - a[2]) - (b[2] - a[2]) * (c[1] - a[1]), (b[2] - a[2]) * (c[0] - a[0]) - (b[0] - a[0]) * (c[2] - a[2]),
                            (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0])};
    const double l = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
    if (!(l > 0.0)) continue;
    for (double side : {-0.003, 0.003})
      points.push_back({(a[0] + b[0] + c[0]) / 3 + side * n[0] / l, (a[1] + b[1] + c[1]) / 3 + side * n[1] / l, (a[2] + b[2] + c[2]) / 3 + side * n[2] / l});
  }
  const FastWindingNumber finer(skin, 6.0);
  double worst = 0.0, worst_finer = 0.0;
  std::size_t inside = 0, disagree = 0;
  for (const auto& p : points) {
    const double exact = winding_number(skin, p), approx = fast(p);
    worst = std::max(worst, std::fabs(exact - approx));
    worst_finer = std::max(worst_finer, std::fabs(exact - finer(p)));
    inside += exact > 0.5;
    disagree += (exact > 0.5) != (approx > 0.5);
  }
  // The default (beta = 3) is within 0.02 of the exact sum (measured 1.6e-2 at 3 mm off the skin);
  // at beta = 6 the error falls about as the expansion's third-order remainder, (6/3)^3 (1.0e-3).
  EXPECT_LT(worst, 0.02);
  EXPECT_LT(worst_finer, 0.2 * worst);
  EXPECT_EQ(disagree, 0u);
  EXPECT_GT(inside, points.size() / 10);  // the test sees both sides
  std::printf("[ info ] fast winding number on %zu triangles at %zu points (%zu lattice, %zu inside): largest difference %.1e "
              "(%.1e at beta = 6)\n",
              skin.triangles.size(), points.size(), lattice, inside, worst, worst_finer);
}

namespace {

// A scene on Debian's rigged human: its skin filled with cells of `cell`, bones from its joints (by
// default from the skin weights); `skeleton` adds Skeleton entries, `rest` whole sections (Loading,
// Solver, Output).
std::string rig_scene(const std::string& name, double cell, const std::string& skeleton, const std::string& rest = "") {
  return std::string(R"x(<ParameterList name="Sinew">
  <Parameter name="Scene" type="string" value=")x") + name + R"x("/>
  <ParameterList name="Mesh">
    <Parameter name="Type" type="string" value="rig"/>
    <Parameter name="Rig" type="string" value=")x" + kEpileptic + R"x("/>
    <Parameter name="Cell size" type="double" value=")x" + std::to_string(cell) + R"x("/>
  </ParameterList>
  <ParameterList name="Material">
    <Parameter name="Model" type="string" value="stable-neohookean"/>
    <Parameter name="Young modulus" type="double" value="2.0e4"/>
    <Parameter name="Poisson ratio" type="double" value="0.45"/>
  </ParameterList>
  <ParameterList name="Skeleton">
    <Parameter name="Rig" type="string" value=")x" + kEpileptic + R"x("/>)x" + skeleton + R"x(
  </ParameterList>)x" + rest + R"x(
</ParameterList>)x";
}

}  // namespace

namespace {

// The rotation nearest to A: A (A^T A)^(-1/2), from the eigen-decomposition of A^T A.
Mat3 polar(const Mat3& A) {
  const Mat3 S = transpose(A) * A;
  double M[9], ev[3], Q[9];
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) M[3 * i + j] = S(i, j);
  jacobi_eigen<3>(M, ev, Q);
  Mat3 inv_sqrt;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) {
      double v = 0.0;
      for (int k = 0; k < 3; ++k) v += Q[3 * i + k] * Q[3 * j + k] / std::sqrt(ev[k]);
      inv_sqrt(i, j) = v;
    }
  return A * inv_sqrt;
}


// After a run: how far the bone nodes are from where their joints' motion from `rest` to `posed`
// puts them, that motion recomputed here (world posed after world at rest inverted, its rotation part
// by the polar decomposition, about the joint's origin); `moved`: the largest bone displacement.
double bone_error(Simulation& sim, const RigFile& rig, const std::vector<Affine>& rest, const std::vector<Affine>& posed,
                  double& moved) {
  const Mesh& mesh = sim.scene().system().mesh();
  const Skeleton& skeleton = sim.scene().skeleton();
  auto X = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), mesh.X);
  auto u = sim.displacement().getLocalViewHost(Tpetra::Access::ReadOnly);
  double err = 0.0;
  moved = 0.0;
  for (std::size_t b = 0; b < skeleton.size(); ++b) {
    const int j = rig.node_index(skeleton.name(b));
    // D = posed[j] o rest[j]^-1: D.A = posed.A rest.A^-1, D(x) = posed(rest^-1(x)); rest transforms of
    // this file are rotations (checked by AProductionCharacterIsReadWithItsJointsWeightsAndClip).
    const Mat3 R = polar(posed[j].A * transpose(rest[j].A));
    const auto origin = rest[j].t, c = posed[j].t;  // the joint's origin, at rest and posed
    for (int n : skeleton.nodes(b)) {
      if (static_cast<std::size_t>(n) >= mesh.n_owned_nodes) continue;
      for (int i = 0; i < 3; ++i) {
        double y = c[i];
        for (int k = 0; k < 3; ++k) y += R(i, k) * (X(n, k) - origin[k]);
        err = std::max(err, std::fabs(X(n, i) + u(3 * n + i, 0) - y));
        moved = std::max(moved, std::fabs(u(3 * n + i, 0)));
      }
    }
  }
  return err;
}

}  // namespace

TEST(RigScene, TheSkinIsFilledAndEachJointMovesTheNodesNearestToIt) {
  // Debian's rigged human: its three open skin pieces filled by the winding number at 3 cm, bones from
  // its 54 joints as 3 cm capsules, 0.1 s of its clip in one step.
  const std::string xml = rig_scene("rig", 0.03, R"x(<Parameter name="Clip end" type="double" value="0.1"/>
    <Parameter name="Bone regions" type="string" value="capsules"/>
    <Parameter name="Bone radius" type="double" value="0.03"/>)x",
                                     R"x(<ParameterList name="Loading"><Parameter name="Steps" type="int" value="1"/></ParameterList>
  <ParameterList name="Solver"><Parameter name="Absolute tolerance" type="double" value="1.0e-4"/></ParameterList>
  <ParameterList name="Output"><Parameter name="HDF5" type="bool" value="false"/><Parameter name="Checkpoint every" type="int" value="0"/></ParameterList>)x");
  Simulation sim(test::config(xml, "test_results/rig/scene"), RunOptions{true, ""});
  const Mesh& mesh = sim.scene().system().mesh();
  const Skeleton& skeleton = sim.scene().skeleton();
  const RigFile rig = read_rig_file(kEpileptic);
  // The lattice holds the body: its volume against the skin's (the divergence theorem over the
  // outward soup, its gaps included) within 10%.
  const TriangleSurface skin = rig_surface(rig, "");
  double enclosed = 0.0;
  for (const auto& T : skin.triangles) {
    const auto &a = skin.vertices[T[0]], &b = skin.vertices[T[1]], &c = skin.vertices[T[2]];
    enclosed += (a[0] * (b[1] * c[2] - b[2] * c[1]) - a[1] * (b[0] * c[2] - b[2] * c[0]) + a[2] * (b[0] * c[1] - b[1] * c[0])) / 6.0;
  }
  const double lattice = static_cast<double>(mesh.global_elements) * 0.03 * 0.03 * 0.03;
  EXPECT_NEAR(lattice / enclosed, 1.0, 0.1);
  // Each bone holds exactly the nodes within 3 cm of its joint's capsule that are nearest to it.
  const auto rest = rig.pose(nullptr, 0.0);
  std::map<std::string, std::pair<std::array<double, 3>, std::array<double, 3>>> capsule;
  for (std::size_t n = 0; n < rig.nodes.size(); ++n) {
    if (!rig.nodes[n].joint) continue;
    auto& c = capsule[rig.nodes[n].name];
    c = {rest[n].t, rest[n].t};
    for (std::size_t k = n + 1; k < rig.nodes.size(); ++k)
      if (rig.nodes[k].parent == static_cast<int>(n) && rig.nodes[k].joint) {
        c.second = rest[k].t;
        break;
      }
  }
  auto X = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), mesh.X);
  // (Ties, at a joint shared by a parent's capsule and a child's, may go either way.)
  std::vector<double> nearest(mesh.local_nodes(), HUGE_VAL);
  auto at = [&](std::size_t n) { return std::array<double, 3>{X(n, 0), X(n, 1), X(n, 2)}; };
  for (std::size_t n = 0; n < mesh.local_nodes(); ++n)
    for (const auto& [name, c] : capsule) nearest[n] = std::min(nearest[n], segment_distance(at(n).data(), c.first, c.second));
  std::size_t held = 0;
  for (std::size_t b = 0; b < skeleton.size(); ++b) {
    const auto& c = capsule.at(skeleton.name(b));
    for (int n : skeleton.nodes(b)) {
      const double d = segment_distance(at(n).data(), c.first, c.second);
      EXPECT_LE(d, 0.03) << "node " << n << " of " << skeleton.name(b);
      EXPECT_NEAR(d, nearest[n], 1e-12) << "node " << n << " is nearer to another joint than to " << skeleton.name(b);
    }
    held += skeleton.nodes(b).size();
  }
  EXPECT_EQ(held, static_cast<std::size_t>(std::count_if(nearest.begin(), nearest.end(), [](double d) { return d <= 0.03; })));
  EXPECT_EQ(skeleton.size() + skeleton.unused_joints(), 54u);
  EXPECT_LT(skeleton.nonrigid(), 1e-4);  // the file's joints turn without scaling (to its float precision)

  // The run: every bone node ends where its joint's motion over 0.1 s of the clip puts it, that motion
  // recomputed here (world at 0.1 s after world at rest inverted, its rotation part by the polar
  // decomposition, about the joint's origin).
  ASSERT_EQ(sim.run(), 0);
  double moved = 0.0;
  const double err = bone_error(sim, rig, rest, rig.pose(&rig.clips[0], 0.1), moved);
  EXPECT_LT(err, 1e-9);
  EXPECT_GT(moved, 1e-3);
  std::printf("[ info ] rig: %lld cells (lattice %.4f m^3, skin %.4f), %zu bones (%d joints hold no node), non-rigidity %.1e; "
              "bone nodes vs the joints' motion: %.1e (moved up to %.3f)\n",
              static_cast<long long>(mesh.global_elements), lattice, enclosed, skeleton.size(), skeleton.unused_joints(),
              skeleton.nonrigid(), err, moved);
}

TEST(RigScene, BonesComeFromTheSkinWeightsAndLeaveTheFleshAroundEachJointFree) {
  // By default a joint is a bone where it dominates skin (the vertices whose largest weight is its
  // own), with a radius of half the median distance from its segment to that skin, and holds only the
  // nodes of the cylinder over its segment that leaves a gap at both ends, none within a cell of another
  // bone's; all recomputed here from the file. A joint listed in 'Skip joints' holds nothing.
  const std::string xml = rig_scene("rig_bones", 0.03, R"x(<Parameter name="Clip end" type="double" value="0.1"/>
    <Parameter name="Skip joints" type="string" value="B_Jaw, B_Neck"/>)x",
                                     R"x(<ParameterList name="Loading"><Parameter name="Steps" type="int" value="1"/></ParameterList>
  <ParameterList name="Output"><Parameter name="HDF5" type="bool" value="false"/><Parameter name="Checkpoint every" type="int" value="0"/></ParameterList>)x");
  Simulation sim(test::config(xml, "test_results/rig/bones"), RunOptions{true, ""});
  const Mesh& mesh = sim.scene().system().mesh();
  const Skeleton& skeleton = sim.scene().skeleton();
  const RigFile rig = read_rig_file(kEpileptic);
  // The dominated skin by brute force: per vertex of every mesh at rest, the joint of its largest weight.
  std::map<std::string, std::vector<std::array<double, 3>>> dominated;
  for (std::size_t m = 0; m < rig.meshes.size(); ++m) {
    const auto x = rig.skin(static_cast<int>(m), nullptr, 0.0);
    std::vector<double> best(x.size(), 0.0);
    std::vector<int> owner(x.size(), -1);
    for (const auto& bone : rig.meshes[m].bones)
      for (const auto& [v, w] : bone.weights)
        if (w > best[v]) {
          best[v] = w;
          owner[v] = bone.node;
        }
    for (std::size_t v = 0; v < x.size(); ++v)
      if (owner[v] >= 0) dominated[rig.nodes[owner[v]].name].push_back(x[v]);
  }
  auto X = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), mesh.X);
  std::map<std::string, std::size_t> bone_index;
  for (std::size_t b = 0; b < skeleton.size(); ++b) bone_index[skeleton.name(b)] = b;
  int bones = 0, skipped = 0, checked_nodes = 0, points = 0;
  for (const Skeleton::Joint& j : skeleton.joints()) {
    const auto& skin = dominated[j.name];
    EXPECT_EQ(j.dominated, static_cast<long long>(skin.size())) << j.name;
    if (j.name == "B_Jaw" || j.name == "B_Neck") {
      EXPECT_FALSE(j.bone) << j.name;
      EXPECT_NE(j.why.find("Skip joints"), std::string::npos) << j.why;
      ++skipped;
      continue;
    }
    // A region of one node would pull the flesh as a point load: no bone either.
    EXPECT_EQ(j.bone, !skin.empty() && j.nodes > 1) << j.name << ": " << j.why;
    if (!skin.empty() && j.nodes == 1) {
      EXPECT_NE(j.why.find("point load"), std::string::npos) << j.name << ": " << j.why;
      ++points;
    }
    EXPECT_EQ(j.bone, bone_index.count(j.name) == 1) << j.name;
    if (!j.bone) continue;
    ++bones;
    // Radius: 'Bone thickness' (its default) times the median distance of the dominated skin from the
    // segment; gap: the larger of a cell and the radius, at most 35% of the segment.
    std::vector<double> d;
    for (const auto& v : skin) d.push_back(segment_distance(v.data(), j.a, j.b));
    std::sort(d.begin(), d.end());
    EXPECT_NEAR(j.radius, SkeletonParameters{}.bone_thickness * d[d.size() / 2], 1e-12) << j.name;
    const double L = std::sqrt((j.b[0] - j.a[0]) * (j.b[0] - j.a[0]) + (j.b[1] - j.a[1]) * (j.b[1] - j.a[1]) +
                               (j.b[2] - j.a[2]) * (j.b[2] - j.a[2]));
    EXPECT_NEAR(j.gap, std::min(std::max(0.03, j.radius), 0.35 * L), 1e-12) << j.name;
    // The joint's origin is the rig's at rest.
    const auto origin = rig.pose(nullptr, 0.0)[rig.node_index(j.name)].t;
    for (int i = 0; i < 3; ++i) EXPECT_NEAR(j.a[i], origin[i], 1e-12);
    for (int n : skeleton.nodes(bone_index[j.name])) {
      double r[3], along = 0.0, perp2 = 0.0;
      for (int i = 0; i < 3; ++i) {
        r[i] = X(n, i) - j.a[i];
        along += r[i] * (j.b[i] - j.a[i]) / L;
      }
      for (int i = 0; i < 3; ++i) perp2 += std::pow(r[i] - along * (j.b[i] - j.a[i]) / L, 2);
      if (L > 2.0 * j.gap) {
        EXPECT_GE(along, j.gap - 1e-12) << "node " << n << " of " << j.name << " lies in the free flesh at its joint";
        EXPECT_LE(along, L - j.gap + 1e-12) << "node " << n << " of " << j.name << " lies in the free flesh at its end";
        EXPECT_LE(std::sqrt(perp2), j.radius + 1e-12) << "node " << n << " of " << j.name;
        ++checked_nodes;
      }
    }
  }
  EXPECT_EQ(skipped, 2);
  EXPECT_GE(bones, 15);  // limbs, spine and pelvis at least
  EXPECT_EQ(static_cast<int>(skeleton.size()), bones);
  EXPECT_EQ(skeleton.size() + skeleton.unused_joints(), 54u);
  // No lattice node within a cell of a limb's knee or elbow is held (the flesh there folds).
  for (const char* joint : {"B_Knee_Left", "B_Knee_Right", "B_ForeArm_Left", "B_ForeArm_Right"}) {
    const auto at = rig.pose(nullptr, 0.0)[rig.node_index(joint)].t;
    for (std::size_t b = 0; b < skeleton.size(); ++b)
      for (int n : skeleton.nodes(b)) {
        const double dist = std::sqrt(std::pow(X(n, 0) - at[0], 2) + std::pow(X(n, 1) - at[1], 2) + std::pow(X(n, 2) - at[2], 2));
        EXPECT_GT(dist, 0.03) << "node " << n << " of " << skeleton.name(b) << " at the joint " << joint;
      }
  }
  // No cell holds nodes of two bones: a free layer lies between any two bones' regions, side by side as
  // well as at a joint (else one bone turning past the other crushes the cell between them).
  std::vector<int> bone_of(mesh.local_nodes(), -1);
  for (std::size_t b = 0; b < skeleton.size(); ++b)
    for (int n : skeleton.nodes(b)) bone_of[n] = static_cast<int>(b);
  auto conn = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), mesh.conn);
  long long shared = 0;
  for (std::size_t e = 0; e < mesh.local_elements(); ++e) {
    int seen = -1;
    for (int a = 0; a < 8; ++a) {
      const int b = bone_of[conn(e, a)];
      if (b < 0) continue;
      if (seen >= 0 && b != seen) ++shared;
      seen = b;
    }
  }
  EXPECT_EQ(shared, 0);
  ASSERT_EQ(sim.run(), 0);
  double moved = 0.0;
  EXPECT_LT(bone_error(sim, rig, rig.pose(nullptr, 0.0), rig.pose(&rig.clips[0], 0.1), moved), 1e-9);
  std::printf("[ info ] bones from the skin weights: %d of 54 joints (%d nodes checked in their cylinders, %d joints of one "
              "node); listing:\n%s", bones, checked_nodes, points, skeleton.joint_listing().c_str());
}

// Two bones' regions side by side, a cell apart: one gives way, so that one free layer of nodes lies
// between their held nodes. The smaller region (by its nodes, `sizes`) frees its nodes next to the other's
// and the larger keeps all of its own; with no sizes, the later joint gives way. (When both gave way, a
// bar two cells thick held little of its flesh and inverted in its dynamic run.)
TEST(RigScene, WhereTwoBonesMeetTheSmallerRegionGivesWay) {
  MeshSpec spec;
  spec.cells = {8, 6, 2};
  spec.upper = {8.0, 6.0, 2.0};
  const Mesh mesh = build_mesh(spec, *Tpetra::getDefaultComm());
  Skeleton::JointSegments s;
  s.joints = {0, 1};
  s.a = {{{1.0, 1.5, 1.0}}, {{1.0, 3.5, 1.0}}};
  s.b = {{{7.0, 1.5, 1.0}}, {{7.0, 3.5, 1.0}}};
  s.radius = {1.2, 0.9};  // joint 0 takes three layers in z, joint 1 one
  s.gap = {0.0, 0.0};
  s.capped = {0, 0};
  s.candidate = {1, 1};
  s.why = {"", ""};
  s.dominated = {1, 1};
  const auto whole = Skeleton::region_nodes(mesh, s, 0.0);
  auto X = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), mesh.X);
  auto next_to = [&](int n, const std::vector<int>& region) {
    for (int m : region) {
      double d = 0.0;
      for (int i = 0; i < 3; ++i) d = std::max(d, std::fabs(X(n, i) - X(m, i)));
      if (d < 1.5) return true;
    }
    return false;
  };
  // The expected split: `keeper` keeps its region, the other frees what lies next to it.
  auto expect_split = [&](const std::vector<std::vector<int>>& held, int keeper, const char* what) {
    const int other = 1 - keeper;
    EXPECT_EQ(held[keeper], whole[keeper]) << what;
    std::vector<int> expect;
    for (int n : whole[other])
      if (!next_to(n, whole[keeper])) expect.push_back(n);
    EXPECT_EQ(held[other], expect) << what;
    EXPECT_LT(held[other].size(), whole[other].size()) << what << ": nothing was next to the other bone";
    EXPECT_FALSE(held[other].empty()) << what;
  };
  ASSERT_FALSE(whole[0].empty());
  ASSERT_FALSE(whole[1].empty());
  const std::vector<long long> sizes{3, 1}, swapped{1, 3};
  expect_split(Skeleton::region_nodes(mesh, s, 1.0, &sizes), 0, "joint 1 is smaller");
  expect_split(Skeleton::region_nodes(mesh, s, 1.0, &swapped), 1, "joint 0 is smaller");
  expect_split(Skeleton::region_nodes(mesh, s, 1.0), 0, "no sizes: the later joint gives way");
}

TEST(RigScene, AJointThatIsNoneOfTheRigsIsNamed) {
  const std::string xml = rig_scene("rig_skip", 0.04, R"x(<Parameter name="Skip joints" type="string" value="B_Knee_Lefd"/>)x");
  try {
    Simulation sim(test::config(xml, "test_results/rig/skip"), RunOptions{true, ""});
    FAIL() << "a joint name that is not in the file was accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("'Skip joints': \"B_Knee_Lefd\" is not a joint"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("did you mean \"B_Knee_Left\""), std::string::npos) << e.what();
  }
}

TEST(RigScene, TheFilesSkinWeightsCanGuideTheFirstGuess) {
  // With 'Rig skinning weights', a node's skinning weights are those of the nearest skin vertex at rest
  // (over the joints that became bones, renormalized), found here by brute force.
  const std::string xml = rig_scene("rig_weights", 0.04, R"x(<Parameter name="Rig skinning weights" type="bool" value="true"/>)x");
  Simulation sim(test::config(xml, "test_results/rig/weights"), RunOptions{true, ""});
  const Mesh& mesh = sim.scene().system().mesh();
  const Skeleton& skeleton = sim.scene().skeleton();
  const RigFile rig = read_rig_file(kEpileptic);
  std::map<std::string, int> bone;
  for (std::size_t b = 0; b < skeleton.size(); ++b) bone[skeleton.name(b)] = static_cast<int>(b);
  auto X = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), mesh.X);
  int checked = 0;
  for (std::size_t n = 0; n < mesh.n_owned_nodes; n += 97) {
    double best = HUGE_VAL;
    std::map<int, double> expect;
    for (std::size_t m = 0; m < rig.meshes.size(); ++m) {
      const auto x = rig.skin(static_cast<int>(m), nullptr, 0.0);
      for (std::size_t v = 0; v < x.size(); ++v) {
        std::map<int, double> w;
        for (const auto& b : rig.meshes[m].bones) {
          const auto it = bone.find(rig.nodes[b.node].name);
          if (it == bone.end()) continue;
          for (const auto& [vv, wt] : b.weights)
            if (vv == static_cast<int>(v)) w[it->second] += wt;
        }
        if (w.empty()) continue;
        const double d = std::pow(x[v][0] - X(n, 0), 2) + std::pow(x[v][1] - X(n, 1), 2) + std::pow(x[v][2] - X(n, 2), 2);
        if (d < best) {
          best = d;
          expect = w;
        }
      }
    }
    double total = 0.0;
    for (const auto& [b, w] : expect) total += w;
    std::map<int, double> got;
    for (const auto& [b, w] : skeleton.weights(n)) got[b] += w;
    ASSERT_EQ(got.size(), expect.size()) << "node " << n;
    for (const auto& [b, w] : expect) EXPECT_NEAR(got[b], w / total, 1e-12) << "node " << n << ", bone " << skeleton.name(b);
    ++checked;
  }
  EXPECT_GT(checked, 10);
}

TEST(RigScene, ARestTimeVoxelizesTheSkinAndStartsTheBonesInThatPose) {
  // At 0.8 s of the clip the arms are away from the body: the skin is filled in that pose, and with
  // the clip starting there every bone is at rest at load 0.
  const std::string xml = rig_scene("rig_rest", 0.04, R"x(<Parameter name="Rest time" type="double" value="0.8"/>
    <Parameter name="Clip start" type="double" value="0.8"/>
    <Parameter name="Clip end" type="double" value="1.2"/>)x");
  Simulation sim(test::config(xml, "test_results/rig/rest"), RunOptions{true, ""});
  const Mesh& mesh = sim.scene().system().mesh();
  const RigFile rig = read_rig_file(kEpileptic);
  // The lattice lies where the skin is at 0.8 s, not at the bind pose: its box against both.
  const TriangleSurface posed = rig_surface(rig, "", &rig.clips[0], 0.8), bind = rig_surface(rig, "");
  double off_posed = 0.0, off_bind = 0.0;
  for (int d = 0; d < 3; ++d) {
    off_posed = std::max({off_posed, std::fabs(mesh.lower[d] - posed.lower[d]), std::fabs(mesh.upper[d] - posed.upper[d])});
    off_bind = std::max({off_bind, std::fabs(mesh.lower[d] - bind.lower[d]), std::fabs(mesh.upper[d] - bind.upper[d])});
  }
  EXPECT_LT(off_posed, 0.1);  // within about two cells (thin fingers and toes may have no cell)
  EXPECT_GT(off_bind, 0.2);   // the raised arms are far outside the bind pose's box
  const Skeleton& skeleton = sim.scene().skeleton();
  double still = 0.0;
  for (std::size_t b = 0; b < skeleton.size(); ++b) {
    const Rigid T = skeleton.transform(b, 0.0);
    for (int k = 0; k < 9; ++k) still = std::max(still, std::fabs(T.R[k] - (k % 4 == 0 ? 1.0 : 0.0)));
    for (int i = 0; i < 3; ++i) still = std::max(still, std::fabs(T.t[i]));
  }
  EXPECT_LT(still, 1e-12);
  EXPECT_EQ(sim.scene().run_up_steps(), 0);  // the clip starts at rest: nothing to run up
  std::printf("[ info ] rest at 0.8 s: lattice box off the posed skin's by %.3f, the bind pose's by %.3f; bones at load 0 off rest by %.1e\n",
              off_posed, off_bind, still);
}

TEST(RigScene, ARunUpCarriesTheBonesFromTheRestPoseToTheClipsStart) {
  // The rest pose at 0.8 s of the clip, the clip from 1.0 s: before step 1 the bones turn from rest to
  // their pose at 1.0 s over one run-up step per 15 degrees of the largest turn (recomputed here from
  // the file), each about its centre along the shorter arc; then the clip runs as usual.
  const std::string xml = rig_scene("rig_run_up", 0.04, R"x(<Parameter name="Rest time" type="double" value="0.8"/>
    <Parameter name="Clip start" type="double" value="1.0"/>
    <Parameter name="Clip end" type="double" value="1.02"/>)x",
                                     R"x(<ParameterList name="Loading"><Parameter name="Steps" type="int" value="1"/></ParameterList>
  <ParameterList name="Output"><Parameter name="HDF5" type="bool" value="false"/><Parameter name="Checkpoint every" type="int" value="0"/></ParameterList>)x");
  Simulation sim(test::config(xml, "test_results/rig/run_up"), RunOptions{true, ""});
  Scene& scene = sim.scene();
  const Skeleton& skeleton = scene.skeleton();
  const RigFile rig = read_rig_file(kEpileptic);
  const auto rest = rig.pose(&rig.clips[0], 0.8), start = rig.pose(&rig.clips[0], 1.0);
  double largest = 0.0;
  for (std::size_t b = 0; b < skeleton.size(); ++b) {
    const int j = rig.node_index(skeleton.name(b));
    const Mat3 R = polar(start[j].A * transpose(rest[j].A));
    largest = std::max(largest, std::acos(std::clamp(0.5 * (R(0, 0) + R(1, 1) + R(2, 2) - 1.0), -1.0, 1.0)));
  }
  EXPECT_NEAR(skeleton.largest_start_rotation(), largest, 1e-5);
  EXPECT_GT(largest, 15.0 * M_PI / 180.0);  // this start is no small step from rest
  EXPECT_EQ(scene.run_up_steps(), std::min(10, static_cast<int>(std::ceil(largest / (15.0 * M_PI / 180.0)))));
  // Along the run-up: rest at s = 0, half the turn about the bone's centre at s = 1/2, the pose at load
  // 0 at s = 1 (and once the run-up is done).
  double at_rest = 0.0, halfway = 0.0, at_start = 0.0;
  for (std::size_t b = 0; b < skeleton.size(); ++b) {
    const Rigid T = skeleton.transform(b, 0.0);
    scene.set_run_up(0.0);
    const Rigid P0 = skeleton.transform(b, 0.0);
    scene.set_run_up(0.5);
    const Rigid P = skeleton.transform(b, 0.0);
    scene.set_run_up(1.0);
    for (int k = 0; k < 9; ++k) at_rest = std::max(at_rest, std::fabs(P0.R[k] - (k % 4 == 0 ? 1.0 : 0.0)));
    for (int i = 0; i < 3; ++i) at_rest = std::max(at_rest, std::fabs(P0.t[i]));
    // Twice the half turn is the whole turn, and a point moves along the chord's middle.
    const Mat3 twice = P.R * P.R;
    for (int k = 0; k < 9; ++k) halfway = std::max(halfway, std::fabs(twice[k] - T.R[k]));
    const auto& n = skeleton.nodes(b);
    auto X = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), scene.system().mesh().X);
    std::array<double, 3> c{0.0, 0.0, 0.0};  // the bone's centre: the mean of its nodes (owned: one rank here)
    for (int nd : n)
      for (int i = 0; i < 3; ++i) c[i] += X(nd, i) / static_cast<double>(n.size());
    const auto Pc = P.apply(c), Tc = T.apply(c);
    for (int i = 0; i < 3; ++i) halfway = std::max(halfway, std::fabs(Pc[i] - 0.5 * (c[i] + Tc[i])));
    at_start = std::max(at_start, std::fabs(skeleton.transform(b, 0.0).t[0] - T.t[0]));
  }
  EXPECT_LT(at_rest, 1e-12);
  EXPECT_LT(halfway, 1e-9);
  EXPECT_EQ(at_start, 0.0);
  // The run: the bones end where the clip puts them at 1.02 s, from rest at 0.8 s.
  ASSERT_EQ(sim.run(), 0);
  double moved = 0.0;
  EXPECT_LT(bone_error(sim, rig, rest, rig.pose(&rig.clips[0], 1.02), moved), 1e-9);
  std::printf("[ info ] run-up: %d steps for a largest turn of %.1f degrees; halfway off by %.1e; step 1: %d Newton\n",
              scene.run_up_steps(), largest * 180.0 / M_PI, halfway, sim.records().at(0).solve.newton_iterations);
}

TEST(RigScene, TheBonesPeakSpeedIsTheFastestHeldNodeBetweenSamples) {
  // What a dynamic rig run prints beside the flesh's shear-wave speed: the fastest a held node moves
  // between consecutive samples of the motion, and the largest second difference. Recomputed here from
  // the bones' public transforms; a motion twice as long halves the speed and quarters the acceleration.
  const std::string xml = rig_scene("rig_speed", 0.04, R"x(<Parameter name="Clip start" type="double" value="1.0"/>
    <Parameter name="Clip end" type="double" value="1.5"/>)x",
                                     R"x(<ParameterList name="Output"><Parameter name="HDF5" type="bool" value="false"/><Parameter name="Checkpoint every" type="int" value="0"/></ParameterList>)x");
  Simulation sim(test::config(xml, "test_results/rig/speed"), RunOptions{true, ""});
  Scene& scene = sim.scene();
  scene.set_run_up(1.0);
  const Skeleton& skeleton = scene.skeleton();
  const Mesh& mesh = scene.system().mesh();
  const auto& comm = *Tpetra::getDefaultComm();
  const int samples = 12;
  const double seconds = 0.5, dt = seconds / samples;
  const Skeleton::PeakSpeed p = skeleton.peak_speed(mesh, comm, samples, seconds);
  auto X = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), mesh.X);
  double speed = 0.0, acceleration = 0.0;
  int at = 0;
  std::string bone;
  for (std::size_t b = 0; b < skeleton.size(); ++b)
    for (int k = 1; k <= samples; ++k) {
      const Rigid T0 = skeleton.transform(b, (k - 1.0) / samples), T1 = skeleton.transform(b, static_cast<double>(k) / samples);
      const Rigid Tm = k >= 2 ? skeleton.transform(b, (k - 2.0) / samples) : T0;
      for (int n : skeleton.nodes(b)) {
        if (static_cast<std::size_t>(n) >= mesh.n_owned_nodes) continue;
        const std::array<double, 3> x{X(n, 0), X(n, 1), X(n, 2)};
        const auto a = T1.apply(x), b0 = T0.apply(x), c = Tm.apply(x);
        double d = 0.0, dd = 0.0;
        for (int i = 0; i < 3; ++i) {
          d += (a[i] - b0[i]) * (a[i] - b0[i]);
          dd += (a[i] - 2.0 * b0[i] + c[i]) * (a[i] - 2.0 * b0[i] + c[i]);
        }
        if (std::sqrt(d) / dt > speed) {
          speed = std::sqrt(d) / dt;
          at = k;
          bone = skeleton.name(b);
        }
        if (k >= 2) acceleration = std::max(acceleration, std::sqrt(dd) / (dt * dt));
      }
    }
  MPI_Allreduce(MPI_IN_PLACE, &speed, 1, MPI_DOUBLE, MPI_MAX, MPI_COMM_WORLD);
  MPI_Allreduce(MPI_IN_PLACE, &acceleration, 1, MPI_DOUBLE, MPI_MAX, MPI_COMM_WORLD);
  EXPECT_GT(speed, 0.1);  // the clip's half second moves the hands
  EXPECT_NEAR(p.speed, speed, 1e-9 * speed);
  EXPECT_NEAR(p.acceleration, acceleration, 1e-9 * acceleration);
  if (comm.getSize() == 1) {
    EXPECT_EQ(p.sample, at);
    EXPECT_EQ(p.bone, bone);
  }
  const Skeleton::PeakSpeed slow = skeleton.peak_speed(mesh, comm, samples, 2.0 * seconds);
  EXPECT_NEAR(slow.speed, 0.5 * p.speed, 1e-9 * p.speed);
  EXPECT_NEAR(slow.acceleration, 0.25 * p.acceleration, 1e-9 * p.acceleration);
  std::printf("[ info ] peak bone speed %.3g m/s ('%s', sample %d), acceleration %.3g m/s^2\n", p.speed, p.bone.c_str(), p.sample,
              p.acceleration);
}

TEST(RigScene, TheFilesOwnSkinIsWrittenBesideTheSimulatedOne) {
  // lbs_NNNNNN.obj: the file's linear-blend skin at the clip's time of each step, with the topology of
  // the simulated skin_NNNNNN.obj (an artist loads either as a cache of the same mesh).
  const std::string out = "test_results/rig/lbs";
  const std::string xml = rig_scene("rig_lbs", 0.04, R"x(<Parameter name="Rest time" type="double" value="0.8"/>
    <Parameter name="Clip start" type="double" value="0.8"/>
    <Parameter name="Clip end" type="double" value="0.9"/>)x",
                                     R"x(<ParameterList name="Loading"><Parameter name="Steps" type="int" value="2"/></ParameterList>
  <ParameterList name="Output"><Parameter name="HDF5" type="bool" value="false"/><Parameter name="Checkpoint every" type="int" value="0"/></ParameterList>)x");
  Simulation sim(test::config(xml, out), RunOptions{true, ""});
  ASSERT_EQ(sim.run(), 0);  // (every file below rewritten by this run)
  const RigFile rig = read_rig_file(kEpileptic);
  for (int step : {0, 1, 2}) {
    const std::string n = "_00000" + std::to_string(step) + ".obj";
    const test::Obj lbs = test::read_obj(out + "/lbs" + n), skin = test::read_obj(out + "/skin" + n);
    ASSERT_EQ(lbs.v.size(), skin.v.size());
    EXPECT_EQ(lbs.f, skin.f) << "step " << step;
    // The file's own skinning at 0.8 + 0.05 step seconds (written with 10 digits).
    const TriangleSurface expected = rig_surface(rig, "", &rig.clips[0], 0.8 + 0.05 * step);
    ASSERT_EQ(expected.vertices.size(), lbs.v.size());
    double err = 0.0, apart = 0.0;
    for (std::size_t v = 0; v < lbs.v.size(); ++v)
      for (int d = 0; d < 3; ++d) {
        err = std::max(err, std::fabs(lbs.v[v][d] - expected.vertices[v][d]));
        apart += std::fabs(lbs.v[v][d] - skin.v[v][d]) / (3.0 * lbs.v.size());
      }
    EXPECT_LT(err, 1e-8) << "step " << step;
    // At rest both are the skin as voxelized; later the simulated flesh departs from the plain skinning
    // but stays near it (the bones drive both), here within 1 cm on average.
    if (step == 0) {
      EXPECT_LT(apart, 1e-9);
    }
    if (step == 2) {
      EXPECT_GT(apart, 1e-4);
      EXPECT_LT(apart, 0.01);
    }
    std::printf("[ info ] step %d: lbs vs the file's skinning %.1e; simulated skin vs lbs %.2e m on average per coordinate\n", step, err, apart);
  }
}

TEST(RigScene, AMotionCaptureDrivesTheRigThroughTheJointMap) {
  // CMU's BVH capture (another skeleton: other names, 14x the size, a T-pose rest) carried onto BCN's
  // joints, from the capture's pose at 1.0 s (where BCN stands in its rest pose, its clip at 0.8 s) to
  // 1.1 s: every bone node ends where its joint's retargeted motion puts it.
  const char* bvh = "/usr/share/assimp/models/BVH/01_01.bvh";
  const std::string map = "Hips:B_Root_Pelvis_L, LeftUpLeg:B_Hip_Left, LeftLeg:B_Knee_Left, RightUpLeg:B_Hip_Right, "
                          "RightLeg:B_Knee_Right, Spine:B_Spine2, LeftArm:B_UpperArm_Left, LeftForeArm:B_ForeArm_Left";
  const std::string xml = rig_scene("rig_mocap", 0.04, R"x(<Parameter name="Rest time" type="double" value="0.8"/>
    <Parameter name="Retarget from" type="string" value=")x" + std::string(bvh) + R"x("/>
    <Parameter name="Joint map" type="string" value=")x" + map + R"x("/>
    <Parameter name="Clip start" type="double" value="1.0"/>
    <Parameter name="Clip end" type="double" value="1.1"/>)x",
                                     R"x(<ParameterList name="Loading"><Parameter name="Steps" type="int" value="1"/></ParameterList>
  <ParameterList name="Solver"><Parameter name="Absolute tolerance" type="double" value="1.0e-4"/></ParameterList>
  <ParameterList name="Output"><Parameter name="HDF5" type="bool" value="false"/><Parameter name="Checkpoint every" type="int" value="0"/></ParameterList>)x");
  Simulation sim(test::config(xml, "test_results/rig/mocap"), RunOptions{true, ""});
  const RigFile rig = read_rig_file(kEpileptic), source = read_rig_file(bvh);
  const std::vector<Affine> rest = rig.pose(&rig.clips[0], 0.8);
  const Retarget retarget(rig, rest, source, source.clips[0], 1.0, Retarget::parse_map(map), 0.0);
  EXPECT_NEAR(retarget.scale(), sim.scene().skeleton().retarget_scale(), 1e-15);
  EXPECT_GT(retarget.scale(), 0.05);  // BCN is about 1.8 m tall, the capture's skeleton about 14 times that
  EXPECT_LT(retarget.scale(), 0.1);
  ASSERT_EQ(sim.run(), 0);
  double moved = 0.0;
  const double err = bone_error(sim, rig, rest, retarget.pose(1.1), moved);
  EXPECT_LT(err, 1e-9);
  EXPECT_GT(moved, 1e-3);
  // An unmapped joint (the right hand) moves rigidly with its mapped ancestor (the right knee's chain is
  // mapped, the right arm is not: it follows the spine).
  const auto W = retarget.pose(1.1);
  const int spine = rig.node_index("B_Spine2"), hand = rig.node_index("B_Hand_Right");
  const Affine relative_rest = rest[spine].inverse().after(rest[hand]), relative = W[spine].inverse().after(W[hand]);
  EXPECT_LT(distance(relative, relative_rest), 1e-9);
  std::printf("[ info ] retargeted capture: scale %.4f; bone nodes vs the retargeted joints' motion %.1e (moved up to %.3f)\n",
              retarget.scale(), err, moved);
}

// ---------------------------------------------------------------------------------------------
// The skin's caches (issue 43): glTF node transforms, Sinew's frame record, PC2 and glTF files.
// ---------------------------------------------------------------------------------------------
#include <sinew/io/skin_cache.hpp>

namespace {

sinew::Affine rotation_scale(double angle, std::array<double, 3> axis, std::array<double, 3> scale, std::array<double, 3> t) {
  const double n = std::sqrt(axis[0] * axis[0] + axis[1] * axis[1] + axis[2] * axis[2]);
  for (double& a : axis) a /= n;
  const double c = std::cos(angle), s = std::sin(angle);
  sinew::Affine m;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) {
      const double skew = (i == j) ? 0.0 : ((j == (i + 1) % 3) ? -axis[3 - i - j] : axis[3 - i - j]);
      m.A(i, j) = ((i == j ? c : 0.0) + (1 - c) * axis[i] * axis[j] + s * skew) * scale[j];
    }
  m.t = t;
  return m;
}

std::vector<char> file_bytes(const std::string& path) {
  std::ifstream f(path, std::ios::binary);
  return std::vector<char>(std::istreambuf_iterator<char>(f), {});
}

sinew::SkinFrame frame(int step, double time, std::size_t vertices, float shift) {
  sinew::SkinFrame f;
  f.step = step;
  f.load = 0.1 * step;
  f.time = time;
  for (std::size_t v = 0; v < 3 * vertices; ++v) f.x.push_back(static_cast<float>(v) + shift);
  f.fields.push_back(std::vector<float>(vertices, 1.0f + shift));
  return f;
}

}  // namespace

TEST(SkinCaches, NodeTransformsSplitIntoTranslationRotationAndScaleThatComposeBack) {
  // Rotations about several axes with uniform, axis and negative (mirror) scales.
  const std::vector<sinew::Affine> cases = {rotation_scale(0.3, {1, 2, 3}, {1, 1, 1}, {1, -2, 3}),
                                            rotation_scale(3.1, {0, 0, 1}, {2, 2, 2}, {0, 0, 0}),
                                            rotation_scale(-2.0, {1, -1, 0.5}, {0.5, 1.5, 3.0}, {0.1, 0.2, 0.3}),
                                            rotation_scale(1.0, {0.2, 1, 0}, {-1, 1, 1}, {5, 0, 0}),
                                            rotation_scale(3.14159, {1, 0, 0}, {1, 1, 1}, {0, 1, 0})};
  for (const auto& m : cases) {
    float t[3], q[4], s[3];
    sinew::decompose_trs(m, t, q, s);
    EXPECT_NEAR(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3], 1.0, 1e-6);
    // R(q) diag(s) must give A back.
    const double x = q[0], y = q[1], z = q[2], w = q[3];
    const double R[3][3] = {{1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)},
                            {2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)},
                            {2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)}};
    for (int i = 0; i < 3; ++i) {
      EXPECT_NEAR(t[i], m.t[i], 1e-6);
      for (int j = 0; j < 3; ++j) EXPECT_NEAR(R[i][j] * s[j], m.A(i, j), 2e-6) << i << "," << j;
    }
  }
}

TEST(SkinCaches, FrameFileKeepsTheFramesUpToTheRestartStepAndCutsOffTheRest) {
  const std::string dir = "test_results/skin_frames";
  std::filesystem::create_directories(dir);
  const std::string path = dir + "/skin.frames";
  const std::vector<std::string> fields{"J"};
  std::vector<sinew::SkinFrame> kept;
  std::string note;
  {
    sinew::SkinFrameFile file(path, 4, fields, -1, kept, note);
    for (int k = 0; k < 5; ++k) file.append(frame(2 * k, 0.5 * k, 4, static_cast<float>(k)));
  }
  EXPECT_EQ(sinew::read_skin_frames(path).size(), 5u);
  // A half-written record at the end (a crash while appending) is ignored and cut off.
  { std::ofstream(path, std::ios::binary | std::ios::app) << "partial"; }
  {
    sinew::SkinFrameFile file(path, 4, fields, 4, kept, note);  // restart after step 4: steps 0, 2, 4 stay
    ASSERT_EQ(kept.size(), 3u);
    EXPECT_TRUE(note.empty()) << note;
    EXPECT_EQ(kept[2].step, 4);
    EXPECT_FLOAT_EQ(kept[2].x[5], 5.0f + 2.0f);
    EXPECT_FLOAT_EQ(kept[1].fields[0][3], 2.0f);
    file.append(frame(5, 2.5, 4, 9.0f));
  }
  std::vector<std::string> names;
  const auto all = sinew::read_skin_frames(path, &names);
  ASSERT_EQ(all.size(), 4u);
  EXPECT_EQ(names, fields);
  EXPECT_EQ(all[3].step, 5);
  EXPECT_DOUBLE_EQ(all[3].time, 2.5);
  EXPECT_FLOAT_EQ(all[3].x[0], 9.0f);
  // Another skin (vertex count) or other fields: started anew, with a note.
  sinew::SkinFrameFile other(path, 5, fields, 4, kept, note);
  EXPECT_TRUE(kept.empty());
  EXPECT_NE(note.find("another skin"), std::string::npos) << note;
  EXPECT_TRUE(sinew::read_skin_frames(path).empty());
}

TEST(SkinCaches, PointCacheHasThePc2HeaderAndEveryFramesPositions) {
  sinew::SkinTrack track;
  track.rest = std::vector<float>(9, 0.0f);
  track.triangles = {{0, 1, 2}};
  track.frame_rate = 24.0;
  track.frames = {frame(0, 0.5, 3, 0.0f), frame(2, 0.75, 3, 1.0f), frame(4, 1.0, 3, 2.0f)};
  std::filesystem::create_directories("test_results/skin_pc2");
  sinew::write_pc2("test_results/skin_pc2/skin.pc2", track);
  const std::vector<char> b = file_bytes("test_results/skin_pc2/skin.pc2");
  ASSERT_EQ(b.size(), 32u + 3 * 9 * 4);
  EXPECT_EQ(std::string(b.data(), 12), std::string("POINTCACHE2\0", 12));
  std::int32_t version, points, samples;
  float start, sampling;
  std::memcpy(&version, &b[12], 4);
  std::memcpy(&points, &b[16], 4);
  std::memcpy(&start, &b[20], 4);
  std::memcpy(&sampling, &b[24], 4);
  std::memcpy(&samples, &b[28], 4);
  EXPECT_EQ(version, 1);
  EXPECT_EQ(points, 3);
  EXPECT_FLOAT_EQ(start, 12.0f);    // 0.5 s at 24 frames per second
  EXPECT_FLOAT_EQ(sampling, 6.0f);  // 0.25 s between frames
  EXPECT_EQ(samples, 3);
  float last;
  std::memcpy(&last, &b[32 + (2 * 9 + 8) * 4], 4);
  EXPECT_FLOAT_EQ(last, 8.0f + 2.0f);
}

TEST(SkinCaches, GlbIsAGltfBinaryWithOneMorphTargetAndOneStepKeyPerFrame) {
  sinew::SkinTrack track;
  track.rest = {0, 0, 0, 1, 0, 0, 0, 1, 0};
  track.triangles = {{0, 1, 2}};
  track.field_names = {"J"};
  track.frames = {frame(0, 0.0, 3, 0.0f), frame(1, 0.1, 3, 0.5f)};
  sinew::SkinRig rig;
  rig.names = {"root", "arm \"left\""};
  rig.parents = {-1, 0};
  rig.pose = [](double load) {
    return std::vector<sinew::Affine>{rotation_scale(0.0, {0, 0, 1}, {1, 1, 1}, {0, 0, 0}),
                                      rotation_scale(load, {0, 0, 1}, {1, 1, 1}, {1, 0, 0})};
  };
  track.rig = &rig;
  std::filesystem::create_directories("test_results/skin_glb");
  sinew::write_glb("test_results/skin_glb/skin.glb", track);
  const std::vector<char> b = file_bytes("test_results/skin_glb/skin.glb");
  ASSERT_GT(b.size(), 28u);
  std::uint32_t head[5];
  std::memcpy(head, b.data(), sizeof head);
  EXPECT_EQ(head[0], 0x46546C67u);  // "glTF"
  EXPECT_EQ(head[1], 2u);
  EXPECT_EQ(head[2], b.size());
  EXPECT_EQ(head[3] % 4, 0u);
  EXPECT_EQ(head[4], 0x4E4F534Au);  // "JSON"
  const std::string json(b.data() + 20, head[3]);
  std::uint32_t bin[2];
  std::memcpy(bin, b.data() + 20 + head[3], sizeof bin);
  EXPECT_EQ(bin[1], 0x004E4942u);  // "BIN"
  EXPECT_EQ(20 + head[3] + 8 + bin[0], b.size());
  for (const char* expect : {"\"targets\":[{\"POSITION\":", "\"interpolation\":\"STEP\"", "\"path\":\"weights\"",
                             "\"name\":\"arm \\\"left\\\"\"", "\"path\":\"rotation\"", "\"sinew_steps\":[0,1]",
                             "\"targetNames\":[\"step_000000\",\"step_000001\"]", "\"sinew_fields\":{\"J\":"})
    EXPECT_NE(json.find(expect), std::string::npos) << expect << " not in " << json;
}
