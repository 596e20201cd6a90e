// Meshes from files and the skeleton that drives them: every Gmsh format reads the same mesh;
// orientation is repaired and counted; the distribution gives every node and element one owner and
// every rank the ghosts it needs; an affine patch test on a Gmsh mesh is exact for every model; a
// twist on a Gmsh mesh is the same on 1 thread, 2 threads and 2 ranks; bone transforms compose
// parents and interpolate keyframes and motion files as documented; bones move their nodes exactly;
// a box tree refitted to moved boxes answers its queries as one built afresh.
#include "scene_test_utils.hpp"
#include "tpetra_test_utils.hpp"

#include <sinew/core/xml_input.hpp>
#include <sinew/discretization/aabb_tree.hpp>
#include <sinew/discretization/boundary.hpp>
#include <sinew/discretization/mesh_file.hpp>
#include <sinew/discretization/triangle_surface.hpp>
#include <sinew/scenes/region.hpp>
#include <sinew/driver/run.hpp>
#include <sinew/materials/models.hpp>
#include <sinew/scenes/scene.hpp>

#include <Teuchos_DefaultMpiComm.hpp>
#include <Tpetra_Core.hpp>
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <set>
#include <sstream>

using namespace sinew;
using namespace sinew::test;

namespace {

auto world() { return Tpetra::getDefaultComm(); }
std::string tag() { return "_np" + std::to_string(world()->getSize()) + "_t" + std::to_string(Kokkos::DefaultExecutionSpace::concurrency()); }
std::string mesh_path(const std::string& name) { return std::string(SINEW_SOURCE_DIR) + "/tests/meshes/" + name; }

double tet_volume(const MeshFile& m, std::size_t e) {
  const int* c = &m.conn[4 * e];
  double a[3], b[3], d[3];
  for (int k = 0; k < 3; ++k) {
    a[k] = m.xyz[3 * c[1] + k] - m.xyz[3 * c[0] + k];
    b[k] = m.xyz[3 * c[2] + k] - m.xyz[3 * c[0] + k];
    d[k] = m.xyz[3 * c[3] + k] - m.xyz[3 * c[0] + k];
  }
  return (a[0] * (b[1] * d[2] - b[2] * d[1]) - a[1] * (b[0] * d[2] - b[2] * d[0]) + a[2] * (b[0] * d[1] - b[1] * d[0])) / 6.0;
}

// A parallelepiped hex (Gmsh order: bottom face 0-1-2-3 counter-clockwise seen from above, top 4-7).
double hex_volume(const MeshFile& m, std::size_t e) {
  const int* c = &m.conn[8 * e];
  double a[3], b[3], d[3];
  for (int k = 0; k < 3; ++k) {
    a[k] = m.xyz[3 * c[1] + k] - m.xyz[3 * c[0] + k];
    b[k] = m.xyz[3 * c[3] + k] - m.xyz[3 * c[0] + k];
    d[k] = m.xyz[3 * c[4] + k] - m.xyz[3 * c[0] + k];
  }
  return a[0] * (b[1] * d[2] - b[2] * d[1]) - a[1] * (b[0] * d[2] - b[2] * d[0]) + a[2] * (b[0] * d[1] - b[1] * d[0]);
}

const std::vector<int>& node_group(const MeshFile& m, const std::string& name) {
  for (std::size_t g = 0; g < m.node_group_names.size(); ++g)
    if (m.node_group_names[g] == name) return m.node_group_nodes[g];
  throw std::runtime_error("no node group " + name);
}

// A scene on the Gmsh unit box (box.geo), with the given model, conditions and skeleton.
std::string box_scene(const std::string& mesh, const std::string& model, double nu, const std::string& conditions,
                      const std::string& skeleton = "", int steps = 1, bool hdf5 = false) {
  return R"x(<ParameterList name="Sinew">
  <Parameter name="Scene" type="string" value="gmsh_box"/>
  <ParameterList name="Mesh">
    <Parameter name="Type" type="string" value="file"/>
    <Parameter name="File" type="string" value=")x" + mesh_path(mesh) + R"x("/>
  </ParameterList>
  <ParameterList name="Material">
    <Parameter name="Model" type="string" value=")x" + model + R"x("/>
    <Parameter name="Young modulus" type="double" value="1.0"/>
    <Parameter name="Poisson ratio" type="double" value=")x" + std::to_string(nu) + R"x("/>
  </ParameterList>)x" + skeleton + R"x(
  <ParameterList name="Loading">
    <Parameter name="Steps" type="int" value=")x" + std::to_string(steps) + R"x("/>
    <ParameterList name="Boundary conditions">)x" + conditions + R"x(
    </ParameterList>
  </ParameterList>
  <ParameterList name="Solver">
    <Parameter name="Absolute tolerance" type="double" value="1.0e-11"/>
    <Parameter name="Maximum iterations" type="int" value="60"/>
  </ParameterList>
  <ParameterList name="Output">
    <Parameter name="HDF5" type="bool" value=")x" + (hdf5 ? "true" : "false") + R"x("/>
    <Parameter name="Checkpoint every" type="int" value="0"/>
  </ParameterList>
</ParameterList>)x";
}

// A file of this rank's own (ranks run the same test side by side).
std::string write_file(const std::string& name, const std::string& text) {
  const std::string dir = "test_results/meshes" + tag() + "_rank" + std::to_string(world()->getRank());
  std::filesystem::create_directories(dir);
  const std::string path = dir + "/" + name;
  std::ofstream(path) << text;
  return path;
}

}  // namespace

TEST(MeshFile, EveryGmshFormatReadsTheSameBox) {
  const MeshFile ref = read_mesh_file(mesh_path("box_v41.msh"));
  EXPECT_EQ(ref.format, "Gmsh MSH 4.1 ASCII");
  ASSERT_EQ(ref.type, ElementType::Tet4);
  EXPECT_EQ(ref.nodes(), 339u);
  EXPECT_EQ(ref.elements(), 1125u);
  double volume = 0.0, smallest = 1.0;
  for (std::size_t e = 0; e < ref.elements(); ++e) {
    volume += tet_volume(ref, e);
    smallest = std::min(smallest, tet_volume(ref, e));
  }
  EXPECT_NEAR(volume, 1.0, 1e-12);  // the unit cube, every element positively oriented after reading
  EXPECT_GT(smallest, 0.0);
  EXPECT_EQ(ref.element_group_names, std::vector<std::string>{"body"});
  for (GroupMask g : ref.element_groups) EXPECT_EQ(g, 1u);
  const std::set<std::string> names(ref.node_group_names.begin(), ref.node_group_names.end());
  EXPECT_EQ(names, (std::set<std::string>{"bottom", "top", "sides", "edge", "corner"}));
  // Each group holds exactly the nodes on its geometry (box.geo: OCC box faces 5/6 are z = 0/1).
  std::size_t on_bottom = 0;
  for (std::size_t n = 0; n < ref.nodes(); ++n) on_bottom += ref.xyz[3 * n + 2] == 0.0;
  EXPECT_EQ(node_group(ref, "bottom").size(), on_bottom);
  for (int n : node_group(ref, "bottom")) EXPECT_EQ(ref.xyz[3 * n + 2], 0.0);
  for (int n : node_group(ref, "top")) EXPECT_EQ(ref.xyz[3 * n + 2], 1.0);
  for (int n : node_group(ref, "sides")) {
    const double x = ref.xyz[3 * n], y = ref.xyz[3 * n + 1];
    EXPECT_TRUE(x == 0.0 || x == 1.0 || y == 0.0 || y == 1.0) << "node " << ref.node_tag[n];
  }
  ASSERT_EQ(node_group(ref, "corner").size(), 1u);
  for (int k = 0; k < 3; ++k) {
    const double x = ref.xyz[3 * node_group(ref, "corner")[0] + k];
    EXPECT_TRUE(x == 0.0 || x == 1.0);
  }

  for (const auto& [file, format] : std::vector<std::pair<std::string, std::string>>{
           {"box_v41_bin.msh", "Gmsh MSH 4.1 binary"}, {"box_v22.msh", "Gmsh MSH 2.2 ASCII"}, {"box_v22_bin.msh", "Gmsh MSH 2.2 binary"}}) {
    const MeshFile m = read_mesh_file(mesh_path(file));
    EXPECT_EQ(m.format, format);
    // Gmsh prints 16 significant digits in ASCII: equal to round-off between encodings.
    ASSERT_EQ(m.xyz.size(), ref.xyz.size());
    double dx = 0.0;
    for (std::size_t i = 0; i < m.xyz.size(); ++i) dx = std::max(dx, std::fabs(m.xyz[i] - ref.xyz[i]));
    EXPECT_LT(dx, 1e-15) << file;
    EXPECT_EQ(m.conn, ref.conn) << file;
    EXPECT_EQ(m.node_tag, ref.node_tag) << file;
    EXPECT_EQ(m.element_tag, ref.element_tag) << file;
    EXPECT_EQ(m.element_groups, ref.element_groups) << file;
    EXPECT_EQ(m.reoriented, ref.reoriented) << file;
    for (const auto& g : names) EXPECT_EQ(node_group(m, g), node_group(ref, g)) << file << " group " << g;
  }
  // The same encoding holds the same numbers to the bit.
  EXPECT_EQ(read_mesh_file(mesh_path("box_v22.msh")).xyz, ref.xyz);
  EXPECT_EQ(read_mesh_file(mesh_path("box_v22_bin.msh")).xyz, read_mesh_file(mesh_path("box_v41_bin.msh")).xyz);
  const MeshGroups groups = read_mesh_groups(mesh_path("box_v22_bin.msh"));
  EXPECT_EQ(groups.element_groups, std::vector<std::string>{"body"});
  EXPECT_EQ(std::set<std::string>(groups.node_groups.begin(), groups.node_groups.end()), names);
}

