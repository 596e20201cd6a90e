// One term of the total energy a step minimizes, E(u) = sum_k E_k(u): the elastic energy of the mesh
// (Eq. 14 and the other models, integrated), the potential of body forces and gravity, inertia (the
// incremental potential of an implicit time step), contact penalties (Sec. 6), a pressure load. Each
// term gives its value, its gradient and a positive semi-definite Hessian, added into what the System
// hands it, in the manner of MFEM's NonlinearFormIntegrators on a NonlinearForm: the System sums, each
// term lives in its own file, and a new physics is a new term rather than an edit of the element loop.
//
// A term also has a life of its own, which the driver runs for every term in the System's order (the
// driver names no physics):
//   set_load(t)          the load fraction of the coming evaluations: ramps, collider poses
//   begin_step(s)        a solve from the converged state s.u (load s.t0) to load s.t1 starts
//   round(u, r)          before the step's first solve (r = 0) and after each converged solve (r >= 1):
//                        a term whose energy depends on the state it was set up at (contact pairs, a
//                        Uzawa multiplier) updates it and asks for another solve
//   regroup(u)           inside a solve that is slow to converge: the set-up again, multipliers kept
//   end_step(u)          the step converged at u; abandon_step(): it failed and is cut
//   save_state/load_state  what a restart needs besides the displacement (checkpoint.h5)
// and says how it is reported: its log columns, lines of the step's summary, node fields of the step
// files; and whether node relaxation may freeze its share of the gradient.
//
// Indices. A term sees the displacement on the System's column map: the mesh's overlap DOFs first
// (3 * local node + component; owned nodes, then ghosts), followed by any extra columns the terms
// asked for (couplings beyond the element graph, e.g. a contact spring between distant surface nodes,
// possibly owned by another rank). Rows [0, owned_dofs) are this rank's: a term adds only into those,
// and counts each energy contribution on exactly one rank.
#pragma once

#include <sinew/algebra/tpetra_types.hpp>
#include <sinew/discretization/element_kernel.hpp>
#include <sinew/discretization/mesh.hpp>

#include <Kokkos_Core.hpp>
#include <Tpetra_CrsMatrix_decl.hpp>

#include <cmath>
#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace sinew {

using DeviceMemory = Kokkos::DefaultExecutionSpace::memory_space;
using LocalMatrix = CrsMatrix::local_matrix_device_type;

// Global results of one evaluation (already reduced over ranks when the System returns them).
struct EvaluationTotals {
  double energy = 0.0;    // the total, the sum of the terms' shares
  // Each term's share of the energy, in the System's order, named by EnergyTerm::name().
  std::vector<std::pair<const char*, double>> shares;
  double volume = 0.0;    // sum over quadrature points of J * reference volume
  double min_J = 0.0;     // smallest J at a quadrature point
  long long inverted = 0;   // quadrature points with J <= 0
  long long undefined = 0;  // points where the energy is +inf (Neo-Hookean, J <= 0)
  long long contacts = 0;   // contacts pressing (springs and collider touches with a positive force)
  double penetration = 0.0;  // deepest penetration among them (>= 0; distance behind the surface)

  // A finite energy with no undefined point: a state a predictor may offer.
  bool energy_defined() const { return undefined == 0 && std::isfinite(energy); }
  // The share of the term named `name` (0 when the System has no such term).
  double share(const std::string& name) const {
    for (const auto& [n, e] : shares)
      if (name == n) return e;
    return 0.0;
  }
};

// What a term keeps across steps that a restart needs, beyond the displacement: arrays the same on every
// rank (`shared`, written once), and per-node arrays (`nodal`: `components` values per owned node, in
// the owned node order; written by node id, so a restart on another number of ranks reads them).
struct TermState {
  struct Nodal {
    std::string name;
    int components = 1;
    std::vector<double> values;
  };
  std::vector<std::pair<std::string, std::vector<double>>> shared;
  std::vector<Nodal> nodal;
  const std::vector<double>* find_shared(const std::string& name) const {
    for (const auto& [n, v] : shared)
      if (n == name) return &v;
    return nullptr;
  }
  const Nodal* find_nodal(const std::string& name) const {
    for (const auto& n : nodal)
      if (n.name == name) return &n;
    return nullptr;
  }
};

// A solve of one step (or of a cut part of it) from the converged state u at load t0 to load t1.
struct StepStart {
  double t0 = 0.0, t1 = 0.0;
  const Vector* u = nullptr;  // owned DOFs
  bool first_attempt = true;   // the load step's first solve (not one after a cut): per-step counts restart
};

// What a term's round found: whether it needs another solve, and a line for the progress output.
struct RoundResult {
  bool again = false;
  std::string line;
};

enum class Backend { Default, Serial };

// What every term reads.
struct TermInput {
  Kokkos::View<const double*, DeviceMemory> u;  // displacement on the column map
  bool want_force = false, want_matrix = false;
  Backend backend = Backend::Default;
  std::optional<Projection> projection;  // the elastic Hessian's projection for all laws, when given
  // Every term its exact Hessian, indefinite parts included (a barrier's per-pair projection off): the
  // solver's last tier near convergence (HessianPolicy).
  bool exact_terms = false;
};

// What every term adds into: rows [0, owned_dofs) of the force (dE/du) and of the matrix (its columns
// on the column map), and its energy share and counts into `totals` (this rank's, not yet reduced).
struct TermOutput {
  Kokkos::View<double*, DeviceMemory> force;
  LocalMatrix matrix;
  int owned_dofs = 0;
  double energy = 0.0;      // the term's energy share (this rank's); the System sums the shares
  EvaluationTotals totals;  // volume, J and contact counts (this rank's, not yet reduced)
  ElementFields<DeviceMemory> fields;  // per-element outputs, when asked for (the elastic term)
};

