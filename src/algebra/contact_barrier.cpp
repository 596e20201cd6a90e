// ContactTerm's barrier self contact (ContactSettings::barrier): detection, energy and the step limit
// (the math in terms/contact_barrier.hpp).
#include <sinew/algebra/system.hpp>
#include <sinew/algebra/terms/contact.hpp>
#include <sinew/algebra/terms/contact_barrier.hpp>
#include <sinew/core/collective.hpp>

#include "contact_detection.hpp"

#include <algorithm>
#include <set>

namespace sinew {

using namespace geom;

namespace {
// Calls fn(e, f) for every pair of edges e < f (e among `mine`) whose boxes, e's grown by `grow`, meet.
template <class Fn>
void edge_box_pairs(const std::vector<int>& mine, const std::vector<Box>& boxes, const AabbTree& tree, double grow, Fn&& fn) {
  for (int e : mine) {
    Box b = boxes[e];
    b.inflate(grow);
    tree.descend([&](int id) { return !tree.node_box(id).overlaps(b); },
                 [&](int f) {
                   if (f > e && boxes[f].overlaps(b)) fn(e, f);
                 });
  }
}
template <class Fn>
void edge_box_pairs(const std::vector<int>& mine, const std::vector<Box>& boxes, double grow, Fn&& fn) {
  edge_box_pairs(mine, boxes, AabbTree(boxes), grow, std::forward<Fn>(fn));
}

// The collision test's trees of swept boxes: refitted (O(n)) for each new direction, and built afresh
// (O(n log n)) every `swept_rebuild` tests, so that the split follows the surface as it moves.
constexpr int swept_rebuild = 8;
void fit(AabbTree& tree, const std::vector<Box>& boxes, bool rebuild) {
  if (rebuild || tree.items() != boxes.size() || tree.empty())
    tree.build(boxes);
  else
    tree.refit(boxes);
}
}  // namespace

void ContactTerm::build_edges() {
  // Every edge once.
  std::vector<std::array<int, 2>> all;
  for (const auto& T : surface_.triangles)
    for (int k = 0; k < 3; ++k) all.push_back({std::min(T[k], T[(k + 1) % 3]), std::max(T[k], T[(k + 1) % 3])});
  std::sort(all.begin(), all.end());
  edges_.clear();
  for (const auto& e : all)
    if (edges_.empty() || edges_.back() != e) edges_.push_back(e);
  owned_edges_.clear();
  for (std::size_t e = 0; e < edges_.size(); ++e)
    if (surface_.owner[edges_[e][0]] == rank_) owned_edges_.push_back(static_cast<int>(e));
}

long long ContactTerm::surface_crossings(const std::vector<Vec>& x) const {
  const auto& T = surface_.triangles;
  const AabbTree tree = triangle_tree(surface_, x);
  long long mine = 0;
  for (int e : owned_edges_) {
    const auto& E = edges_[e];
    Box b;
    b.add(x[E[0]]);
    b.add(x[E[1]]);
    tree.descend([&](int id) { return !tree.node_box(id).overlaps(b); },
                 [&](int t) {
                   const auto& tri = T[t];
                   for (int m : tri)
                     if (m == E[0] || m == E[1]) return;  // (an edge of the triangle, or one meeting it at a corner)
                   if (segment_crosses_triangle(x[E[0]], x[E[1]], x[tri[0]], x[tri[1]], x[tri[2]])) ++mine;
                 });
  }
  long long all = 0;
  MPI_Allreduce(&mine, &all, 1, MPI_LONG_LONG, MPI_SUM, raw_comm(*system_.comm()));
  return all;
}

void ContactTerm::build_edge_pairs() {
  // A third of each of its triangles' reference areas (IPC's edge areas).
  edge_area_.assign(edges_.size(), 0.0);
  for (const auto& T : surface_.triangles) {
    const double a = 0.5 * norm(cross(surface_.X[T[1]] - surface_.X[T[0]], surface_.X[T[2]] - surface_.X[T[0]]));
    for (int k = 0; k < 3; ++k) {
      const std::array<int, 2> e{std::min(T[k], T[(k + 1) % 3]), std::max(T[k], T[(k + 1) % 3])};
      edge_area_[std::lower_bound(edges_.begin(), edges_.end(), e) - edges_.begin()] += a / 3.0;
    }
  }
  std::vector<int> every(edges_.size());
  for (std::size_t e = 0; e < edges_.size(); ++e) every[e] = static_cast<int>(e);
  // What nearly touches at rest (on every rank alike: the surface is replicated), as clearance_ for the
  // vertices: its barrier starts at half that distance.
  const double delta = settings_.thickness;
  edge_clearance_.assign(edges_.size(), delta);
  std::vector<Box> boxes(edges_.size());
  for (std::size_t e = 0; e < edges_.size(); ++e)
    for (int v : edges_[e]) boxes[e].add(surface_.X[v]);
  edge_box_pairs(every, boxes, delta, [&](int e, int f) {
    const auto &E = edges_[e], &F = edges_[f];
    if (E[0] == F[0] || E[0] == F[1] || E[1] == F[0] || E[1] == F[1]) return;
    const double d = barrier::segment_distance(surface_.X[E[0]], surface_.X[E[1]], surface_.X[F[0]], surface_.X[F[1]]);
    edge_clearance_[e] = std::min(edge_clearance_[e], d);
    edge_clearance_[f] = std::min(edge_clearance_[f], d);
  });
}

bool ContactTerm::edge_skips(int e, int f) const {
  const auto &E = edges_[e], &F = edges_[f];
  if (E[0] == F[0] || E[0] == F[1] || E[1] == F[0] || E[1] == F[1]) return true;
  // An edge of tied nodes is the attachment's; a pair touching at rest has no barrier (nor limit).
  if (!tied_.empty() && ((tied_[E[0]] && tied_[E[1]]) || (tied_[F[0]] && tied_[F[1]]))) return true;
  return !(edge_dhat(e, f) > 0.0);
}

long long ContactTerm::detect_barrier(const Positions& at, const std::vector<Chosen>& last,
                                      const std::vector<std::array<int, 2>>& last_edges, ContactDetection& stats) {
  // Every owned sample with every triangle but its own within the margin: the pairs the energy
  // sums over until the next detection (those farther than their dhat add nothing yet).
  if (prescribed_samples_ < 0) {  // counted once: the prescribed DOFs are set before any detection
    const std::vector<char> fixed = system_.fixed_owned_mask();
    long long mine = 0;
    for (int n : owned_samples_) mine += fixed[3 * n] || fixed[3 * n + 1] || fixed[3 * n + 2];
    MPI_Allreduce(&mine, &prescribed_samples_, 1, MPI_LONG_LONG, MPI_SUM, raw_comm(*system_.comm()));
  }
  const auto& T = surface_.triangles;
  const auto& x = at.surface;
  const AabbTree near_tree = triangle_tree(surface_, x);
  const double margin = settings_.margin;
  std::vector<Candidate> found;
  for (int v : sample_vertex_) {
    if (!tied_.empty() && tied_[v]) continue;
    near_tree.near(x[v], margin, [&](int t) {
      if (excluded(t, v)) return;
      double w[3];
      const double d2 = distance2(x[v], closest_on_triangle(x[v], x[T[t][0]], x[T[t][1]], x[T[t][2]], w));
      if (d2 >= margin * margin) return;
      found.push_back({v, 2, t, {w[0], w[1], w[2]}, {0.0, 0.0, 0.0}, d2, 0, 0.0});
    });
  }
  // The depth of samples inside the body (reported, as for the springs; none should be).
  const std::vector<char> unpaired(surface_.vertices(), 0);
  const std::vector<double> zero(surface_.vertices(), 0.0);
  ContactDetection inside;
  inside_candidates(at, unpaired, zero, inside);
  stats.inside = inside.folded + inside.crossed;
  stats.deepest = inside.deepest;
  stats.folded = inside.folded;
  stats.crossed = inside.crossed;
  stats.crossed_deepest = inside.crossed_deepest;

  std::vector<Candidate> all = allgatherv(raw_comm(*system_.comm()), found);
  std::sort(all.begin(), all.end(), [](const Candidate& a, const Candidate& b) {
    return a.vertex != b.vertex ? a.vertex < b.vertex : a.triangle < b.triangle;
  });
  std::set<std::pair<int, int>> before;
  for (const Chosen& c : last) before.emplace(c.vertex, c.triangle);
  long long added = 0;
  chosen_.clear();
  for (const Candidate& c : all) {
    const double dhat = barrier_dhat(c.vertex);
    if (c.d2 < dhat * dhat && !before.count({c.vertex, c.triangle})) ++added;
    chosen_.push_back({c.vertex, c.triangle, {c.beta[0], c.beta[1], c.beta[2]}, {0.0, 0.0, 0.0}, 0.0});
  }
  // The edge pairs within the margin, likewise.
  if (edge_pairs()) {
    std::vector<Box> boxes(edges_.size());
    for (std::size_t e = 0; e < edges_.size(); ++e)
      for (int v : edges_[e]) boxes[e].add(x[v]);
    struct Near {  // (the distance travels with the pair, so no rank computes it twice)
      int e, f;
      double d;
    };
    std::vector<Near> near;
    edge_box_pairs(owned_edges_, boxes, margin, [&](int e, int f) {
      if (edge_skips(e, f)) return;
      const auto &E = edges_[e], &F = edges_[f];
      const double d = barrier::segment_distance(x[E[0]], x[E[1]], x[F[0]], x[F[1]]);
      if (d < margin) near.push_back({e, f, d});
    });
    std::vector<Near> all_edges = allgatherv(raw_comm(*system_.comm()), near);
    std::sort(all_edges.begin(), all_edges.end(), [](const Near& a, const Near& b) { return a.e != b.e ? a.e < b.e : a.f < b.f; });
    const std::set<std::array<int, 2>> edges_before(last_edges.begin(), last_edges.end());
    chosen_edges_.clear();
    for (const Near& n : all_edges) {
      if (n.d < edge_dhat(n.e, n.f) && !edges_before.count({n.e, n.f})) ++added;
      chosen_edges_.push_back({n.e, n.f});
    }
  }
  stats.proximity = static_cast<long long>(chosen_.size() + chosen_edges_.size());
  install();
  for (Pair& p : pairs_)  // (an edge pair keeps the edge_dhat install() gave it)
    if (!p.edges) p.delta = barrier_dhat(surface_.vertex_of(p.node[0]));
  return added;
}

void ContactTerm::add_barrier(const TermInput& in, TermOutput& out, double& energy, long long& pressing) const {
  // E = kappa b(d^2), kappa = k A / dhat^2 (k the stiffness, a traction per length; A the sample's
  // area): at half its dhat a pair pushes with 4.3 k A dhat, where a spring compressed by half the
  // thickness pushes with k A dhat / 2. The Hessian kappa (b'' grad D grad D^T + b' hess D) is projected
  // to PSD per pair (its 12 x 12 eigen-system), except in the solver's exact-terms tier (b' < 0: the
  // projection stiffens the directions along which the surfaces slide, HessianPolicy).
  const auto u = in.u;
  const auto f = out.force;
  const auto A = out.matrix;
  const int owned_dofs = out.owned_dofs;
  for (const Pair& p : pairs_) {
    if (p.col[0] < 0 || p.col[1] < 0 || p.col[2] < 0 || p.col[3] < 0)
      throw std::logic_error("ContactTerm: a pair's node is not a column here (System::update_pattern not called)");
    const double dhat = p.delta;
    if (!(dhat > 0.0)) continue;
    Vec x[4];
    for (int j = 0; j < 4; ++j)
      for (int c = 0; c < 3; ++c) x[j][c] = p.X[j][c] + u(p.col[j] + c);
    const double d = p.edges ? barrier::segment_distance(x[0], x[1], x[2], x[3]) : barrier::point_triangle_distance(x[0], x[1], x[2], x[3]);
    if (!(d < dhat)) continue;
    if (!(d > 0.0)) {  // touching: the energy is +inf there, a state no line search accepts
      energy = HUGE_VAL;
      continue;
    }
    const double Dhat = dhat * dhat, kappa = barrier_stiffness() * p.area / Dhat;
    // g: the pair's energy per kappa, its gradient and (wanted or not) Hessian in the twelve coordinates.
    barrier::Distance2 g;
    if (p.edges) {
      g = barrier::edge_edge_barrier(x[0], x[1], x[2], x[3], barrier::closest_edge_feature(x[0], x[1], x[2], x[3]), Dhat, p.mollifier);
    } else {
      const barrier::Distance2 D = barrier::distance2(x[0], x[1], x[2], x[3], barrier::closest_feature(x[0], x[1], x[2], x[3]));
      const barrier::Law b = barrier::law(D.value, Dhat);
      g.value = b.e;
      for (int i = 0; i < 12; ++i) g.grad[i] = b.d1 * D.grad[i];
      if (in.want_matrix)
        for (int i = 0; i < 12; ++i)
          for (int j = 0; j < 12; ++j) g.hess[i * 12 + j] = b.d2 * D.grad[i] * D.grad[j] + b.d1 * D.hess[i * 12 + j];
    }
    if (p.owner == rank_) {
      energy += kappa * g.value;
      ++pressing;
      // (the traction on the pair's first node: |dE/dx_0|, per its area)
      pressure_[p.col[0] / 3] += kappa * std::sqrt(g.grad[0] * g.grad[0] + g.grad[1] * g.grad[1] + g.grad[2] * g.grad[2]) / p.area;
    }
    double H[144];
    if (in.want_matrix) {
      for (int i = 0; i < 144; ++i) H[i] = kappa * g.hess[i];
      if (!in.exact_terms) barrier::project_psd(H);
    }
    for (int j = 0; j < 4; ++j) {
      if (p.col[j] >= owned_dofs) continue;  // not a row of this rank
      for (int c = 0; c < 3; ++c) {
        const int row = p.col[j] + c, i = 3 * j + c;
        if (in.want_force) f(row) += kappa * g.grad[i];
        if (in.want_matrix) {
          int cols[12];
          for (int l = 0; l < 4; ++l)
            for (int e = 0; e < 3; ++e) cols[3 * l + e] = p.col[l] + e;
          A.sumIntoValues(row, cols, 12, H + 12 * i, true, true);
        }
      }
    }
  }
}

namespace {
// Calls fn(v, t, fraction) for every pair (owned sample v, triangle t) whose path from x0 to x1 the CCD
// bounds below 1, skipping samples (t = -1) and pairs `skips` names.
template <class Skips, class Fn>
void limited_pairs(const SurfaceMesh& s, const std::vector<int>& samples, const std::vector<Vec>& x0, const std::vector<Vec>& x1,
                   AabbTree& tree, bool rebuild, Skips&& skips, Fn&& fn) {
  const auto& T = s.triangles;
  std::vector<Box> swept(T.size());
  for (std::size_t t = 0; t < T.size(); ++t)
    for (int m : T[t]) {
      swept[t].add(x0[m]);
      swept[t].add(x1[m]);
    }
  fit(tree, swept, rebuild);
  for (int v : samples) {
    if (skips(-1, v)) continue;
    Box b;
    b.add(x0[v]);
    b.add(x1[v]);
    tree.descend([&](int id) { return !tree.node_box(id).overlaps(b); },
                 [&](int t) {
                   if (!swept[t].overlaps(b) || skips(t, v)) return;
                   const auto& tri = T[t];
                   const double f = barrier::vertex_triangle_toi(x0[v], x0[tri[0]], x0[tri[1]], x0[tri[2]], x1[v] - x0[v],
                                                                 x1[tri[0]] - x0[tri[0]], x1[tri[1]] - x0[tri[1]],
                                                                 x1[tri[2]] - x0[tri[2]], 1.0);
                   if (f < 1.0) fn(v, t, f);
                 });
  }
}

// The same for edge pairs (e among `mine`, e < f): fn(e, f, fraction).
template <class Skips, class Fn>
void limited_edge_pairs(const std::vector<std::array<int, 2>>& edges, const std::vector<int>& mine, const std::vector<Vec>& x0,
                        const std::vector<Vec>& x1, AabbTree& tree, bool rebuild, Skips&& skips, Fn&& fn) {
  std::vector<Box> swept(edges.size());
  for (std::size_t e = 0; e < edges.size(); ++e)
    for (int m : edges[e]) {
      swept[e].add(x0[m]);
      swept[e].add(x1[m]);
    }
  fit(tree, swept, rebuild);
  edge_box_pairs(mine, swept, tree, 0.0, [&](int e, int f) {
    if (skips(e, f)) return;
    const auto &E = edges[e], &F = edges[f];
    const double t = barrier::edge_edge_toi(x0[E[0]], x0[E[1]], x0[F[0]], x0[F[1]], x1[E[0]] - x0[E[0]], x1[E[1]] - x0[E[1]],
                                            x1[F[0]] - x0[F[0]], x1[F[1]] - x0[F[1]], 1.0);
    if (t < 1.0) fn(e, f, t);
  });
}
}  // namespace

bool ContactTerm::ccd_skips(int t, int v) const {
  // t < 0: the sample itself. A tied one is the attachment's; one touching a face at rest has no
  // barrier, and no limit either (it would hold every step at 0).
  if (t < 0) return (!tied_.empty() && tied_[v]) || !(barrier_dhat(v) > 0.0);
  return excluded(t, v);
}

void ContactTerm::admit_guess(const Vector& u, Vector& guess) const {
  if (!limits_steps()) return;
  ensure_tied();
  Positions at0(system_, u), at1(system_, guess);
  gather_surface(at0);
  gather_surface(at1);
  std::vector<double> fraction(surface_.vertices(), 1.0);
  const bool rebuild = swept_tests_++ % swept_rebuild == 0;
  limited_pairs(surface_, sample_vertex_, at0.surface, at1.surface, swept_triangles_, rebuild,
                [&](int t, int v) { return ccd_skips(t, v); },
                [&](int v, int t, double f) {
                  fraction[v] = std::min(fraction[v], 0.9 * f);
                  for (int m : surface_.triangles[t]) fraction[m] = std::min(fraction[m], 0.9 * f);
                });
  if (edge_pairs())
    limited_edge_pairs(edges_, owned_edges_, at0.surface, at1.surface, swept_edges_, rebuild, [&](int e, int f) { return edge_skips(e, f); },
                       [&](int e, int f, double t) {
                         for (int m : edges_[e]) fraction[m] = std::min(fraction[m], 0.9 * t);
                         for (int m : edges_[f]) fraction[m] = std::min(fraction[m], 0.9 * t);
                       });
  std::vector<double> global(fraction.size());
  MPI_Allreduce(fraction.data(), global.data(), static_cast<int>(fraction.size()), MPI_DOUBLE, MPI_MIN, raw_comm(*system_.comm()));
  const std::vector<char> fixed = system_.fixed_owned_mask();
  auto g = guess.getLocalViewHost(Tpetra::Access::ReadWrite);
  auto u0 = u.getLocalViewHost(Tpetra::Access::ReadOnly);
  for (std::size_t n = 0; n < system_.mesh().n_owned_nodes; ++n) {
    const int v = surface_.vertex_of(system_.mesh().node_gid[n]);
    if (v < 0 || global[v] >= 1.0) continue;
    for (int c = 0; c < 3; ++c) {
      const std::size_t i = 3 * n + c;
      if (!fixed[i]) g(i, 0) = u0(i, 0) + global[v] * (g(i, 0) - u0(i, 0));
    }
  }
}

double ContactTerm::step_limit(const Vector& u, const Vector& du, double t_max) const {
  if (!limits_steps()) return t_max;
  // Positions at u and at u + t_max du (every surface vertex, replicated); each rank tests its own
  // samples against every triangle whose swept box meets the sample's, and the smallest limit wins.
  ensure_tied();
  Positions at0(system_, u);
  gather_surface(at0);
  auto end = system_.create_vector();
  end->update(1.0, u, t_max, du, 0.0);
  Positions at1(system_, *end);
  gather_surface(at1);
  double limit = 1.0;
  const bool rebuild = swept_tests_++ % swept_rebuild == 0;
  limited_pairs(surface_, sample_vertex_, at0.surface, at1.surface, swept_triangles_, rebuild,
                [&](int t, int v) { return ccd_skips(t, v); },
                [&](int, int, double f) { limit = std::min(limit, f); });
  if (edge_pairs())
    limited_edge_pairs(edges_, owned_edges_, at0.surface, at1.surface, swept_edges_, rebuild, [&](int e, int f) { return edge_skips(e, f); },
                       [&](int, int, double t) { limit = std::min(limit, t); });
  double global = limit;
  MPI_Allreduce(&limit, &global, 1, MPI_DOUBLE, MPI_MIN, raw_comm(*system_.comm()));
  return global * t_max;
}

}  // namespace sinew
