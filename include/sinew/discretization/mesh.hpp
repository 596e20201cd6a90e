// Distributed structured meshes: an "extruded lattice" (a 2D mask of active cells in x-y, repeated over
// nz layers in z) covers the box and the voxelized cylinder of the paper's stretch test (Fig. 5). Hexes
// can be split into six tetrahedra (Kuhn split, conforming without parity rules).
//
// Distribution: element layers are split into contiguous z-slabs, one per rank. A rank builds only its
// slab plus one ghost layer of elements below it, so every row it owns sees all of its elements and
// assembly needs no communication (Tpetra's "total element loop" pattern). Node DOF global ids are
// interleaved, 3 * node + component, with a node's three DOFs on one rank, as MueLu expects.
#pragma once

#include <sinew/core/errors.hpp>
#include <sinew/core/section.hpp>

#include <Kokkos_Core.hpp>
#include <Teuchos_Comm.hpp>
#include <Teuchos_RCP.hpp>

#include <array>
#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

namespace sinew {

enum class ElementType { Hex8, Tet4 };

constexpr int nodes_per_element(ElementType t) { return t == ElementType::Hex8 ? 8 : 4; }
constexpr int quadrature_points(ElementType t) { return t == ElementType::Hex8 ? 8 : 1; }

// A hex8 (VTK node order): its faces, outward (counter-clockwise seen from outside), and its Kuhn split
// into six positively oriented tets around the diagonal 0-6 (the contact detection's inside test: the
// paper locates samples in "a tetrahedralization of the hexahedral mesh", Sec. 6; the tet meshes made
// from hexes; scripts/sinew-interpenetration).
inline constexpr int kHexFaces[6][4] = {{0, 3, 2, 1}, {4, 5, 6, 7}, {0, 1, 5, 4}, {1, 2, 6, 5}, {2, 3, 7, 6}, {3, 0, 4, 7}};
inline constexpr int kHexTets[6][4] = {{0, 1, 2, 6}, {0, 2, 3, 6}, {0, 3, 7, 6}, {0, 7, 4, 6}, {0, 4, 5, 6}, {0, 5, 1, 6}};
// The diagonal of hex face f that the six tets cut it along: 0 for its corners 0-2, 1 for 1-3. The
// boundary surface splits each face the same way, so that its triangles are the tets' own faces.
constexpr int hex_face_diagonal(int f) {
  const int a = kHexFaces[f][0], c = kHexFaces[f][2];
  for (const auto& t : kHexTets)
    for (int i = 0; i < 4; ++i)
      for (int j = 0; j < 4; ++j)
        if (t[i] == a && t[j] == c) return 0;
  return 1;
}
std::string to_string(ElementType t);

inline const Choices<ElementType>& element_choices() {
  static const Choices<ElementType> c = {{"hex8", ElementType::Hex8}, {"tet4", ElementType::Tet4}};
  return c;
}

// Where a scene's mesh comes from: a lattice Sinew generates (box, cylinder), a mesh file, or a lattice
// filling a closed surface (voxelize) or a rigged character's skin (rig).
enum class MeshType { Box, Cylinder, File, Voxelize, Rig };
std::string to_string(MeshType t);
inline const Choices<MeshType>& mesh_type_choices() {
  static const Choices<MeshType> c = {{"box", MeshType::Box},
                                      {"cylinder", MeshType::Cylinder},
                                      {"file", MeshType::File},
                                      {"voxelize", MeshType::Voxelize},
                                      {"rig", MeshType::Rig}};
  return c;
}
// A lattice fills a surface (and carries it along as the skin): voxelize and rig.
inline bool has_skin(MeshType t) { return t == MeshType::Voxelize || t == MeshType::Rig; }

// The "Mesh" section of a scene.
struct MeshParameters {
  MeshType type = MeshType::Box;
  std::string file, surface, rig, rig_meshes;
  double cell_size = 0.0;
  // Not entries: the scene sets them from Skeleton/Clip and Skeleton/Rest time (the pose a rig's skin is
  // voxelized in; rest_time < 0: the bind pose).
  std::string rig_rest_clip;
  double rig_rest_time = -1.0;
  ElementType element = ElementType::Hex8;
  std::array<int, 3> cells{};
  std::array<double, 3> lower{}, upper{};
  double radius = 0.0, length = 0.0, jitter = 0.0;
  int jitter_seed = 0;