TEST(MeshFile, HexahedraWithTwoVolumeGroups) {
  const MeshFile m = read_mesh_file(mesh_path("hexbox_v41.msh"));
  ASSERT_EQ(m.type, ElementType::Hex8);
  EXPECT_EQ(m.nodes(), 112u);  // 4 x 4 x 7 lattice nodes
  EXPECT_EQ(m.elements(), 54u);
  double volume = 0.0;
  for (std::size_t e = 0; e < m.elements(); ++e) {
    EXPECT_NEAR(hex_volume(m, e), 1.0 / 27.0, 1e-12) << "element " << m.element_tag[e];
    volume += hex_volume(m, e);
  }
  EXPECT_NEAR(volume, 2.0, 1e-12);
  ASSERT_EQ(m.element_group_names.size(), 2u);
  for (std::size_t e = 0; e < m.elements(); ++e) {
    double z = 0.0;
    for (int a = 0; a < 8; ++a) z += m.xyz[3 * m.conn[8 * e + a] + 2] / 8.0;
    const int g = z < 1.0 ? 0 : 1;
    EXPECT_EQ(m.element_group_names[g], z < 1.0 ? "lower" : "upper");
    EXPECT_EQ(m.element_groups[e], GroupMask{1} << g);
  }
  EXPECT_EQ(node_group(m, "floor").size(), 16u);
}

TEST(MeshFile, AnElementInTwoVolumeGroupsIsInBothAndCountedOnce) {
  // nested_groups.geo: "all" = both cubes, "tendon" = the second. MSH 4.1 lists each element once with
  // its entity's groups; MSH 2.2 lists an element of the second cube twice (once per group, new tags).
  const MeshFile v41 = read_mesh_file(mesh_path("nested_groups_v41.msh"));
  const MeshFile v22 = read_mesh_file(mesh_path("nested_groups_v22.msh"));
  for (const MeshFile* m : {&v41, &v22}) {
    ASSERT_EQ(m->element_group_names, (std::vector<std::string>{"all", "tendon"})) << m->format;
    EXPECT_EQ(m->elements(), 200u) << m->format;  // 100 per cube, none twice
    double volume = 0.0, tendon = 0.0;
    for (std::size_t e = 0; e < m->elements(); ++e) {
      const double v = tet_volume(*m, e);
      double x = 0.0;
      for (int a = 0; a < 4; ++a) x += m->xyz[3 * m->conn[4 * e + a]] / 4.0;
      EXPECT_EQ(m->element_groups[e], x < 1.0 ? 1u : 3u) << m->format << " element " << m->element_tag[e];
      volume += v;
      if (m->element_groups[e] & 2u) tendon += v;
    }
    EXPECT_NEAR(volume, 2.0, 1e-12) << m->format;  // was 3 for MSH 2.2: the second cube assembled twice
    EXPECT_NEAR(tendon, 1.0, 1e-12) << m->format;
  }
  EXPECT_EQ(v22.merged, 100);
  EXPECT_EQ(v41.merged, 0);
  // The run's header says what reading changed.
  ASSERT_FALSE(v22.notes.empty());
  EXPECT_NE(v22.notes.back().find("100 repeated copies of elements in several volume groups merged"), std::string::npos)
      << v22.notes.back();
}

TEST(MeshFile, AnElementListedTwiceOrATagUsedTwiceIsAnError) {
  const std::string head = "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Nodes\n5\n1 0 0 0\n2 1 0 0\n3 0 1 0\n4 0 0 1\n5 1 1 1\n$EndNodes\n";
  auto expect_error = [&](const std::string& name, const std::string& elements, const std::string& what) {
    try {
      read_mesh_file(write_file(name, head + "$Elements\n" + elements + "$EndElements\n"));
      ADD_FAILURE() << name << ": no error";
    } catch (const InputError& e) {
      EXPECT_EQ(e.kind, InputErrorKind::BadMesh);
      EXPECT_NE(std::string(e.what()).find(what), std::string::npos) << e.what();
    }
  };
  // The same tet twice (its nodes in another order), in the same group: it would be assembled twice.
  expect_error("same_element.msh", "2\n1 4 2 1 1 1 2 3 4\n2 4 2 1 1 2 1 4 3\n", "elements 1 and 2 have the same nodes");
  expect_error("same_tag.msh", "2\n7 4 2 1 1 1 2 3 4\n7 4 2 1 1 2 3 4 5\n", "element tag 7 is used by two different elements");
}

TEST(MeshFile, NegativelyOrientedElementsAreReorderedAndCounted) {
  // Two tets of the unit corner, the second listed with negative orientation; and a hex listed upside down.
  const std::string tets = write_file("inverted_tets.msh", R"($MeshFormat
2.2 0 8
$EndMeshFormat
$Nodes
5
1 0 0 0
2 1 0 0
3 0 1 0
4 0 0 1
5 0 0 -1
$EndNodes
$Elements
2
1 4 2 1 1 1 2 3 4
2 4 2 1 1 1 2 3 5
$EndElements
)");
  const MeshFile m = read_mesh_file(tets);
  EXPECT_EQ(m.reoriented, 1);
  EXPECT_NEAR(tet_volume(m, 0), 1.0 / 6.0, 1e-15);
  EXPECT_NEAR(tet_volume(m, 1), 1.0 / 6.0, 1e-15);

  std::string hex = "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Nodes\n8\n";
  const int corners[8][3] = {{0, 0, 1}, {1, 0, 1}, {1, 1, 1}, {0, 1, 1}, {0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}};  // top first
  for (int a = 0; a < 8; ++a)
    hex += std::to_string(a + 1) + " " + std::to_string(corners[a][0]) + " " + std::to_string(corners[a][1]) + " " +
           std::to_string(corners[a][2]) + "\n";
  hex += "$EndNodes\n$Elements\n1\n1 5 2 1 1 1 2 3 4 5 6 7 8\n$EndElements\n";
  const MeshFile h = read_mesh_file(write_file("inverted_hex.msh", hex));
  EXPECT_EQ(h.reoriented, 1);
  EXPECT_NEAR(hex_volume(h, 0), 1.0, 1e-15);
}

TEST(Distribution, EveryNodeAndElementHasOneOwnerAndGhostsAreComplete) {
  const SceneConfig c = config(box_scene("box_v41.msh", "stable-neohookean", 0.3, ""), "unused");
  const Mesh mesh = build_scene_mesh(c.params.mesh, *world());
  const MeshFile file = read_mesh_file(mesh_path("box_v41.msh"));  // every rank reads it, for the test
  const auto comm = world();
  EXPECT_EQ(mesh.global_nodes, 339);
  EXPECT_EQ(mesh.global_elements, 1125);
  long long owned[2] = {static_cast<long long>(mesh.n_owned_nodes), static_cast<long long>(mesh.n_owned_elements)}, total[2];
  Teuchos::reduceAll(*comm, Teuchos::REDUCE_SUM, 2, owned, total);
  EXPECT_EQ(total[0], 339);
  EXPECT_EQ(total[1], 1125);
  // Coordinates and connectivity by global id are the file's (global ids follow the file's order).
  auto X = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), mesh.X);
  auto conn = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), mesh.conn);
  std::vector<char> here(file.nodes(), 0);
  for (std::size_t n = 0; n < mesh.local_nodes(); ++n) {
    const auto g = static_cast<std::size_t>(mesh.node_gid[n]);
    for (int k = 0; k < 3; ++k) EXPECT_EQ(X(n, k), file.xyz[3 * g + k]);
    EXPECT_EQ(mesh.node_tag[n], file.node_tag[g]);
    EXPECT_EQ(mesh.node_owner[n] == comm->getRank(), n < mesh.n_owned_nodes);
    here[g] = 1;
  }
  std::vector<int> around_here(file.nodes(), 0), around_all(file.nodes(), 0);
  for (std::size_t e = 0; e < file.elements(); ++e)
    for (int a = 0; a < 4; ++a) ++around_all[file.conn[4 * e + a]];
  for (std::size_t e = 0; e < mesh.local_elements(); ++e) {
    const auto g = static_cast<std::size_t>(mesh.element_gid[e]);
    EXPECT_EQ(mesh.element_tag[e], file.element_tag[g]);
    for (int a = 0; a < 4; ++a) {
      EXPECT_EQ(mesh.node_gid[conn(e, a)], file.conn[4 * g + a]);
      ++around_here[mesh.node_gid[conn(e, a)]];
    }
  }
  // Every owned node sees all its elements on this rank (assembly needs no communication).
  for (std::size_t n = 0; n < mesh.n_owned_nodes; ++n) {
    const auto g = mesh.node_gid[n];
    EXPECT_EQ(around_here[g], around_all[g]) << "node " << file.node_tag[g] << " on rank " << comm->getRank();
  }
  // Output numbering: a permutation of 0..N-1 across ranks, each rank's owned rows contiguous.
  std::vector<long long> ids(339, 0), all_ids(339, 0);
  for (std::size_t n = 0; n < mesh.n_owned_nodes; ++n) {
    EXPECT_EQ(mesh.node_output_id[n], mesh.first_output_node + static_cast<long long>(n));
    ids[mesh.node_output_id[n]] += 1;
  }
  Teuchos::reduceAll(*comm, Teuchos::REDUCE_SUM, 339, ids.data(), all_ids.data());
  for (long long k : all_ids) EXPECT_EQ(k, 1);
  if (comm->getSize() > 1) {
    EXPECT_LT(mesh.n_owned_elements, 1125u) << "the elements were not spread over the ranks";
    EXPECT_LT(mesh.local_nodes(), 339u) << "a rank kept the whole mesh";
  }
}

