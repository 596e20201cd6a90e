// AttachmentTerm (terms/attachment.hpp): pairs found at rest, the energy's host loop, the rounds.
#include <sinew/algebra/system.hpp>
#include <sinew/algebra/terms/attachment.hpp>
#include <sinew/core/errors.hpp>
#include <sinew/discretization/aabb_tree.hpp>


#include <algorithm>
#include <cmath>
#include <cstdio>
#include <stdexcept>

namespace sinew {

using namespace geom;  // Vec and its operators

static_assert(Kokkos::SpaceAccessibility<Kokkos::HostSpace, DeviceMemory>::accessible,
              "AttachmentTerm's loop runs on the host: it needs host-accessible memory (CUDA UVM)");

namespace {

// An orthonormal frame of triangle (a, b, c): the first edge, the in-plane perpendicular, the normal.
struct Frame {
  Vec e[3];
};
Frame frame_of(const Vec& a, const Vec& b, const Vec& c) {
  Frame f;
  f.e[0] = normalized(b - a);
  f.e[2] = normalized(cross(b - a, c - a));
  f.e[1] = cross(f.e[2], f.e[0]);
  return f;
}

// The point beta_a x_a + beta_b x_b + beta_c x_c of triangle t.
Vec point_on(const std::vector<std::array<int, 3>>& T, const std::vector<Vec>& x, int t, const double beta[3]) {
  return beta[0] * x[T[t][0]] + beta[1] * x[T[t][1]] + beta[2] * x[T[t][2]];
}

std::string format_gap(double g) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.3g", g);
  return buf;
}

}  // namespace

