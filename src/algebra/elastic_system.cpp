// ElasticSystem: maps, graph, material blocks, the evaluation (element loop + Dirichlet elimination +
// reductions) and MueLu's rigid-body modes.
#include "assembly.hpp"

#include <sinew/core/errors.hpp>
#include <sinew/core/parameters.hpp>
#include <sinew/discretization/mesh_file.hpp>

#include <Teuchos_CommHelpers.hpp>
#include <Tpetra_CrsGraph.hpp>
#include <Tpetra_CrsMatrix.hpp>
#include <Tpetra_Import.hpp>
#include <Tpetra_MultiVector.hpp>
#include <Tpetra_Vector.hpp>

#include <algorithm>
#include <cmath>

namespace sinew {

namespace {

Teuchos::RCP<const Map> make_map(const std::vector<GO>& gids, const Teuchos::RCP<const Teuchos::Comm<int>>& comm) {
  const Tpetra::global_size_t invalid = Teuchos::OrdinalTraits<Tpetra::global_size_t>::invalid();
  return Teuchos::rcp(new Map(invalid, Teuchos::ArrayView<const GO>(gids.data(), gids.size()), 0, comm));
}

std::vector<GO> dof_gids(const std::vector<GlobalId>& node_gids, std::size_t count) {
  std::vector<GO> out(3 * count);
  for (std::size_t n = 0; n < count; ++n)
    for (int c = 0; c < 3; ++c) out[3 * n + c] = 3 * static_cast<GO>(node_gids[n]) + c;
  return out;
}

}  // namespace

ElasticSystem::ElasticSystem(Teuchos::RCP<const Teuchos::Comm<int>> comm, Mesh mesh, const MaterialAssignment& materials)
    : comm_(std::move(comm)), mesh_(std::move(mesh)) {
  build_blocks(materials);
  elements_ = compute_element_data(mesh_, *comm_);
  const std::size_t n_owned = mesh_.n_owned_nodes, n_local = mesh_.local_nodes();
  std::vector<GO> owned_node_gids(mesh_.node_gid.begin(), mesh_.node_gid.begin() + n_owned);
  owned_nodes_ = make_map(owned_node_gids, comm_);
  owned_dofs_ = make_map(dof_gids(mesh_.node_gid, n_owned), comm_);
  overlap_dofs_ = make_map(dof_gids(mesh_.node_gid, n_local), comm_);
  importer_ = Teuchos::rcp(new Import(owned_dofs_, overlap_dofs_));
  u_overlap_ = Teuchos::rcp(new Vector(overlap_dofs_));
  fixed_ = Kokkos::View<char*>("fixed", 3 * n_local);
  build_graph();
  // Reference volume of the owned elements, summed over ranks.
  auto w = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), elements_.wdetJ);
  double local = 0.0;
  for (std::size_t p = 0; p < mesh_.n_owned_elements * static_cast<std::size_t>(elements_.nqp); ++p) local += w(p);
  Teuchos::reduceAll(*comm_, Teuchos::REDUCE_SUM, local, Teuchos::outArg(reference_volume_));
}

void ElasticSystem::build_blocks(const MaterialAssignment& materials) {
  // One block per law: the default law first, then one per region in the order given; an element
  // belongs to the last region listed that contains it. Kernels run block by block, so each law's
  // kernel is its own instantiation with no per-element switch.
  const std::size_t ne = mesh_.local_elements();
  std::vector<int> block_of(ne, 0);
  std::vector<MaterialSpec> laws{materials.default_law};
  const auto& names = mesh_.element_group_names;
  for (const auto& [name, law] : materials.regions) {
    const auto it = std::find(names.begin(), names.end(), name);
    if (it == names.end()) throw unknown_group("Material/" + name, name, {}, names);
    const int group = static_cast<int>(it - names.begin());
    for (std::size_t e = 0; e < ne; ++e)
      if (!mesh_.element_group.empty() && mesh_.element_group[e] == group) block_of[e] = static_cast<int>(laws.size());
    laws.push_back(law);
  }
  for (std::size_t b = 0; b < laws.size(); ++b) {
    std::vector<int> ids;
    for (std::size_t e = 0; e < ne; ++e)
      if (block_of[e] == static_cast<int>(b)) ids.push_back(static_cast<int>(e));
    Block blk{laws[b], Kokkos::View<int*>("block elements", ids.size())};
    auto h = Kokkos::create_mirror_view(blk.elements);
    for (std::size_t k = 0; k < ids.size(); ++k) h(k) = ids[k];
    Kokkos::deep_copy(blk.elements, h);
    blocks_.push_back(blk);
  }
}

