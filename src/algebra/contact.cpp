// ContactTerm: collider distances, self-contact detection and the penalty energy (terms/contact.hpp).
#include <sinew/algebra/system.hpp>
#include <sinew/algebra/terms/contact.hpp>
#include "contact_detection.hpp"
#include <sinew/core/collective.hpp>
#include <sinew/core/errors.hpp>

#include <Tpetra_Import.hpp>
#include <Tpetra_Vector.hpp>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <map>

namespace sinew {

using namespace geom;

static_assert(Kokkos::SpaceAccessibility<Kokkos::HostSpace, DeviceMemory>::accessible,
              "the contact term runs on the host: it needs host-accessible vectors and matrices");

namespace {

Vec triangle_normal(const Vec& a, const Vec& b, const Vec& c) { return normalized(cross(b - a, c - a)); }

double angle_between(const Vec& u, const Vec& v) {
  const double nu = norm(u), nv = norm(v);
  if (!(nu > 0.0 && nv > 0.0)) return 0.0;
  return std::acos(std::clamp(dot(u, v) / (nu * nv), -1.0, 1.0));
}

}  // namespace

// ---- colliders ---------------------------------------------------------------------------------------

void ColliderShape::prepare() {
  switch (kind) {
    case Kind::HalfSpace:
      if (!(norm(normal) > 0.0)) throw InputError("a half-space needs a non-zero 'Normal'");
      normal = normalized(normal);
      return;
    case Kind::Sphere:
    case Kind::Capsule:
    case Kind::Cylinder:
      if (!(radius > 0.0)) throw InputError("a sphere, capsule or cylinder needs 'Radius' > 0");
      if (kind == Kind::Cylinder && !(distance2(a, b) > 0.0))
        throw InputError("a cylinder needs two different points 'Start' and 'End' on its axis");
      return;
    case Kind::Mesh: break;
  }
  if (!surface) throw InputError("a mesh collider needs a closed 'Surface'");
  const auto& V = surface->vertices;
  const auto& T = surface->triangles;
  face_normal_.resize(T.size());
  vertex_normal_.assign(V.size(), Vec{0.0, 0.0, 0.0});
  edge_normal_.assign(T.size(), {});
  std::vector<Box> boxes(T.size());
  std::map<std::pair<int, int>, std::vector<int>> edges;  // undirected edge -> its triangles
  for (std::size_t t = 0; t < T.size(); ++t) {
    const Vec &a = V[T[t][0]], &b = V[T[t][1]], &c = V[T[t][2]];
    face_normal_[t] = triangle_normal(a, b, c);
    for (int k = 0; k < 3; ++k) {
      const int i = T[t][k], j = T[t][(k + 1) % 3], l = T[t][(k + 2) % 3];
      // Angle-weighted vertex pseudo-normals (Baerentzen and Aanaes 2005): the sign of the distance is
      // then right wherever the closest point lies.
      const double angle = angle_between(V[j] - V[i], V[l] - V[i]);
      vertex_normal_[i] = vertex_normal_[i] + angle * face_normal_[t];
      edges[{std::min(i, j), std::max(i, j)}].push_back(static_cast<int>(t));
    }
    boxes[t].add(a);
    boxes[t].add(b);
    boxes[t].add(c);
  }
  for (std::size_t t = 0; t < T.size(); ++t)
    for (int k = 0; k < 3; ++k) {
      const int i = T[t][k], j = T[t][(k + 1) % 3];
      Vec n{0.0, 0.0, 0.0};
      for (int u : edges[{std::min(i, j), std::max(i, j)}]) n = n + face_normal_[u];
      edge_normal_[t][k] = n;
    }
  tree_.build(boxes);
}

double ColliderShape::distance(const Vec& x, Vec& g, double* hess) const {
  // Distance to a point q (radius r) or to a line through q along the unit axis `along` (when given):
  // the Hessian of |x - q| is (I - g g^T - along along^T) / |x - q|.
  auto from_point = [&](const Vec& q, double r, const Vec* along) {
    const Vec d = x - q;
    const double l = norm(d);
    g = l > 0.0 ? (1.0 / l) * d : Vec{0.0, 0.0, 1.0};
    if (hess)
      for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j)
          hess[3 * i + j] = l > 0.0 ? ((i == j) - g[i] * g[j] - (along ? (*along)[i] * (*along)[j] : 0.0)) / l : 0.0;
    return l - r;
  };
  if (hess)
    for (int k = 0; k < 9; ++k) hess[k] = 0.0;
  switch (kind) {
    case Kind::HalfSpace: g = normal; return dot(x - point, normal);
    case Kind::Sphere: return from_point(center, radius, nullptr);
    case Kind::Capsule: {
      const double s = closest_on_segment(x, a, b);
      const Vec axis = normalized(b - a);
      return from_point(a + s * (b - a), radius, s > 0.0 && s < 1.0 ? &axis : nullptr);
    }
    case Kind::Cylinder: {
      const Vec ab = b - a, axis = normalized(ab);
      const double s = dot(x - a, ab) / dot(ab, ab);
      return from_point(a + s * ab, radius, &axis);
    }
    case Kind::Mesh: break;
  }
  const auto& V = surface->vertices;
  const auto& T = surface->triangles;
  double best2 = 0.0;
  const int t = tree_.closest(x, HUGE_VAL, [&](int k) {
    double w[3];
    return distance2(x, closest_on_triangle(x, V[T[k][0]], V[T[k][1]], V[T[k][2]], w));
  }, best2);
  double w[3];
  const Vec q = closest_on_triangle(x, V[T[t][0]], V[T[t][1]], V[T[t][2]], w);
  // The pseudo-normal of the feature the closest point lies on: the face, an edge or a vertex.
  Vec pn = face_normal_[t];
  Vec edge{0.0, 0.0, 0.0};
  const int on = (w[0] > 1e-12) + (w[1] > 1e-12) + (w[2] > 1e-12);
  if (on == 1) {
    pn = vertex_normal_[T[t][w[0] > 1e-12 ? 0 : (w[1] > 1e-12 ? 1 : 2)]];
  } else if (on == 2) {
    const int k = w[2] <= 1e-12 ? 0 : (w[0] <= 1e-12 ? 1 : 2);  // edge (0-1), (1-2) or (2-0)
    pn = edge_normal_[t][k];
    edge = normalized(V[T[t][(k + 1) % 3]] - V[T[t][k]]);
  }
  const Vec d = x - q;
  const double l = std::sqrt(best2);
  const double sign = dot(d, pn) >= 0.0 ? 1.0 : -1.0;
  g = l > 1e-14 ? (sign / l) * d : normalized(pn);
  if (hess && on < 3 && l > 1e-14)  // over an edge or a corner the level set is curved
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) hess[3 * i + j] = sign * ((i == j) - g[i] * g[j] - edge[i] * edge[j]) / l;
  return sign * l;
}

