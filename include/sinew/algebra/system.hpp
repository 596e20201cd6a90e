// The discrete system on Tpetra: DOF maps, the CRS graph (the mesh's element couplings, built once,
// plus the couplings energy terms ask for), and the total energy E(u) = sum of its terms (energy_term.hpp)
// with its gradient and PSD Hessian: the elastic energy of the mesh (terms/elastic.hpp), external
// forces (terms/external_force.hpp) and whatever terms a scene adds (contact, inertia). After the
// terms, the Dirichlet elimination (the system owns the essential DOFs, as MFEM's NonlinearForm does).
// Also the rigid-body near-null space and coordinates MueLu needs.
#pragma once

#include <sinew/algebra/energy_term.hpp>
#include <sinew/algebra/node_relaxation.hpp>
#include <sinew/discretization/elements.hpp>
#include <sinew/discretization/mesh.hpp>
#include <sinew/materials/models.hpp>

#include <memory>
#include <optional>
#include <set>

namespace sinew {

// Which law each element has: a default, and laws for named element groups (volume regions) of the mesh.
struct MaterialAssignment {
  MaterialSpec default_law;
  std::vector<std::pair<std::string, MaterialSpec>> regions;
};

class ElasticTerm;
class ExternalForceTerm;

class System {
 public:
  // Throws InputError when a region of `materials` is not an element group of the mesh.
  System(Teuchos::RCP<const Teuchos::Comm<int>> comm, Mesh mesh, const MaterialAssignment& materials);
  System(Teuchos::RCP<const Teuchos::Comm<int>> comm, Mesh mesh, const MaterialSpec& material)
      : System(std::move(comm), std::move(mesh), MaterialAssignment{material, {}}) {}
  ~System();

  const Mesh& mesh() const { return mesh_; }
  // Shape-function gradients and point weights of the local elements (for terms with an element loop).
  const ElementData& element_data() const { return elements_; }
  // The law of elements in no region (the only one for a mesh without regions).
  const MaterialSpec& material() const;
  // Largest (mu_L + |lambda_L|) over the laws in use: the stiffness scale of the energy's terms.
  double stiffness_scale() const;
  Teuchos::RCP<const Teuchos::Comm<int>> comm() const { return comm_; }
  Teuchos::RCP<const Map> owned_dofs() const { return owned_dofs_; }
  Teuchos::RCP<const Map> overlap_dofs() const { return overlap_dofs_; }
  // The overlap DOFs followed by the extra columns terms asked for (the graph's column map).
  Teuchos::RCP<const Map> column_dofs() const { return column_dofs_; }
  Teuchos::RCP<const Map> owned_nodes() const { return owned_nodes_; }
  Teuchos::RCP<const CrsGraph> graph() const { return graph_; }
  double reference_volume() const { return reference_volume_; }
  // Per owned node: integral of its shape function over the mesh (the lumped volume), and the same
  // weighted by the elements' densities (the lumped mass).
  const std::vector<double>& nodal_volume() const { return nodal_volume_; }
  const std::vector<double>& nodal_mass() const { return nodal_mass_; }
  // Mean edge length of the owned elements over all ranks (a length scale for penalties and tolerances).
  double cell_size() const { return cell_size_; }

  // A matrix on the current graph. Matrices made before a pattern change (update_pattern) are stale.
  Teuchos::RCP<CrsMatrix> create_matrix() const;
  // A matrix on the mesh's own graph (element couplings only, never grown; its column indices are the
  // overlap DOFs, the first columns of every later graph): mass and damping matrices live there.
  Teuchos::RCP<CrsMatrix> create_mesh_matrix() const;
  // The mass matrix on the mesh's graph, M_(ai)(bj) = delta_ij int rho N_a N_b dV (tet4: the exact
  // rho V / 20 (1 + delta_ab); hex8: 2x2x2 Gauss), or its lumped form (row sums on the diagonal, the
  // nodal masses). Dirichlet rows and columns are not eliminated: it is data, not a Hessian.
  Teuchos::RCP<CrsMatrix> mass_matrix(bool lumped) const;
  // The elastic energy's Hessian alone at u (projected as each law says), Dirichlet rows and columns
  // eliminated, into a matrix on the mesh's graph (Rayleigh damping's stiffness).
  void elastic_hessian(const Vector& u, CrsMatrix& K) const;
  Teuchos::RCP<Vector> create_vector() const;

