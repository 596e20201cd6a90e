// Scene: resolves boundary regions to nodes, applies the load path and the initial state.
#include <sinew/core/errors.hpp>
#include <sinew/core/hash.hpp>
#include <sinew/scenes/scene.hpp>

#include <Teuchos_CommHelpers.hpp>
#include <Tpetra_Vector.hpp>

#include <cmath>
#include <map>

namespace sinew {

namespace {

// Rotation matrix about a unit axis (Rodrigues).
Mat3 rotation(const std::array<double, 3>& k, double angle) {
  const double c = std::cos(angle), s = std::sin(angle), t = 1 - c;
  Mat3 R;
  R(0, 0) = c + k[0] * k[0] * t;
  R(0, 1) = k[0] * k[1] * t - k[2] * s;
  R(0, 2) = k[0] * k[2] * t + k[1] * s;
  R(1, 0) = k[1] * k[0] * t + k[2] * s;
  R(1, 1) = c + k[1] * k[1] * t;
  R(1, 2) = k[1] * k[2] * t - k[0] * s;
  R(2, 0) = k[2] * k[0] * t - k[1] * s;
  R(2, 1) = k[2] * k[1] * t + k[0] * s;
  R(2, 2) = c + k[2] * k[2] * t;
  return R;
}

// The nodes a condition's 'Region' names, as a predicate on the reference position.
std::function<bool(const std::array<double, 3>&)> region_predicate(const Mesh& mesh, const std::string& region,
                                                                 const BoundaryConditionParameters& p, const std::string& where) {
  if (region.rfind("face ", 0) == 0) {
    try {
      return face_predicate(mesh, region.substr(5));
    } catch (const InputError& e) {
      throw e.prefixed(where + ": 'Region' ");
    }
  }
  if (region == "box") {
    const auto lo = p.box_lower, hi = p.box_upper;
    return [lo, hi](const std::array<double, 3>& X) {
      for (int k = 0; k < 3; ++k)
        if (X[k] < lo[k] || X[k] > hi[k]) return false;
      return true;
    };
  }
  if (region == "corners") {
    // Four non-coplanar corners of the bounding box pin every rigid motion and nothing more.
    const auto lo = mesh.lower, hi = mesh.upper;
    const double tol = 1e-9 * std::max({hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2]});
    return [lo, hi, tol](const std::array<double, 3>& X) {
      auto at = [&](int k, const std::array<double, 3>& c) { return std::fabs(X[k] - c[k]) <= tol; };
      const bool x0 = at(0, lo), y0 = at(1, lo), z0 = at(2, lo);
      return (x0 && y0 && z0) || (at(0, hi) && y0 && z0) || (x0 && at(1, hi) && z0) || (x0 && y0 && at(2, hi));
    };
  }
  if (region == "all") return [](const std::array<double, 3>&) { return true; };
  throw InputError(where + ": unknown 'Region' \"" + region + "\" (face x-..z+, box, corners, all)");
}

}  // namespace

std::array<double, 3> BoundaryCondition::value(const std::array<double, 3>& X, double t) const {
  using Motion = BoundaryConditionParameters::Motion;
  switch (p.motion) {
    case Motion::Fixed: return {0, 0, 0};
    case Motion::Translate: return {t * p.displacement[0], t * p.displacement[1], t * p.displacement[2]};
    case Motion::Rotate: {
      const Mat3 R = rotation(p.axis, t * p.angle);
      const auto& center = p.center;
      std::array<double, 3> d{X[0] - center[0], X[1] - center[1], X[2] - center[2]}, out{};
      for (int i = 0; i < 3; ++i) out[i] = R(i, 0) * d[0] + R(i, 1) * d[1] + R(i, 2) * d[2] - d[i];
      return out;
    }
  }
  return {0, 0, 0};
}