void ElasticSystem::build_graph() {
  // Once per mesh: each owned node couples to every node of every element around it (all of which are
  // on this rank, owned or ghost), so the graph needs no communication and Newton only refills values.
  const std::size_t n_owned = mesh_.n_owned_nodes;
  auto conn = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), mesh_.conn);
  const int npe = nodes_per_element(mesh_.type);
  std::vector<std::vector<int>> neighbours(n_owned);
  for (std::size_t e = 0; e < mesh_.local_elements(); ++e)
    for (int a = 0; a < npe; ++a) {
      const int na = conn(e, a);
      if (static_cast<std::size_t>(na) >= n_owned) continue;
      for (int b = 0; b < npe; ++b) neighbours[na].push_back(conn(e, b));
    }
  std::vector<std::size_t> counts(3 * n_owned);
  for (std::size_t n = 0; n < n_owned; ++n) {
    auto& nb = neighbours[n];
    std::sort(nb.begin(), nb.end());
    nb.erase(std::unique(nb.begin(), nb.end()), nb.end());
    for (int c = 0; c < 3; ++c) counts[3 * n + c] = 3 * nb.size();
  }
  // The column map is the overlap map itself: local column index = overlap DOF index, which is what
  // the kernels scatter with and what the Dirichlet elimination reads.
  auto graph = Teuchos::rcp(new CrsGraph(owned_dofs_, overlap_dofs_, Teuchos::ArrayView<const std::size_t>(counts)));
  std::vector<LO> cols;
  for (std::size_t n = 0; n < n_owned; ++n) {
    cols.clear();
    for (int m : neighbours[n])
      for (int c = 0; c < 3; ++c) cols.push_back(3 * m + c);
    for (int c = 0; c < 3; ++c) graph->insertLocalIndices(static_cast<LO>(3 * n + c), Teuchos::ArrayView<const LO>(cols));
  }
  graph->fillComplete(owned_dofs_, owned_dofs_);
  graph_ = graph;
}

ElasticSystem::~ElasticSystem() = default;

double ElasticSystem::stiffness_scale() const {
  double s = 0.0;
  for (const auto& b : blocks_) s = std::max(s, b.law.mu_L + std::fabs(b.law.lambda_L));
  return s;
}

Teuchos::RCP<CrsMatrix> ElasticSystem::create_matrix() const { return Teuchos::rcp(new CrsMatrix(graph_)); }
Teuchos::RCP<Vector> ElasticSystem::create_vector() const { return Teuchos::rcp(new Vector(owned_dofs_)); }

void ElasticSystem::set_fixed_dofs(const std::vector<int>& overlap_dofs) {
  auto h = Kokkos::create_mirror_view(fixed_);
  Kokkos::deep_copy(h, 0);
  fixed_owned_.clear();
  any_fixed_ = !overlap_dofs.empty();
  const int n_owned_dofs = static_cast<int>(3 * mesh_.n_owned_nodes);
  for (int d : overlap_dofs) {
    if (d < 0 || static_cast<std::size_t>(d) >= h.extent(0)) throw std::out_of_range("set_fixed_dofs: bad DOF index");
    h(d) = 1;
  }
  for (int d = 0; d < n_owned_dofs; ++d)
    if (h(d)) fixed_owned_.push_back(d);
  Kokkos::deep_copy(fixed_, h);
}

std::size_t ElasticSystem::global_fixed_dofs() const {
  std::size_t local = fixed_owned_.size(), global = 0;
  Teuchos::reduceAll(*comm_, Teuchos::REDUCE_SUM, local, Teuchos::outArg(global));
  return global;
}

void ElasticSystem::set_body_force(const std::array<double, 3>& f) { body_ = f; }

EvaluationTotals ElasticSystem::evaluate(const Vector& u, Vector* force, CrsMatrix* K, Backend backend,
                                         std::optional<Projection> projection) const {
  return run(u, force, K, backend, projection, {});
}

