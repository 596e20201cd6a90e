// Contact as a term of the total energy (Smith et al. 2018, Sec. 6, after Hirota et al. 2001, Irving
// et al. 2004 and McAdams et al. 2011): penalty springs on the boundary surface's vertices (the samples),
// frictionless, one-sided.
//
// Self-contact. A detection pass (between solves, not inside Newton, so that the energy a solve
// minimizes does not change under it) pairs samples with target points on the surface:
//   - a sample found inside a deformed element (hex8 split into six tets) that is not in its ring at rest
//     (an element sharing a node with an element of the sample) is mapped to the reference domain by
//     that tet's barycentric coordinates; the closest reference surface point (away from the sample's
//     ring) is mapped back to the deformed surface: the paper's two linear maps. With `refine`, the
//     target then walks over neighbouring triangles of the deformed surface to the closest point
//     (the paper's optional local optimization, "typically converges in a single iteration");
//   - a sample outside but within `margin` of a surface triangle outside its ring is paired with the
//     closest point, so that a contact about to close is resisted in the same solve.
// Each pair keeps its target triangle (a, b, c), the barycentric weights beta of the target point and
// the outward normal n of the target triangle at detection. Its energy is the augmented-Lagrangian
// penalty
//   E = A / (2 k) (max(0, lambda + k (delta - g))^2 - lambda^2),   g = n . (x_s - beta_a x_a - beta_b x_b - beta_c x_c),
// with A the sample's reference area, k the stiffness (traction per unit of penetration), delta the
// contact thickness and lambda >= 0 a traction the pair carries: 0 gives the plain penalty k A/2
// max(0, delta - g)^2; between solves a pair whose sample is still behind its target gets lambda +=
// k (delta - g) (Uzawa), which drives penetration out without a stiffer, worse-conditioned penalty.
// For a frozen n, beta and lambda, E is a convex function of the twelve coordinates: its Hessian
// k A (w (x) n)(w (x) n)^T, w = (1, -beta), is PSD and exact.
//
// Smooth onset of the self-contact springs (ContactSettings::onset = eps > 0; 'Smooth onset' sets the
// thickness, off by default): k A phi(s) replaces k A/2 max(0, s)^2, s = lambda / k + delta - g, with phi'' ramping
// linearly from 0 to 1 over [0, eps] and 1 after (contact_spring_law below): the energy is C2 and the
// Hessian k A phi''(s) (w (x) n)(w (x) n)^T still PSD and exact, so a spring that engages or lets go
// inside a Newton step no longer makes the model wrong by its whole stiffness. A smooth spring rests
// inside its onset, so its traction is raised only for a sample deeper than clearance - eps - delta/10.
//
// Colliders (kinematic: a half-space, a sphere, a capsule, an infinite cylinder, or a closed triangle
// mesh, each at a pose set per step) act on every sample with the same energy in g = phi(x_s), phi the
// signed distance (positive outside), and a multiplier per sample and collider; the Hessian
// k A (grad phi grad phi^T - (delta - phi + lambda / k) hess phi) is projected to k A grad phi grad phi^T
// (the curvature part is negative semi-definite for convex shapes, so this is the PSD projection; for a
// mesh collider it is the Gauss-Newton part), except where the solver asks for the exact Hessian (near
// convergence; without the curvature part Newton converges linearly on a body resting on a cylinder:
// 10-55 iterations per time step instead of 2-5).
//
// Across ranks: the surface (vertices, triangles, rings) is replicated; each rank locates samples in
// the elements it owns and pairs its own samples by proximity; the pairs are gathered, and each rank
// keeps those touching a node it owns, asking the System for the couplings its rows need.
#pragma once

#include <sinew/algebra/energy_term.hpp>
#include <sinew/core/rigid.hpp>
#include <sinew/discretization/aabb_tree.hpp>
#include <sinew/discretization/boundary.hpp>
#include <sinew/discretization/triangle_surface.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <functional>
#include <memory>
#include <string>
#include <vector>

namespace sinew {

class System;

// A kinematic collider's shape in its own frame.
struct ColliderShape {
  enum class Kind { HalfSpace, Sphere, Capsule, Cylinder, Mesh };
  Kind kind = Kind::HalfSpace;
  geom::Vec point{}, normal{{0.0, 0.0, 1.0}};  // half-space: a point on the plane and the outward normal
  geom::Vec center{};                          // sphere
  geom::Vec a{}, b{};                          // capsule: the segment; cylinder: two points on the axis
  double radius = 0.0;                          // sphere, capsule, cylinder
  std::shared_ptr<const TriangleSurface> surface;  // mesh: closed and outward (read_triangle_surface)

