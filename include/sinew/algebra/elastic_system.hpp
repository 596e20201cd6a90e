// The discrete elastic system on Tpetra: DOF maps, the CRS graph (built once from the mesh), the
// assembly of energy, internal force and (projected) stiffness, Dirichlet elimination, and the
// rigid-body near-null-space and coordinates MueLu needs.
#pragma once

#include <sinew/discretization/elements.hpp>
#include <sinew/discretization/mesh.hpp>
#include <sinew/materials/models.hpp>

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

class ElasticSystem {
 public:
  ElasticSystem(Teuchos::RCP<const Teuchos::Comm<int>> comm, Mesh mesh, const MaterialSpec& material);
  ~ElasticSystem();

  const Mesh& mesh() const { return mesh_; }
  const MaterialSpec& material() const { return material_; }
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
  void set_projection(Projection p) { material_.projection = p; }

  // Energy, internal force (dE/du, zero in Dirichlet rows) and stiffness (projected as the material
  // says; Dirichlet rows and columns eliminated). force and K may be null. u holds total displacements.
  EvaluationTotals evaluate(const Vector& u, Vector* force, CrsMatrix* K, Backend backend = Backend::Default) const;

  // Per owned element: volume-averaged energy density and J of the last evaluate() that asked for them.
  void element_fields(const Vector& u, std::vector<double>& psi, std::vector<double>& J) const;

  // Six rigid-body modes (3 translations, 3 rotations about the centroid) on the owned DOF map, and the
  // reference coordinates (3 columns) on the owned node map: MueLu's "Nullspace" and "Coordinates".
  Teuchos::RCP<MultiVector> rigid_body_modes() const;
  Teuchos::RCP<MultiVector> coordinates() const;

 private:
  EvaluationTotals run(const Vector& u, Vector* force, CrsMatrix* K, Backend backend, bool fields,
                       Kokkos::View<double*> psi, Kokkos::View<double*> J) const;

  Teuchos::RCP<const Teuchos::Comm<int>> comm_;
  Mesh mesh_;
  MaterialSpec material_;
  ElementData elements_;
  Teuchos::RCP<const Map> owned_dofs_, overlap_dofs_, owned_nodes_;
  Teuchos::RCP<const Import> importer_;
  Teuchos::RCP<const CrsGraph> graph_;
  Teuchos::RCP<Vector> u_overlap_;
  Kokkos::View<char*> fixed_;
  std::vector<int> fixed_owned_;
  std::array<double, 3> body_{{0.0, 0.0, 0.0}};
  double reference_volume_ = 0.0;
};

}  // namespace sinew