void ElasticSystem::element_fields(const Vector& u, std::vector<double>& psi, std::vector<double>& J) const {
  ElementFields<detail::MemorySpace> fields{Kokkos::View<double*>("elem_psi", mesh_.n_owned_elements),
                                            Kokkos::View<double*>("elem_J", mesh_.n_owned_elements)};
  run(u, nullptr, nullptr, Backend::Default, std::nullopt, fields);
  auto ph = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), fields.psi);
  auto jh = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), fields.J);
  psi.assign(ph.data(), ph.data() + ph.extent(0));
  J.assign(jh.data(), jh.data() + jh.extent(0));
}

EvaluationTotals ElasticSystem::run(const Vector& u, Vector* force, CrsMatrix* K, Backend backend,
                                    std::optional<Projection> projection, ElementFields<detail::MemorySpace> fields) const {
  u_overlap_->doImport(u, *importer_, Tpetra::INSERT);
  if (force) force->putScalar(0.0);
  if (K) {
    K->resumeFill();
    K->setAllToScalar(0.0);
  }
  AssemblyTotals t;
  t.min_J = HUGE_VAL;
  {
    detail::AssemblyRequest r;
    r.geometry = element_geometry(mesh_, elements_);
    auto u_view = u_overlap_->getLocalViewDevice(Tpetra::Access::ReadOnly);
    r.u = Kokkos::subview(u_view, Kokkos::ALL(), 0);
    Kokkos::View<double**, Kokkos::LayoutLeft, Vector::device_type> f_view;
    if (force) {
      f_view = force->getLocalViewDevice(Tpetra::Access::ReadWrite);
      r.target.force = Kokkos::subview(f_view, Kokkos::ALL(), 0);
    }
    if (K) r.target.matrix = K->getLocalMatrixDevice();
    r.target.owned_dofs = static_cast<int>(3 * mesh_.n_owned_nodes);
    r.want_force = force != nullptr;
    r.want_matrix = K != nullptr;
    r.fields = fields;
    for (int i = 0; i < 3; ++i) r.body[i] = body_[i];
    const bool hex = mesh_.type == ElementType::Hex8;
    for (const Block& b : blocks_) {
      if (b.elements.extent(0) == 0) continue;
      const Projection p = projection.value_or(b.law.projection);
#if defined(KOKKOS_ENABLE_SERIAL) && defined(KOKKOS_ENABLE_OPENMP)
      if (backend == Backend::Serial) {
        t.add(hex ? detail::assemble_hex8<Kokkos::Serial>(b.law, p, b.elements, r)
                  : detail::assemble_tet4<Kokkos::Serial>(b.law, p, b.elements, r));
        continue;
      }
#endif
      (void)backend;
      t.add(hex ? detail::assemble_hex8<Kokkos::DefaultExecutionSpace>(b.law, p, b.elements, r)
                : detail::assemble_tet4<Kokkos::DefaultExecutionSpace>(b.law, p, b.elements, r));
    }
    Kokkos::fence();
  }
  eliminate_dirichlet(force, K);
  if (K) K->fillComplete(owned_dofs_, owned_dofs_);

  EvaluationTotals g;
  const double sums[2] = {t.energy, t.volume};
  double gsums[2];
  Teuchos::reduceAll(*comm_, Teuchos::REDUCE_SUM, 2, sums, gsums);
  g.energy = gsums[0];
  g.volume = gsums[1];
  Teuchos::reduceAll(*comm_, Teuchos::REDUCE_MIN, t.min_J, Teuchos::outArg(g.min_J));
  const long long counts[2] = {t.inverted, t.undefined};
  long long gcounts[2];
  Teuchos::reduceAll(*comm_, Teuchos::REDUCE_SUM, 2, counts, gcounts);
  g.inverted = gcounts[0];
  g.undefined = gcounts[1];
  return g;
}

