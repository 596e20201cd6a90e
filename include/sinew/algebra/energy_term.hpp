// One term of the total energy a step minimizes, E(u) = sum_k E_k(u): the elastic energy of the mesh
// (Eq. 14 and the other models, integrated), the potential of body forces and gravity, inertia (the
// incremental potential of an implicit time step), contact penalties (Sec. 6). Each term gives its
// value, its gradient and a positive semi-definite Hessian, added into what the System hands it, in
// the manner of MFEM's NonlinearFormIntegrators on a NonlinearForm: the System sums, each term lives in
// its own file, and a new physics is a new term rather than an edit of the element loop.
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
#include <utility>
#include <vector>

namespace sinew {

using DeviceMemory = Kokkos::DefaultExecutionSpace::memory_space;
using LocalMatrix = CrsMatrix::local_matrix_device_type;

// Global results of one evaluation (already reduced over ranks when the System returns them).
struct EvaluationTotals {
  double energy = 0.0;    // the total, the sum of the terms' shares below
  double elastic = 0.0;   // stored elastic energy
  double external = 0.0;  // potential of body forces and gravity (minus their work)
  double inertia = 0.0;   // the kinetic part of an implicit step's incremental potential
  double contact = 0.0;   // contact penalty energy
  double volume = 0.0;    // sum over quadrature points of J * reference volume
  double min_J = 0.0;     // smallest J at a quadrature point
  long long inverted = 0;   // quadrature points with J <= 0
  long long undefined = 0;  // points where the energy is +inf (Neo-Hookean, J <= 0)
  long long contacts = 0;   // contacts pressing (springs and collider touches with a positive force)
  double penetration = 0.0;  // deepest penetration among them (>= 0; distance behind the surface)

  // A finite energy with no undefined point: a state a predictor may offer.
  bool energy_defined() const { return undefined == 0 && std::isfinite(energy); }
};

enum class Backend { Default, Serial };

// What every term reads.
struct TermInput {
  Kokkos::View<const double*, DeviceMemory> u;  // displacement on the column map
  bool want_force = false, want_matrix = false;
  Backend backend = Backend::Default;
  std::optional<Projection> projection;  // the elastic Hessian's projection for all laws, when given
};

// What every term adds into: rows [0, owned_dofs) of the force (dE/du) and of the matrix (its columns
// on the column map), and its energy share and counts into `totals` (this rank's, not yet reduced).
struct TermOutput {
  Kokkos::View<double*, DeviceMemory> force;
  LocalMatrix matrix;
  int owned_dofs = 0;
  EvaluationTotals totals;
  ElementFields<DeviceMemory> fields;  // per-element outputs, when asked for (the elastic term)
};

class EnergyTerm {
 public:
  virtual ~EnergyTerm() = default;
  virtual const char* name() const = 0;
  // Adds the term's energy, gradient (if in.want_force) and PSD Hessian (if in.want_matrix).
  virtual void add(const TermInput& in, TermOutput& out) const = 0;
  // Node couplings (global node ids: row node, column node) beyond the mesh's element graph that the
  // Hessian needs in the rows of this rank's owned nodes. Asked by System::update_pattern.
  virtual void couplings(std::vector<std::pair<GlobalId, GlobalId>>& out) const { (void)out; }
  // Called when the System's column map changed: resolve global ids to column indices again.
  virtual void columns_changed(const Map& columns) { (void)columns; }
};

}  // namespace sinew