  // Builds what a mesh collider's queries need; throws InputError for a degenerate shape.
  void prepare();
  // Signed distance at x (positive outside) and its gradient (unit outward direction); with hessian
  // given, also its Hessian (row-major 3x3: the level set's curvature, zero for a half-space or over a
  // mesh face).
  double distance(const geom::Vec& x, geom::Vec& gradient, double* hessian = nullptr) const;
  // A box outside which the distance exceeds `band` (infinite for a half-space).
  geom::Box bounds(double band) const;

 private:
  geom::AabbTree tree_;
  std::vector<geom::Vec> face_normal_, vertex_normal_;  // angle-weighted pseudo-normals at vertices
  std::vector<std::array<geom::Vec, 3>> edge_normal_;  // per triangle, its edges (0-1, 1-2, 2-0)
};

// The spring's energy per k A as a function of its stretch s, and its first two derivatives: a cubic
// onset over [0, eps], where the stiffness ramps linearly from 0 to 1, then the quadratic with the same
// value, slope and curvature at eps (C2; eps = 0 gives the plain max(0, s)^2 / 2). With a sharp onset
// the Hessian jumps from nothing to k A n n^T as a spring engages, and Newton's model is wrong on one
// side of every spring that is about to touch or let go: BCN's knee crease went round a cycle of step
// lengths 2 and 1/8 for 50 iterations (docs/performance.md). Public for tests.
struct ContactSpringLaw {
  double e, d1, d2;
};
inline ContactSpringLaw contact_spring_law(double s, double eps) {
  if (s <= 0.0) return {0.0, 0.0, 0.0};
  if (s < eps) return {s * s * s / (6.0 * eps), 0.5 * s * s / eps, s / eps};
  return {0.5 * s * s - 0.5 * eps * s + eps * eps / 6.0, s - 0.5 * eps, 1.0};
}

struct ContactSettings {
  bool self = true;
  double stiffness = 0.0;  // k: traction per unit of penetration (> 0)
  double thickness = 0.0;  // delta: the springs act below this gap (>= 0)
  double margin = 0.0;     // proximity pairing distance (> thickness)
  bool refine = true;      // walk targets to the closest deformed-surface point
  int rounds = 10;         // at most this many detect-and-solve rounds per step (round())
  double onset = 0.0;      // the stretch over which a spring's stiffness ramps from 0 to k (0: sharp)
  bool keep = false;       // a step's first detection keeps the last converged state's springs (round())
  // Self contact by a log barrier on the distance from each surface vertex to the triangles within
  // `margin` (contact_barrier.hpp) instead of penalty springs: `thickness` is where the barrier starts
  // (dhat), and every Newton step is cut short of any vertex passing through a triangle (step_limit).
  bool barrier = false;
  // The barrier's k (kappa = k A / dhat^2), where it differs from the springs' (0: `stiffness`).
  double barrier_stiffness = 0.0;
  // With the barrier, edge-edge pairs beside the vertex-triangle ones, in the energy and in the step
  // limit: without them two edges can pass through each other with no vertex crossing a face (the
  // scene's default is on: docs/performance.md, "Surfaces through themselves"; off here, as a bare
  // ContactSettings is the paper's springs).
  bool edge_pairs = false;
};

// What one detection pass found (global counts).
struct ContactDetection {
  long long inside = 0;     // samples inside the deformed volume (paired through the reference map)
  long long proximity = 0;  // samples near the surface (paired with the closest point)
  long long refined = 0;    // inside pairs whose target moved in the local search
  long long unpaired = 0;   // inside samples with no admissible target
  long long kept = 0;       // pairs kept from the previous pass (keep mode)
  long long refrozen = 0;   // kept pairs whose normal and target point were frozen again (their sample inside)
  long long added = 0;      // new pairs that push at once (inside, or nearer than the thickness), and refrozen ones
  long long raised = 0;     // multipliers raised for samples still behind their target (keep mode)
  double deepest = 0.0;     // the largest distance from a sample inside the volume to the surface
  // The samples inside, each counted once over all ranks: those the surface does not enclose (their
  // winding number is in (0, 1): inside an element only where the mesh folds or overlaps itself, no face
  // crossed), and the others, the points through a face, with the deepest of them (the penetration a
  // report gives).
  long long folded = 0, crossed = 0;
  double crossed_deepest = 0.0;
  double seconds = 0.0;
};

class ContactTerm final : public EnergyTerm {
 public:
  // Collective (replicates the boundary surface). The system must outlive the term.
  ContactTerm(const System& system, const ContactSettings& settings, std::vector<ColliderShape> colliders);