Box ColliderShape::bounds(double band) const {
  Box b;
  const double big = 1e300;
  switch (kind) {
    case Kind::HalfSpace:
    case Kind::Cylinder:
      b.lo = {-big, -big, -big};
      b.hi = {big, big, big};
      return b;
    case Kind::Sphere:
      b.add(center);
      b.inflate(radius + band);
      return b;
    case Kind::Capsule:
      b.add(a);
      b.add(this->b);
      b.inflate(radius + band);
      return b;
    case Kind::Mesh: break;
  }
  b.add(Vec{surface->lower[0], surface->lower[1], surface->lower[2]});
  b.add(Vec{surface->upper[0], surface->upper[1], surface->upper[2]});
  b.inflate(band);
  return b;
}

// ---- the term ----------------------------------------------------------------------------------------

ContactTerm::ContactTerm(const System& system, const ContactSettings& settings, std::vector<ColliderShape> colliders)
    : system_(system), settings_(settings), colliders_(std::move(colliders)), poses_(colliders_.size()) {
  rank_ = system.comm()->getRank();
  surface_ = replicate_boundary(system.mesh(), *system.comm());
  std::vector<Box> boxes(surface_.triangles.size());
  for (std::size_t t = 0; t < boxes.size(); ++t)
    for (int v : surface_.triangles[t]) boxes[t].add(surface_.X[v]);
  reference_tree_.build(boxes);
  owned_samples_ = local_boundary(system.mesh()).owned_vertices;
  for (int n : owned_samples_) sample_vertex_.push_back(surface_.vertex_of(system.mesh().node_gid[n]));
  for (auto& c : colliders_) c.prepare();
  collider_lambda_.assign(owned_samples_.size() * colliders_.size(), 0.0);
  // What touches at rest (every rank finds the same on the replicated surface): a surface point closer
  // than the thickness to a face outside its ring. Its springs push only from that clearance on.
  const double delta = settings_.thickness;
  clearance_.assign(surface_.vertices(), delta);
  if (settings_.self && delta > 0.0)
    for (std::size_t v = 0; v < surface_.vertices(); ++v)
      reference_tree_.near(surface_.X[v], delta, [&](int t) {
        if (excluded(t, static_cast<int>(v))) return;
        const auto& T = surface_.triangles[t];
        double w[3];
        const double d = std::sqrt(
            distance2(surface_.X[v], closest_on_triangle(surface_.X[v], surface_.X[T[0]], surface_.X[T[1]], surface_.X[T[2]], w)));
        clearance_[v] = std::min(clearance_[v], d);
      });
  if (settings_.self) build_edges();
  if (edge_pairs()) build_edge_pairs();
}

std::vector<std::string> ContactTerm::notes() const {
  long long points = 0;
  for (std::size_t v = 0; v < clearance_.size(); ++v) points += clearance_[v] < settings_.thickness && !system_.tied(surface_.gid[v]);
  if (points == 0) return {};
  char buf[256];
  std::snprintf(buf, sizeof buf,
                "%lld surface points lie closer than the contact thickness (%.3g) to the surface at rest (pieces meshed "
                "touching, a fused crease): their springs push only where they come closer than at rest",
                points, settings_.thickness);
  return {buf};
}

bool ContactTerm::allows_node_relaxation(std::vector<char>& held) const {
  // Column DOF 3 n is local node n's first (the column map follows the local nodes; the columns past
  // them are other ranks' nodes only springs couple, which no relaxation here moves).
  for (const Pair& p : pairs_)
    for (int j = 0; j < 4; ++j)
      if (p.col[j] >= 0 && static_cast<std::size_t>(p.col[j] / 3) < held.size()) held[static_cast<std::size_t>(p.col[j] / 3)] = 1;
  if (!colliders_.empty() || self_barrier())  // (a barrier: any sample may come near any face)
    for (int n : owned_samples_) held[static_cast<std::size_t>(n)] = 1;
  return true;
}

void ContactTerm::columns_changed(const Map& columns) {
  for (Pair& p : pairs_)
    for (int j = 0; j < 4; ++j) {
      const LO lid = columns.getLocalElement(3 * static_cast<GO>(p.node[j]));
      p.col[j] = lid == Teuchos::OrdinalTraits<LO>::invalid() ? -1 : static_cast<int>(lid);
    }
}

void ContactTerm::couplings(std::vector<std::pair<GlobalId, GlobalId>>& out) const {
  // Each pair couples its four nodes in the rows this rank owns. The sample's row also reserves the
  // vertices around the target triangle (and they reserve it), so that a target sliding to a neighbour
  // at the next detection needs no new pattern.
  auto owned = [&](GlobalId g) { return surface_.owner[surface_.vertex_of(g)] == rank_; };
  for (const Pair& p : pairs_) {
    for (int j = 0; j < 4; ++j) {
      if (!owned(p.node[j])) continue;
      for (int l = 0; l < 4; ++l)
        if (l != j) out.emplace_back(p.node[j], p.node[l]);
    }
    if (p.edges) continue;  // (a barrier's pairs are found afresh before every solve)
    const bool sample_owned = owned(p.node[0]);
    for (int j = 1; j < 4; ++j) {
      const int v = surface_.vertex_of(p.node[j]);
      for (int k = surface_.tri_offsets[v]; k < surface_.tri_offsets[v + 1]; ++k)
        for (int m : surface_.triangles[surface_.vertex_tris[k]]) {
          const GlobalId g = surface_.gid[m];
          if (g == p.node[0]) continue;
          if (sample_owned) out.emplace_back(p.node[0], g);
          if (surface_.owner[m] == rank_) out.emplace_back(g, p.node[0]);
        }
    }
  }
}