TEST(MeshScenes, AffinePatchTestOnAGmshMeshIsExactForEveryModel) {
  // Every boundary node moved by one affine map: the homogeneous deformation is the exact discrete
  // solution for every hyperelastic model, so the interior nodes must follow it to the solver tolerance.
  const std::string G = "{0.10, 0.05, 0.0, 0.0, -0.05, 0.02, 0.03, 0.0, 0.08}";
  const double g[9] = {0.10, 0.05, 0.0, 0.0, -0.05, 0.02, 0.03, 0.0, 0.08};
  const std::string bc = R"x(
      <ParameterList name="surface">
        <Parameter name="Region" type="string" value="group bottom, top, sides"/>
        <Parameter name="Motion" type="string" value="affine"/>
        <Parameter name="Gradient" type="Array(double)" value=")x" + G + R"x("/>
        <Parameter name="Center" type="Array(double)" value="{0.5, 0.5, 0.5}"/>
        <Parameter name="Displacement" type="Array(double)" value="{0.01, -0.02, 0.03}"/>
      </ParameterList>)x";
  const MeshFile file = read_mesh_file(mesh_path("box_v41.msh"));
  double worst = 0.0;
  for (const auto& model : material_model_names()) {
    Simulation sim(config(box_scene("box_v41.msh", model, 0.3, bc), "test_results/patch" + tag()), RunOptions{true, ""});
    ASSERT_EQ(sim.run(), 0) << model;
    // The interior was moved by a solve: Newton's, or the tangent predictor's CG (the linearised
    // response to an affine motion is that motion, which may already meet the tolerance).
    EXPECT_GT(sim.records().front().solve.linear_iterations, 0) << model;
    const auto u = gather(sim.displacement());
    ASSERT_EQ(u.size(), 3 * file.nodes());
    double err = 0.0;
    for (std::size_t n = 0; n < file.nodes(); ++n)
      for (int i = 0; i < 3; ++i) {
        const double d[3] = {0.01, -0.02, 0.03};
        double expect = d[i];
        for (int j = 0; j < 3; ++j) expect += g[3 * i + j] * (file.xyz[3 * n + j] - 0.5);
        err = std::max(err, std::fabs(u[3 * n + i] - expect));
      }
    EXPECT_LT(err, 1e-8) << model;
    worst = std::max(worst, err);
  }
  if (world()->getRank() == 0) std::printf("[ info ] affine patch test on box_v41.msh, every model: max |u - u_affine| = %.2e\n", worst);
}

TEST(MeshScenes, GmshTwistIsTheSameOnThreadsAndRanks) {
  // A 1 rad twist of the Gmsh box. With 2 ranks, also solved by each rank alone; all variants compare
  // with the 1-thread reference file CTest writes first.
  const std::string bc = R"x(
      <ParameterList name="bottom">
        <Parameter name="Region" type="string" value="group bottom"/>
      </ParameterList>
      <ParameterList name="top">
        <Parameter name="Region" type="string" value="group top"/>
        <Parameter name="Motion" type="string" value="rotate"/>
        <Parameter name="Center" type="Array(double)" value="{0.5, 0.5, 1}"/>
        <Parameter name="Angle" type="double" value="1.0"/>
      </ParameterList>)x";
  const SceneConfig c = config(box_scene("box_v41_bin.msh", "stable-neohookean", 0.45, bc, "", 2, true), "test_results/gmsh_twist" + tag());
  Simulation sim(c, RunOptions{true, ""});
  ASSERT_EQ(sim.run(), 0);
  const auto u = gather(sim.displacement());
  EXPECT_GT(max_abs(u), 0.3);
  if (world()->getSize() > 1) {
    SceneConfig alone = c;
    alone.params.output.directory += "_self" + std::to_string(world()->getRank());
    Simulation self(alone, RunOptions{true, ""}, Teuchos::rcp(new Teuchos::MpiComm<int>(MPI_COMM_SELF)));
    ASSERT_EQ(self.run(), 0);
    const double d = rel_diff(gather(self.displacement()), u);
    EXPECT_LT(d, 1e-8);
    if (world()->getRank() == 0) std::printf("[ info ] 2 ranks vs 1 rank: max |du| / max |u| = %.2e\n", d);
  }
  agree_with_reference(u, world()->getRank(), 1e-8);
}

namespace {

Mat3 rotation_between(const Mat3& A, const Mat3& B) { return transpose(A) * B; }
double rotation_angle(const Mat3& R) { return std::acos(std::clamp(0.5 * (R(0, 0) + R(1, 1) + R(2, 2) - 1.0), -1.0, 1.0)); }
double distance(const Rigid& a, const Rigid& b) {
  double d = std::sqrt(frobenius2(a.R - b.R));
  for (int i = 0; i < 3; ++i) d = std::max(d, std::fabs(a.t[i] - b.t[i]));
  return d;
}
std::size_t bone(const Skeleton& s, const std::string& name) {
  for (std::size_t b = 0; b < s.size(); ++b)
    if (s.name(b) == name) return b;
  throw std::runtime_error("no bone " + name);
}
Rigid about(const std::array<double, 3>& axis, double angle, const std::array<double, 3>& pivot, const std::array<double, 3>& shift = {}) {
  Rigid T;
  T.R = axis_angle(axis, angle);
  const auto Rp = T.apply(pivot);
  for (int i = 0; i < 3; ++i) T.t[i] = pivot[i] - Rp[i] + shift[i];
  return T;
}

const char* kTwoBones = R"x(
  <ParameterList name="Skeleton">
    <Parameter name="Skinning guess" type="bool" value="false"/>
    <ParameterList name="Bones">
      <ParameterList name="root">
        <Parameter name="Region" type="string" value="group bottom"/>
        <ParameterList name="Keyframes">
          <ParameterList name="a">
            <Parameter name="Time" type="double" value="0.5"/>
            <Parameter name="Translation" type="Array(double)" value="{0, 0, 0.1}"/>
          </ParameterList>
          <ParameterList name="b">
            <Parameter name="Time" type="double" value="1.0"/>
            <Parameter name="Translation" type="Array(double)" value="{0, 0, 0.3}"/>
          </ParameterList>
        </ParameterList>
      </ParameterList>
      <ParameterList name="tip">
        <Parameter name="Parent" type="string" value="root"/>
        <Parameter name="Region" type="string" value="group top"/>
        <Parameter name="Pivot" type="Array(double)" value="{0.5, 0.5, 1}"/>
        <ParameterList name="Keyframes">
          <ParameterList name="half">
            <Parameter name="Time" type="double" value="0.5"/>
            <Parameter name="Axis" type="Array(double)" value="{1, 0, 0}"/>
            <Parameter name="Angle" type="double" value="0.4"/>
          </ParameterList>
          <ParameterList name="full">
            <Parameter name="Time" type="double" value="1.0"/>
            <Parameter name="Axis" type="Array(double)" value="{0, 1, 0}"/>
            <Parameter name="Angle" type="double" value="0.6"/>
          </ParameterList>
        </ParameterList>
      </ParameterList>
    </ParameterList>
  </ParameterList>)x";

}  // namespace

