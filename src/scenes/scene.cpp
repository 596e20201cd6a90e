#include <sinew/core/errors.hpp>
#include <sinew/core/hash.hpp>
#include <sinew/core/validation.hpp>
#include <sinew/scenes/scene.hpp>

#include <Teuchos_Array.hpp>
#include <Teuchos_CommHelpers.hpp>
#include <Tpetra_Vector.hpp>

#include <cmath>
#include <map>

namespace sinew {

Teuchos::ParameterList valid_boundary_condition_parameters() {
  Teuchos::ParameterList v("boundary condition");
  v.set("Region", std::string("face z-"), "face x-|x+|y-|y+|z-|z+ (as 'face z-'), box, corners, all");
  v.set("Motion", std::string("fixed"), "fixed | rotate | translate");
  v.set("Box lower", Teuchos::Array<double>({0.0, 0.0, 0.0}), "box region: lower corner");
  v.set("Box upper", Teuchos::Array<double>({0.0, 0.0, 0.0}), "box region: upper corner");
  v.set("Axis", Teuchos::Array<double>({0.0, 0.0, 1.0}), "rotate: axis direction");
  v.set("Center", Teuchos::Array<double>({0.0, 0.0, 0.0}), "rotate: a point on the axis");
  v.set("Angle", 0.0, "rotate: total angle in radians, reached at the last step");
  v.set("Displacement", Teuchos::Array<double>({0.0, 0.0, 0.0}), "translate: total displacement");
  return v;
}

Teuchos::ParameterList valid_loading_parameters() {
  Teuchos::ParameterList v("Loading");
  v.set("Steps", 1, "number of quasi-static load steps");
  v.sublist("Boundary conditions", false, "one sublist per condition");
  v.set("Body force", Teuchos::Array<double>({0.0, 0.0, 0.0}), "force per reference volume, ramped with the load");
  v.set("Initial state", std::string("rest"), "rest | scramble (vertices placed at random, Fig. 3)");
  v.set("Scramble scale", 2.0, "scramble: the vertices fill a box of this many times the rest volume");
  v.set("Scramble seed", 1, "scramble: random seed");
  v.set("Maximum cuts", 6, "a step that fails is retried with half the load increment, at most this many times");
  return v;
}

namespace {

std::array<double, 3> vec3(const Teuchos::ParameterList& p, const char* key, const std::string& where) {
  const auto a = p.get<Teuchos::Array<double>>(key);
  if (a.size() != 3) throw InputError(where + ": '" + key + "' needs 3 entries");
  for (double x : a)
    if (!std::isfinite(x)) throw InputError(where + ": '" + key + "' has a non-finite entry");
  return {a[0], a[1], a[2]};
}

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

}  // namespace

std::array<double, 3> BoundaryCondition::value(const std::array<double, 3>& X, double t) const {
  switch (motion) {
    case Motion::Fixed: return {0, 0, 0};
    case Motion::Translate: return {t * displacement[0], t * displacement[1], t * displacement[2]};
    case Motion::Rotate: {
      const Mat3 R = rotation(axis, t * angle);
      std::array<double, 3> d{X[0] - center[0], X[1] - center[1], X[2] - center[2]}, out{};
      for (int i = 0; i < 3; ++i) out[i] = R(i, 0) * d[0] + R(i, 1) * d[1] + R(i, 2) * d[2] - d[i];
      return out;
    }
  }
  return {0, 0, 0};
}

Scene::Scene(const SceneConfig& config, Teuchos::RCP<const Teuchos::Comm<int>> comm) {
  const auto& P = *config.params;
  name_ = get_or<std::string>(P, "Scene", "custom");
  const std::string file = config.file + ": ";
  try {
    const MeshSpec ms = mesh_from_parameters(P.isSublist("Mesh") ? P.sublist("Mesh") : Teuchos::ParameterList());
    system_ = std::make_unique<ElasticSystem>(comm, build_mesh(ms, *comm), config.material);
  } catch (const InputError& e) {
    throw e.prefixed(file);
  }
  const Mesh& mesh = system_->mesh();
  X_ = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), mesh.X);

  const Teuchos::ParameterList loading = P.isSublist("Loading") ? P.sublist("Loading") : Teuchos::ParameterList();
  const Teuchos::ParameterList vl = valid_loading_parameters();
  try {
    require_known_entries(loading, vl, "Loading");
  } catch (const InputError& e) {
    throw e.prefixed(file);
  }
  steps_ = get_or<int>(loading, "Steps", 1);
  if (steps_ < 1 || steps_ > 1000000) throw InputError(file + "Loading: 'Steps' must lie in [1, 1e6]");
  if (loading.isParameter("Body force")) body_ = vec3(loading, "Body force", file + "Loading");
  initial_ = get_or<std::string>(loading, "Initial state", "rest");
  if (initial_ != "rest" && initial_ != "scramble")
    throw InputError(file + "Loading: 'Initial state' must be rest or scramble, got \"" + initial_ + "\"");
  scramble_scale_ = get_or<double>(loading, "Scramble scale", 2.0);
  scramble_seed_ = static_cast<unsigned>(get_or<int>(loading, "Scramble seed", 1));
  if (!(scramble_scale_ > 0.0)) throw InputError(file + "Loading: 'Scramble scale' must be positive");
  max_cuts_ = get_or<int>(loading, "Maximum cuts", 6);
  if (max_cuts_ < 0 || max_cuts_ > 30) throw InputError(file + "Loading: 'Maximum cuts' must lie in [0, 30]");

  const Teuchos::ParameterList vbc = valid_boundary_condition_parameters();
  std::vector<int> owner(mesh.local_nodes(), -1);  // which condition claims each node
  if (loading.isSublist("Boundary conditions")) {
    const auto& list = loading.sublist("Boundary conditions");
    for (auto it = list.begin(); it != list.end(); ++it) {
      const std::string bname = list.name(it);
      const std::string where = "Loading/Boundary conditions/" + bname;
      if (!list.isSublist(bname)) throw InputError(file + where + " must be a sublist", InputErrorKind::WrongType);
      const auto& p = list.sublist(bname);
      try {
        require_known_entries(p, vbc, where);
      } catch (const InputError& e) {
        throw e.prefixed(file);
      }
      BoundaryCondition bc;
      bc.name = bname;
      bc.region = get_or<std::string>(p, "Region", "face z-");
      const std::string motion = get_or<std::string>(p, "Motion", "fixed");
      if (motion == "fixed")
        bc.motion = BoundaryCondition::Motion::Fixed;
      else if (motion == "rotate")
        bc.motion = BoundaryCondition::Motion::Rotate;
      else if (motion == "translate")
        bc.motion = BoundaryCondition::Motion::Translate;
      else
        throw InputError(file + where + ": 'Motion' must be fixed, rotate or translate, got \"" + motion + "\"");
      if (p.isParameter("Axis")) bc.axis = vec3(p, "Axis", file + where);
      if (p.isParameter("Center")) bc.center = vec3(p, "Center", file + where);
      if (p.isParameter("Displacement")) bc.displacement = vec3(p, "Displacement", file + where);
      bc.angle = get_or<double>(p, "Angle", 0.0);
      const double n = std::sqrt(bc.axis[0] * bc.axis[0] + bc.axis[1] * bc.axis[1] + bc.axis[2] * bc.axis[2]);
      if (bc.motion == BoundaryCondition::Motion::Rotate && !(n > 0.0))
        throw InputError(file + where + ": 'Axis' must be a non-zero vector");
      for (double& a : bc.axis) a /= (n > 0.0 ? n : 1.0);

      std::function<bool(const std::array<double, 3>&)> pred;
      if (bc.region.rfind("face ", 0) == 0) {
        try {
          pred = face_predicate(mesh, bc.region.substr(5));
        } catch (const InputError& e) {
          throw e.prefixed(file + where + ": 'Region' ");
        }
      } else if (bc.region == "box") {
        const auto lo = vec3(p, "Box lower", file + where), hi = vec3(p, "Box upper", file + where);
        pred = [lo, hi](const std::array<double, 3>& X) {
          for (int d = 0; d < 3; ++d)
            if (X[d] < lo[d] || X[d] > hi[d]) return false;
          return true;
        };
      } else if (bc.region == "corners") {
        const auto lo = mesh.lower, hi = mesh.upper;
        const double tol = 1e-9 * std::max({hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2]});
        pred = [lo, hi, tol](const std::array<double, 3>& X) {
          auto at = [&](int d, const std::array<double, 3>& c) { return std::fabs(X[d] - c[d]) <= tol; };
          const bool x0 = at(0, lo), y0 = at(1, lo), z0 = at(2, lo);
          return (x0 && y0 && z0) || (at(0, hi) && y0 && z0) || (x0 && at(1, hi) && z0) || (x0 && y0 && at(2, hi));
        };
      } else if (bc.region == "all") {
        pred = [](const std::array<double, 3>&) { return true; };
      } else {
        throw InputError(file + where + ": unknown 'Region' \"" + bc.region + "\" (face x-..z+, box, corners, all)");
      }
      bc.nodes = select_nodes(mesh, pred);
      long long owned = 0;
      for (int nd : bc.nodes)
        if (static_cast<std::size_t>(nd) < mesh.n_owned_nodes) ++owned;
      long long total = 0;
      Teuchos::reduceAll(*comm, Teuchos::REDUCE_SUM, owned, Teuchos::outArg(total));
      if (total == 0) throw InputError(file + where + ": region \"" + bc.region + "\" selects no node", InputErrorKind::EmptyRegion);
      // A node under two conditions would be prescribed twice: refuse (all ranks agree, since the
      // check is collective below).
      int local_conflict = -1;
      for (int nd : bc.nodes) {
        if (owner[nd] >= 0 && local_conflict < 0) local_conflict = owner[nd];
        owner[nd] = static_cast<int>(bcs_.size());
      }
      int conflict = -1;
      Teuchos::reduceAll(*comm, Teuchos::REDUCE_MAX, local_conflict, Teuchos::outArg(conflict));
      if (conflict >= 0)
        throw InputError(file + where + ": its nodes overlap those of '" + bcs_[conflict].name +
                         "'; a node cannot be both '" + bcs_[conflict].name + "' and '" + bname + "'",
                         InputErrorKind::ConflictingConditions);
      bcs_.push_back(std::move(bc));
    }
  }
  std::vector<int> fixed;
  for (const auto& bc : bcs_)
    for (int nd : bc.nodes)
      for (int c = 0; c < 3; ++c) fixed.push_back(3 * nd + c);
  system_->set_fixed_dofs(fixed);
}

