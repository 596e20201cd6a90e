// Distributed structured meshes: an "extruded lattice" (a 2D mask of active cells in x-y, repeated over
// nz layers in z) covers the box and the voxelized cylinder of the paper's stretch test (Fig. 5). Hexes
// can be split into six tetrahedra (Kuhn split, conforming without parity rules).
//
// Distribution: element layers are split into contiguous z-slabs, one per rank. A rank builds only its
// slab plus one ghost layer of elements below it, so every row it owns sees all of its elements and
// assembly needs no communication (Tpetra's "total element loop" pattern). Node DOF global ids are
// interleaved, 3 * node + component, with a node's three DOFs on one rank, as MueLu expects.
#pragma once

#include <Kokkos_Core.hpp>
#include <Teuchos_Comm.hpp>
#include <Teuchos_RCP.hpp>

#include <array>
#include <functional>
#include <string>
#include <vector>

namespace Teuchos {
class ParameterList;
}

namespace sinew {

enum class ElementType { Hex8, Tet4 };

constexpr int nodes_per_element(ElementType t) { return t == ElementType::Hex8 ? 8 : 4; }
constexpr int quadrature_points(ElementType t) { return t == ElementType::Hex8 ? 8 : 1; }
std::string to_string(ElementType t);

struct MeshSpec {
  std::string shape = "box";  // box | cylinder
  ElementType element = ElementType::Hex8;
  std::array<int, 3> cells{{4, 4, 4}};  // box: cells per axis; cylinder: cells across the diameter (x, y), along z
  std::array<double, 3> lower{{0, 0, 0}}, upper{{1, 1, 1}};  // box corners; cylinder: its bounding box
  double jitter = 0.0;  // random displacement of nodes off the bounding box, in cell sizes (robustness tests)
  int jitter_seed = 1;
};

// Mesh spec from a "Mesh" sublist (validated; throws InputError naming the entry).
MeshSpec mesh_from_parameters(const Teuchos::ParameterList& list);
Teuchos::ParameterList valid_mesh_parameters();

using GlobalId = long long;

// One rank's part of the mesh. Host-side vectors describe the layout; Views hold what kernels read.
struct Mesh {
  ElementType type = ElementType::Hex8;
  GlobalId global_nodes = 0, global_elements = 0;
  std::array<double, 3> lower{}, upper{};  // global bounding box of the reference configuration

  // Local nodes: the first n_owned_nodes are owned (ascending global id), the rest are ghosts.
  std::vector<GlobalId> node_gid;
  std::size_t n_owned_nodes = 0;
  Kokkos::View<double* [3]> X;  // reference coordinates of local nodes

  // Local elements: the first n_owned_elements are owned, the rest are ghosts (needed for owned rows).
  std::vector<GlobalId> element_gid;
  std::size_t n_owned_elements = 0;
  Kokkos::View<int**> conn;  // element x nodes_per_element, local node indices

  std::size_t local_nodes() const { return node_gid.size(); }
  std::size_t local_elements() const { return element_gid.size(); }
};

// Builds this rank's slab of the mesh described by spec.
Mesh build_mesh(const MeshSpec& spec, const Teuchos::Comm<int>& comm);

// Local node indices (owned and ghost) whose reference position satisfies pred.
std::vector<int> select_nodes(const Mesh& mesh, const std::function<bool(const std::array<double, 3>&)>& pred);

// A predicate for one face of the bounding box: "x-", "x+", "y-", "y+", "z-", "z+".
std::function<bool(const std::array<double, 3>&)> face_predicate(const Mesh& mesh, const std::string& face);

}  // namespace sinew
