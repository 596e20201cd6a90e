// Attachments between surfaces: bodies given as separate pieces of one mesh (a muscle inside fat, a
// layer over a layer, a tendon on a bone's surface) held together where they touch at rest, as FEBio's
// tied and sliding interfaces and Ziva's attachments hold tissues.
//
// Pairs. Each attachment names a source region and a target region; every boundary vertex of the
// source (the sample s, with its reference area A_s) within `distance` of a target boundary triangle
// at rest is paired with its closest point there, p = beta_a x_a + beta_b x_b + beta_c x_c (triangles
// sharing an element with the sample are skipped, so a region attached to itself pairs across a cut,
// not with its own neighbours). A sample belongs to the first attachment that reaches it.
//
// Energy per pair, an augmented-Lagrangian penalty as contact's (Sec. 6; Uzawa updates between solves):
//   fixed:    E = A_s (lambda . g + k/2 |g|^2),   g = x_s - p - R r0    (the surfaces move together)
//   sliding:  E = A_s (lambda g + k/2 g^2),       g = n . (x_s - p) - g0 (the normal gap stays, the
//                                                 tangential motion is free)
// with r0 the rest offset x_s - p in the target triangle's rest frame (zero where the surfaces touch),
// R that triangle's current frame, g0 the rest normal gap and n the target's unit normal. R and n are
// frozen during a solve and refreshed between solves (round()), and a sliding sample's target point
// moves to the closest point of the deformed target surface there. For the frozen quantities g is
// linear in the twelve coordinates, w = (1, -beta): the Hessian is exactly
//   fixed:   k A_s (w w^T) (x) I_3,      sliding:  k A_s (w (x) n)(w (x) n)^T,
// positive semi-definite. After each converged solve lambda += k g drives the gap to `tolerance`
// without a stiffer (worse-conditioned) penalty: the step solves again while a gap exceeds it, at
// most `rounds` solves.
//
// Self contact leaves attached surfaces alone (System::tie_nodes): the two sides of a sliding
// interface touch at rest and would otherwise push apart.
//
// Across ranks: the boundary surface and the pairs are the same on every rank (surface-sized); a rank
// adds the rows of the pair nodes it owns and counts a pair's energy where its sample is owned.
#pragma once

#include <sinew/algebra/energy_term.hpp>
#include <sinew/discretization/boundary.hpp>

#include <string>
#include <vector>

namespace sinew {

class System;

enum class AttachmentKind { Fixed, Sliding };

struct AttachmentSpec {
  std::string name;
  AttachmentKind kind = AttachmentKind::Fixed;
  std::vector<GlobalId> sources, targets;  // the regions' nodes (global ids, the same on every rank)
  double distance = 0.0;   // samples within this distance of the target at rest are paired (> 0)
  double stiffness = 0.0;  // k: traction per unit of gap (> 0)
  double tolerance = 0.0;  // the gap the rounds close to (> 0)
};

class AttachmentTerm final : public EnergyTerm {
 public:
  // Collective. Throws InputError naming the attachment that pairs nothing (its surfaces farther apart
  // than its distance, with the closest distance found) or whose regions hold no surface. Marks the
  // attached nodes as tied in the system (for self contact). The system must outlive the term.
  AttachmentTerm(System& system, std::vector<AttachmentSpec> specs, int rounds);

  const char* name() const override { return "attachment"; }
  void add(const TermInput& in, TermOutput& out) const override;
  void couplings(std::vector<std::pair<GlobalId, GlobalId>>& out) const override;
  void columns_changed(const Map& columns) override;

  // round(): Uzawa update after a converged solve, then the frames, normals and sliding targets frozen
  // at u again; another solve while a gap exceeds its tolerance.
  RoundResult round(const Vector& u, int round) override;
  void end_step(const Vector& u) override;
  void abandon_step() override;
  void save_state(TermState& state) const override;
  void load_state(const TermState& state) override;
  std::vector<std::string> log_columns() const override;
  std::vector<double> log_values(const EvaluationTotals& totals) const override;
  std::vector<std::string> summary(const EvaluationTotals& totals) const override;

  struct Pair {
    int spec = 0, vertex = 0, triangle = 0;  // the attachment, the sample's surface vertex, the target triangle
    double beta[3] = {0, 0, 0};              // weights of the target point
    double rest[3] = {0, 0, 0};              // fixed: r0 in the target's rest frame; sliding: rest[0] = g0
    double frozen[3] = {0, 0, 0};            // fixed: R r0 at the last freeze; sliding: the normal n
    double lambda[3] = {0, 0, 0};            // fixed: the traction vector; sliding: lambda[0]
    double area = 0.0;                       // A_s
    int rest_triangle = 0;                   // the target at rest, and its weights: what the sample
    double rest_beta[3] = {0, 0, 0};         // touched then (the slide is measured from it)
  };
  // Every pair, the same on every rank.
  const std::vector<Pair>& pairs() const { return pairs_; }
  const std::vector<AttachmentSpec>& specs() const { return specs_; }
  const SurfaceMesh& surface() const { return surface_; }
  // Collective: per attachment, the largest |gap| at u (owned DOFs) with the frozen frames and targets.
  std::vector<double> largest_gaps(const Vector& u) const;


 private:
  std::vector<geom::Vec> positions(const Vector& u) const;  // every surface vertex at u (collective)
  // The gap of a pair whose sample lies at d = x_s - p from its target point (sliding: component 0), and
  // at surface positions x.
  geom::Vec gap(const Pair& p, const geom::Vec& d) const;
  geom::Vec gap(const Pair& p, const std::vector<geom::Vec>& x) const;
  void freeze(const std::vector<geom::Vec>& x);  // frames, normals, sliding targets at x
  int column(GlobalId g) const;

  System& system_;
  std::vector<AttachmentSpec> specs_;
  int rounds_ = 10;
  int rank_ = 0;
  SurfaceMesh surface_;
  std::vector<int> owned_surface_, owned_vertex_;  // local owned nodes on the surface, their surface vertices
  std::vector<std::vector<int>> target_triangles_;  // per spec: surface triangles of its target
  std::vector<Pair> pairs_, committed_;
  std::vector<double> last_gap_, last_slide_;  // per spec, at the last round
  // Per attachment, the largest slide at x: how far a sample moved from the target point it touched at
  // rest (a fixed pair's slide is its gap; a sliding one's, its tangential travel).
  std::vector<double> slides(const std::vector<geom::Vec>& x) const;
  std::vector<long long> moved_;  // per spec: sliding targets moved to another triangle in this step
  Teuchos::RCP<const Map> columns_;
};

}  // namespace sinew