AttachmentTerm::AttachmentTerm(System& system, std::vector<AttachmentSpec> specs, int rounds)
    : system_(system), specs_(std::move(specs)), rounds_(rounds) {
  rank_ = system.comm()->getRank();
  surface_ = replicate_boundary(system.mesh(), *system.comm());
  owned_surface_ = local_boundary(system.mesh()).owned_vertices;
  for (int n : owned_surface_) owned_vertex_.push_back(surface_.vertex_of(system.mesh().node_gid[n]));
  const auto& T = surface_.triangles;
  const std::size_t V = surface_.vertices();
  auto member = [&](const std::vector<GlobalId>& nodes) {
    std::vector<char> in(V, 0);
    for (GlobalId g : nodes) {
      const int v = surface_.vertex_of(g);
      if (v >= 0) in[v] = 1;
    }
    return in;
  };
  std::vector<char> taken(V, 0);
  std::vector<GlobalId> tied;
  target_triangles_.resize(specs_.size());
  for (std::size_t s = 0; s < specs_.size(); ++s) {
    const AttachmentSpec& spec = specs_[s];
    const std::string where = "Attachments/" + spec.name;
    const std::vector<char> source = member(spec.sources), target = member(spec.targets);
    std::vector<int>& tris = target_triangles_[s];
    for (std::size_t t = 0; t < T.size(); ++t)
      if (target[T[t][0]] && target[T[t][1]] && target[T[t][2]]) tris.push_back(static_cast<int>(t));
    long long samples = 0;
    for (std::size_t v = 0; v < V; ++v) samples += source[v];
    if (samples == 0) throw InputError(where + ": its region has no node on the boundary surface", InputErrorKind::EmptyRegion);
    if (tris.empty())
      throw InputError(where + ": its target has no face of the boundary surface (all three nodes of a face in the target)",
                       InputErrorKind::EmptyRegion);
    std::vector<Box> boxes(tris.size());
    for (std::size_t i = 0; i < tris.size(); ++i)
      for (int m : T[tris[i]]) boxes[i].add(surface_.X[m]);
    const AabbTree tree(boxes);
    // Every rank pairs every sample, the same way (the surface is replicated): no exchange needed.
    const double limit2 = spec.distance * spec.distance;
    double nearest = HUGE_VAL;
    const std::size_t first = pairs_.size();
    for (std::size_t v = 0; v < V; ++v) {
      if (!source[v] || taken[v]) continue;
      const Vec& x = surface_.X[v];
      auto d2 = [&](int i) {
        if (surface_.touches_ring(tris[i], static_cast<int>(v))) return HUGE_VAL;
        double w[3];
        const auto& t = T[tris[i]];
        return distance2(x, closest_on_triangle(x, surface_.X[t[0]], surface_.X[t[1]], surface_.X[t[2]], w));
      };
      double best2 = 0.0;
      const int i = tree.closest(x, limit2 * (1.0 + 1e-12), d2, best2);
      if (i < 0) {
        double any2 = 0.0;
        if (tree.closest(x, HUGE_VAL, d2, any2) >= 0) nearest = std::min(nearest, std::sqrt(any2));
        continue;
      }
      Pair p;
      p.spec = static_cast<int>(s);
      p.vertex = static_cast<int>(v);
      p.triangle = tris[i];
      p.area = surface_.area[v];
      const auto& t = T[p.triangle];
      const Vec q = closest_on_triangle(x, surface_.X[t[0]], surface_.X[t[1]], surface_.X[t[2]], p.beta);
      if (spec.kind == AttachmentKind::Fixed) {  // r0 in the target's frame (a sliding pair's g0 follows the freeze below)
        const Frame f = frame_of(surface_.X[t[0]], surface_.X[t[1]], surface_.X[t[2]]);
        for (int d = 0; d < 3; ++d) p.rest[d] = dot(x - q, f.e[d]);
      }
      p.rest_triangle = p.triangle;
      std::copy(p.beta, p.beta + 3, p.rest_beta);
      taken[v] = 1;
      pairs_.push_back(p);
    }
    if (pairs_.size() == first) {
      std::string msg = where + ": no surface point of its region lies within 'Distance' " + format_gap(spec.distance) +
                        " of its target at rest";
      msg += std::isfinite(nearest) ? " (the closest lies " + format_gap(nearest) + " away)" : "";
      throw InputError(msg);
    }
    for (std::size_t k = first; k < pairs_.size(); ++k) {
      tied.push_back(surface_.gid[pairs_[k].vertex]);
      for (int m : T[pairs_[k].triangle]) tied.push_back(surface_.gid[m]);
    }
  }
  system_.tie_nodes(tied);
  last_gap_.assign(specs_.size(), 0.0);
  last_slide_.assign(specs_.size(), 0.0);
  moved_.assign(specs_.size(), 0);
  // Frames and normals at rest; a sliding pair's g0 along the normal a round freezes (interpolated),
  // so that rest is g = 0.
  freeze(surface_.X);
  std::fill(moved_.begin(), moved_.end(), 0);
  for (Pair& p : pairs_)
    if (specs_[p.spec].kind == AttachmentKind::Sliding)
      p.rest[0] = dot(surface_.X[p.vertex] - point_on(T, surface_.X, p.triangle, p.beta), Vec{p.frozen[0], p.frozen[1], p.frozen[2]});
  committed_ = pairs_;
}

void AttachmentTerm::columns_changed(const Map&) { columns_ = system_.column_dofs(); }

int AttachmentTerm::column(GlobalId g) const {
  const LO lid = columns_->getLocalElement(3 * static_cast<GO>(g));
  return lid == Teuchos::OrdinalTraits<LO>::invalid() ? -1 : static_cast<int>(lid);
}