TEST(Skeleton, ChildrenMoveWithTheirParentsAndKeyframesInterpolate) {
  Simulation sim(config(box_scene("box_v41.msh", "stable-neohookean", 0.3, "", kTwoBones, 4), "test_results/bones" + tag()),
                 RunOptions{true, ""});
  const Skeleton& s = sim.scene().skeleton();
  ASSERT_EQ(s.size(), 2u);
  const std::size_t root = bone(s, "root"), tip = bone(s, "tip");
  // The root translates linearly between keyframes: 0.05 at t = 0.25, 0.2 at t = 0.75, held after 1.
  EXPECT_LT(distance(s.transform(root, 0.25), about({0, 0, 1}, 0.0, {}, {0, 0, 0.05})), 1e-15);
  EXPECT_LT(distance(s.transform(root, 0.75), about({0, 0, 1}, 0.0, {}, {0, 0, 0.2})), 1e-15);
  EXPECT_LT(distance(s.transform(root, 1.0), about({0, 0, 1}, 0.0, {}, {0, 0, 0.3})), 1e-15);
  EXPECT_LT(distance(s.transform(root, 0.0), Rigid{}), 1e-15);
  // The tip: one axis from rest to the first keyframe (linear angle), composed after its parent.
  const Rigid tip_quarter = s.transform(root, 0.25).after(about({1, 0, 0}, 0.2, {0.5, 0.5, 1}));
  EXPECT_LT(distance(s.transform(tip, 0.25), tip_quarter), 1e-14);
  // Between two keyframes with different axes: the geodesic (slerp) midpoint, equally far from both.
  const Mat3 R1 = axis_angle({1, 0, 0}, 0.4), R2 = axis_angle({0, 1, 0}, 0.6);
  const Mat3 Rm = s.transform(tip, 0.75).R;  // the root does not rotate
  EXPECT_LT(std::sqrt(frobenius2(transpose(Rm) * Rm - Mat3::identity())), 1e-14);
  EXPECT_NEAR(det(Rm), 1.0, 1e-14);
  const double whole = rotation_angle(rotation_between(R1, R2));
  EXPECT_NEAR(rotation_angle(rotation_between(R1, Rm)), 0.5 * whole, 1e-12);
  EXPECT_NEAR(rotation_angle(rotation_between(Rm, R2)), 0.5 * whole, 1e-12);
  // The pivot stays on the parent's path: the tip's pivot moves only by the root's translation.
  const auto p = s.transform(tip, 0.75).apply({0.5, 0.5, 1});
  EXPECT_NEAR(p[0], 0.5, 1e-14);
  EXPECT_NEAR(p[1], 0.5, 1e-14);
  EXPECT_NEAR(p[2], 1.2, 1e-14);

  // The run: every bone node ends exactly where its bone puts it.
  ASSERT_EQ(sim.run(), 0);
  const auto u = gather(sim.displacement());
  const MeshFile file = read_mesh_file(mesh_path("box_v41.msh"));
  double err = 0.0;
  for (const auto& [group, b] : std::vector<std::pair<std::string, std::size_t>>{{"bottom", root}, {"top", tip}})
    for (int n : node_group(file, group)) {
      const std::array<double, 3> X{file.xyz[3 * n], file.xyz[3 * n + 1], file.xyz[3 * n + 2]};
      const auto x = s.transform(b, 1.0).apply(X);
      for (int i = 0; i < 3; ++i) err = std::max(err, std::fabs(X[i] + u[3 * n + i] - x[i]));
    }
  EXPECT_LT(err, 1e-14);
}

TEST(Skeleton, ADynamicStepsGuessAddsTheSkinnedAccelerationOfTheBones) {
  // Two bones that translate at one speed up to load 0.5 and at another after it. The inertial
  // predictor u_n + h v_n carries the flesh on at the old speed; a flesh that moved with its skin must
  // start the step at the skin's new place: the predictor plus the skinned second difference
  // (Scene::predict_acceleration), exact for translations whatever the blend of weights.
  // A bone of a face group, translated to `half` at load 0.5 and to `full` at 1.
  auto bone = [](const std::string& group, const std::string& half, const std::string& full) {
    return R"x(<ParameterList name=")x" + group + R"x("><Parameter name="Region" type="string" value="group )x" + group +
           R"x("/><ParameterList name="Keyframes">
          <ParameterList name="a"><Parameter name="Time" type="double" value="0.5"/>
            <Parameter name="Translation" type="Array(double)" value=")x" + half + R"x("/></ParameterList>
          <ParameterList name="b"><Parameter name="Time" type="double" value="1.0"/>
            <Parameter name="Translation" type="Array(double)" value=")x" + full + R"x("/></ParameterList>
        </ParameterList></ParameterList>)x";
  };
  const std::string skeleton = R"x(<ParameterList name="Skeleton"><ParameterList name="Bones">)x" +
                               bone("bottom", "{0, 0, 0.1}", "{0, 0.1, 0.3}") + bone("top", "{0.1, 0, 0}", "{0.4, 0, 0.05}") +
                               "</ParameterList></ParameterList>";
  Simulation sim(config(box_scene("box_v41.msh", "stable-neohookean", 0.3, "", skeleton, 4), "test_results/skin_acceleration" + tag()),
                 RunOptions{true, ""});
  Scene& scene = sim.scene();
  const System& sys = scene.system();
  const Skeleton& s = scene.skeleton();
  const std::vector<char> fixed = sys.fixed_owned_mask();
  const std::size_t owned = sys.mesh().n_owned_nodes;
  // Where the skin puts an owned node at load t: the blend of its bones' translations.
  auto skinned = [&](std::size_t n, double t) {
    std::array<double, 3> d{0.0, 0.0, 0.0};
    for (const auto& [b, w] : s.weights(n))
      for (int i = 0; i < 3; ++i) d[i] += w * s.transform(b, t).t[i];
    return d;
  };
  auto check = [&](double t0, double t1, double scale) {
    const double tp = t0 - (t1 - t0);
    auto u = sys.create_vector(), guess = sys.create_vector();
    double err = 0.0, acceleration = 0.0;
    std::size_t checked = 0;
    {
      auto a = u->getLocalViewHost(Tpetra::Access::OverwriteAll);
      auto g = guess->getLocalViewHost(Tpetra::Access::OverwriteAll);
      for (std::size_t n = 0; n < owned; ++n) {
        const auto d0 = skinned(n, t0), dp = skinned(n, tp);
        for (int i = 0; i < 3; ++i) {
          a(3 * n + i, 0) = d0[i];
          g(3 * n + i, 0) = d0[i] + scale * (d0[i] - dp[i]);  // u_n + reach v_n, v_n = (u_n - u_n-1) / h
        }
      }
    }
    scene.predict_acceleration(t0, t1, *u, *guess, scale);
    auto g = guess->getLocalViewHost(Tpetra::Access::ReadOnly);
    for (std::size_t n = 0; n < owned; ++n) {
      if (fixed[3 * n] || s.weights(n).empty()) continue;
      ++checked;
      const auto d0 = skinned(n, t0), d1 = skinned(n, t1), dp = skinned(n, tp);
      for (int i = 0; i < 3; ++i) {
        err = std::max(err, std::fabs(g(3 * n + i, 0) - (d0[i] + scale * (d1[i] - d0[i]))));
        acceleration = std::max(acceleration, std::fabs(d1[i] - 2.0 * d0[i] + dp[i]));
      }
    }
    EXPECT_GT(checked, 0u);
    EXPECT_LT(err, 1e-14) << "t0 " << t0 << ", scale " << scale;
    return acceleration;
  };
  // Across the change of speed (backward Euler's u_n+1, then the midpoint's y: half way).
  EXPECT_GT(check(0.5, 0.625, 1.0), 0.01);  // what the inertial predictor alone would miss
  EXPECT_GT(check(0.5, 0.625, 0.5), 0.01);
  // At one speed there is nothing to add.
  EXPECT_LT(check(0.75, 0.875, 1.0), 1e-15);
}

