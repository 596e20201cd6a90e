// The discrete elastic system on Tpetra: DOF maps, the CRS graph (built once from the mesh), the
// assembly of energy, internal force and (projected) stiffness by the element kernels, the Dirichlet
// elimination (the algebra owns the essential DOFs, as MFEM's NonlinearForm does), and the rigid-body
// near-null space and coordinates MueLu needs.
#pragma once

#include <sinew/discretization/elements.hpp>
#include <sinew/discretization/mesh.hpp>
#include <sinew/materials/models.hpp>

#include <optional>

#include <Tpetra_CrsGraph_fwd.hpp>
#include <Tpetra_CrsMatrix_fwd.hpp>
#include <Tpetra_Import_fwd.hpp>
#include <Tpetra_Map.hpp>
#include <Tpetra_MultiVector_fwd.hpp>
#include <Tpetra_Vector_fwd.hpp>

namespace sinew {

using Map = Tpetra::Map<>;
using LO = Map::local_ordinal_type;
using GO = Map::global_ordinal_type;
using NodeType = Map::node_type;
using Vector = Tpetra::Vector<double, LO, GO, NodeType>;
using MultiVector = Tpetra::MultiVector<double, LO, GO, NodeType>;
using CrsGraph = Tpetra::CrsGraph<LO, GO, NodeType>;
using CrsMatrix = Tpetra::CrsMatrix<double, LO, GO, NodeType>;
using Import = Tpetra::Import<LO, GO, NodeType>;

struct AssemblyTotals;

// Global results of one evaluation (already reduced over ranks).
struct EvaluationTotals {
  double energy = 0.0;        // elastic energy minus body-force work
  double volume = 0.0;        // sum over quadrature points of J * reference volume
  double min_J = 0.0;         // smallest J at a quadrature point
  long long inverted = 0;     // quadrature points with J <= 0
  long long undefined = 0;    // points where the energy is +inf (Neo-Hookean, J <= 0)
};

enum class Backend { Default, Serial };

// Which law each element has: a default, and laws for named element groups (volume regions) of the mesh.
struct MaterialAssignment {
  MaterialSpec default_law;
  std::vector<std::pair<std::string, MaterialSpec>> regions;
};

class ElasticSystem {
 public:
  // Throws InputError when a region of `materials` is not an element group of the mesh.
  ElasticSystem(Teuchos::RCP<const Teuchos::Comm<int>> comm, Mesh mesh, const MaterialAssignment& materials);
  ElasticSystem(Teuchos::RCP<const Teuchos::Comm<int>> comm, Mesh mesh, const MaterialSpec& material)
      : ElasticSystem(std::move(comm), std::move(mesh), MaterialAssignment{material, {}}) {}
  ~ElasticSystem();

  const Mesh& mesh() const { return mesh_; }
  // The law of elements in no region (the only one for a mesh without regions).
  const MaterialSpec& material() const { return blocks_.front().law; }
  // Largest (mu_L + |lambda_L|) over the laws in use: the stiffness scale of the energy's terms.
  double stiffness_scale() const;
  Teuchos::RCP<const Teuchos::Comm<int>> comm() const { return comm_; }
  Teuchos::RCP<const Map> owned_dofs() const { return owned_dofs_; }
  Teuchos::RCP<const Map> overlap_dofs() const { return overlap_dofs_; }
  Teuchos::RCP<const Map> owned_nodes() const { return owned_nodes_; }
  Teuchos::RCP<const CrsGraph> graph() const { return graph_; }
  double reference_volume() const { return reference_volume_; }

  Teuchos::RCP<CrsMatrix> create_matrix() const;
  Teuchos::RCP<Vector> create_vector() const;

  // Dirichlet DOFs, given as local overlap DOF indices (3 * local node + component). Every rank must
  // mark its ghost DOFs too, which it can: selections are functions of the node's reference position.
  void set_fixed_dofs(const std::vector<int>& overlap_dofs);
  const std::vector<int>& fixed_owned_dofs() const { return fixed_owned_; }
  std::size_t global_fixed_dofs() const;
  void set_body_force(const std::array<double, 3>& force_per_reference_volume);

  // Energy, internal force (dE/du, zero in Dirichlet rows) and stiffness (projected as each law says,
  // or as `projection` says for all when given; Dirichlet rows and columns eliminated). force and K may
  // be null. u holds total displacements.
  EvaluationTotals evaluate(const Vector& u, Vector* force, CrsMatrix* K, Backend backend = Backend::Default,
                            std::optional<Projection> projection = std::nullopt) const;

  // Per owned element: volume-averaged energy density and J of the last evaluate() that asked for them.
  void element_fields(const Vector& u, std::vector<double>& psi, std::vector<double>& J) const;

  // Six rigid-body modes (3 translations, 3 rotations about the centroid) on the owned DOF map, and the
  // reference node coordinates (3 columns) on the owned node map: MueLu's "Nullspace" and "Coordinates".
  Teuchos::RCP<MultiVector> rigid_body_modes() const;
  Teuchos::RCP<MultiVector> coordinates() const;
  // The same written into existing multivectors (MueLu holds them by reference), of the reference
  // configuration or, when u (owned DOFs) is given, of the current one x = X + u: the tangent stiffness
  // at u annihilates infinitesimal rotations about x, not about X.
  void fill_rigid_body_modes(MultiVector& modes, const Vector* u) const;
  void fill_coordinates(MultiVector& X, const Vector* u) const;

 private:
  void build_blocks(const MaterialAssignment& materials);
  void build_graph();
  EvaluationTotals run(const Vector& u, Vector* force, CrsMatrix* K, Backend backend, std::optional<Projection> projection,
                       ElementFields<Kokkos::DefaultExecutionSpace::memory_space> fields) const;
  // Rows and columns of Dirichlet DOFs: off-diagonal entries zeroed, the diagonal kept (the sum of the
  // elements' own diagonal entries, a positive scale matching the stiffness, so CG sees a well-conditioned
  // identity-like block there); their force entries zeroed.
  void eliminate_dirichlet(Vector* force, CrsMatrix* K) const;

  // The elements of one law.
  struct Block {
    MaterialSpec law;
    Kokkos::View<int*> elements;  // local element ids
  };

  Teuchos::RCP<const Teuchos::Comm<int>> comm_;
  Mesh mesh_;
  std::vector<Block> blocks_;  // blocks_[0]: the default law (possibly with no elements)
  ElementData elements_;
  Teuchos::RCP<const Map> owned_dofs_, overlap_dofs_, owned_nodes_;
  Teuchos::RCP<const Import> importer_;
  Teuchos::RCP<const CrsGraph> graph_;
  Teuchos::RCP<Vector> u_overlap_;
  Kokkos::View<char*> fixed_;
  std::vector<int> fixed_owned_;
  bool any_fixed_ = false;  // some local (owned or ghost) DOF is fixed
  std::array<double, 3> body_{{0.0, 0.0, 0.0}};
  double reference_volume_ = 0.0;
};

}  // namespace sinew