void AttachmentTerm::couplings(std::vector<std::pair<GlobalId, GlobalId>>& out) const {
  // A pair couples its four nodes in the rows this rank owns. A sliding sample's row also reserves the
  // vertices around its target triangle (and they reserve it): a target that slides to a neighbour
  // needs no new pattern.
  const auto& T = surface_.triangles;
  for (const Pair& p : pairs_) {
    const int v[4] = {p.vertex, T[p.triangle][0], T[p.triangle][1], T[p.triangle][2]};
    for (int j = 0; j < 4; ++j) {
      if (surface_.owner[v[j]] != rank_) continue;
      for (int l = 0; l < 4; ++l)
        if (l != j) out.emplace_back(surface_.gid[v[j]], surface_.gid[v[l]]);
    }
    if (specs_[p.spec].kind != AttachmentKind::Sliding) continue;
    const bool sample_owned = surface_.owner[p.vertex] == rank_;
    for (int j = 1; j < 4; ++j)
      for (int k = surface_.tri_offsets[v[j]]; k < surface_.tri_offsets[v[j] + 1]; ++k)
        for (int m : T[surface_.vertex_tris[k]]) {
          if (m == p.vertex) continue;
          if (sample_owned) out.emplace_back(surface_.gid[p.vertex], surface_.gid[m]);
          if (surface_.owner[m] == rank_) out.emplace_back(surface_.gid[m], surface_.gid[p.vertex]);
        }
  }
}

void AttachmentTerm::add(const TermInput& in, TermOutput& out) const {
  if (!columns_) throw std::logic_error("AttachmentTerm: no column map yet (System::update_pattern not called)");
  const auto u = in.u;
  const auto f = out.force;
  const auto A = out.matrix;
  const int owned_dofs = out.owned_dofs;
  const auto& T = surface_.triangles;
  double energy = 0.0;
  for (const Pair& p : pairs_) {
    const int v[4] = {p.vertex, T[p.triangle][0], T[p.triangle][1], T[p.triangle][2]};
    bool here = false;
    for (int j = 0; j < 4; ++j) here = here || surface_.owner[v[j]] == rank_;
    if (!here) continue;
    int col[4];
    for (int j = 0; j < 4; ++j) {
      col[j] = column(surface_.gid[v[j]]);
      if (col[j] < 0) throw std::logic_error("AttachmentTerm: a pair's node is not a column here (System::update_pattern not called)");
    }
    const double w[4] = {1.0, -p.beta[0], -p.beta[1], -p.beta[2]};
    Vec d{0.0, 0.0, 0.0};  // x_s - p
    for (int j = 0; j < 4; ++j)
      for (int c = 0; c < 3; ++c) d[c] += w[j] * (surface_.X[v[j]][c] + u(col[j] + c));
    const double k = specs_[p.spec].stiffness, kA = k * p.area;
    const bool fixed = specs_[p.spec].kind == AttachmentKind::Fixed;
    const Vec g = gap(p, d);  // sliding: g[0] along the normal, the rest zero
    // t: the traction (lambda + k g), a vector (fixed) or along n (sliding).
    const double dir[3] = {p.frozen[0], p.frozen[1], p.frozen[2]};
    double t[3];
    for (int c = 0; c < 3; ++c) t[c] = fixed ? p.lambda[c] + k * g[c] : (p.lambda[0] + k * g[0]) * dir[c];
    if (surface_.owner[p.vertex] == rank_)  // the sample's owner counts the energy
      energy += p.area * (dot(Vec{p.lambda[0], p.lambda[1], p.lambda[2]}, g) + 0.5 * k * dot(g, g));
    for (int j = 0; j < 4; ++j) {
      if (col[j] >= owned_dofs) continue;  // not a row of this rank
      for (int c = 0; c < 3; ++c) {
        const int row = col[j] + c;
        if (in.want_force) f(row) += p.area * w[j] * t[c];
        if (!in.want_matrix) continue;
        int cols[12];
        double vals[12];
        for (int l = 0; l < 4; ++l)
          for (int e = 0; e < 3; ++e) {
            cols[3 * l + e] = col[l] + e;
            vals[3 * l + e] = kA * w[j] * w[l] * (fixed ? (c == e ? 1.0 : 0.0) : dir[c] * dir[e]);
          }
        A.sumIntoValues(row, cols, 12, vals, true, true);
      }
    }
  }
  out.energy += energy;
}