TEST(Skeleton, AMotionFileIsInterpolatedBetweenItsFrames) {
  // Three frames of world transforms; frame f is reached at load f / 2.
  const Rigid f1 = about({0, 0, 1}, 0.3, {0.5, 0.5, 1}, {0.1, 0, 0}), f2 = about({0.6, 0.8, 0}, 0.5, {0.5, 0.5, 1}, {0.2, 0, 0.1});
  std::ostringstream csv;
  csv.precision(17);
  csv << "frame,bone,r00,r01,r02,r10,r11,r12,r20,r21,r22,tx,ty,tz\n";
  const Rigid frames[3] = {Rigid{}, f1, f2};
  for (int f = 0; f < 3; ++f)
    for (const std::string b : {"top", "bottom"}) {
      const Rigid T = b == "top" ? frames[f] : Rigid{};
      csv << f << "," << b;
      for (int k = 0; k < 9; ++k) csv << "," << T.R(k / 3, k % 3);
      for (int k = 0; k < 3; ++k) csv << "," << T.t[k];
      csv << "\n";
    }
  const std::string path = std::filesystem::absolute(write_file("motion.csv", csv.str())).string();
  const std::string skeleton = R"x(
  <ParameterList name="Skeleton">
    <Parameter name="Motion file" type="string" value=")x" + path + R"x("/>
    <ParameterList name="Bones">
      <ParameterList name="bottom"><Parameter name="Region" type="string" value="group bottom"/></ParameterList>
      <ParameterList name="top"><Parameter name="Region" type="string" value="group top"/></ParameterList>
    </ParameterList>
  </ParameterList>)x";
  Simulation sim(config(box_scene("box_v41.msh", "stable-neohookean", 0.3, "", skeleton, 4), "test_results/motion" + tag()),
                 RunOptions{true, ""});
  const Skeleton& s = sim.scene().skeleton();
  const std::size_t top = bone(s, "top");
  EXPECT_LT(distance(s.transform(top, 0.5), f1), 1e-14);
  EXPECT_LT(distance(s.transform(top, 1.0), f2), 1e-14);
  const Rigid m = s.transform(top, 0.75);
  for (int i = 0; i < 3; ++i) EXPECT_NEAR(m.t[i], 0.5 * (f1.t[i] + f2.t[i]), 1e-14);
  const double whole = rotation_angle(rotation_between(f1.R, f2.R));
  EXPECT_NEAR(rotation_angle(rotation_between(f1.R, m.R)), 0.5 * whole, 1e-12);
  EXPECT_NEAR(rotation_angle(rotation_between(m.R, f2.R)), 0.5 * whole, 1e-12);
  ASSERT_EQ(sim.run(), 0);
}

namespace {

// Closed and consistently oriented: every directed edge once, and its reverse once. Returns the
// enclosed volume (divergence theorem), positive when the triangles face outward.
double check_closed(const Obj& o, const std::string& what) {
  std::map<std::pair<int, int>, int> edges;
  for (const auto& t : o.f)
    for (int a = 0; a < 3; ++a) ++edges[{t[a], t[(a + 1) % 3]}];
  for (const auto& [e, n] : edges) {
    EXPECT_EQ(n, 1) << what << ": edge " << e.first << "-" << e.second << " used " << n << " times in one direction";
    EXPECT_EQ(edges.count({e.second, e.first}), 1u) << what << ": edge " << e.first << "-" << e.second << " is a border";
  }
  double V = 0.0;
  for (const auto& t : o.f) {
    const auto &a = o.v[t[0]], &b = o.v[t[1]], &c = o.v[t[2]];
    V += (a[0] * (b[1] * c[2] - b[2] * c[1]) - a[1] * (b[0] * c[2] - b[2] * c[0]) + a[2] * (b[0] * c[1] - b[1] * c[0])) / 6.0;
  }
  return V;
}

}  // namespace

// The collision test refits its swept-box trees between rebuilds (contact_barrier.cpp): a tree refitted
// to boxes that moved far (the split no longer follows them) must find exactly what a brute-force search
// and a tree built afresh find.
TEST(BoxTree, ARefittedTreeAnswersAsOneBuiltAfresh) {
  auto unit = [](std::uint64_t k) { return static_cast<double>((k * 0x9E3779B97F4A7C15ull) >> 11) / 9007199254740992.0; };
  auto boxes_at = [&](int n, std::uint64_t seed, double spread) {
    std::vector<geom::Box> boxes(n);
    for (int i = 0; i < n; ++i) {
      const std::uint64_t k = seed * 1000003ull + 7ull * static_cast<std::uint64_t>(i);
      const geom::Vec c{spread * unit(k + 1), spread * unit(k + 2), spread * unit(k + 3)};
      boxes[i].add(c);
      boxes[i].add(geom::Vec{c[0] + 0.05 * unit(k + 4), c[1] + 0.05 * unit(k + 5), c[2] + 0.05 * unit(k + 6)});
    }
    return boxes;
  };
  const int n = 500;
  geom::AabbTree tree(boxes_at(n, 1, 1.0));
  for (std::uint64_t round = 2; round < 5; ++round) {
    const auto moved = boxes_at(n, round, 1.0 + round);  // every box elsewhere, the cloud larger
    tree.refit(moved);
    const geom::AabbTree fresh(moved);
    ASSERT_EQ(tree.items(), moved.size());
    for (int q = 0; q < 40; ++q) {
      const std::uint64_t k = 77ull * round + static_cast<std::uint64_t>(q);
      const geom::Vec p{(1.0 + round) * unit(k + 11), (1.0 + round) * unit(k + 12), (1.0 + round) * unit(k + 13)};
      const double r = 0.3 * unit(k + 14);
      std::vector<int> brute, refitted, built;
      for (int i = 0; i < n; ++i)
        if (moved[i].distance2(p) <= r * r) brute.push_back(i);
      tree.near(p, r, [&](int i) { refitted.push_back(i); });
      fresh.near(p, r, [&](int i) { built.push_back(i); });
      std::sort(refitted.begin(), refitted.end());
      std::sort(built.begin(), built.end());
      EXPECT_EQ(refitted, brute);
      EXPECT_EQ(built, brute);
      double a = 0.0, b = 0.0;
      auto d2 = [&](int i) { return moved[i].distance2(p); };
      const int ia = tree.closest(p, HUGE_VAL, d2, a), ib = fresh.closest(p, HUGE_VAL, d2, b);
      ASSERT_GE(ia, 0);
      ASSERT_GE(ib, 0);
      EXPECT_EQ(a, b);  // (a tie between boxes holding p may name either)
      EXPECT_EQ(d2(ia), a);
    }
    // Every node's box holds its items' boxes.
    for (int id = 0; id < tree.node_count(); ++id)
      for (int k = tree.node_begin(id); k < tree.node_end(id); ++k) {
        const geom::Box& in = moved[tree.item(k)];
        EXPECT_TRUE(tree.node_box(id).contains(in.lo) && tree.node_box(id).contains(in.hi));
      }
  }
}

TEST(Surface, BoundarySurfacesAreClosedOutwardAndCountedOnAnyNumberOfRanks) {
  const std::string twist = R"x(
      <ParameterList name="bottom">
        <Parameter name="Region" type="string" value="face z-"/>
      </ParameterList>
      <ParameterList name="top">
        <Parameter name="Region" type="string" value="face z+"/>
        <Parameter name="Motion" type="string" value="rotate"/>
        <Parameter name="Center" type="Array(double)" value="{0.5, 0.5, 1}"/>
        <Parameter name="Angle" type="double" value="1.2"/>
      </ParameterList>)x";
  struct Case {
    std::string name, mesh;
    long long triangles, vertices;
  };
  // Generated 3 x 3 x 4 boxes: 2 (3*3 + 3*4 + 3*4) quads of 2 triangles; 2 (4*4 + 4*5 + 4*5) - 4 (4 + 4 + 5) + 8
  // surface nodes. The Gmsh box: its boundary faces counted here from the file, by brute force.
  const MeshFile file = read_mesh_file(mesh_path("box_v41.msh"));
  std::map<std::array<int, 3>, int> faces;
  for (std::size_t e = 0; e < file.elements(); ++e)
    for (int skip = 0; skip < 4; ++skip) {
      std::array<int, 3> f;
      int k = 0;
      for (int a = 0; a < 4; ++a)
        if (a != skip) f[k++] = file.conn[4 * e + a];
      std::sort(f.begin(), f.end());
      ++faces[f];
    }
  std::set<int> surface_nodes;
  long long boundary = 0;
  for (const auto& [f, n] : faces)
    if (n == 1) {
      ++boundary;
      surface_nodes.insert(f.begin(), f.end());
    }
  const std::vector<Case> cases = {{"hex8", "", 132, 68}, {"tet4", "", 132, 68}, {"gmsh", "box_v41.msh", boundary, static_cast<long long>(surface_nodes.size())}};
  for (const auto& c : cases) {
    std::string xml = box_scene(c.mesh.empty() ? "box_v41.msh" : c.mesh, "stable-neohookean", 0.4, twist, "", 2);
    if (c.mesh.empty()) {  // a generated box instead of the file
      const std::string file_mesh = R"x(<Parameter name="Type" type="string" value="file"/>
    <Parameter name="File" type="string" value=")x" + mesh_path("box_v41.msh") + R"x("/>)x";
      const std::string box = R"x(<Parameter name="Type" type="string" value="box"/>
    <Parameter name="Element" type="string" value=")x" + c.name + R"x("/>
    <Parameter name="Elements" type="Array(int)" value="{3, 3, 4}"/>)x";
      xml.replace(xml.find(file_mesh), file_mesh.size(), box);
    }
    const std::string dir = "test_results/surface_" + c.name + tag();
    Simulation sim(config(xml, dir), RunOptions{true, ""});
    ASSERT_EQ(sim.run(), 0) << c.name;
    for (int step : {0, 2}) {
      const Obj o = read_obj(dir + "/surface_00000" + std::to_string(step) + ".obj");
      EXPECT_EQ(static_cast<long long>(o.f.size()), c.triangles) << c.name;
      EXPECT_EQ(static_cast<long long>(o.v.size()), c.vertices) << c.name;
      ASSERT_EQ(o.vn.size(), o.v.size());
      const double V = check_closed(o, c.name + " step " + std::to_string(step));
      // The enclosed volume is the mesh's (deformed) volume: 1 at rest, the log's ratio after the twist;
      // exactly for tets, while a twisted hex face is warped and its two triangles cut corners.
      const double expect = step == 0 ? 1.0 : sim.records().back().volume_ratio;
      if (c.name != "hex8") {
        EXPECT_NEAR(V, expect, 1e-8) << c.name << " step " << step;
      } else {
        // A hex face is a bilinear patch, which the OBJ splits by one diagonal (triangles 2k, 2k+1:
        // a-b-c, a-c-d or a-b-d, b-c-d, as the element's tets cut it). The volume under a bilinear
        // patch is the mean of its two splits', so the mean over both diagonals must give the mesh's
        // volume exactly, warped faces and all.
        double both = 0.0;
        auto tet = [&](int a, int b, int d) {
          const auto &p = o.v[a], &q = o.v[b], &r = o.v[d];
          return (p[0] * (q[1] * r[2] - q[2] * r[1]) - p[1] * (q[0] * r[2] - q[2] * r[0]) + p[2] * (q[0] * r[1] - q[1] * r[0])) / 6.0;
        };
        ASSERT_EQ(o.f.size() % 2, 0u);
        for (std::size_t t = 0; t < o.f.size(); t += 2) {
          const auto &t1 = o.f[t], &t2 = o.f[t + 1];
          const bool ac = t2[0] == t1[0] && t2[1] == t1[2], bd = t2[0] == t1[1] && t2[2] == t1[2];
          ASSERT_TRUE(ac || bd) << "triangles " << t << " and " << t + 1 << " are not one face's split";
          const int a = t1[0], b = t1[1], cc = ac ? t1[2] : t2[1], d = ac ? t2[2] : t1[2];
          both += 0.5 * (tet(a, b, cc) + tet(a, cc, d)) + 0.5 * (tet(a, b, d) + tet(b, cc, d));
        }
        EXPECT_NEAR(both, expect, 1e-8) << "hex8 step " << step;
        EXPECT_NEAR(V, expect, step == 0 ? 1e-8 : 0.05) << "hex8 step " << step;  // one split: warped faces cut corners
      }
      if (step == 0)  // the rest box is convex: every vertex normal points away from its centre
        for (std::size_t k = 0; k < o.v.size(); ++k) {
          double d = 0.0;
          for (int i = 0; i < 3; ++i) d += o.vn[k][i] * (o.v[k][i] - 0.5);
          EXPECT_GT(d, 0.0) << c.name << " vertex " << k;
        }
    }
  }
}