void ContactTerm::add(const TermInput& in, TermOutput& out) const {
  pressure_.assign(system_.mesh().n_owned_nodes, 0.0);
  if (pairs_.empty() && colliders_.empty()) return;
  const auto u = in.u;
  const auto f = out.force;
  const auto A = out.matrix;
  const int owned_dofs = out.owned_dofs;
  const double k = settings_.stiffness, delta = settings_.thickness, eps = settings_.onset;
  double energy = 0.0, penetration = 0.0;
  long long pressing = 0;

  // Self contact: the barrier's pairs, or springs.
  static const std::vector<Pair> none;
  if (settings_.barrier) add_barrier(in, out, energy, pressing);
  for (const Pair& p : settings_.barrier ? none : pairs_) {
    if (p.col[0] < 0 || p.col[1] < 0 || p.col[2] < 0 || p.col[3] < 0)
      throw std::logic_error("ContactTerm: a pair's node is not a column here (System::update_pattern not called)");
    double g = 0.0;
    for (int j = 0; j < 4; ++j)
      for (int c = 0; c < 3; ++c) g += p.w[j] * p.normal[c] * (p.X[j][c] + u(p.col[j] + c));
    // s: the spring's stretch, its traction k phi'(s) (k max(0, s) with a sharp onset).
    const double s = p.lambda / k + p.delta - g, kA = k * p.area;
    if (p.owner == rank_) energy -= 0.5 * p.area * p.lambda * p.lambda / k;
    if (s <= 0.0) continue;
    const ContactSpringLaw law = contact_spring_law(s, eps);
    if (p.owner == rank_) {
      energy += kA * law.e;
      ++pressing;
      penetration = std::max(penetration, -g);
      pressure_[p.col[0] / 3] += k * law.d1;
    }
    for (int j = 0; j < 4; ++j) {
      if (p.col[j] >= owned_dofs) continue;  // not a row of this rank
      for (int c = 0; c < 3; ++c) {
        const int row = p.col[j] + c;
        if (in.want_force) f(row) -= kA * law.d1 * p.w[j] * p.normal[c];
        if (in.want_matrix) {
          int cols[12];
          double vals[12];
          for (int l = 0; l < 4; ++l)
            for (int d = 0; d < 3; ++d) {
              cols[3 * l + d] = p.col[l] + d;
              vals[3 * l + d] = kA * law.d2 * p.w[j] * p.w[l] * p.normal[c] * p.normal[d];
            }
          A.sumIntoValues(row, cols, 12, vals, true, true);
        }
      }
    }
  }

  // Colliders, on this rank's samples.
  if (!colliders_.empty()) {
    const auto& mesh = system_.mesh();
    auto X = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), mesh.X);
    std::vector<Rigid> to_local(colliders_.size());
    std::vector<Box> bounds(colliders_.size());
    for (std::size_t c = 0; c < colliders_.size(); ++c) {
      to_local[c] = poses_[c].inverse();
      bounds[c] = colliders_[c].bounds(delta);
    }
    for (std::size_t i = 0; i < owned_samples_.size(); ++i) {
      const int n = owned_samples_[i];
      const Vec x{X(n, 0) + u(3 * n), X(n, 1) + u(3 * n + 1), X(n, 2) + u(3 * n + 2)};
      const double kA = k * surface_.area[sample_vertex_[i]];
      for (std::size_t c = 0; c < colliders_.size(); ++c) {
        const Vec xl = to_local[c].apply(x);
        const double lambda = collider_lambda_[i * colliders_.size() + c];
        energy -= 0.5 * surface_.area[sample_vertex_[i]] * lambda * lambda / k;
        if (!bounds[c].contains(xl) && lambda == 0.0) continue;
        Vec gl;
        double Hl[9];
        const bool exact = in.want_matrix && in.projection && *in.projection != Projection::Clamp && *in.projection != Projection::Abs;
        const double phi = colliders_[c].distance(xl, gl, exact ? Hl : nullptr);
        const double s = lambda / k + delta - phi;
        if (s <= 0.0) continue;
        const Vec g = poses_[c].rotate(gl);
        // The exact Hessian k A (g g^T - s hess phi) when asked for (hess phi rotated to the world frame).
        double curvature[3][3] = {};
        if (exact) {
          const Mat3& R = poses_[c].R;
          for (int a = 0; a < 3; ++a)
            for (int b = 0; b < 3; ++b)
              for (int m = 0; m < 3; ++m)
                for (int n2 = 0; n2 < 3; ++n2) curvature[a][b] += R(a, m) * Hl[3 * m + n2] * R(b, n2);
        }
        // Colliders keep the sharp onset: their distance is exact and smooth, and a smooth onset measured
        // 1,486 -> 1,618 Newton iterations on squash.xml (bodies resting on cylinders sit inside the
        // onset's cubic, which Newton does not solve in one step as it does the quadratic).
        const ContactSpringLaw law = contact_spring_law(s, 0.0);
        energy += kA * law.e;
        ++pressing;
        penetration = std::max(penetration, -phi);
        pressure_[n] += k * law.d1;
        for (int a = 0; a < 3; ++a) {
          if (in.want_force) f(3 * n + a) -= kA * law.d1 * g[a];
          if (in.want_matrix) {
            const int cols[3] = {3 * n, 3 * n + 1, 3 * n + 2};
            double vals[3];
            for (int b = 0; b < 3; ++b) vals[b] = kA * (law.d2 * g[a] * g[b] - law.d1 * curvature[a][b]);
            A.sumIntoValues(3 * n + a, cols, 3, vals, true, true);
          }
        }
      }
    }
  }
  out.energy += energy;
  out.totals.contacts += pressing;
  out.totals.penetration = std::max(out.totals.penetration, penetration);
}

// ---- detection, in named steps ------------------------------------------------------------------------

ContactDetection ContactTerm::detect(const Vector& u, bool keep, bool multipliers, double slide) {
  const auto t0 = std::chrono::steady_clock::now();
  ContactDetection stats;
  const MPI_Comm comm = raw_comm(*system_.comm());
  Positions at(system_, u);
  long long raised = multipliers ? update_collider_tractions(at, keep) : 0;
  MPI_Allreduce(&raised, &stats.raised, 1, MPI_LONG_LONG, MPI_SUM, comm);

  pairs_.clear();
  global_pairs_ = 0;
  const std::vector<Chosen> last = std::move(chosen_);
  chosen_.clear();
  const std::vector<std::array<int, 2>> last_edges = std::move(chosen_edges_);
  chosen_edges_.clear();
  if (!settings_.self) {
    stats.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    return stats;
  }
  gather_surface(at);
  ensure_tied();
  if (settings_.barrier) {
    stats.added = detect_barrier(at, last, last_edges, stats);
  } else {
    detect_springs(at, last, keep, multipliers, slide, stats);
  }
  long long unpaired = stats.unpaired;
  MPI_Allreduce(&unpaired, &stats.unpaired, 1, MPI_LONG_LONG, MPI_SUM, comm);
  double deepest = stats.deepest;
  MPI_Allreduce(&deepest, &stats.deepest, 1, MPI_DOUBLE, MPI_MAX, comm);
  stats.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return stats;
}