  template <class V>
  void visit(V& v) {
    v.choice("Type", type, MeshType::Box, mesh_type_choices(),
             "box or cylinder (lattices Sinew generates; the cylinder voxelized, axis along z), file, voxelize "
             "(a hex8 lattice filling a closed surface), or rig (a hex8 lattice filling a rigged character's skin)");
    v.entry("File", file, std::string(""),
            "file: a Gmsh mesh (.msh, format 4.1 or 2.2, ASCII or binary) of tet4 or hex8 elements; a relative "
            "path is taken from the scene file's folder");
    v.entry("Surface", surface, std::string(""),
            "voxelize: a closed triangle surface (.obj or .stl) to fill with hex8 cells; it is carried along and "
            "written per output step as DIR/skin_NNNNNN.obj; a relative path is taken from the scene file's folder");
    v.entry("Rig", rig, std::string(""),
            "rig: a rigged character (glTF, FBX, COLLADA, DirectX .x; read with Assimp, see sinew-rig) whose skin, in "
            "its rest pose, is filled with hex8 cells (inside: the generalized winding number, so skins made of "
            "several open pieces work); a relative path is taken from the scene file's folder");
    v.entry("Rig meshes", rig_meshes, std::string(""), "rig: the meshes that form the flesh, comma-separated (empty: all)");
    v.entry("Cell size", cell_size, 0.0, "voxelize, rig: the edge length of the lattice cells", Range::non_negative());
    v.choice("Element", element, ElementType::Hex8, element_choices(),
             "hex8 (2x2x2 Gauss points) or tet4 (each lattice cell split into 6 tets, 1 point)");
    v.entry("Elements", cells, {4, 4, 4}, "cells along x, y, z (cylinder: across the diameter in x and y, along z)",
            Range::closed(1, 100000));
    v.entry("Lower corner", lower, {0.0, 0.0, 0.0}, "box: lower corner");
    v.entry("Upper corner", upper, {1.0, 1.0, 1.0}, "box: upper corner");
    v.entry("Radius", radius, 0.5, "cylinder: radius", Range::positive());
    v.entry("Length", length, 1.0, "cylinder: length along z (from z = 0)", Range::positive());
    v.entry("Jitter", jitter, 0.0, "move nodes off the bounding box at random by up to this many cell sizes",
            Range::closed_open(0.0, 10.0));
    v.entry("Jitter seed", jitter_seed, 1, "seed of the jitter");
  }
  template <class Context>
  void check(const Context& c) const {
    if (type == MeshType::File) {
      if (file.empty()) c.fail("missing entry 'File' (the mesh file of Type file)", InputErrorKind::MissingEntry);
      for (const char* lattice_only : {"Element", "Elements", "Lower corner", "Upper corner", "Radius", "Length", "Jitter",
                                       "Jitter seed", "Surface", "Cell size", "Rig", "Rig meshes"})
        if (c.given(lattice_only))
          c.fail("'" + std::string(lattice_only) + "' applies to generated meshes, not to Type file (the file says it)");
      return;
    }
    if (type == MeshType::Rig) {
      if (rig.empty()) c.fail("missing entry 'Rig' (the rigged character whose skin to fill)", InputErrorKind::MissingEntry);
      if (!(cell_size > 0.0)) c.fail("missing entry 'Cell size' (> 0) of the voxel lattice", InputErrorKind::MissingEntry);
      for (const char* other : {"File", "Surface", "Elements", "Lower corner", "Upper corner", "Radius", "Length", "Jitter", "Jitter seed"})
        if (c.given(other)) c.fail("'" + std::string(other) + "' does not apply to Type rig (Rig and Cell size say it)");
      if (c.given("Element") && element != ElementType::Hex8) c.fail("Type rig makes hex8 cells ('Element' tet4 is not offered)");
      return;
    }
    if (c.given("Rig") || c.given("Rig meshes")) c.fail("'Rig' and 'Rig meshes' apply to Type rig only");
    if (type == MeshType::Voxelize) {
      if (surface.empty()) c.fail("missing entry 'Surface' (the closed surface to voxelize)", InputErrorKind::MissingEntry);
      if (!(cell_size > 0.0)) c.fail("missing entry 'Cell size' (> 0) of the voxel lattice", InputErrorKind::MissingEntry);
      for (const char* other : {"File", "Elements", "Lower corner", "Upper corner", "Radius", "Length", "Jitter", "Jitter seed"})
        if (c.given(other)) c.fail("'" + std::string(other) + "' does not apply to Type voxelize (Surface and Cell size say it)");
      if (c.given("Element") && element != ElementType::Hex8) c.fail("Type voxelize makes hex8 cells ('Element' tet4 is not offered)");
      return;
    }
    if (c.given("Surface") || c.given("Cell size")) c.fail("'Surface' and 'Cell size' apply to Type voxelize only");
    if (c.given("File")) c.fail("'File' applies to Type file only");
    if (!c.given("Elements")) c.fail("missing entry 'Elements' (cells along x, y, z)", InputErrorKind::MissingEntry);
    for (int k = 0; k < 3; ++k)
      if (type == MeshType::Box && !(upper[k] > lower[k])) c.fail("'Upper corner' must exceed 'Lower corner' in every coordinate");
  }
};

// A lattice: an extruded 2D mask of cells over a bounding box.
struct MeshSpec {
  MeshType shape = MeshType::Box;  // Box or Cylinder
  ElementType element = ElementType::Hex8;
  std::array<int, 3> cells{{4, 4, 4}};  // box: cells per axis; cylinder: cells across the diameter (x, y), along z
  std::array<double, 3> lower{{0, 0, 0}}, upper{{1, 1, 1}};  // box corners; cylinder: its bounding box
  double jitter = 0.0;  // random displacement of nodes off the bounding box, in cell sizes (robustness tests)
  int jitter_seed = 1;
};

// The lattice a "Mesh" section describes.
MeshSpec lattice_spec(const MeshParameters& p);

using GlobalId = long long;

// The volume groups an element belongs to, one bit each: a mesh may have at most 64.
using GroupMask = std::uint64_t;
constexpr int kMaxVolumeGroups = 64;

// A triangle surface carried along by the mesh (a voxelized character's skin): each vertex moves with
// the displacement interpolated from eight nodes (global ids) by fixed weights.
struct EmbeddedSurface {
  std::vector<std::array<double, 3>> rest;
  std::vector<std::array<int, 3>> triangles;
  std::vector<std::array<GlobalId, 8>> nodes;
  std::vector<std::array<double, 8>> weights;
};

// One rank's part of the mesh. Host-side vectors describe the layout; Views hold what kernels read.
//
// Global ids do not depend on the number of ranks (lattice position, or the file's order), so results
// can be compared across layouts. Output files need each rank's rows contiguous, which a partition of
// an unstructured mesh does not give: the output numbering renumbers owned nodes and elements rank by
// rank (node_output_id), and files keep the global ids beside the data.
struct Mesh {
  ElementType type = ElementType::Hex8;
  GlobalId global_nodes = 0, global_elements = 0;
  std::array<double, 3> lower{}, upper{};  // global bounding box of the reference configuration
  std::string source;                      // what the mesh came from, for the run's header