// The boundary triangles of a hex mesh are faces of its elements' six tets (kHexTets), so that a point
// in a tet is behind the surface: checked on a jittered box on any number of ranks, every triangle
// against the tets of the elements holding its three nodes. The faces' first diagonal alone (corners
// 0-2, as before) gives triangles of faces 4 and 5 that no tet has (the test can fail).
TEST(Surface, AHexFacesTrianglesAreFacesOfItsElementsTets) {
  MeshSpec spec;
  spec.cells = {3, 3, 4};
  spec.jitter = 0.2;
  const Mesh m = build_mesh(spec, *Tpetra::getDefaultComm());
  auto conn = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), m.conn);
  std::set<std::array<GlobalId, 3>> tet_faces, first_diagonal;
  for (std::size_t e = 0; e < m.local_elements(); ++e) {
    for (const auto& t : kHexTets)
      for (int skip = 0; skip < 4; ++skip) {
        std::array<GlobalId, 3> f;
        int k = 0;
        for (int a = 0; a < 4; ++a)
          if (a != skip) f[k++] = m.node_gid[conn(e, t[a])];
        std::sort(f.begin(), f.end());
        tet_faces.insert(f);
      }
    for (const auto& q : kHexFaces)
      for (const auto& tri : {std::array<int, 3>{q[0], q[1], q[2]}, std::array<int, 3>{q[0], q[2], q[3]}}) {
        std::array<GlobalId, 3> f{m.node_gid[conn(e, tri[0])], m.node_gid[conn(e, tri[1])], m.node_gid[conn(e, tri[2])]};
        std::sort(f.begin(), f.end());
        first_diagonal.insert(f);
      }
  }
  const LocalBoundary b = local_boundary(m);
  long long checked = 0, missing = 0, missing_first = 0;
  for (auto f : b.triangles) {
    std::sort(f.begin(), f.end());
    ++checked;
    missing += !tet_faces.count(f);
  }
  // The old split on this rank's faces, for the can-fail half.
  for (const auto& f : first_diagonal) missing_first += !tet_faces.count(f);
  EXPECT_GT(checked, 0);
  EXPECT_EQ(missing, 0);
  EXPECT_GT(missing_first, 0);
  for (int f = 0; f < 6; ++f) EXPECT_EQ(hex_face_diagonal(f), f >= 4 ? 1 : 0) << "face " << f;
}

namespace {

// A unit cube as STL triangles (outward), ASCII or binary.
std::string cube_stl(bool binary) {
  const double c[8][3] = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}, {0, 0, 1}, {1, 0, 1}, {1, 1, 1}, {0, 1, 1}};
  const int q[6][4] = {{0, 3, 2, 1}, {4, 5, 6, 7}, {0, 1, 5, 4}, {1, 2, 6, 5}, {2, 3, 7, 6}, {3, 0, 4, 7}};
  std::vector<std::array<int, 3>> tris;
  for (const auto& f : q) {
    tris.push_back({f[0], f[1], f[2]});
    tris.push_back({f[0], f[2], f[3]});
  }
  std::string out;
  if (!binary) {
    out = "solid cube\n";
    for (const auto& t : tris) {
      out += " facet normal 0 0 0\n  outer loop\n";
      for (int v : t) out += "   vertex " + std::to_string(c[v][0]) + " " + std::to_string(c[v][1]) + " " + std::to_string(c[v][2]) + "\n";
      out += "  endloop\n endfacet\n";
    }
    return out + "endsolid cube\n";
  }
  out.assign(80, ' ');
  const std::uint32_t n = static_cast<std::uint32_t>(tris.size());
  out.append(reinterpret_cast<const char*>(&n), 4);
  for (const auto& t : tris) {
    float rec[12] = {0, 0, 0};
    for (int k = 0; k < 3; ++k)
      for (int d = 0; d < 3; ++d) rec[3 + 3 * k + d] = static_cast<float>(c[t[k]][d]);
    out.append(reinterpret_cast<const char*>(rec), 48);
    out.append(2, '\0');
  }
  return out;
}

}  // namespace