void ContactTerm::ensure_tied() const {
  if (!tied_known_) {  // the attachments' nodes: they are set up after this term, before any detection
    std::vector<char> tied(surface_.vertices(), 0);
    bool any = false;
    for (std::size_t v = 0; v < surface_.vertices(); ++v) any = (tied[v] = system_.tied(surface_.gid[v])) || any;
    if (any) tied_ = std::move(tied);
    tied_known_ = true;
  }
}

void ContactTerm::detect_springs(const Positions& at, const std::vector<Chosen>& last, bool keep, bool multipliers, double slide,
                                 ContactDetection& stats) {
  const MPI_Comm comm = raw_comm(*system_.comm());
  // paired: 1 for a kept pair, 2 for one whose spring already sees its sample behind the target (the
  // inside test cannot tell it more).
  std::vector<char> paired(surface_.vertices(), 0);
  std::vector<Candidate> kept = keep ? kept_candidates(at, last, paired, multipliers, slide, stats) : std::vector<Candidate>();
  // A sample paired again after a fresh start carries its traction.
  std::vector<double> carried(surface_.vertices(), 0.0);
  if (!keep)  // (a pair that no longer pushes has dropped its traction already)
    for (const Chosen& c : last) carried[c.vertex] = c.lambda;
  std::vector<Candidate> found = inside_candidates(at, paired, carried, stats);
  proximity_candidates(at, paired, carried, found);
  // Every rank sees every candidate and chooses the same.
  std::vector<Candidate> all = allgatherv(comm, found);
  all.insert(all.end(), kept.begin(), kept.end());
  const long long pressing_new = choose(std::move(all), stats);
  install();
  // What changes the energy at this state: a converged state stays converged under new pairs that do
  // not push yet (they wait in the pair set for the next solve).
  stats.added = pressing_new + stats.refrozen;
}

long long ContactTerm::update_collider_tractions(const Positions& at, bool keep) {
  // Colliders: a sample still behind a collider by more than a tenth of the thickness gets its traction
  // raised (Uzawa, between the solves of a step), one off contact loses it (at every detection).
  const double k = settings_.stiffness, delta = settings_.thickness;
  long long raised = 0;
  for (std::size_t i = 0; i < owned_samples_.size() && !colliders_.empty(); ++i) {
    const Vec x = at.node(owned_samples_[i]);
    for (std::size_t c = 0; c < colliders_.size(); ++c) {
      const Vec xl = poses_[c].inverse().apply(x);
      double& lambda = collider_lambda_[i * colliders_.size() + c];
      if (!colliders_[c].bounds(delta + lambda / k).contains(xl)) {
        lambda = 0.0;
        continue;
      }
      Vec gl;
      const double phi = colliders_[c].distance(xl, gl);
      if (keep && phi < -0.1 * delta) {
        lambda = std::max(0.0, lambda + k * (delta - phi));
        ++raised;
      } else if (lambda / k + delta - phi <= 0.0) {
        lambda = 0.0;  // off contact: its traction goes (the state feels no difference; the energy a constant)
      }
    }
  }
  return raised;
}

void ContactTerm::gather_surface(Positions& at) const {
  at.surface = gather_surface_positions(surface_, *system_.comm(), owned_samples_, sample_vertex_, [&](int n) { return at.node(n); });
}

bool ContactTerm::excluded(int t, int v) const {
  // Attached surfaces (System::tie_nodes) are the attachment's: a tied sample, or a face of tied nodes.
  if (!tied_.empty() && (tied_[v] || (tied_[surface_.triangles[t][0]] && tied_[surface_.triangles[t][1]] && tied_[surface_.triangles[t][2]])))
    return true;
  // The barrier pairs a vertex with every face but its own: a crease folding within two cells (which the
  // springs, after the paper, leave alone) is held apart too, and a face is no nearer than about half
  // a cell at rest on a lattice (the dhat a vertex gets is below its clearance wherever it is nearer).
  if (settings_.barrier) {
    const auto& T = surface_.triangles[t];
    return T[0] == v || T[1] == v || T[2] == v;
  }
  return surface_.touches_ring(t, v);
}

std::vector<ContactTerm::Candidate> ContactTerm::kept_candidates(const Positions& at, const std::vector<Chosen>& previous,
                                                                 std::vector<char>& paired, bool multipliers, double slide,
                                                                 ContactDetection& stats) const {
  // Every rank decides the same from the replicated positions.
  const auto& T = surface_.triangles;
  const auto& x = at.surface;
  const double k = settings_.stiffness, delta = settings_.thickness;
  std::vector<Candidate> kept;
  for (const Chosen& c : previous) {
    const Vec q = c.beta[0] * x[T[c.triangle][0]] + c.beta[1] * x[T[c.triangle][1]] + c.beta[2] * x[T[c.triangle][2]];
    const Vec n{c.normal[0], c.normal[1], c.normal[2]};
    const double g = dot(x[c.vertex] - q, n);
    if (g > settings_.margin) continue;
    if (norm(x[c.vertex] - q - g * n) > slide) continue;  // slid off along its plane: paired afresh
    paired[c.vertex] = std::max<char>(paired[c.vertex], g < 0.0 ? 2 : 1);
    double lambda = c.lambda;
    const double clear = clearance_[c.vertex];  // the thickness, or less where it touched at rest
    // Uzawa: the traction that would have held it at its clearance, for a sample pushed deeper than the
    // onset (where a sharp onset's spring would hold it at its clearance, a smooth one rests inside the
    // onset's width by design: raising it there only costs solves) by a tenth of the thickness.
    if (!multipliers) {
      // (a regroup: the tractions stay as the last converged state left them)
    } else if (g < clear - settings_.onset - 0.1 * delta) {
      lambda = std::max(0.0, lambda + k * (clear - g));
      ++stats.raised;
    } else if (lambda / k + clear - g <= 0.0) {
      lambda = 0.0;  // not pushing: its traction goes (the state feels no difference)
    }
    kept.push_back({c.vertex, 1, c.triangle, {c.beta[0], c.beta[1], c.beta[2]}, {c.normal[0], c.normal[1], c.normal[2]}, 0.0, 0, lambda});
  }
  return kept;
}

namespace {

// A sample found inside, as a rank reports it: whether the surface encloses it (went through a face),
// and its depth.
struct InsideSample {
  int vertex;
  int crossed;
  double depth;
};

}  // namespace

double ContactTerm::winding_number(const std::vector<Vec>& x, int v) const {
  // The triangles around v subtend no solid angle from it, so on a closed surface that does not pass
  // through itself this is the share of the sphere around v that the body fills: in (0, 1). It moves
  // by a whole number only where v passes through a face (or a face over v), never by folding.
  const auto& T = surface_.triangles;
  double omega = 0.0;
  for (const auto& t : T)
    if (t[0] != v && t[1] != v && t[2] != v) omega += solid_angle(x[v], x[t[0]], x[t[1]], x[t[2]]);
  return omega / (4.0 * M_PI);
}