std::vector<Vec> AttachmentTerm::positions(const Vector& u) const {
  auto X = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), system_.mesh().X);
  auto uh = u.getLocalViewHost(Tpetra::Access::ReadOnly);
  return gather_surface_positions(surface_, *system_.comm(), owned_surface_, owned_vertex_, [&](int n) {
    return Vec{X(n, 0) + uh(3 * n, 0), X(n, 1) + uh(3 * n + 1, 0), X(n, 2) + uh(3 * n + 2, 0)};
  });
}

Vec AttachmentTerm::gap(const Pair& p, const Vec& d) const {
  const Vec frozen{p.frozen[0], p.frozen[1], p.frozen[2]};
  if (specs_[p.spec].kind == AttachmentKind::Fixed) return d - frozen;
  return {dot(d, frozen) - p.rest[0], 0.0, 0.0};
}

Vec AttachmentTerm::gap(const Pair& p, const std::vector<Vec>& x) const {
  return gap(p, x[p.vertex] - point_on(surface_.triangles, x, p.triangle, p.beta));
}

void AttachmentTerm::freeze(const std::vector<Vec>& x) {
  const auto& T = surface_.triangles;
  // Sliding samples move to the closest point of their deformed target surface, searched near the
  // current target (within twice the farther of the attachment distance and the sample's distance).
  // The normal is interpolated from the target's area-weighted vertex normals (Phong's), so that it
  // turns continuously as a sample slides over an edge or a vertex of a faceted curved surface: with
  // the faces' own normals a sample at a vertex flips between planes from one round to the next.
  std::vector<AabbTree> trees(specs_.size());
  std::vector<std::vector<Vec>> vertex_normal(specs_.size());
  for (std::size_t s = 0; s < specs_.size(); ++s) {
    if (specs_[s].kind != AttachmentKind::Sliding) continue;
    std::vector<Box> boxes(target_triangles_[s].size());
    vertex_normal[s].assign(surface_.vertices(), Vec{0.0, 0.0, 0.0});
    for (std::size_t i = 0; i < boxes.size(); ++i) {
      const auto& t = T[target_triangles_[s][i]];
      const Vec n2 = cross(x[t[1]] - x[t[0]], x[t[2]] - x[t[0]]);  // twice the area times the normal
      for (int m : t) {
        boxes[i].add(x[m]);
        vertex_normal[s][m] = vertex_normal[s][m] + n2;
      }
    }
    trees[s].build(boxes);
  }
  for (Pair& p : pairs_) {
    const AttachmentSpec& spec = specs_[p.spec];
    if (spec.kind == AttachmentKind::Sliding) {
      const auto& tris = target_triangles_[p.spec];
      const Vec& xs = x[p.vertex];
      const auto& t0 = T[p.triangle];
      const double now = norm(xs - point_on(T, x, p.triangle, p.beta));
      const double limit = 2.0 * std::max(spec.distance, now) + 1e-12;
      double best2 = 0.0;
      const int i = trees[p.spec].closest(xs, limit * limit, [&](int k) {
        if (surface_.touches_ring(tris[k], p.vertex)) return HUGE_VAL;
        double w[3];
        const auto& t = T[tris[k]];
        return distance2(xs, closest_on_triangle(xs, x[t[0]], x[t[1]], x[t[2]], w));
      }, best2);
      if (i >= 0) {
        // Ties go to the current triangle: a sample on a shared edge stays where it was.
        double w[3];
        const double here = distance2(xs, closest_on_triangle(xs, x[t0[0]], x[t0[1]], x[t0[2]], w));
        if (tris[i] != p.triangle && best2 < here * (1.0 - 1e-12)) {
          p.triangle = tris[i];
          ++moved_[p.spec];
        }
        const auto& t = T[p.triangle];
        closest_on_triangle(xs, x[t[0]], x[t[1]], x[t[2]], p.beta);
      }
      const auto& t = T[p.triangle];
      const auto& N = vertex_normal[p.spec];
      Vec n = normalized(p.beta[0] * normalized(N[t[0]]) + p.beta[1] * normalized(N[t[1]]) + p.beta[2] * normalized(N[t[2]]));
      if (norm(n) == 0.0) n = frame_of(x[t[0]], x[t[1]], x[t[2]]).e[2];
      // A traction belongs to its direction: one whose normal turned by more than 30 degrees (a sample
      // that slid round a bend of a coarse surface) starts again from zero rather than push sideways.
      if (dot(n, Vec{p.frozen[0], p.frozen[1], p.frozen[2]}) < std::cos(M_PI / 6.0)) p.lambda[0] = 0.0;
      for (int d = 0; d < 3; ++d) p.frozen[d] = n[d];
    } else {
      const auto& t = T[p.triangle];
      const Frame f = frame_of(x[t[0]], x[t[1]], x[t[2]]);
      for (int d = 0; d < 3; ++d) p.frozen[d] = p.rest[0] * f.e[0][d] + p.rest[1] * f.e[1][d] + p.rest[2] * f.e[2][d];
    }
  }
}