void ElasticSystem::eliminate_dirichlet(Vector* force, CrsMatrix* K) const {
  // Ghost DOFs count too: a rank with no fixed row may still have fixed columns.
  if (!any_fixed_) return;
  const auto fixed = fixed_;
  const int rows = static_cast<int>(3 * mesh_.n_owned_nodes);
  if (force) {
    auto f = force->getLocalViewDevice(Tpetra::Access::ReadWrite);
    Kokkos::parallel_for(
        "sinew::dirichlet_force", Kokkos::RangePolicy<>(0, rows), KOKKOS_LAMBDA(const int r) {
          if (fixed(r)) f(r, 0) = 0.0;
        });
  }
  if (K) {
    const auto A = K->getLocalMatrixDevice();
    // Local column indices are overlap DOF indices (the graph's column map is the overlap map).
    Kokkos::parallel_for(
        "sinew::dirichlet_matrix", Kokkos::RangePolicy<>(0, rows), KOKKOS_LAMBDA(const int r) {
          const bool row_fixed = fixed(r) != 0;
          for (auto k = A.graph.row_map(r); k < A.graph.row_map(r + 1); ++k) {
            const int c = A.graph.entries(k);
            if ((row_fixed || fixed(c)) && c != r) A.values(k) = 0.0;
          }
        });
  }
  Kokkos::fence();
}

namespace {
// Host copy of the owned nodes' positions, X + u where u (owned DOFs) is given.
Kokkos::View<double**, Kokkos::HostSpace> owned_positions(const Mesh& mesh, const Vector* u) {
  auto Xh = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), mesh.X);
  Kokkos::View<double**, Kokkos::HostSpace> x("positions", mesh.n_owned_nodes, 3);
  for (std::size_t n = 0; n < mesh.n_owned_nodes; ++n)
    for (int d = 0; d < 3; ++d) x(n, d) = Xh(n, d);
  if (u) {
    auto uh = u->getLocalViewHost(Tpetra::Access::ReadOnly);
    for (std::size_t n = 0; n < mesh.n_owned_nodes; ++n)
      for (int d = 0; d < 3; ++d) x(n, d) += uh(3 * n + d, 0);
  }
  return x;
}
}  // namespace

void ElasticSystem::fill_coordinates(MultiVector& X, const Vector* u) const {
  const auto x = owned_positions(mesh_, u);
  auto v = X.getLocalViewHost(Tpetra::Access::OverwriteAll);
  for (std::size_t n = 0; n < mesh_.n_owned_nodes; ++n)
    for (int d = 0; d < 3; ++d) v(n, d) = x(n, d);
}

Teuchos::RCP<MultiVector> ElasticSystem::coordinates() const {
  auto X = Teuchos::rcp(new MultiVector(owned_nodes_, 3));
  fill_coordinates(*X, nullptr);
  return X;
}

void ElasticSystem::fill_rigid_body_modes(MultiVector& modes, const Vector* u) const {
  const auto xh = owned_positions(mesh_, u);
  double local[4] = {0, 0, 0, static_cast<double>(mesh_.n_owned_nodes)}, global[4];
  for (std::size_t n = 0; n < mesh_.n_owned_nodes; ++n)
    for (int d = 0; d < 3; ++d) local[d] += xh(n, d);
  Teuchos::reduceAll(*comm_, Teuchos::REDUCE_SUM, 4, local, global);
  const double c[3] = {global[0] / global[3], global[1] / global[3], global[2] / global[3]};
  auto v = modes.getLocalViewHost(Tpetra::Access::OverwriteAll);
  Kokkos::deep_copy(v, 0.0);
  for (std::size_t n = 0; n < mesh_.n_owned_nodes; ++n) {
    const double x = xh(n, 0) - c[0], y = xh(n, 1) - c[1], z = xh(n, 2) - c[2];
    for (int d = 0; d < 3; ++d) v(3 * n + d, d) = 1.0;  // translations
    // rotations omega x (x - c) about x, y, z
    v(3 * n + 1, 3) = -z;
    v(3 * n + 2, 3) = y;
    v(3 * n + 0, 4) = z;
    v(3 * n + 2, 4) = -x;
    v(3 * n + 0, 5) = -y;
    v(3 * n + 1, 5) = x;
  }
}

Teuchos::RCP<MultiVector> ElasticSystem::rigid_body_modes() const {
  auto modes = Teuchos::rcp(new MultiVector(owned_dofs_, 6));
  fill_rigid_body_modes(*modes, nullptr);
  return modes;
}

}  // namespace sinew