std::vector<ContactTerm::Candidate> ContactTerm::inside_candidates(const Positions& at, const std::vector<char>& paired,
                                                                   const std::vector<double>& carried,
                                                                   ContactDetection& stats) const {
  // Samples inside the deformed elements this rank owns.
  const Mesh& mesh = system_.mesh();
  const auto& T = surface_.triangles;
  const auto& x = at.surface;
  auto conn = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), mesh.conn);
  const bool hex = mesh.type == ElementType::Hex8;
  const int npe = nodes_per_element(mesh.type);
  std::vector<Box> eboxes(mesh.n_owned_elements);
  for (std::size_t e = 0; e < mesh.n_owned_elements; ++e)
    for (int a = 0; a < npe; ++a) eboxes[e].add(at.node(conn(e, a)));
  const AabbTree element_tree(eboxes);
  std::vector<Candidate> found;
  std::vector<InsideSample> report;
  // Every sample, kept pairs included: a kept spring whose target has slid away while its sample went
  // in through a neighbouring triangle is stale, and the sample's new inside pair replaces it.
  for (std::size_t v = 0; v < surface_.vertices(); ++v) {
    if (paired[v] == 2 || (!tied_.empty() && tied_[v])) continue;
    bool inside = false;
    Vec Xref{};
    element_tree.at_point(x[v], [&](int e) {
      if (inside) return;
      for (int a = 0; a < npe; ++a)
        if (surface_.in_ring(static_cast<int>(v), mesh.node_gid[conn(e, a)])) return;
      const int ntets = hex ? 6 : 1;
      for (int k = 0; k < ntets; ++k) {
        int nodes[4];
        for (int a = 0; a < 4; ++a) nodes[a] = conn(e, hex ? kHexTets[k][a] : a);
        double l[4];
        if (!tet_barycentric(x[v], at.node(nodes[0]), at.node(nodes[1]), at.node(nodes[2]), at.node(nodes[3]), l)) continue;
        if (l[0] < -1e-12 || l[1] < -1e-12 || l[2] < -1e-12 || l[3] < -1e-12) continue;
        inside = true;
        Xref = {0.0, 0.0, 0.0};
        for (int a = 0; a < 4; ++a) Xref = Xref + l[a] * Vec{at.X(nodes[a], 0), at.X(nodes[a], 1), at.X(nodes[a], 2)};
        break;
      }
    });
    if (!inside) continue;
    // The closest reference surface point away from the sample's ring, mapped back.
    double best2 = 0.0, w[3];
    int t = reference_tree_.closest(Xref, HUGE_VAL, [&](int k) {
      if (excluded(k, static_cast<int>(v))) return HUGE_VAL;
      double ww[3];
      return distance2(Xref, closest_on_triangle(Xref, surface_.X[T[k][0]], surface_.X[T[k][1]], surface_.X[T[k][2]], ww));
    }, best2);
    if (t < 0) {
      ++stats.unpaired;
      continue;
    }
    closest_on_triangle(Xref, surface_.X[T[t][0]], surface_.X[T[t][1]], surface_.X[T[t][2]], w);
    double d2 = distance2(x[v], w[0] * x[T[t][0]] + w[1] * x[T[t][1]] + w[2] * x[T[t][2]]);
    auto behind = [&](int tri, const double ww[3]) {  // the sample lies behind the target's face
      const Vec face = triangle_normal(x[T[tri][0]], x[T[tri][1]], x[T[tri][2]]);
      return dot((ww[0] * x[T[tri][0]] + ww[1] * x[T[tri][1]] + ww[2] * x[T[tri][2]]) - x[v], face) > 0.0;
    };
    int refined = 0;
    if (settings_.refine) {
      // A refined target in front of which the sample lies (the walk went round a tangled fold, where
      // a sample can be in an element yet outside the nearest face) would hold no spring: its pair
      // never pushed a sample 0.16 deep on the FBX bar. Keep the mapped target then.
      int t2 = t;
      double w2[3] = {w[0], w[1], w[2]}, d22 = d2;
      refined = refine_target(x, static_cast<int>(v), t2, w2, d22);
      if (refined && (behind(t2, w2) || !behind(t, w))) {
        t = t2;
        std::copy(w2, w2 + 3, w);
        d2 = d22;
      } else {
        refined = 0;
      }
    }
    // The spring's direction: from the sample out to the target point (the gradient of the distance,
    // also right where the target lies on an edge or a corner), or the target's normal when the two
    // points coincide or disagree about which side is out.
    const Vec face = triangle_normal(x[T[t][0]], x[T[t][1]], x[T[t][2]]);
    const Vec d = (w[0] * x[T[t][0]] + w[1] * x[T[t][1]] + w[2] * x[T[t][2]]) - x[v];
    const Vec n = norm(d) > 1e-12 * settings_.margin && dot(d, face) > 0.0 ? normalized(d) : face;
    found.push_back({static_cast<int>(v), 0, t, {w[0], w[1], w[2]}, {n[0], n[1], n[2]}, d2, refined, carried[v]});
    stats.deepest = std::max(stats.deepest, std::sqrt(d2));
    // Told apart for the report only (the pair is made either way): a sample inside an element is
    // through a face only where the surface encloses it (its winding number past 1). Where the mesh
    // folds, elements overlap each other and the surface around them without any face having passed a
    // point (BCN's knee with the barrier: a hex folded at a corner whose quadrature points all stay
    // positive held a sample 0.7 mm in front of the nearest face, reported 7.3 mm deep). The volume
    // test alone cannot tell: an element next to a fold is sound and still overlaps.
    const double wn = winding_number(x, static_cast<int>(v));
    report.push_back({static_cast<int>(v), wn > 1.0 + 1e-9 || wn < -1e-9 ? 1 : 0, std::sqrt(d2)});
  }
  // Per sample over all ranks (each holds its own elements; every rank computes the same winding).
  std::vector<InsideSample> all = allgatherv(raw_comm(*system_.comm()), report);
  std::sort(all.begin(), all.end(), [](const InsideSample& a, const InsideSample& b) { return a.vertex < b.vertex; });
  for (std::size_t i = 0; i < all.size();) {
    int crossed = 0;
    double depth = 0.0;
    const int v = all[i].vertex;
    for (; i < all.size() && all[i].vertex == v; ++i) {
      crossed = std::max(crossed, all[i].crossed);
      depth = std::max(depth, all[i].depth);
    }
    if (crossed) {
      ++stats.crossed;
      stats.crossed_deepest = std::max(stats.crossed_deepest, depth);
    } else {
      ++stats.folded;
    }
  }
  return found;
}

