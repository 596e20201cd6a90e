// Scene: the mesh and its material blocks, boundary conditions and bones resolved to nodes (no
// component prescribed twice), the load path, the skinning predictor and the initial state.
#include <sinew/algebra/terms/bone_springs.hpp>
#include <sinew/core/errors.hpp>
#include <sinew/core/hash.hpp>
#include <sinew/core/parameters.hpp>
#include <sinew/scenes/scene.hpp>

#include <Teuchos_CommHelpers.hpp>
#include <Tpetra_Vector.hpp>

#include <cmath>
#include <type_traits>

namespace sinew {

namespace {

using Displacement = std::function<std::array<double, 3>(const std::array<double, 3>&, double)>;

// The prescribed displacement of a boundary condition's motion at load fraction t.
Displacement motion_of(const BoundaryConditionParameters& p) {
  using Motion = BoundaryConditionParameters::Motion;
  switch (p.motion) {
    case Motion::Translate: {
      const auto d = p.displacement;
      return [d](const std::array<double, 3>&, double t) { return std::array<double, 3>{t * d[0], t * d[1], t * d[2]}; };
    }
    case Motion::Rotate: {
      const double n = std::sqrt(p.axis[0] * p.axis[0] + p.axis[1] * p.axis[1] + p.axis[2] * p.axis[2]);
      const std::array<double, 3> k{p.axis[0] / n, p.axis[1] / n, p.axis[2] / n};
      const auto c = p.center;
      const double angle = p.angle;
      return [k, c, angle](const std::array<double, 3>& X, double t) {
        const Mat3 R = axis_angle(k, t * angle);
        const std::array<double, 3> d{X[0] - c[0], X[1] - c[1], X[2] - c[2]};
        std::array<double, 3> out;
        for (int i = 0; i < 3; ++i) out[i] = R(i, 0) * d[0] + R(i, 1) * d[1] + R(i, 2) * d[2] - d[i];
        return out;
      };
    }
    case Motion::Affine: {
      const auto G = p.gradient;
      const auto c = p.center, d = p.displacement;
      return [G, c, d](const std::array<double, 3>& X, double t) {
        std::array<double, 3> out;
        for (int i = 0; i < 3; ++i)
          out[i] = t * (G[3 * i] * (X[0] - c[0]) + G[3 * i + 1] * (X[1] - c[1]) + G[3 * i + 2] * (X[2] - c[2]) + d[i]);
        return out;
      };
    }
    case Motion::Fixed: break;
  }
  return [](const std::array<double, 3>&, double) { return std::array<double, 3>{0.0, 0.0, 0.0}; };
}

}  // namespace

Scene::Scene(const SceneDescription& d, Teuchos::RCP<const Teuchos::Comm<int>> comm)
    : name_(d.name), loading_(d.loading), time_(d.time) {
  const std::string file = d.file + ": ";
  // Each step names the file in its input errors.
  auto step = [&](auto&& fn) {
    try {
      fn();
    } catch (const InputError& e) {
      throw e.prefixed(file);
    }
  };
  step([&] { build_system(d, comm); });
  X_ = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), system_->mesh().X);
  step([&] { resolve_conditions(*comm); });
  step([&] { add_bones(d.skeleton, *comm); });
  step([&] { check_conditions(d, *comm); });
  // The registered terms the scene asks for (scenes/term_registry.hpp: contact, pressure).
  step([&] { d.terms.add_terms(TermContext{*system_, *comm, *skeleton_, dynamic()}); });
  fix_prescribed_dofs();
  // Body force and gravity ramp with the load in a quasi-static run, and act in full from the start of
  // a dynamic one.
  system_->set_external_loads(loading_.body_force, loading_.gravity, !dynamic());
}