RoundResult AttachmentTerm::round(const Vector& u, int round) {
  const std::vector<Vec> x = positions(u);
  if (round == 0) std::fill(moved_.begin(), moved_.end(), 0);
  // The gap the solve just converged to, against what it held frozen: what the multipliers take up
  // (Uzawa) and what decides another solve. Refreezing then measures the gap against the target as it
  // now stands: a fixed pair's offset turned with its target's frame asks for another solve; a sliding
  // sample's slide round a bend is reported and the next solve works on it, but it alone asks for
  // none: on a coarse curved surface a sample sliding under a large traction would chase its own
  // tangent planes from round to round.
  std::vector<double> solved(specs_.size(), 0.0);
  if (round > 0)
    for (Pair& p : pairs_) {
      const Vec g = gap(p, x);
      solved[p.spec] = std::max(solved[p.spec], norm(g));
      const double k = specs_[p.spec].stiffness;
      for (int d = 0; d < 3; ++d) p.lambda[d] += k * g[d];
    }
  freeze(x);
  std::fill(last_gap_.begin(), last_gap_.end(), 0.0);
  for (const Pair& p : pairs_) last_gap_[p.spec] = std::max(last_gap_[p.spec], norm(gap(p, x)));
  last_slide_ = slides(x);
  RoundResult r;
  if (round == 0) return r;
  bool open = false;
  std::string worst;
  for (std::size_t s = 0; s < specs_.size(); ++s) {
    const double g = specs_[s].kind == AttachmentKind::Fixed ? std::max(solved[s], last_gap_[s]) : solved[s];
    if (g > specs_[s].tolerance) {
      open = true;
      worst += (worst.empty() ? "" : ", ") + specs_[s].name + " " + format_gap(g) + " > " + format_gap(specs_[s].tolerance);
    }
  }
  r.again = open && round < rounds_;
  if (open)
    r.line = "attachments, round " + std::to_string(round) + ": gap " + worst +
             (r.again ? "; tractions raised, solving again" : "; rounds exhausted ('Maximum rounds')");
  return r;
}

std::vector<double> AttachmentTerm::largest_gaps(const Vector& u) const {
  const std::vector<Vec> x = positions(u);
  std::vector<double> g(specs_.size(), 0.0);
  for (const Pair& p : pairs_) g[p.spec] = std::max(g[p.spec], norm(gap(p, x)));
  return g;
}

std::vector<double> AttachmentTerm::slides(const std::vector<Vec>& x) const {
  const auto& T = surface_.triangles;
  std::vector<double> out(specs_.size(), 0.0);
  for (const Pair& p : pairs_) {
    const Vec now = x[p.vertex] - point_on(T, x, p.rest_triangle, p.rest_beta);
    // A fixed pair's offset turns with its target (R r0): its slide is its gap.
    const Vec rest = specs_[p.spec].kind == AttachmentKind::Fixed
                         ? Vec{p.frozen[0], p.frozen[1], p.frozen[2]}
                         : surface_.X[p.vertex] - point_on(T, surface_.X, p.rest_triangle, p.rest_beta);
    out[p.spec] = std::max(out[p.spec], norm(now - rest));
  }
  return out;
}