int ContactTerm::refine_target(const std::vector<Vec>& x, int v, int& t, double w[3], double& d2) const {
  // The paper's local optimization: walk from the mapped target over the triangles around its
  // vertices (away from the sample's ring) to the closest point of the deformed surface; "typically
  // converges in a single iteration" (at most 8 here). Returns 1 when the target moved.
  const auto& T = surface_.triangles;
  int refined = 0;
  for (int iter = 0; iter < 8; ++iter) {
    int next = -1;
    double nw[3] = {0, 0, 0};
    for (int m : T[t])
      for (int k = surface_.tri_offsets[m]; k < surface_.tri_offsets[m + 1]; ++k) {
        const int t2 = surface_.vertex_tris[k];
        if (t2 == t || excluded(t2, v)) continue;
        double w2[3];
        const double dd = distance2(x[v], closest_on_triangle(x[v], x[T[t2][0]], x[T[t2][1]], x[T[t2][2]], w2));
        if (dd < d2 * (1.0 - 1e-12)) {
          d2 = dd;
          next = t2;
          std::copy(w2, w2 + 3, nw);
        }
      }
    if (next < 0) break;
    t = next;
    std::copy(nw, nw + 3, w);
    refined = 1;
  }
  return refined;
}

void ContactTerm::proximity_candidates(const Positions& at, const std::vector<char>& paired, const std::vector<double>& carried,
                                       std::vector<Candidate>& found) const {
  // This rank's samples near the deformed surface, outside it.
  const auto& T = surface_.triangles;
  const auto& x = at.surface;
  const AabbTree near_tree = triangle_tree(surface_, x);
  const double margin = settings_.margin;
  for (int v : sample_vertex_) {
    if (paired[v]) continue;
    int best = -1;
    double best2 = margin * margin, bw[3] = {0, 0, 0};
    near_tree.near(x[v], margin, [&](int t) {
      if (excluded(t, v)) return;
      double w[3];
      const Vec q = closest_on_triangle(x[v], x[T[t][0]], x[T[t][1]], x[T[t][2]], w);
      const double dd = distance2(x[v], q);
      if (dd >= best2) return;
      if (dot(x[v] - q, triangle_normal(x[T[t][0]], x[T[t][1]], x[T[t][2]])) < 0.0) return;  // behind: inside
      best = t;
      best2 = dd;
      std::copy(w, w + 3, bw);
    });
    if (best < 0) continue;
    // From the target point out to the sample: the face normal for a point over the face, the
    // perpendicular of the edge or the direction from the corner where the closest point is one.
    const Vec q = bw[0] * x[T[best][0]] + bw[1] * x[T[best][1]] + bw[2] * x[T[best][2]];
    const Vec n = norm(x[v] - q) > 1e-12 * margin ? normalized(x[v] - q) : triangle_normal(x[T[best][0]], x[T[best][1]], x[T[best][2]]);
    found.push_back({v, 2, best, {bw[0], bw[1], bw[2]}, {n[0], n[1], n[2]}, best2, 0, carried[v]});
  }
}

long long ContactTerm::choose(std::vector<Candidate> all, ContactDetection& stats) {
  // A sample keeps all its kept pairs; an inside pair whose target triangle none of them has joins them
  // (up to four: a sample in a crease is pushed by both sides, where one frozen plane would let it slip
  // in past its target's edge); a sample with no kept pair takes its inside pair, or else its nearest
  // proximity one.
  std::sort(all.begin(), all.end(), [](const Candidate& a, const Candidate& b) {
    if (a.vertex != b.vertex) return a.vertex < b.vertex;
    if (a.kind != b.kind) return a.kind < b.kind;
    if (a.d2 != b.d2) return a.d2 < b.d2;
    return a.triangle < b.triangle;
  });
  std::vector<Candidate> picked;
  for (std::size_t i = 0; i < all.size();) {
    std::size_t j = i;
    while (j < all.size() && all[j].vertex == all[i].vertex) ++j;
    const std::size_t first = picked.size();
    for (std::size_t m = i; m < j; ++m)
      if (all[m].kind == 1) picked.push_back(all[m]);
    const bool has_kept = picked.size() > first;
    if (all[i].kind == 0) {
      // Inside, yet a kept spring on the same triangle thinks it outside: the triangle has turned
      // since its normal was frozen. Refreeze it (the traction stays).
      auto same = std::find_if(picked.begin() + static_cast<long>(first), picked.end(),
                               [&](const Candidate& c) { return c.triangle == all[i].triangle; });
      if (same != picked.end()) {
        const double lambda = same->lambda;
        *same = all[i];
        same->lambda = lambda;
        ++stats.refrozen;
      } else if (picked.size() - first < 4) {
        picked.push_back(all[i]);
      }
    }
    if (!has_kept && picked.size() == first) picked.push_back(all[i]);
    i = j;
  }
  long long pressing_new = 0;  // new pairs that push at once: inside ones, and near ones within the thickness
  chosen_.clear();
  for (const Candidate& c : picked) {
    if (c.kind == 1)
      ++stats.kept;
    else
      (c.kind == 0 ? stats.inside : stats.proximity) += 1;
    if (c.kind == 0 || (c.kind == 2 && c.d2 < clearance_[c.vertex] * clearance_[c.vertex])) ++pressing_new;
    stats.refined += c.refined;
    chosen_.push_back({c.vertex, c.triangle, {c.beta[0], c.beta[1], c.beta[2]}, {c.normal[0], c.normal[1], c.normal[2]}, c.lambda});
  }
  return pressing_new;
}