void Scene::build_system(const SceneDescription& d, const Teuchos::RCP<const Teuchos::Comm<int>>& comm) {
  MaterialAssignment materials{d.material.law.spec(), {}};
  for (const auto& [region, law] : d.material.regions) materials.regions.emplace_back(region, law.spec());
  system_ = std::make_unique<System>(comm, build_scene_mesh(d.mesh, *comm), materials);
}

void Scene::resolve_conditions(const Teuchos::Comm<int>& comm) {
  for (const auto& [bname, p] : loading_.conditions) {
    BoundaryCondition bc;
    bc.name = bname;
    for (int c = 0; c < 3; ++c) bc.prescribed[c] = p.components.find(static_cast<char>('x' + c)) != std::string::npos;
    bc.nodes = select_region(system_->mesh(), comm, p.region, "Loading/Boundary conditions/" + bname);
    bc.value = motion_of(p);
    bcs_.push_back(std::move(bc));
  }
}

void Scene::add_bones(const SkeletonParameters& p, const Teuchos::Comm<int>& comm) {
  skeleton_ = std::make_unique<Skeleton>(p, system_->mesh(), comm, "Skeleton");
  if (p.attachment == SkeletonParameters::Attachment::Soft) {
    // Springs to the bones' motion instead of prescribed nodes (terms/bone_springs.hpp).
    std::vector<BoneSpringTerm::Bone> bones;
    const Skeleton* sk = skeleton_.get();
    for (std::size_t b = 0; b < skeleton_->size(); ++b)
      bones.push_back({skeleton_->name(b), skeleton_->nodes(b),
                       [sk, b](const std::array<double, 3>& X, double t) { return sk->transform(b, t).apply(X); }});
    const double h = system_->cell_size();
    const double kappa = p.bone_stiffness > 0.0 ? p.bone_stiffness : 100.0 * system_->stiffness_scale() / (h * h);
    if (!bones.empty()) system_->add_term(std::make_shared<BoneSpringTerm>(*system_, std::move(bones), kappa));
    return;
  }
  for (std::size_t b = 0; b < skeleton_->size(); ++b) {
    BoundaryCondition bc;
    bc.name = "bone " + skeleton_->name(b);
    bc.nodes = skeleton_->nodes(b);
    const Skeleton* sk = skeleton_.get();
    bc.value = [sk, b](const std::array<double, 3>& X, double t) {
      const auto x = sk->transform(b, t).apply(X);
      return std::array<double, 3>{x[0] - X[0], x[1] - X[1], x[2] - X[2]};
    };
    bcs_.push_back(std::move(bc));
  }
}

void Scene::check_conditions(const SceneDescription& d, const Teuchos::Comm<int>& comm) const {
  // Every condition must hold some node, and no component may be prescribed twice (two conditions
  // may share a node when they prescribe different components of it: rollers meeting at an edge).
  // Both checks are collective, so every rank agrees.
  const Mesh& mesh = system_->mesh();
  std::vector<int> owner(3 * mesh.local_nodes(), -1);
  for (std::size_t k = 0; k < bcs_.size(); ++k) {
    const BoundaryCondition& bc = bcs_[k];
    long long owned = 0;
    for (int nd : bc.nodes)
      if (static_cast<std::size_t>(nd) < mesh.n_owned_nodes) ++owned;
    long long total = 0;
    Teuchos::reduceAll(comm, Teuchos::REDUCE_SUM, owned, Teuchos::outArg(total));
    const bool bone = k >= loading_.conditions.size();
    const std::string where = bone ? "Skeleton/Bones/" + bc.name.substr(5) : "Loading/Boundary conditions/" + bc.name;
    if (total == 0) {
      const std::string region = bone ? d.skeleton.bones[k - loading_.conditions.size()].second.region.region
                                      : loading_.conditions[k].second.region.region;
      throw InputError(where + ": region \"" + region + "\" selects no node", InputErrorKind::EmptyRegion);
    }
    int local_conflict = -1;
    for (int nd : bc.nodes)
      for (int c = 0; c < 3; ++c) {
        if (!bc.prescribed[c]) continue;
        int& o = owner[3 * nd + c];
        if (o >= 0 && local_conflict < 0) local_conflict = o;
        o = static_cast<int>(k);
      }
    int conflict = -1;
    Teuchos::reduceAll(comm, Teuchos::REDUCE_MAX, local_conflict, Teuchos::outArg(conflict));
    if (conflict >= 0)
      throw InputError(where + ": its nodes overlap those of '" + bcs_[conflict].name + "'; a node cannot be both '" +
                           bcs_[conflict].name + "' and '" + bc.name + "'",
                       InputErrorKind::ConflictingConditions);
  }
}