TEST(Voxelize, SurfacesAreReadCheckedClosedAndFilled) {
  // STL, ASCII and binary: corners merged into 8 vertices; the inside test and the voxelizer on them.
  for (const bool binary : {false, true}) {
    const TriangleSurface cube = read_triangle_surface(write_file(binary ? "cube_bin.stl" : "cube.stl", cube_stl(binary)));
    EXPECT_EQ(cube.vertices.size(), 8u);
    EXPECT_EQ(cube.triangles.size(), 12u);
    const InsideTest in(cube);
    EXPECT_TRUE(in.inside({0.5, 0.5, 0.5}));
    EXPECT_TRUE(in.inside({0.25, 0.5, 0.75}));  // a ray through the cube's edges and diagonals
    EXPECT_FALSE(in.inside({1.5, 0.5, 0.5}));
    EXPECT_FALSE(in.inside({-0.5, 0.5, 0.5}));
    const Lattice L = voxelize(cube, 0.25);
    EXPECT_EQ(L.mesh.elements(), 64u);
    EXPECT_EQ(L.mesh.nodes(), 125u);
  }
  // An open surface (one triangle missing) is named.
  std::string cube = cube_stl(false);
  const auto cut = cube.find(" facet", cube.find(" facet") + 1);
  cube.erase(cut, cube.find("endfacet", cut) + 9 - cut);
  try {
    read_triangle_surface(write_file("open.stl", cube));
    ADD_FAILURE() << "an open surface was accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("the surface is not closed: the edge from vertex"), std::string::npos) << e.what();
  }
  // The ball: cells whose centres lie inside the icosphere's inscribed sphere are kept, those outside
  // its circumscribed sphere are not; the lattice's volume is the ball's to the cells' resolution.
  const TriangleSurface ball = read_triangle_surface(mesh_path("ball.obj"));
  EXPECT_EQ(ball.triangles.size(), 320u);
  double r_in = 1.0;
  for (const auto& t : ball.triangles) {
    const auto &a = ball.vertices[t[0]], &b = ball.vertices[t[1]], &c = ball.vertices[t[2]];
    const double u[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]}, v[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
    double n[3] = {u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]};
    const double len = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
    r_in = std::min(r_in, std::fabs(n[0] * a[0] + n[1] * a[1] + n[2] * a[2]) / len);
  }
  // Triangles flipped at random (as some exporters write them) come back consistent and outward.
  {
    std::ifstream in(mesh_path("ball.obj"));
    std::string text, line;
    int f = 0;
    while (std::getline(in, line)) {
      if (line.rfind("f ", 0) == 0 && (f++ % 3 == 0)) {
        std::istringstream ss(line.substr(2));
        std::string a, b, c;
        ss >> a >> b >> c;
        line = "f " + a + " " + c + " " + b;
      }
      text += line + "\n";
    }
    TriangleSurface flipped = read_triangle_surface(write_file("flipped.obj", text));
    Obj o;
    o.v = flipped.vertices;
    o.f = flipped.triangles;
    EXPECT_NEAR(check_closed(o, "flipped ball"), 4.0, 0.2);  // the icosphere's volume, positive: outward
  }
  const Lattice L = voxelize(ball, 0.125);
  std::size_t kept = 0;
  for (int k = 0; k < L.cells[2]; ++k)
    for (int j = 0; j < L.cells[1]; ++j)
      for (int i = 0; i < L.cells[0]; ++i) {
        const double c[3] = {L.origin[0] + (i + 0.5) * L.h, L.origin[1] + (j + 0.5) * L.h, L.origin[2] + (k + 0.5) * L.h};
        const double r = std::sqrt(c[0] * c[0] + c[1] * c[1] + c[2] * c[2]);
        const bool in = L.cell_element[(static_cast<std::size_t>(k) * L.cells[1] + j) * L.cells[0] + i] >= 0;
        if (r < r_in - 1e-9) {
          EXPECT_TRUE(in) << "cell centre at radius " << r;
        }
        if (r > 1.0 + 1e-9) {
          EXPECT_FALSE(in) << "cell centre at radius " << r;
        }
        kept += in;
      }
  EXPECT_EQ(kept, L.mesh.elements());
  const double V = static_cast<double>(kept) * std::pow(0.125, 3), ball_volume = 4.0 / 3.0 * M_PI;
  EXPECT_NEAR(V / ball_volume, 1.0, 0.05);
  for (std::size_t e = 0; e < L.mesh.elements(); ++e) EXPECT_NEAR(hex_volume(L.mesh, e), std::pow(0.125, 3), 1e-15);
  if (world()->getRank() == 0)
    std::printf("[ info ] ball voxelized at h = 0.125: %zu cells, volume %.4f of %.4f; inscribed radius %.4f\n", kept, V,
                ball_volume, r_in);
}

namespace {

// Axis-aligned boxes [lo, hi] as one OBJ, every box written outward (or inward where flip says).
struct Box {
  double lo[3], hi[3];
  bool flip = false;
};
std::string boxes_obj(const std::vector<Box>& boxes) {
  std::string out;
  const int q[6][4] = {{0, 3, 2, 1}, {4, 5, 6, 7}, {0, 1, 5, 4}, {1, 2, 6, 5}, {2, 3, 7, 6}, {3, 0, 4, 7}};
  int base = 1;
  for (const Box& b : boxes) {
    for (int v = 0; v < 8; ++v) {
      const int bit[3] = {(v == 1 || v == 2 || v == 5 || v == 6), (v == 2 || v == 3 || v == 6 || v == 7), v >= 4};
      out += "v";
      for (int d = 0; d < 3; ++d) out += " " + std::to_string(bit[d] ? b.hi[d] : b.lo[d]);
      out += "\n";
    }
    for (const auto& f : q) {
      const int a = base + f[0], c = base + f[2];
      const int p = base + (b.flip ? f[3] : f[1]), r = base + (b.flip ? f[1] : f[3]);
      out += "f " + std::to_string(a) + " " + std::to_string(p) + " " + std::to_string(c) + " " + std::to_string(r) + "\n";
    }
    base += 8;
  }
  return out;
}

// Signed volume of the triangles of a surface whose first vertex is a corner of the box.
double shell_volume(const TriangleSurface& s, const Box& b) {
  double v = 0.0;
  for (const auto& T : s.triangles) {
    const auto &a = s.vertices[T[0]], &p = s.vertices[T[1]], &c = s.vertices[T[2]];
    bool in = true;
    for (int d = 0; d < 3; ++d) in = in && (std::fabs(a[d] - b.lo[d]) < 1e-12 || std::fabs(a[d] - b.hi[d]) < 1e-12);
    if (in) v += (a[0] * (p[1] * c[2] - p[2] * c[1]) - a[1] * (p[0] * c[2] - p[2] * c[0]) + a[2] * (p[0] * c[1] - p[1] * c[0])) / 6.0;
  }
  return v;
}

}  // namespace

TEST(Voxelize, EveryShellIsTurnedOutOfTheMaterialACavityInward) {
  // A hollow box (outer [0,3]^3, cavity [1,2]^3) with an island box inside the cavity, each shell
  // written with the orientation an exporter might choose; the material's outward normal is the
  // outer shell's outward one, the cavity's inward one (into the hole), the island's outward one.
  for (const bool flip : {false, true}) {
    const Box outer{{0, 0, 0}, {3, 3, 3}, flip}, cavity{{1, 1, 1}, {2, 2, 2}, false}, island{{1.25, 1.25, 1.25}, {1.75, 1.75, 1.75}, !flip};
    const TriangleSurface s = read_triangle_surface(write_file("hollow.obj", boxes_obj({outer, cavity, island})));
    EXPECT_NEAR(shell_volume(s, outer), 27.0, 1e-9) << "outer shell";
    EXPECT_NEAR(shell_volume(s, cavity), -1.0, 1e-9) << "cavity";
    EXPECT_NEAR(shell_volume(s, island), 0.125, 1e-9) << "island";
  }
}

TEST(Voxelize, OnlyTheLargestFaceConnectedPieceIsKeptAndTheRestIsNotedOrRefused) {
  // A 4x4x4-cell cube and a one-cell box beside it: the stray cell is removed and the header says so.
  const Lattice L = voxelize(read_triangle_surface(write_file("stray.obj", boxes_obj({{{0, 0, 0}, {1, 1, 1}}, {{1.3, 1.3, 1.3}, {1.55, 1.55, 1.55}}}))), 0.25);
  EXPECT_EQ(L.mesh.elements(), 64u);
  EXPECT_EQ(L.mesh.nodes(), 125u);
  ASSERT_EQ(L.mesh.notes.size(), 1u);
  EXPECT_NE(L.mesh.notes[0].find("1 of 65 cells inside the surface removed"), std::string::npos) << L.mesh.notes[0];
  // Two bodies of the same size: which one to simulate is not Sinew's guess.
  try {
    voxelize(read_triangle_surface(write_file("twins.obj", boxes_obj({{{0, 0, 0}, {1, 1, 1}}, {{2, 0, 0}, {3, 1, 1}}}))), 0.25);
    ADD_FAILURE() << "two separate bodies were voxelized as one";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("form 2 pieces joined by no face (the largest has 64 of 128 cells)"), std::string::npos) << e.what();
  }
  // Two cubes touching along an edge only would hinge on a line of nodes: also two pieces.
  try {
    voxelize(read_triangle_surface(write_file("hinge.obj", boxes_obj({{{0, 0, 0}, {1, 1, 1}}, {{1, 1, 0}, {2, 2, 1}}}))), 0.25);
    ADD_FAILURE() << "two cubes joined by an edge were voxelized as one body";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("pieces joined by no face"), std::string::npos) << e.what();
  }
  // A cell size that would overflow the lattice's counts is refused before any allocation.
  const TriangleSurface cube = read_triangle_surface(write_file("cube_tiny.stl", cube_stl(false)));
  for (const double h : {1e-4, 1e-300}) {
    try {
      voxelize(cube, h);
      ADD_FAILURE() << "cell size " << h << " accepted";
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find("choose a larger cell size"), std::string::npos) << e.what();
    }
  }
}

TEST(Voxelize, ATruncatedBinaryStlIsNamedAsSuch) {
  std::string stl = cube_stl(true);
  stl.resize(stl.size() - 30);
  try {
    read_triangle_surface(write_file("cut.stl", stl));
    ADD_FAILURE() << "a truncated binary STL was accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("declares 12 triangles, which take 684 bytes, has 654 bytes (truncated?)"), std::string::npos)
        << e.what();
  }
}