void ContactTerm::install() {
  // The springs of the chosen pairs that touch a node of this rank (the same list on every rank).
  const auto& T = surface_.triangles;
  pairs_.clear();
  global_pairs_ = static_cast<long long>(chosen_.size());
  for (const Chosen& c : chosen_) {
    Pair p;
    const int verts[4] = {c.vertex, T[c.triangle][0], T[c.triangle][1], T[c.triangle][2]};
    bool here = false;
    for (int j = 0; j < 4; ++j) {
      p.node[j] = surface_.gid[verts[j]];
      for (int d = 0; d < 3; ++d) p.X[j][d] = surface_.X[verts[j]][d];
      p.w[j] = j == 0 ? 1.0 : -c.beta[j - 1];
      p.col[j] = -1;
      here = here || surface_.owner[verts[j]] == rank_;
    }
    if (!here) continue;
    for (int d = 0; d < 3; ++d) p.normal[d] = c.normal[d];
    p.area = surface_.area[c.vertex];
    p.delta = clearance_[c.vertex];
    p.lambda = c.lambda;
    p.owner = surface_.owner[c.vertex];
    pairs_.push_back(p);
  }
  global_pairs_ += static_cast<long long>(chosen_edges_.size());
  for (const auto& [e, f] : chosen_edges_) {
    Pair p{};
    const int verts[4] = {edges_[e][0], edges_[e][1], edges_[f][0], edges_[f][1]};
    bool here = false;
    for (int j = 0; j < 4; ++j) {
      p.node[j] = surface_.gid[verts[j]];
      for (int d = 0; d < 3; ++d) p.X[j][d] = surface_.X[verts[j]][d];
      p.col[j] = -1;
      here = here || surface_.owner[verts[j]] == rank_;
    }
    if (!here) continue;
    p.edges = true;
    p.area = 0.5 * (edge_area_[e] + edge_area_[f]);
    p.delta = edge_dhat(e, f);
    p.owner = surface_.owner[verts[0]];
    // IPC's eps_x: 1e-3 |A1 - A0|^2 |B1 - B0|^2 at rest.
    p.mollifier = 1e-3 * distance2(surface_.X[verts[0]], surface_.X[verts[1]]) * distance2(surface_.X[verts[2]], surface_.X[verts[3]]);
    pairs_.push_back(p);
  }
  columns_changed(*system_.column_dofs());
}

// ---- lifecycle -------------------------------------------------------------------------------------------

void ContactTerm::set_load(double t) {
  if (pose_of_)
    for (std::size_t k = 0; k < colliders_.size(); ++k) poses_[k] = pose_of_(k, t);
}

void ContactTerm::begin_step(const StepStart& s) {
  if (s.first_attempt) step_ = StepCounts{};
}

RoundResult ContactTerm::round(const Vector& u, int round) {
  // The first round pairs afresh at the step's first guess; later ones keep those pairs and add the
  // samples the last solve pushed into contact. The step ends when a detection adds none, or after
  // the maximum of solves; either way the end state has been looked at.
  // With `keep`, a step starts from the springs its last state converged with, so that a small increment
  // starts near equilibrium (a fresh detection pairs each sample with one target, where a sample in a
  // crease held by two sides went in again in the first iterations: BCN's steps 16-30 took 413 Newton
  // iterations fresh, 153 kept); a pair whose sample has slid farther than the margin along its
  // target's plane is dropped and the sample paired afresh. After a failed attempt, or with no springs
  // yet, the detection is fresh (abandon_step). Off by default: kept, BCN's clip stopped at step 41.
  const bool fresh = round == 0 && (fresh_start_ || !settings_.keep);
  const ContactDetection d = fresh ? detect(u, false) : detect(u, true, round > 0, round == 0 ? settings_.margin : HUGE_VAL);
  step_.rounds += 1;
  step_.seconds += d.seconds;
  step_.pairs = global_pairs_;
  step_.inside_depth = d.deepest;
  step_.crossed_depth = d.crossed_deepest;
  step_.inside_folded = d.folded;
  // The same pairs (sample, target triangle) as an earlier round of this step and no traction raised:
  // a solve already had these springs, so another would only go round the same cycle. (A sample stuck
  // in a crease re-entered as "inside" round after round, and two proximity pairs came and went in
  // turn: huesitos' steps ran all 10 rounds, 84 Newton iterations where 4 rounds had settled it.)
  std::vector<std::pair<int, int>> pairs;
  pairs.reserve(chosen_.size());
  for (const Chosen& c : chosen_) pairs.emplace_back(c.vertex, c.triangle);
  for (const auto& [e, f] : chosen_edges_) pairs.emplace_back(-1 - e, f);
  std::sort(pairs.begin(), pairs.end());
  // Only while the samples inside get no shallower (or none is inside then and now): refreezing a
  // stuck sample's springs is what pushes it out of a fold (tests/fold_test.sh).
  if (round == 0) round_pairs_.clear();
  bool unchanged = false;
  if (round > 0 && d.raised == 0)
    for (const auto& [seen, deepest] : round_pairs_)
      if (seen == pairs && (d.deepest == 0.0 ? deepest == 0.0 : deepest > 0.0 && d.deepest >= 0.99 * deepest)) unchanged = true;
  round_pairs_.emplace_back(std::move(pairs), d.deepest);
  RoundResult r;
  r.again = !((round > 0 && d.added + d.raised == 0) || unchanged || round == settings_.rounds);
  char buf[320];
  std::snprintf(buf, sizeof buf,
                "contact round %d: %lld pairs (%lld kept, %lld inside, %lld near the surface, %lld targets refined%s), "
                "%lld tractions raised, %.2f s",
                round + 1, global_pairs_, d.kept, d.inside, d.proximity, d.refined,
                d.unpaired ? (", " + std::to_string(d.unpaired) + " unpaired").c_str() : "", d.raised, d.seconds);
  r.line = buf;
  if (settings_.barrier && prescribed_samples_ > 0 && !prescribed_reported_) {
    r.line += "\n  contact note: " + std::to_string(prescribed_samples_) +
              " surface points are prescribed (bones, boundary conditions): they move outside the barrier's step limit "
              "and can be carried through a face ('Bone attachment' soft keeps a skeleton's under it)";
    prescribed_reported_ = true;
  }
  return r;
}

std::string ContactTerm::regroup(const Vector& u) {
  if (!regroups()) return {};
  const ContactDetection d = detect(u, true, false);
  step_.seconds += d.seconds;
  step_.pairs = global_pairs_;
  if (d.added == 0) return {};
  char buf[256];
  std::snprintf(buf, sizeof buf, "contact regroup: %lld pairs (%lld kept, %lld inside, %lld near the surface, %lld refrozen), %.2f s",
                global_pairs_, d.kept, d.inside, d.proximity, d.refrozen, d.seconds);
  return buf;
}

void ContactTerm::end_step(const Vector& u) {
  commit();
  fresh_start_ = false;
  if (settings_.self) {  // what the step's report gives: the surface at the converged state, once a step
    Positions at(system_, u);
    gather_surface(at);
    step_.edges_through_faces = surface_crossings(at.surface);
  }
}

// A failed solve: the next attempt pairs afresh at its first guess (round()), carrying the tractions
// this one found, as the rounds of a cut step always did. With 'Keep springs across steps', not from
// the failed attempt's springs: they held another state (BCN's step 31 started each cut at |F| = 111
// with an increment of 2e-4); nor from the last converged state's: a cut that failed from there failed
// the same way at every increment (a slide off an unstable equilibrium the kept springs allow). A
// restart inside the cut step starts where the run would (save_state keeps the choice).
void ContactTerm::abandon_step() {
  commit();
  fresh_start_ = true;
}