  const char* name() const override { return "contact"; }
  void add(const TermInput& in, TermOutput& out) const override;
  void couplings(std::vector<std::pair<GlobalId, GlobalId>>& out) const override;
  void columns_changed(const Map& columns) override;

  // Lifecycle (energy_term.hpp). set_load: the colliders' poses (set_pose_source). round: a detection
  // (fresh at round 0, keeping the pairs after) with the Uzawa update of the tractions; another solve
  // while a detection adds pairs that push or raises tractions, up to settings().rounds. The pairs and
  // tractions a step ends with (or a failed attempt leaves) are the state a checkpoint keeps.
  void set_load(double t) override;
  void begin_step(const StepStart& s) override;
  RoundResult round(const Vector& u, int round) override;
  // A detection in keep mode at a state the solve has not converged to: samples that slid past their
  // frozen targets and went in get their springs now rather than after the solve (tractions kept).
  std::string regroup(const Vector& u) override;
  bool regroups() const override { return settings_.self; }
  void end_step(const Vector& u) override;
  void abandon_step() override;
  void save_state(TermState& state) const override;
  void load_state(const TermState& state) override;
  // The barrier: its energy depends on the positions alone (a guess from its linearisation passes the
  // collision test as any guess does). The springs: their pairs and planes are the last detection's.
  bool linearisable() const override { return settings_.barrier; }
  // Away from the springs' nodes (and, with colliders, the surface): the energy does not depend on them.
  bool allows_node_relaxation(std::vector<char>& held) const override;
  // With the barrier: the largest step along du from u (at most t_max) after which no surface vertex has
  // passed through a triangle (additive CCD over every vertex-triangle pair whose swept boxes meet).
  bool limits_steps() const override { return self_barrier(); }
  bool projects_hessian() const override { return self_barrier(); }
  double step_limit(const Vector& u, const Vector& du, double t_max) const override;
  // The surface vertices whose path to the guess passes through a face (or a face through them), and
  // the vertices of those faces, are pulled back to 0.9 of the pair's admissible fraction; the rest of
  // the guess stays (a crease does not hold back the whole body's skinning guess).
  void admit_guess(const Vector& u, Vector& guess) const override;
  std::vector<std::string> log_columns() const override;
  std::vector<double> log_values(const EvaluationTotals& totals) const override;
  std::vector<std::string> summary(const EvaluationTotals& totals) const override;
  // How many surface points touch the surface at rest (see clearance()).
  std::vector<std::string> notes() const override;
  // Per surface vertex: the thickness its springs hold it at, the contact thickness, or its distance at
  // rest to the nearest face outside its ring where that is less (pieces meshed touching, a crease
  // fused by a lattice): what touches at rest is not pushed apart at the first step, only resisted where
  // it comes closer.
  const std::vector<double>& clearance() const { return clearance_; }
  std::vector<std::pair<std::string, int>> node_field_names() const override;
  void node_fields(std::vector<TermState::Nodal>& fields) const override;
  // Where collider k stands at load fraction t.
  void set_pose_source(std::function<Rigid(std::size_t k, double t)> pose_of) { pose_of_ = std::move(pose_of); }