  // Local nodes: the first n_owned_nodes are owned (ascending global id), the rest are ghosts.
  std::vector<GlobalId> node_gid;
  std::size_t n_owned_nodes = 0;
  Kokkos::View<double* [3]> X;  // reference coordinates of local nodes
  std::vector<int> node_owner;  // the rank owning each local node

  // Local elements: the first n_owned_elements are owned, the rest are ghosts (needed for owned rows).
  std::vector<GlobalId> element_gid;
  std::size_t n_owned_elements = 0;
  Kokkos::View<int**> conn;  // element x nodes_per_element, local node indices

  // Tags of a mesh file's nodes and elements (empty for lattices): messages and output use them.
  std::vector<long long> node_tag, element_tag;

  // Element groups (the volume physical groups of a mesh file): their names, and each local element's
  // groups as a bit mask (an element may be in several: "all" and "tendon"; empty for lattices).
  std::vector<std::string> element_group_names;
  std::vector<GroupMask> element_groups;
  bool in_group(std::size_t e, int g) const { return !element_groups.empty() && ((element_groups[e] >> g) & 1u); }
  // Node groups (surface, curve and point physical groups): names and, per group, the local nodes
  // (owned and ghost) in it.
  std::vector<std::string> node_group_names;
  std::vector<std::vector<int>> node_group_nodes;

  // Output numbering: owned nodes and elements are rows [first_output_*, first_output_* + n_owned_*)
  // of the output files; node_output_id gives every local node's row (connectivity needs the ghosts').
  GlobalId first_output_node = 0, first_output_element = 0;
  std::vector<GlobalId> node_output_id;
  long long reoriented = 0;  // elements of a mesh file reordered to positive orientation (all ranks)
  std::vector<std::string> notes;  // what reading the file changed (reordered, merged, removed), all ranks
  // The surface a voxelized mesh was made from (rank 0 holds it; has_embedded is set on every rank).
  std::shared_ptr<const EmbeddedSurface> embedded;
  bool has_embedded = false;

  std::size_t local_nodes() const { return node_gid.size(); }
  std::size_t local_elements() const { return element_gid.size(); }
  // The file's tag of an element for messages, or its global id for a lattice.
  long long element_label(std::size_t local) const { return element_tag.empty() ? element_gid[local] : element_tag[local]; }
};

// Sets the output numbering (collective): exclusive prefix sums of the owned counts, and the ghost
// nodes' rows from their owners.
void number_for_output(Mesh& mesh, const Teuchos::Comm<int>& comm);

// Builds this rank's slab of the mesh described by spec.
Mesh build_mesh(const MeshSpec& spec, const Teuchos::Comm<int>& comm);

// This rank's part of the mesh a "Mesh" section describes: a generated lattice, or a mesh file read by
// rank 0 and distributed (collective; errors are raised on every rank).
Mesh build_scene_mesh(const MeshParameters& p, const Teuchos::Comm<int>& comm);

// Local node indices (owned and ghost) whose reference position satisfies pred.
std::vector<int> select_nodes(const Mesh& mesh, const std::function<bool(const std::array<double, 3>&)>& pred);

// A predicate for one face of the bounding box: "x-", "x+", "y-", "y+", "z-", "z+".
std::function<bool(const std::array<double, 3>&)> face_predicate(const Mesh& mesh, const std::string& face);

}  // namespace sinew