namespace {

// The ball (ball.obj) filled with cells of 0.25, Stable Neo-Hookean of Young modulus `young`; `rest`:
// the Loading (and Solver) sections; no HDF5 output or checkpoints (the tests read the skin OBJs).
std::string ball_scene(const std::string& name, double young, const std::string& rest) {
  return R"x(<ParameterList name="Sinew">
  <Parameter name="Scene" type="string" value=")x" + name + R"x("/>
  <ParameterList name="Mesh">
    <Parameter name="Type" type="string" value="voxelize"/>
    <Parameter name="Surface" type="string" value=")x" + mesh_path("ball.obj") + R"x("/>
    <Parameter name="Cell size" type="double" value="0.25"/>
  </ParameterList>
  <ParameterList name="Material">
    <Parameter name="Model" type="string" value="stable-neohookean"/>
    <Parameter name="Young modulus" type="double" value=")x" + std::to_string(young) + R"x("/>
    <Parameter name="Poisson ratio" type="double" value="0.45"/>
  </ParameterList>
)x" + rest + R"x(
  <ParameterList name="Output">
    <Parameter name="HDF5" type="bool" value="false"/>
    <Parameter name="Checkpoint every" type="int" value="0"/>
  </ParameterList>
</ParameterList>)x";
}

}  // namespace

TEST(Voxelize, TheSkinFollowsTheLatticeAndBonesTakeTheNodesInsideThem) {
  // The ball filled with cells of 0.25; every node moved by one affine map (all nodes prescribed):
  // trilinear interpolation reproduces an affine field, so every skin vertex must land on the affine
  // image of its rest position, on any number of ranks. A bone given as a surface takes exactly the
  // lattice nodes inside it.
  const std::string xml = ball_scene("ball", 1.0, R"x(  <ParameterList name="Loading">
    <Parameter name="Steps" type="int" value="1"/>
    <ParameterList name="Boundary conditions">
      <ParameterList name="everything">
        <Parameter name="Region" type="string" value="all"/>
        <Parameter name="Motion" type="string" value="affine"/>
        <Parameter name="Gradient" type="Array(double)" value="{0.2, 0.1, 0, 0, -0.1, 0.05, 0.1, 0, 0.3}"/>
        <Parameter name="Displacement" type="Array(double)" value="{0.5, 0, -0.25}"/>
      </ParameterList>
    </ParameterList>
  </ParameterList>)x");
  const std::string dir = "test_results/voxel_ball" + tag();
  Simulation sim(config(xml, dir), RunOptions{true, ""});
  ASSERT_EQ(sim.run(), 0);
  const TriangleSurface ball = read_triangle_surface(mesh_path("ball.obj"));
  const double G[9] = {0.2, 0.1, 0, 0, -0.1, 0.05, 0.1, 0, 0.3}, d[3] = {0.5, 0, -0.25};
  double err = 0.0;
  for (int step : {0, 1}) {
    const Obj skin = read_obj(dir + "/skin_00000" + std::to_string(step) + ".obj");
    ASSERT_EQ(skin.v.size(), ball.vertices.size());
    ASSERT_EQ(skin.f.size(), ball.triangles.size());
    for (std::size_t v = 0; v < skin.v.size(); ++v)
      for (int i = 0; i < 3; ++i) {
        double expect = ball.vertices[v][i];
        if (step == 1) {
          expect += d[i];
          for (int j = 0; j < 3; ++j) expect += G[3 * i + j] * ball.vertices[v][j];
        }
        err = std::max(err, std::fabs(skin.v[v][i] - expect));
      }
    EXPECT_GT(check_closed(skin, "skin"), 3.5);  // closed, consistently oriented, outward (the ball: 4.19)
  }
  EXPECT_LT(err, 1e-9);  // the OBJ holds 10 significant digits
  if (world()->getRank() == 0) std::printf("[ info ] skin vertices vs the affine map: max error %.2e\n", err);

  // The bone region: the nodes inside core.obj, the same as testing every lattice node directly.
  RegionParameters bone;
  bone.region = "inside";
  bone.surface = mesh_path("core.obj");
  const Mesh& mesh = sim.scene().system().mesh();
  const std::vector<int> nodes = select_region(mesh, *world(), bone, "bone");
  const TriangleSurface core = read_triangle_surface(mesh_path("core.obj"));
  const InsideTest in(core);
  auto X = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), mesh.X);
  long long mine = 0, total = 0, expect_total = 0;
  for (std::size_t n = 0; n < mesh.local_nodes(); ++n) {
    const bool picked = std::binary_search(nodes.begin(), nodes.end(), static_cast<int>(n));
    EXPECT_EQ(picked, in.inside({X(n, 0), X(n, 1), X(n, 2)}));
    const double r = std::sqrt(X(n, 0) * X(n, 0) + X(n, 1) * X(n, 1) + X(n, 2) * X(n, 2));
    if (r < 0.3) {
      EXPECT_TRUE(picked);  // well inside the core (inscribed radius about 0.33)
    }
    if (r > 0.35) {
      EXPECT_FALSE(picked);
    }
    if (n < mesh.n_owned_nodes) mine += picked;
  }
  Teuchos::reduceAll(*world(), Teuchos::REDUCE_SUM, 1, &mine, &total);
  // Lattice nodes at multiples of 0.25 around the centre: (0,0,0) and its 6 neighbours at 0.25 lie inside.
  expect_total = 7;
  EXPECT_EQ(total, expect_total);
}

TEST(Voxelize, TheSkinFollowsASolvedDeformation) {
  // The ball on its bottom layer of nodes, sagging under a body force (a solve, not a prescribed map):
  // each skin vertex in a kept cell must sit at its rest position plus the trilinear interpolation of
  // the solved nodal displacements of that cell, computed here from the lattice and the gathered
  // solution (not from the embedding's weights).
  const std::string xml = ball_scene("ball_sag", 100.0, R"x(  <ParameterList name="Loading">
    <Parameter name="Steps" type="int" value="2"/>
    <Parameter name="Body force" type="Array(double)" value="{0.3, 0, -1.0}"/>
    <ParameterList name="Boundary conditions">
      <ParameterList name="base"><Parameter name="Region" type="string" value="face z-"/></ParameterList>
    </ParameterList>
  </ParameterList>
  <ParameterList name="Solver"><Parameter name="Absolute tolerance" type="double" value="1.0e-8"/></ParameterList>)x");
  const std::string dir = "test_results/voxel_sag" + tag();
  Simulation sim(config(xml, dir), RunOptions{true, ""});
  ASSERT_EQ(sim.run(), 0);
  const auto u = gather(sim.displacement());  // by global id: the voxelizer's node order
  const TriangleSurface ball = read_triangle_surface(mesh_path("ball.obj"));
  const Lattice L = voxelize(ball, 0.25);
  ASSERT_EQ(u.size(), 3 * L.mesh.nodes());
  const Obj skin = read_obj(dir + "/skin_000002.obj");
  ASSERT_EQ(skin.v.size(), ball.vertices.size());
  double err = 0.0, sag = 0.0;
  std::size_t checked = 0;
  for (std::size_t v = 0; v < ball.vertices.size(); ++v) {
    const auto& p = ball.vertices[v];
    int c[3];
    for (int d = 0; d < 3; ++d) c[d] = static_cast<int>(std::floor((p[d] - L.origin[d]) / L.h));
    if (c[0] < 0 || c[1] < 0 || c[2] < 0 || c[0] >= L.cells[0] || c[1] >= L.cells[1] || c[2] >= L.cells[2]) continue;
    const int e = L.cell_element[(static_cast<std::size_t>(c[2]) * L.cells[1] + c[1]) * L.cells[0] + c[0]];
    if (e < 0) continue;  // a vertex outside every kept cell is extrapolated from a neighbour
    // The cell's lowest corner from its nodes' coordinates; weights from the vertex's offset.
    double lo[3] = {HUGE_VAL, HUGE_VAL, HUGE_VAL};
    for (int a = 0; a < 8; ++a)
      for (int d = 0; d < 3; ++d) lo[d] = std::min(lo[d], L.mesh.xyz[3 * L.mesh.conn[8 * e + a] + d]);
    double x[3] = {p[0], p[1], p[2]};
    for (int a = 0; a < 8; ++a) {
      const int n = L.mesh.conn[8 * e + a];
      double w = 1.0;
      for (int d = 0; d < 3; ++d) {
        const double t = (p[d] - lo[d]) / L.h;
        w *= L.mesh.xyz[3 * n + d] > lo[d] + 0.5 * L.h ? t : 1.0 - t;
      }
      for (int d = 0; d < 3; ++d) x[d] += w * u[3 * n + d];
    }
    for (int d = 0; d < 3; ++d) err = std::max(err, std::fabs(skin.v[v][d] - x[d]));
    sag = std::max(sag, std::fabs(x[2] - p[2]));
    ++checked;
  }
  EXPECT_GT(checked, ball.vertices.size() / 2);
  EXPECT_GT(sag, 0.05);   // it did deform
  EXPECT_LT(err, 1e-9);   // the OBJ holds 10 significant digits
  if (world()->getRank() == 0)
    std::printf("[ info ] solved sag: %zu of %zu skin vertices checked, max sag %.3f, max error %.2e\n", checked,
                ball.vertices.size(), sag, err);
}