  // Collective: self-contact pairs at displacement u (owned DOFs). Call System::update_pattern after.
  // With `keep`, the pairs of the last pass stay as they are (same target, weights and normal, so the
  // energy a converged state minimized does not move) while their gap is within the margin, and only
  // samples without one are paired anew: the next round of a step adds what the last solve missed;
  // and every spring (and collider contact) whose sample lies behind its target by more than a tenth
  // of the thickness has its multiplier raised. Without `keep`, a sample paired again carries the
  // multiplier it had.
  // With `multipliers` false (a regroup inside a solve), no traction is raised or dropped: the state is
  // not converged, and Uzawa's update needs one that is.
  // `slide`: a kept pair whose sample lies farther than this from its target point along the target's
  // plane is dropped (and the sample paired afresh).
  ContactDetection detect(const Vector& u, bool keep = false, bool multipliers = true, double slide = HUGE_VAL);
  void set_collider_pose(std::size_t k, const Rigid& pose) { poses_[k] = pose; }
  std::size_t colliders() const { return colliders_.size(); }
  const SurfaceMesh& surface() const { return surface_; }
  const ContactSettings& settings() const { return settings_; }
  double barrier_stiffness() const { return settings_.barrier_stiffness > 0.0 ? settings_.barrier_stiffness : settings_.stiffness; }
  // Per owned node, the contact pressure (the springs' and colliders' traction on it, summed) of the
  // last evaluation: zero off contact.
  const std::vector<double>& pressure() const { return pressure_; }
  // Pairs kept on this rank and their global count.
  std::size_t local_pairs() const { return pairs_.size(); }
  long long global_pairs() const { return global_pairs_; }
  // The rounds, pairs and seconds of the load step under way (or just ended).
  struct StepCounts {
    int rounds = 0;
    long long pairs = 0;
    double seconds = 0.0, inside_depth = 0.0;
    double crossed_depth = 0.0;  // inside_depth without the samples inside folded elements (ContactDetection)
    long long inside_folded = 0;
    long long edges_through_faces = 0;  // at the step's end (end_step; surface_crossings)
  };
  const StepCounts& step_counts() const { return step_; }

  // One self-contact spring (public for tests).
  struct Pair {
    GlobalId node[4];  // the sample, then the target triangle's vertices
    double w[4];       // 1, -beta_a, -beta_b, -beta_c
    double X[4][3];    // reference positions of the four nodes
    double normal[3];  // outward normal of the target at detection
    double area;       // the sample's reference area
    double delta;      // the thickness it is held at: the sample's clearance (clearance()); the barrier's dhat
    double lambda;     // augmented-Lagrangian traction (>= 0)
    int owner;         // the rank that owns the sample and counts the energy
    int col[4];        // column of each node's first DOF on this rank (-1: none)
    // The barrier's edge-edge pairs: node holds the two edges' ends (a0, a1, b0, b1), area their share
    // of the surface, and mollifier the |ea x eb|^2 below which the barrier fades (edge_edge_barrier).
    bool edges = false;
    double mollifier = 0.0;
  };
  const std::vector<Pair>& pairs() const { return pairs_; }

 private:
  // Self contact by the barrier (not springs): its step limit, its projected pair Hessians.
  bool self_barrier() const { return settings_.self && settings_.barrier; }
  bool edge_pairs() const { return self_barrier() && settings_.edge_pairs; }