  // Dirichlet DOFs, given as local overlap DOF indices (3 * local node + component). Every rank must
  // mark its ghost DOFs too, which it can: selections are functions of the node's reference position.
  void set_fixed_dofs(const std::vector<int>& overlap_dofs);
  const std::vector<int>& fixed_owned_dofs() const { return fixed_owned_; }
  // Per owned DOF: 1 where it is prescribed.
  std::vector<char> fixed_owned_mask() const;
  std::size_t global_fixed_dofs() const;

  // External loads (the external-force term): force per reference volume, and gravity (acceleration,
  // times each element's density), in full; set_load(t) scales them by t unless `ramped` is false.
  void set_external_loads(const std::array<double, 3>& force_per_reference_volume, const std::array<double, 3>& acceleration,
                          bool ramped = true);
  // The same at their current values (no ramp): tests, and the ramp's own setting.
  void set_body_force(const std::array<double, 3>& force_per_reference_volume);
  void set_gravity(const std::array<double, 3>& acceleration);

  // Surface nodes a term ties to another surface (an attachment's samples and targets, global ids; every
  // rank passes the same): self contact neither samples them nor pushes on faces made of them, since
  // the two sides of an attached interface touch at rest.
  void tie_nodes(const std::vector<GlobalId>& nodes) { tied_.insert(nodes.begin(), nodes.end()); }
  bool tied(GlobalId g) const { return tied_.count(g) != 0; }

  // Terms beyond the elastic energy and the external forces (which every system has), summed in the
  // order added. Their names must differ (they name log columns and checkpoint records).
  void add_term(std::shared_ptr<EnergyTerm> term);
  const std::vector<std::shared_ptr<EnergyTerm>>& terms() const { return terms_; }
  // The first term of type T, or null.
  template <class T>
  T* find_term() const {
    for (const auto& t : terms_)
      if (auto* p = dynamic_cast<T*>(t.get())) return p;
    return nullptr;
  }

  // The terms' lifecycle (energy_term.hpp), each hook called on every term in order. Collective.
  // The external loads' ramp: body force and gravity in full from load 0 (a dynamic run) or ramped.
  void set_load(double t);
  void begin_step(const StepStart& s);
  // Every term's round at u; the pattern grown for the couplings they now need. `again`: some term
  // asked for another solve; `lines`: what they report; `pattern_changed`: the matrix pattern grew.
  struct Round {
    bool again = false, pattern_changed = false;
    std::vector<std::string> lines;
  };
  Round round(const Vector& u, int round);
  // Every term's regroup at u (a solve that has not converged yet) and the pattern grown: `again` says
  // some term changed its energy, `lines` what they report.
  Round regroup(const Vector& u);
  bool regroups() const;  // some term's regroup can change its energy
  void end_step(const Vector& u);
  void abandon_step();
  // Every term's state, by term name; load_states gives each term its own (a term whose name the
  // checkpoint lacks gets none and keeps its fresh state).
  std::vector<std::pair<std::string, TermState>> save_states() const;
  void load_states(const std::vector<std::pair<std::string, TermState>>& states);
  // Some term bounds the steps (EnergyTerm::limits_steps), and the bound along du from u: the smallest
  // of the terms' (t_max when none). Collective.
  bool limits_steps() const;
  bool projects_hessians() const;  // some term's Hessian is a projection it can drop (EnergyTerm::projects_hessian)
  double step_limit(const Vector& u, const Vector& du, double t_max) const;
  // Pulls a step's first guess back towards u (owned DOFs) where some term bounds the path from u to
  // it: the free DOFs to 0.9 of the admissible fraction, the Dirichlet ones left where the guess has
  // them. Returns the fraction taken (1: the guess as it was). Collective.
  double admit_guess(const Vector& u, Vector& guess) const;
  // The terms' accelerations of the nodes by forces that do not depend on u (EnergyTerm::
  // add_load_acceleration), summed into `a` (overwritten); false, and `a` zero, when no term has any.
  bool load_acceleration(Vector& a) const;
  // The tangent predictor may linearise the energy (every term allows it).
  bool linearisable() const;
  // log.csv's term columns ("<term>_energy" and each term's own), and their values at a step's end.
  std::vector<std::string> log_columns() const;
  std::vector<double> log_values(const EvaluationTotals& totals) const;
  // Every term's summary lines for a step's end.
  std::vector<std::string> summary(const EvaluationTotals& totals) const;
  // The terms' node fields at u (an evaluation first, when some term has any).
  std::vector<TermState::Nodal> node_fields(const Vector& u) const;
  std::vector<std::pair<std::string, int>> node_field_names() const;
  // The terms' element fields (per owned element; a muscle's fibre direction), as they stand.
  std::vector<TermState::Nodal> term_element_fields() const;
  // Collective: asks every term for its couplings and rebuilds the graph with them when some are
  // missing (the pattern only grows). Returns true, on every rank, when it changed.
  bool update_pattern();
  // Counts pattern changes: a solver holding a matrix compares it with the value it was made at.
  unsigned pattern_version() const { return pattern_version_; }