void AttachmentTerm::end_step(const Vector&) { committed_ = pairs_; }
void AttachmentTerm::abandon_step() { pairs_ = committed_; }

void AttachmentTerm::save_state(TermState& state) const {
  std::vector<double> triangle, beta, frozen, lambda;
  for (const Pair& p : committed_) {
    triangle.push_back(p.triangle);
    beta.insert(beta.end(), p.beta, p.beta + 3);
    frozen.insert(frozen.end(), p.frozen, p.frozen + 3);
    lambda.insert(lambda.end(), p.lambda, p.lambda + 3);
  }
  state.shared.emplace_back("triangle", std::move(triangle));
  state.shared.emplace_back("beta", std::move(beta));
  state.shared.emplace_back("frozen", std::move(frozen));
  state.shared.emplace_back("lambda", std::move(lambda));
}

void AttachmentTerm::load_state(const TermState& state) {
  const std::size_t n = pairs_.size();
  const char* names[4] = {"triangle", "beta", "frozen", "lambda"};
  const std::vector<double>* a[4];
  for (int k = 0; k < 4; ++k) {
    a[k] = state.find_shared(names[k]);
    if (!a[k] || a[k]->size() != (k == 0 ? n : 3 * n))
      throw InputError("checkpoint: the attachments' '" + std::string(names[k]) + "' does not match this scene's " +
                       std::to_string(n) + " attachment pairs (another mesh or other Attachments?)");
  }
  for (std::size_t i = 0; i < n; ++i) {
    Pair& p = pairs_[i];
    const double t = (*a[0])[i];
    if (!(t >= 0.0 && t < static_cast<double>(surface_.triangles.size())))
      throw InputError("checkpoint: attachment pair " + std::to_string(i) + " names no surface triangle");
    p.triangle = static_cast<int>(t);
    for (int d = 0; d < 3; ++d) {
      p.beta[d] = (*a[1])[3 * i + d];
      p.frozen[d] = (*a[2])[3 * i + d];
      p.lambda[d] = (*a[3])[3 * i + d];
    }
  }
  committed_ = pairs_;
}

std::vector<std::string> AttachmentTerm::log_columns() const {
  std::vector<std::string> c;
  for (const auto& s : specs_) {
    c.push_back("attachment_gap_" + s.name);
    c.push_back("attachment_slide_" + s.name);
  }
  return c;
}

std::vector<double> AttachmentTerm::log_values(const EvaluationTotals&) const {
  std::vector<double> v;
  for (std::size_t s = 0; s < specs_.size(); ++s) {
    v.push_back(last_gap_[s]);
    v.push_back(last_slide_[s]);
  }
  return v;
}

std::vector<std::string> AttachmentTerm::summary(const EvaluationTotals&) const {
  std::vector<std::string> lines;
  for (std::size_t s = 0; s < specs_.size(); ++s) {
    long long n = 0;
    double force[3] = {0.0, 0.0, 0.0};  // the multipliers' resultant on the samples: what the surfaces exchange
    for (const Pair& p : pairs_)
      if (p.spec == static_cast<int>(s)) {
        ++n;
        for (int d = 0; d < 3; ++d)
          force[d] += p.area * (specs_[s].kind == AttachmentKind::Fixed ? p.lambda[d] : p.lambda[0] * p.frozen[d]);
      }
    char buf[256];
    std::snprintf(buf, sizeof buf, "attachment %s (%s): %lld pairs, largest gap %.3g, largest slide %.3g, force (%.3g, %.3g, %.3g)%s",
                  specs_[s].name.c_str(), specs_[s].kind == AttachmentKind::Fixed ? "fixed" : "sliding", n, last_gap_[s],
                  last_slide_[s], force[0], force[1], force[2],
                  moved_[s] > 0 ? (", " + std::to_string(moved_[s]) + " targets slid to a neighbour").c_str() : "");
    lines.push_back(buf);
  }
  return lines;
}

}  // namespace sinew