  const System& system_;
  ContactSettings settings_;
  std::vector<ColliderShape> colliders_;
  std::vector<Rigid> poses_;
  SurfaceMesh surface_;
  geom::AabbTree reference_tree_;  // of the reference surface triangles
  std::vector<int> owned_samples_;   // local owned nodes on the surface
  std::vector<int> sample_vertex_;   // ... their surface vertex
  std::vector<double> collider_lambda_;  // per owned sample and collider (sample-major)
  std::vector<Pair> pairs_;
  // Every pair of the last pass, the same on every rank: sample vertex, target triangle, weights, normal.
  struct Chosen {
    int vertex, triangle;
    double beta[3], normal[3], lambda;
  };
  std::vector<Chosen> chosen_;
  // The barrier's edge-edge pairs of the last pass (edge indices, first < second; the same on every rank).
  std::vector<std::array<int, 2>> chosen_edges_, committed_chosen_edges_;
  // The surface's edges (vertex pairs, first < second) and those whose first vertex this rank owns
  // (with self contact); with edge pairs, each one's share of the reference area (a third of its
  // triangles') and its distance at rest to the nearest edge it shares no vertex with (at most the
  // thickness).
  std::vector<std::array<int, 2>> edges_;
  std::vector<int> owned_edges_;
  std::vector<double> edge_area_, edge_clearance_;
  bool fresh_start_ = true;  // the next step's first detection pairs afresh (none yet, or after a failed attempt)
  // Per round of this step: its pairs (sample, triangle; sorted) and the deepest sample inside.
  std::vector<std::pair<std::vector<std::pair<int, int>>, double>> round_pairs_;
  // The detection's steps (contact.cpp).
  struct Positions;
  struct Candidate;
  long long update_collider_tractions(const Positions& at, bool keep);
  void gather_surface(Positions& at) const;
  void ensure_tied() const;  // tied_ from the system, at the first detection (or step limit)
  void detect_springs(const Positions& at, const std::vector<Chosen>& last, bool keep, bool multipliers, double slide,
                      ContactDetection& stats);
  bool excluded(int triangle, int vertex) const;  // springs: the triangle touches the vertex's ring at rest; barrier: it is one of the vertex's own
  std::vector<Candidate> kept_candidates(const Positions& at, const std::vector<Chosen>& previous, std::vector<char>& paired,
                                         bool multipliers, double slide, ContactDetection& stats) const;
  // Samples inside the deformed elements this rank owns; stats gets their count of those folded and
  // the deepest of the others over all ranks (collective).
  std::vector<Candidate> inside_candidates(const Positions& at, const std::vector<char>& paired,
                                           const std::vector<double>& carried, ContactDetection& stats) const;
  // The winding number of the deformed surface (positions x) at its vertex v: in (0, 1) unless v went
  // through a face.
  double winding_number(const std::vector<geom::Vec>& x, int v) const;
  // Moves target triangle t and weights w of sample v to the closest deformed-surface point nearby.
  int refine_target(const std::vector<geom::Vec>& x, int v, int& t, double w[3], double& d2) const;
  void proximity_candidates(const Positions& at, const std::vector<char>& paired, const std::vector<double>& carried,
                            std::vector<Candidate>& found) const;
  long long choose(std::vector<Candidate> all, ContactDetection& stats);  // fills chosen_; returns new pushing pairs
  void install();  // pairs_ from chosen_
  // The barrier's detection at `at`: every owned sample's triangles within the margin, gathered; the
  // count of pairs nearer than their dhat that `last` lacked (contact_barrier.cpp).
  long long detect_barrier(const Positions& at, const std::vector<Chosen>& last, const std::vector<std::array<int, 2>>& last_edges,
                           ContactDetection& stats);
  void add_barrier(const TermInput& in, TermOutput& out, double& energy, long long& pressing) const;
  // The pairs the barrier's CCD leaves out (t < 0: the sample v itself).
  bool ccd_skips(int t, int v) const;
  // The same for edges e and f (sharing a vertex, tied, touching at rest), and their pair's dhat.
  bool edge_skips(int e, int f) const;
  double edge_dhat(int e, int f) const {
    return std::min(settings_.thickness, 0.5 * std::min(edge_clearance_[e], edge_clearance_[f]));
  }
  void build_edges();       // edges_, owned_edges_
  void build_edge_pairs();  // edge_area_, edge_clearance_
  // The owned surface edges that pass through a face of the surface at x (geom::segment_crosses_triangle),
  // summed over the ranks (collective): a state with none has no surface through another, which the
  // samples' winding numbers alone cannot tell (two edges can cross with no vertex behind a face).
  long long surface_crossings(const std::vector<geom::Vec>& x) const;
  // The barrier's dhat for surface vertex v: the thickness, or half the vertex's clearance at rest.
  double barrier_dhat(int v) const { return std::min(settings_.thickness, 0.5 * clearance_[v]); }
  void commit();
  std::vector<Chosen> committed_chosen_;
  std::vector<double> committed_collider_lambda_;
  std::function<Rigid(std::size_t, double)> pose_of_;
  StepCounts step_;
  long long global_pairs_ = 0;
  int rank_ = 0;
  mutable std::vector<double> pressure_;
  mutable std::vector<char> tied_;  // per surface vertex: tied by an attachment (empty: none is)
  mutable bool tied_known_ = false;  // tied_ read from the system (at the first detection)
  // The collision test's trees of swept triangles and edges, kept between tests (contact_barrier.cpp, fit).
  mutable geom::AabbTree swept_triangles_, swept_edges_;
  mutable long long swept_tests_ = 0;
  std::vector<double> clearance_;
  long long prescribed_samples_ = -1;  // the barrier's: surface points with a prescribed DOF (-1: not counted yet)
  bool prescribed_reported_ = false;
};

}  // namespace sinew