void ContactTerm::commit() {
  committed_chosen_ = chosen_;
  committed_chosen_edges_ = chosen_edges_;
  committed_collider_lambda_ = collider_lambda_;
}

void ContactTerm::save_state(TermState& state) const {
  // The pairs (the same on every rank): sample vertex, target triangle, beta, normal, lambda.
  std::vector<double> pairs;
  pairs.reserve(9 * committed_chosen_.size());
  for (const Chosen& c : committed_chosen_) {
    pairs.insert(pairs.end(), {static_cast<double>(c.vertex), static_cast<double>(c.triangle), c.beta[0], c.beta[1], c.beta[2],
                               c.normal[0], c.normal[1], c.normal[2], c.lambda});
  }
  state.shared.emplace_back("pairs", std::move(pairs));
  if (!committed_chosen_edges_.empty()) {  // the barrier's edge-edge pairs: the two edges
    std::vector<double> edges;
    for (const auto& [e, f] : committed_chosen_edges_) edges.insert(edges.end(), {static_cast<double>(e), static_cast<double>(f)});
    state.shared.emplace_back("edge pairs", std::move(edges));
  }
  state.shared.emplace_back("fresh start", std::vector<double>{fresh_start_ ? 1.0 : 0.0});
  if (!colliders_.empty()) {
    // Per owned node, its traction on each collider (0 off the surface).
    TermState::Nodal n{"collider tractions", static_cast<int>(colliders_.size()), {}};
    n.values.assign(system_.mesh().n_owned_nodes * colliders_.size(), 0.0);
    for (std::size_t i = 0; i < owned_samples_.size(); ++i)
      for (std::size_t c = 0; c < colliders_.size(); ++c)
        n.values[owned_samples_[i] * colliders_.size() + c] = committed_collider_lambda_[i * colliders_.size() + c];
    state.nodal.push_back(std::move(n));
  }
}

void ContactTerm::load_state(const TermState& state) {
  const std::vector<double>* pairs = state.find_shared("pairs");
  if (!pairs || pairs->size() % 9 != 0) throw InputError("contact: the checkpoint's pairs are missing or malformed");
  chosen_.clear();
  const auto V = static_cast<double>(surface_.vertices()), T = static_cast<double>(surface_.triangles.size());
  for (std::size_t k = 0; k < pairs->size(); k += 9) {
    const double* r = pairs->data() + k;
    if (!(r[0] >= 0 && r[0] < V && r[1] >= 0 && r[1] < T && r[8] >= 0.0))
      throw InputError("contact: the checkpoint's pair " + std::to_string(k / 9) + " names no surface vertex or triangle of this mesh");
    chosen_.push_back({static_cast<int>(r[0]), static_cast<int>(r[1]), {r[2], r[3], r[4]}, {r[5], r[6], r[7]}, r[8]});
  }
  chosen_edges_.clear();
  // (A checkpoint of a run with edge pairs restarted without them: its pairs are dropped.)
  const std::vector<double>* edges = edge_pairs() ? state.find_shared("edge pairs") : nullptr;
  if (edges) {
    const auto E = static_cast<double>(edges_.size());
    if (edges->size() % 2 != 0) throw InputError("contact: the checkpoint's edge pairs are malformed");
    for (std::size_t k = 0; k < edges->size(); k += 2) {
      const double e = (*edges)[k], f = (*edges)[k + 1];
      if (!(e >= 0 && e < E && f >= 0 && f < E))
        throw InputError("contact: the checkpoint's edge pair " + std::to_string(k / 2) + " names no surface edge of this mesh");
      chosen_edges_.push_back({static_cast<int>(e), static_cast<int>(f)});
    }
  }
  if (!colliders_.empty()) {
    const TermState::Nodal* n = state.find_nodal("collider tractions");
    if (!n || n->components != static_cast<int>(colliders_.size()))
      throw InputError("contact: the checkpoint's collider tractions are missing or for another number of colliders");
    for (std::size_t i = 0; i < owned_samples_.size(); ++i)
      for (std::size_t c = 0; c < colliders_.size(); ++c)
        collider_lambda_[i * colliders_.size() + c] = n->values[owned_samples_[i] * colliders_.size() + c];
  }
  // (Absent from checkpoints written before steps kept their springs: those paired afresh.)
  const std::vector<double>* fresh = state.find_shared("fresh start");
  fresh_start_ = !fresh || fresh->empty() || (*fresh)[0] != 0.0;
  install();
  commit();
}

std::vector<std::string> ContactTerm::log_columns() const {
  return {"contacts", "penetration", "contact_pairs", "contact_rounds", "seconds_contact", "inside_depth", "crossed_depth",
          "inside_folded", "edges_through_faces"};
}

std::vector<double> ContactTerm::log_values(const EvaluationTotals& totals) const {
  return {static_cast<double>(totals.contacts), totals.penetration, static_cast<double>(step_.pairs),
          static_cast<double>(step_.rounds), step_.seconds, step_.inside_depth, step_.crossed_depth,
          static_cast<double>(step_.inside_folded), static_cast<double>(step_.edges_through_faces)};
}

std::vector<std::string> ContactTerm::summary(const EvaluationTotals& totals) const {
  if (totals.contacts == 0 && step_.pairs == 0 && step_.edges_through_faces == 0) return {};
  char buf[320];
  std::snprintf(buf, sizeof buf, "contact: %lld pressing, deepest penetration %.3g (springs) %.3g (surface points through a face), energy %.4g",
                totals.contacts, totals.penetration, step_.crossed_depth, totals.share(name()));
  std::string line = buf;
  if (step_.inside_folded > 0) {
    std::snprintf(buf, sizeof buf, "; %lld more surface points inside elements where the mesh folds (%.3g deep, no face crossed)",
                  step_.inside_folded, step_.inside_depth);
    line += buf;
  }
  if (step_.edges_through_faces > 0) {
    std::snprintf(buf, sizeof buf, "; %lld surface edges through a face (the surface passes through itself)", step_.edges_through_faces);
    line += buf;
  }
  return {line};
}

std::vector<std::pair<std::string, int>> ContactTerm::node_field_names() const { return {{"contact_pressure", 1}}; }

void ContactTerm::node_fields(std::vector<TermState::Nodal>& fields) const {
  fields.push_back({"contact_pressure", 1, pressure_});
}

}  // namespace sinew