void Scene::apply_load(double t, Vector& u) {
  auto v = u.getLocalViewHost(Tpetra::Access::ReadWrite);
  const std::size_t n_owned = system_->mesh().n_owned_nodes;
  for (const auto& bc : bcs_)
    for (int nd : bc.nodes) {
      if (static_cast<std::size_t>(nd) >= n_owned) continue;
      const auto d = bc.value({X_(nd, 0), X_(nd, 1), X_(nd, 2)}, t);
      for (int c = 0; c < 3; ++c) v(3 * nd + c, 0) = d[c];
    }
  system_->set_body_force({t * body_[0], t * body_[1], t * body_[2]});
}

void Scene::initial_state(Vector& u) const {
  u.putScalar(0.0);
  if (initial_ != "scramble") return;
  // Every vertex moves to a random point of a box centred on the body's, scramble_scale times its
  // volume; the choice depends only on the node's global id, so it does not depend on the ranks.
  const Mesh& m = system_->mesh();
  const double f = std::cbrt(scramble_scale_);
  auto v = u.getLocalViewHost(Tpetra::Access::OverwriteAll);
  for (std::size_t n = 0; n < m.n_owned_nodes; ++n) {
    for (int c = 0; c < 3; ++c) {
      const double r = unit_hash(m.node_gid[n], c, static_cast<int>(scramble_seed_));
      const double mid = 0.5 * (m.lower[c] + m.upper[c]), half = 0.5 * f * (m.upper[c] - m.lower[c]);
      v(3 * n + c, 0) = mid + (2.0 * r - 1.0) * half - X_(n, c);
    }
  }
}

}  // namespace sinew