class EnergyTerm {
 public:
  virtual ~EnergyTerm() = default;
  // The term's name: its energy share's in the log ("<name>_energy") and in messages.
  virtual const char* name() const = 0;
  // Adds the term's energy (into out.energy), gradient (if in.want_force) and PSD Hessian (if
  // in.want_matrix).
  virtual void add(const TermInput& in, TermOutput& out) const = 0;
  // Node couplings (global node ids: row node, column node) beyond the mesh's element graph that the
  // Hessian needs in the rows of this rank's owned nodes. Asked by System::update_pattern.
  virtual void couplings(std::vector<std::pair<GlobalId, GlobalId>>& out) const { (void)out; }
  // Called when the System's column map changed: resolve global ids to column indices again.
  virtual void columns_changed(const Map& columns) { (void)columns; }

  // Lifecycle (see the top of this file). All are collective: every rank calls them in the same order.
  virtual void set_load(double t) { (void)t; }
  virtual void begin_step(const StepStart& s) { (void)s; }
  virtual RoundResult round(const Vector& u, int round) {
    (void)u;
    (void)round;
    return {};
  }
  // Within a solve that has gone a while without converging (Solver/'Regroup after'): a term whose
  // set-up goes stale as the state moves (contact pairs, which samples slide past) may set it up again
  // at u, leaving what only a converged state may change (Uzawa multipliers) as it is. Returns a line
  // for the progress output, empty when nothing changed. Collective.
  virtual std::string regroup(const Vector& u) {
    (void)u;
    return {};
  }
  // Whether regroup can change anything (the driver stops a slow solve for it only then).
  virtual bool regroups() const { return false; }
  virtual void end_step(const Vector& u) { (void)u; }
  virtual void abandon_step() {}
  virtual void save_state(TermState& state) const { (void)state; }
  // Throws InputError when the state is not one this term can continue from (say which entry).
  virtual void load_state(const TermState& state) { (void)state; }

  // Node relaxation (System::relax_nodes) moves a node with the other terms' share of its gradient
  // frozen: a term linear in u allows it everywhere (returns true); a term whose energy is nonlinear in
  // some nodes only (contact: the nodes of its springs) allows it elsewhere, marking those nodes in
  // `held` (per local node, 1: not moved); false forbids it everywhere (inertia).
  virtual bool allows_node_relaxation(std::vector<char>& held) const {
    (void)held;
    return false;
  }
  // A term whose energy is +inf past some surface (a contact barrier) bounds the steps along a
  // direction: step_limit(u, du, t_max) is the largest t <= t_max such that u + s du is admissible for
  // all s in [0, t] (owned DOFs; collective). The line search starts no longer, and a step's first
  // guess is pulled back to it.
  virtual bool limits_steps() const { return false; }
  // Whether the term's Hessian is a PSD projection of its exact one, which it drops when asked
  // (TermInput::exact_terms): the solver's exact-terms tier is offered only then.
  virtual bool projects_hessian() const { return false; }
  virtual double step_limit(const Vector& u, const Vector& du, double t_max) const {
    (void)u;
    (void)du;
    return t_max;
  }
  // Such a term may first pull back only the part of a step's first guess whose path it does not admit
  // (owned DOFs; Dirichlet ones left as they are; collective); System::admit_guess then checks the
  // whole path again.
  virtual void admit_guess(const Vector& u, Vector& guess) const {
    (void)u;
    (void)guess;
  }
  // A dynamic step's first guess (Dynamics::begin): a term whose force does not depend on u (external
  // loads) adds to `a` (owned DOFs, interleaved xyz) the acceleration it alone gives each node, its
  // nodal force over the node's lumped mass, and returns whether it added any. The guess then lies
  // reach^2 a beyond the inertial predictor u_n + reach v_n, where a body in free fall is already in
  // equilibrium (the inertia term's M (y - predictor) / reach^2 balances M a exactly).
  virtual bool add_load_acceleration(Vector& a) const {
    (void)a;
    return false;
  }
  // The tangent predictor linearises the total energy about the last state: a term set up at a state
  // (contact pairs found there) cannot be carried to a new one that way.
  virtual bool linearisable() const { return true; }

  // Reporting. Columns of log.csv after the energy share's, and their values for the step just logged
  // (collective: may reduce); lines of the step's summary (rank 0 prints them); node fields of the step
  // files (per owned node: `components` values, e.g. a pressure or a velocity) and element fields.
  virtual std::vector<std::string> log_columns() const { return {}; }
  virtual std::vector<double> log_values(const EvaluationTotals& totals) const {
    (void)totals;
    return {};
  }
  virtual std::vector<std::string> summary(const EvaluationTotals& totals) const {
    (void)totals;
    return {};
  }
  // What the term found when it was set up that a user should know (printed under the run's header as
  // "<name> note: ..."; the same on every rank).
  virtual std::vector<std::string> notes() const { return {}; }
  // Names and components of the node fields; the fields themselves, of the last evaluation.
  virtual std::vector<std::pair<std::string, int>> node_field_names() const { return {}; }
  virtual void node_fields(std::vector<TermState::Nodal>& fields) const { (void)fields; }
  // The same per owned element (in the owned element order, each field naming its components): a
  // muscle's fibre direction. Written as they stand, with no evaluation first.
  virtual void element_fields(std::vector<TermState::Nodal>& fields) const { (void)fields; }
};

}  // namespace sinew