Scene::Scene(const SceneDescription& d, Teuchos::RCP<const Teuchos::Comm<int>> comm)
    : name_(d.name), loading_(d.loading) {
  const std::string file = d.file + ": ";
  try {
    MaterialAssignment materials{d.material.law.spec(), {}};
    for (const auto& [region, law] : d.material.regions) materials.regions.emplace_back(region, law.spec());
    system_ = std::make_unique<ElasticSystem>(comm, build_scene_mesh(d.mesh, *comm), materials);
  } catch (const InputError& e) {
    throw e.prefixed(file);
  }
  const Mesh& mesh = system_->mesh();
  X_ = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), mesh.X);

  // Which condition prescribes each (node, component): two conditions may share a node when they
  // prescribe different components of it (rollers on two faces meeting at an edge).
  std::vector<int> owner(3 * mesh.local_nodes(), -1);
  for (const auto& [bname, p] : loading_.conditions) {
    const std::string where = "Loading/Boundary conditions/" + bname;
    BoundaryCondition bc;
    bc.name = bname;
    bc.p = p;
    const double n = std::sqrt(p.axis[0] * p.axis[0] + p.axis[1] * p.axis[1] + p.axis[2] * p.axis[2]);
    for (double& a : bc.p.axis) a /= (n > 0.0 ? n : 1.0);
    for (int c = 0; c < 3; ++c) bc.prescribed[c] = p.components.find(static_cast<char>('x' + c)) != std::string::npos;

    bc.nodes = select_nodes(mesh, region_predicate(mesh, p.region, p, file + where));
    long long owned = 0;
    for (int nd : bc.nodes)
      if (static_cast<std::size_t>(nd) < mesh.n_owned_nodes) ++owned;
    long long total = 0;
    Teuchos::reduceAll(*comm, Teuchos::REDUCE_SUM, owned, Teuchos::outArg(total));
    if (total == 0) throw InputError(file + where + ": region \"" + p.region + "\" selects no node", InputErrorKind::EmptyRegion);
    // A component prescribed by two conditions would be prescribed twice: refuse (all ranks agree,
    // since the check is collective below).
    int local_conflict = -1;
    for (int nd : bc.nodes)
      for (int c = 0; c < 3; ++c) {
        if (!bc.prescribed[c]) continue;
        int& o = owner[3 * nd + c];
        if (o >= 0 && local_conflict < 0) local_conflict = o;
        o = static_cast<int>(bcs_.size());
      }
    int conflict = -1;
    Teuchos::reduceAll(*comm, Teuchos::REDUCE_MAX, local_conflict, Teuchos::outArg(conflict));
    if (conflict >= 0)
      throw InputError(file + where + ": its nodes overlap those of '" + bcs_[conflict].name + "'; a node cannot be both '" +
                           bcs_[conflict].name + "' and '" + bname + "'",
                       InputErrorKind::ConflictingConditions);
    bcs_.push_back(std::move(bc));
  }
  std::vector<int> fixed;
  for (const auto& bc : bcs_)
    for (int nd : bc.nodes)
      for (int c = 0; c < 3; ++c)
        if (bc.prescribed[c]) fixed.push_back(3 * nd + c);
  system_->set_fixed_dofs(fixed);
}

void Scene::apply_load(double t, Vector& u) {
  auto v = u.getLocalViewHost(Tpetra::Access::ReadWrite);
  const std::size_t n_owned = system_->mesh().n_owned_nodes;
  for (const auto& bc : bcs_)
    for (int nd : bc.nodes) {
      if (static_cast<std::size_t>(nd) >= n_owned) continue;
      const auto d = bc.value({X_(nd, 0), X_(nd, 1), X_(nd, 2)}, t);
      for (int c = 0; c < 3; ++c)
        if (bc.prescribed[c]) v(3 * nd + c, 0) = d[c];
    }
  const auto& b = loading_.body_force;
  system_->set_body_force({t * b[0], t * b[1], t * b[2]});
}

void Scene::initial_state(Vector& u) const {
  u.putScalar(0.0);
  if (loading_.initial != LoadingParameters::Initial::Scramble) return;
  // Every vertex moves to a random point of a box centred on the body's, scramble_scale times its
  // volume; the choice depends only on the node's global id, so it does not depend on the ranks.
  const Mesh& m = system_->mesh();
  const double f = std::cbrt(loading_.scramble_scale);
  auto v = u.getLocalViewHost(Tpetra::Access::OverwriteAll);
  for (std::size_t n = 0; n < m.n_owned_nodes; ++n) {
    for (int c = 0; c < 3; ++c) {
      const double r = unit_hash(m.node_gid[n], c, loading_.scramble_seed);
      const double mid = 0.5 * (m.lower[c] + m.upper[c]), half = 0.5 * f * (m.upper[c] - m.lower[c]);
      v(3 * n + c, 0) = mid + (2.0 * r - 1.0) * half - X_(n, c);
    }
  }
}

}  // namespace sinew