void Scene::fix_prescribed_dofs() {
  std::vector<int> fixed;
  free_.assign(system_->mesh().n_owned_nodes, 1);
  for (const auto& bc : bcs_)
    for (int nd : bc.nodes)
      for (int c = 0; c < 3; ++c)
        if (bc.prescribed[c]) {
          fixed.push_back(3 * nd + c);
          if (static_cast<std::size_t>(nd) < system_->mesh().n_owned_nodes) free_[nd] = 0;
        }
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
  system_->set_load(t);  // every term's: the loads' ramp, the colliders' poses
}

void Scene::predict(double t0, double t1, Vector& u) const {
  if (skeleton_->empty() || !skeleton_->skinning()) return;
  auto v = u.getLocalViewHost(Tpetra::Access::ReadWrite);
  // skin() reads the coordinates as packed xyz triples: a host mirror in LayoutRight.
  static_assert(std::is_same_v<decltype(X_)::array_layout, Kokkos::LayoutRight>, "skin() needs xyz triples");
  skeleton_->skin(t0, t1, X_.data(), free_, v.data(), system_->mesh().n_owned_nodes);
}

void Scene::predict_acceleration(double t0, double t1, const Vector& u, Vector& guess, double scale) const {
  if (skeleton_->empty() || !skeleton_->skinning()) return;
  auto g = guess.getLocalViewHost(Tpetra::Access::ReadWrite);
  auto a = u.getLocalViewHost(Tpetra::Access::ReadOnly);
  skeleton_->skin_acceleration(t0, t1, X_.data(), free_, a.data(), g.data(), scale, system_->mesh().n_owned_nodes);
}

void Scene::predict_run_up(double s0, double s1, Vector& u) const {
  if (skeleton_->empty() || !skeleton_->skinning()) return;
  auto v = u.getLocalViewHost(Tpetra::Access::ReadWrite);
  skeleton_->skin_run_up(s0, s1, X_.data(), free_, v.data(), system_->mesh().n_owned_nodes);
}

void Scene::initial_velocity(Vector& v) const {
  const Mesh& m = system_->mesh();
  double local[4] = {0, 0, 0, static_cast<double>(m.n_owned_nodes)}, c[4];
  for (std::size_t n = 0; n < m.n_owned_nodes; ++n)
    for (int d = 0; d < 3; ++d) local[d] += X_(n, d);
  Teuchos::reduceAll(*system_->comm(), Teuchos::REDUCE_SUM, 4, local, c);
  const auto& w = time_.initial_spin;
  const auto& v0 = time_.initial_velocity;
  auto h = v.getLocalViewHost(Tpetra::Access::OverwriteAll);
  for (std::size_t n = 0; n < m.n_owned_nodes; ++n) {
    const double r[3] = {X_(n, 0) - c[0] / c[3], X_(n, 1) - c[1] / c[3], X_(n, 2) - c[2] / c[3]};
    h(3 * n + 0, 0) = v0[0] + w[1] * r[2] - w[2] * r[1];
    h(3 * n + 1, 0) = v0[1] + w[2] * r[0] - w[0] * r[2];
    h(3 * n + 2, 0) = v0[2] + w[0] * r[1] - w[1] * r[0];
  }
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