  // Energy, gradient (force = dE/du, zero in Dirichlet rows) and Hessian (each elastic law projected as
  // it says, or as `projection` says for all when given; the other terms' Hessians are PSD, or with
  // `exact_terms` exact (TermInput::exact_terms); Dirichlet
  // rows and columns eliminated). force and K may be null. u holds total displacements (owned DOFs).
  EvaluationTotals evaluate(const Vector& u, Vector* force, CrsMatrix* K, Backend backend = Backend::Default,
                            std::optional<Projection> projection = std::nullopt, bool exact_terms = false) const;

  // For an increment d (of prescribed and free DOFs alike): force = f(u) + K(u) d in the free rows, zero
  // in the Dirichlet ones, and K as evaluate() leaves it. The right-hand side of the linearised response
  // to a new prescribed motion (a load step's tangent predictor).
  EvaluationTotals evaluate_lifted(const Vector& u, const Vector& d, Vector& force, CrsMatrix& K,
                                   std::optional<Projection> projection = std::nullopt, bool exact_terms = false) const;

  // The gradient with no Dirichlet elimination, of every term or of one: at an equilibrium its
  // prescribed rows are the reactions, and one term's part is the force that term exerts (e.g. the
  // contact force on a body).
  void gradient(const Vector& u, Vector& force, const EnergyTerm* only = nullptr) const;

  // Nonlinear elimination of the residual's hot spots (ElasticTerm::relax): the owned nodes free in all
  // three components whose force holds at least `share` of |force|^2 (and up to `rings` element rings of
  // free owned nodes around them) are relaxed one by one, the rest held; u (owned DOFs) is updated.
  // Only when every term allows it (EnergyTerm::allows_node_relaxation: the elastic and external-force
  // terms everywhere, contact away from its springs' nodes; inertia is not linear in a node's
  // displacement, and is left to Newton): returns zero totals otherwise. Collective; the
  // caller checks the new state's energy (nodes moved at once on two ranks may share an element).
  NodeRelaxationTotals relax_nodes(Vector& u, const Vector& force, double share, int rings,
                                   const NodeRelaxationSettings& settings) const;

  // Per owned element: volume-averaged energy density and J at u.
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
  void build_graph();
  void compute_nodal_weights();
  EvaluationTotals run(const Vector& u, Vector* force, CrsMatrix* K, Backend backend, std::optional<Projection> projection,
                       ElementFields<DeviceMemory> fields, const EnergyTerm* only = nullptr, bool eliminate = true,
                       bool exact_terms = false) const;
  // Rows and columns of Dirichlet DOFs: off-diagonal entries zeroed, the diagonal kept (the sum of the
  // elements' own diagonal entries, a positive scale matching the stiffness, so CG sees a well-conditioned
  // identity-like block there); their force entries zeroed.
  void eliminate_dirichlet(Vector* force, CrsMatrix* K) const;
  // The fixed flags of the extra columns (from their owners).
  void refresh_fixed_columns();

  Teuchos::RCP<const Teuchos::Comm<int>> comm_;
  Mesh mesh_;
  std::shared_ptr<ElasticTerm> elastic_;
  std::shared_ptr<ExternalForceTerm> external_;
  std::vector<std::shared_ptr<EnergyTerm>> terms_;  // every term, elastic first
  ElementData elements_;
  Teuchos::RCP<const Map> owned_dofs_, overlap_dofs_, column_dofs_, owned_nodes_;
  Teuchos::RCP<const Import> column_importer_;
  Teuchos::RCP<const CrsGraph> graph_, mesh_graph_;
  Teuchos::RCP<Vector> u_columns_;
  std::set<std::pair<GlobalId, GlobalId>> extra_;  // couplings beyond the mesh graph (owned row node, column node)
  std::set<GlobalId> tied_;
  unsigned pattern_version_ = 0;
  Kokkos::View<char*> fixed_;  // per column DOF
  std::vector<int> fixed_owned_;
  bool any_fixed_ = false;  // some local (owned or ghost) DOF is fixed
  double reference_volume_ = 0.0, cell_size_ = 0.0;
  std::vector<double> nodal_volume_, nodal_mass_;
};

}  // namespace sinew
