// System: maps, the graph (element couplings plus the terms' extra couplings), the sum of the energy
// terms, the Dirichlet elimination, the reductions, nodal weights and MueLu's rigid-body modes.
#include <sinew/algebra/system.hpp>
#include <sinew/algebra/terms/elastic.hpp>
#include <sinew/algebra/terms/external_force.hpp>
#include <sinew/core/errors.hpp>
#include <sinew/core/memory.hpp>

#include <Teuchos_CommHelpers.hpp>
#include <Tpetra_CrsGraph.hpp>
#include <Tpetra_CrsMatrix.hpp>
#include <Tpetra_Import.hpp>
#include <Tpetra_MultiVector.hpp>
#include <Tpetra_Vector.hpp>

#include <algorithm>
#include <cstdlib>
#include <cmath>
#include <unordered_map>

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

System::System(Teuchos::RCP<const Teuchos::Comm<int>> comm, Mesh mesh, const MaterialAssignment& materials)
    : comm_(std::move(comm)), mesh_(std::move(mesh)) {
  trace_memory("mesh");
  // SINEW_STORE_GRADIENTS=1 stores dN/dX per point even for a voxel mesh, to compare with one
  // inverse Jacobian per element (docs/performance.md).
  const char* store = std::getenv("SINEW_STORE_GRADIENTS");
  elements_ = compute_element_data(mesh_, *comm_, store && std::atoi(store) != 0 ? GradientStorage::PerPoint : GradientStorage::Automatic);
  trace_memory("element data");
  elastic_ = std::make_shared<ElasticTerm>(mesh_, elements_, materials);
  // A law that no element takes is a mistake the user cannot see in the results: the group is empty,
  // or a region listed after it holds all its elements (the last region listed wins).
  std::vector<long long> mine = elastic_->owned_region_elements(), all(mine.size(), 0);
  if (!mine.empty()) Teuchos::reduceAll(*comm_, Teuchos::REDUCE_SUM, static_cast<int>(mine.size()), mine.data(), all.data());
  for (std::size_t k = 0; k < all.size(); ++k)
    if (all[k] == 0) {
      const std::string& name = materials.regions[k].first;
      std::string later;
      for (std::size_t j = k + 1; j < materials.regions.size(); ++j) later += (later.empty() ? "'" : ", '") + materials.regions[j].first + "'";
      throw InputError("Material/" + name + ": no element takes this law: the volume group '" + name + "' " +
                       (later.empty() ? std::string("has no element")
                                      : "has no element, or each of its elements is also in a region listed after it (" + later +
                                            "), and an element takes the law of the last region listed that holds it"));
    }
  const std::size_t n_owned = mesh_.n_owned_nodes, n_local = mesh_.local_nodes();
  std::vector<GO> owned_node_gids(mesh_.node_gid.begin(), mesh_.node_gid.begin() + n_owned);
  owned_nodes_ = make_map(owned_node_gids, comm_);
  owned_dofs_ = make_map(dof_gids(mesh_.node_gid, n_owned), comm_);
  overlap_dofs_ = make_map(dof_gids(mesh_.node_gid, n_local), comm_);
  fixed_ = Kokkos::View<char*>("fixed", 3 * n_local);
  build_graph();
  trace_memory("maps and graph");
  compute_nodal_weights();
  external_ = std::make_shared<ExternalForceTerm>(nodal_volume_, nodal_mass_);
  terms_ = {elastic_, external_};
}

System::~System() = default;

const MaterialSpec& System::material() const { return elastic_->default_law(); }
double System::stiffness_scale() const { return elastic_->stiffness_scale(); }

void System::compute_nodal_weights() {
  // V_a = sum_e sum_q w_q N_a(xi_q) over the elements around owned node a (all on this rank), the
  // quadrature the element kernel uses; m_a the same weighted by the element's density.
  const std::size_t n_owned = mesh_.n_owned_nodes;
  nodal_volume_.assign(n_owned, 0.0);
  nodal_mass_.assign(n_owned, 0.0);
  auto conn = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), mesh_.conn);
  auto w = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), elements_.wdetJ);
  auto Xh = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), mesh_.X);
  const std::vector<double> rho = elastic_->element_density();
  const bool hex = mesh_.type == ElementType::Hex8;
  const int npe = nodes_per_element(mesh_.type), nqp = elements_.nqp;
  double local_volume = 0.0, edge_sum = 0.0;
  long long edges = 0;
  for (std::size_t e = 0; e < mesh_.local_elements(); ++e) {
    for (int q = 0; q < nqp; ++q) {
      double N[8];
      if (hex)
        Hex8::values(q, N);
      else
        Tet4::values(q, N);
      const double wq = w(e * nqp + q);
      if (e < mesh_.n_owned_elements) local_volume += wq;
      for (int a = 0; a < npe; ++a) {
        const int n = conn(e, a);
        if (static_cast<std::size_t>(n) >= n_owned) continue;
        nodal_volume_[n] += wq * N[a];
        nodal_mass_[n] += rho[e] * wq * N[a];
      }
    }
    if (e >= mesh_.n_owned_elements) continue;
    // Edges from node 0 to the others that share an edge with it (hex: 1, 3, 4; tet: all).
    for (int b : hex ? std::vector<int>{1, 3, 4} : std::vector<int>{1, 2, 3}) {
      double d2 = 0.0;
      for (int c = 0; c < 3; ++c) d2 += std::pow(Xh(conn(e, b), c) - Xh(conn(e, 0), c), 2);
      edge_sum += std::sqrt(d2);
      ++edges;
    }
  }
  Teuchos::reduceAll(*comm_, Teuchos::REDUCE_SUM, local_volume, Teuchos::outArg(reference_volume_));
  double gsum = 0.0;
  long long gcount = 0;
  Teuchos::reduceAll(*comm_, Teuchos::REDUCE_SUM, edge_sum, Teuchos::outArg(gsum));
  Teuchos::reduceAll(*comm_, Teuchos::REDUCE_SUM, edges, Teuchos::outArg(gcount));
  cell_size_ = gcount > 0 ? gsum / gcount : 0.0;
}

void System::build_graph() {
  // Each owned node couples to every node of every element around it (all of which are on this rank,
  // owned or ghost), and to the extra nodes terms asked for. The column map is the overlap map followed
  // by the extra columns: local column index = overlap DOF index for mesh nodes, which is what the
  // element kernels scatter with and what the Dirichlet elimination reads.
  const std::size_t n_owned = mesh_.n_owned_nodes, n_local = mesh_.local_nodes();
  auto conn = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), mesh_.conn);
  const int npe = nodes_per_element(mesh_.type);
  std::unordered_map<GlobalId, int> local_of;
  for (std::size_t n = 0; n < n_local; ++n) local_of[mesh_.node_gid[n]] = static_cast<int>(n);
  // Extra column nodes that are not local mesh nodes get column slots after the overlap.
  std::vector<GlobalId> extra_nodes;
  for (const auto& [row, col] : extra_)
    if (!local_of.count(col)) extra_nodes.push_back(col);
  std::sort(extra_nodes.begin(), extra_nodes.end());
  extra_nodes.erase(std::unique(extra_nodes.begin(), extra_nodes.end()), extra_nodes.end());
  std::unordered_map<GlobalId, int> column_of(local_of);
  for (std::size_t k = 0; k < extra_nodes.size(); ++k) column_of[extra_nodes[k]] = static_cast<int>(n_local + k);

  std::vector<std::vector<int>> neighbours(n_owned);
  for (std::size_t e = 0; e < mesh_.local_elements(); ++e)
    for (int a = 0; a < npe; ++a) {
      const int na = conn(e, a);
      if (static_cast<std::size_t>(na) >= n_owned) continue;
      for (int b = 0; b < npe; ++b) neighbours[na].push_back(conn(e, b));
    }
  for (const auto& [row, col] : extra_) {
    const auto it = local_of.find(row);
    if (it == local_of.end() || static_cast<std::size_t>(it->second) >= n_owned) continue;
    neighbours[it->second].push_back(column_of.at(col));
  }
  std::vector<std::size_t> counts(3 * n_owned);
  for (std::size_t n = 0; n < n_owned; ++n) {
    auto& nb = neighbours[n];
    std::sort(nb.begin(), nb.end());
    nb.erase(std::unique(nb.begin(), nb.end()), nb.end());
    for (int c = 0; c < 3; ++c) counts[3 * n + c] = 3 * nb.size();
  }
  std::vector<GO> col_gids = dof_gids(mesh_.node_gid, n_local);
  for (GlobalId g : extra_nodes)
    for (int c = 0; c < 3; ++c) col_gids.push_back(3 * static_cast<GO>(g) + c);
  // Map construction is collective: every rank makes one, with extras or without.
  column_dofs_ = pattern_version_ == 0 ? overlap_dofs_ : make_map(col_gids, comm_);
  auto graph = Teuchos::rcp(new CrsGraph(owned_dofs_, column_dofs_, Teuchos::ArrayView<const std::size_t>(counts)));
  std::vector<LO> cols;
  for (std::size_t n = 0; n < n_owned; ++n) {
    cols.clear();
    for (int m : neighbours[n])
      for (int c = 0; c < 3; ++c) cols.push_back(3 * m + c);
    for (int c = 0; c < 3; ++c) graph->insertLocalIndices(static_cast<LO>(3 * n + c), Teuchos::ArrayView<const LO>(cols));
  }
  graph->fillComplete(owned_dofs_, owned_dofs_);
  graph_ = graph;
  if (mesh_graph_.is_null()) mesh_graph_ = graph;
  column_importer_ = Teuchos::rcp(new Import(owned_dofs_, column_dofs_));
  u_columns_ = Teuchos::rcp(new Vector(column_dofs_));
  if (fixed_.extent(0) != col_gids.size()) {
    Kokkos::View<char*> grown("fixed", col_gids.size());
    Kokkos::deep_copy(Kokkos::subview(grown, std::make_pair<std::size_t, std::size_t>(0, 3 * n_local)),
                      Kokkos::subview(fixed_, std::make_pair<std::size_t, std::size_t>(0, 3 * n_local)));
    fixed_ = grown;
  }
  refresh_fixed_columns();
  ++pattern_version_;
}

void System::add_term(std::shared_ptr<EnergyTerm> term) {
  for (const auto& t : terms_)
    if (std::string(t->name()) == term->name())
      throw std::logic_error(std::string("System::add_term: a second term named '") + term->name() + "'");
  term->columns_changed(*column_dofs_);
  terms_.push_back(std::move(term));
}

void System::set_load(double t) {
  for (const auto& term : terms_) term->set_load(t);
}

void System::begin_step(const StepStart& s) {
  for (const auto& term : terms_) term->begin_step(s);
}

System::Round System::round(const Vector& u, int round) {
  Round r;
  for (const auto& term : terms_) {
    RoundResult t = term->round(u, round);
    r.again = r.again || t.again;
    if (!t.line.empty()) r.lines.push_back(std::move(t.line));
  }
  r.pattern_changed = update_pattern();
  return r;
}

System::Round System::regroup(const Vector& u) {
  Round r;
  for (const auto& term : terms_) {
    std::string line = term->regroup(u);
    if (line.empty()) continue;
    r.again = true;
    r.lines.push_back(std::move(line));
  }
  r.pattern_changed = update_pattern();
  return r;
}

bool System::regroups() const {
  return std::any_of(terms_.begin(), terms_.end(), [](const auto& t) { return t->regroups(); });
}

void System::end_step(const Vector& u) {
  for (const auto& term : terms_) term->end_step(u);
}

void System::abandon_step() {
  for (const auto& term : terms_) term->abandon_step();
}

std::vector<std::pair<std::string, TermState>> System::save_states() const {
  std::vector<std::pair<std::string, TermState>> out;
  for (const auto& term : terms_) {
    TermState s;
    term->save_state(s);
    if (!s.shared.empty() || !s.nodal.empty()) out.emplace_back(term->name(), std::move(s));
  }
  return out;
}

void System::load_states(const std::vector<std::pair<std::string, TermState>>& states) {
  for (const auto& term : terms_)
    for (const auto& [name, state] : states)
      if (name == term->name()) term->load_state(state);
  update_pattern();  // the couplings the restored state needs (contact springs)
}

bool System::linearisable() const {
  return std::all_of(terms_.begin(), terms_.end(), [](const auto& t) { return t->linearisable(); });
}

bool System::projects_hessians() const {
  return std::any_of(terms_.begin(), terms_.end(), [](const auto& t) { return t->projects_hessian(); });
}

bool System::limits_steps() const {
  return std::any_of(terms_.begin(), terms_.end(), [](const auto& t) { return t->limits_steps(); });
}

double System::step_limit(const Vector& u, const Vector& du, double t_max) const {
  double t = t_max;
  for (const auto& term : terms_)
    if (term->limits_steps()) t = std::min(t, term->step_limit(u, du, t_max));
  return t;
}

double System::admit_guess(const Vector& u, Vector& guess) const {
  if (!limits_steps()) return 1.0;
  // The terms' own pull-backs first, a few passes (a vertex pulled back can be met by a neighbour that
  // was not), then the whole guess when the path still crosses.
  auto d = create_vector();
  double t = 1.0;
  for (int pass = 0; pass < 4; ++pass) {
    for (const auto& term : terms_)
      if (term->limits_steps()) term->admit_guess(u, guess);
    d->update(1.0, guess, -1.0, u, 0.0);
    t = step_limit(u, *d, 1.0);
    if (t >= 1.0) return 1.0;
  }
  // The free DOFs at 0.9 of the way; where the prescribed ones still cross on that path (a bone that
  // holds surface nodes), the free ones at the last state: the least a guess can then do.
  const std::vector<char> fixed = fixed_owned_mask();
  auto pulled = [&](double taken) {
    auto out = create_vector();
    out->assign(guess);
    auto g = out->getLocalViewHost(Tpetra::Access::ReadWrite);
    auto u0 = u.getLocalViewHost(Tpetra::Access::ReadOnly);
    for (std::size_t i = 0; i < g.extent(0); ++i)
      if (!fixed[i]) g(i, 0) = u0(i, 0) + taken * (g(i, 0) - u0(i, 0));
    return out;
  };
  double taken = 0.9 * t;
  auto candidate = pulled(taken);
  d->update(1.0, *candidate, -1.0, u, 0.0);
  if (step_limit(u, *d, 1.0) < 1.0) {
    taken = 0.0;
    candidate = pulled(taken);
  }
  guess.assign(*candidate);
  return taken;
}

bool System::load_acceleration(Vector& a) const {
  a.putScalar(0.0);
  bool any = false;
  for (const auto& term : terms_) any = term->add_load_acceleration(a) || any;
  return any;
}

std::vector<std::string> System::log_columns() const {
  std::vector<std::string> c;
  for (const auto& term : terms_) {
    c.push_back(std::string(term->name()) + "_energy");
    for (auto& own : term->log_columns()) c.push_back(std::move(own));
  }
  return c;
}

std::vector<double> System::log_values(const EvaluationTotals& totals) const {
  std::vector<double> v;
  for (const auto& term : terms_) {
    v.push_back(totals.share(term->name()));
    const std::vector<double> own = term->log_values(totals);
    if (own.size() != term->log_columns().size())
      throw std::logic_error(std::string("System::log_values: term '") + term->name() + "' gave values not matching its columns");
    v.insert(v.end(), own.begin(), own.end());
  }
  return v;
}

std::vector<std::string> System::summary(const EvaluationTotals& totals) const {
  std::vector<std::string> lines;
  for (const auto& term : terms_)
    for (auto& line : term->summary(totals)) lines.push_back(std::move(line));
  return lines;
}

std::vector<std::pair<std::string, int>> System::node_field_names() const {
  std::vector<std::pair<std::string, int>> names;
  for (const auto& term : terms_)
    for (auto& n : term->node_field_names()) names.push_back(std::move(n));
  return names;
}

std::vector<TermState::Nodal> System::node_fields(const Vector& u) const {
  std::vector<TermState::Nodal> fields;
  if (node_field_names().empty()) return fields;
  evaluate(u, nullptr, nullptr);  // the fields of this state (a contact pressure)
  for (const auto& term : terms_) term->node_fields(fields);
  return fields;
}

std::vector<TermState::Nodal> System::term_element_fields() const {
  std::vector<TermState::Nodal> fields;
  for (const auto& term : terms_) term->element_fields(fields);
  return fields;
}

bool System::update_pattern() {
  std::vector<std::pair<GlobalId, GlobalId>> wanted;
  for (const auto& t : terms_) t->couplings(wanted);
  std::size_t before = extra_.size();
  for (const auto& p : wanted) extra_.insert(p);
  int grew = extra_.size() > before ? 1 : 0, any = 0;
  Teuchos::reduceAll(*comm_, Teuchos::REDUCE_MAX, grew, Teuchos::outArg(any));
  if (!any) return false;
  build_graph();
  for (const auto& t : terms_) t->columns_changed(*column_dofs_);
  return true;
}

Teuchos::RCP<CrsMatrix> System::create_matrix() const { return Teuchos::rcp(new CrsMatrix(graph_)); }
Teuchos::RCP<CrsMatrix> System::create_mesh_matrix() const { return Teuchos::rcp(new CrsMatrix(mesh_graph_)); }

Teuchos::RCP<CrsMatrix> System::mass_matrix(bool lumped) const {
  auto M = create_mesh_matrix();
  M->resumeFill();
  M->setAllToScalar(0.0);
  auto local = M->getLocalMatrixHost();
  const std::size_t n_owned = mesh_.n_owned_nodes;
  if (lumped) {
    for (std::size_t n = 0; n < n_owned; ++n)
      for (int c = 0; c < 3; ++c) {
        const LO row = static_cast<LO>(3 * n + c);
        local.sumIntoValues(row, &row, 1, &nodal_mass_[n]);
      }
  } else {
    auto conn = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), mesh_.conn);
    auto w = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), elements_.wdetJ);
    const std::vector<double> rho = elastic_->element_density();
    const bool hex = mesh_.type == ElementType::Hex8;
    const int npe = nodes_per_element(mesh_.type), nqp = elements_.nqp;
    for (std::size_t e = 0; e < mesh_.local_elements(); ++e) {
      double Me[8][8] = {};
      if (hex) {
        for (int q = 0; q < nqp; ++q) {
          double N[8];
          Hex8::values(q, N);
          for (int a = 0; a < 8; ++a)
            for (int b = 0; b < 8; ++b) Me[a][b] += rho[e] * w(e * nqp + q) * N[a] * N[b];
        }
      } else {  // linear tet: int N_a N_b = V (1 + delta_ab) / 20, exactly
        const double V = w(e);
        for (int a = 0; a < 4; ++a)
          for (int b = 0; b < 4; ++b) Me[a][b] = rho[e] * V * (a == b ? 2.0 : 1.0) / 20.0;
      }
      for (int a = 0; a < npe; ++a) {
        const int na = conn(e, a);
        if (static_cast<std::size_t>(na) >= n_owned) continue;
        for (int c = 0; c < 3; ++c) {
          LO cols[8];
          double vals[8];
          for (int b = 0; b < npe; ++b) {
            cols[b] = static_cast<LO>(3 * conn(e, b) + c);
            vals[b] = Me[a][b];
          }
          local.sumIntoValues(static_cast<LO>(3 * na + c), cols, npe, vals);
        }
      }
    }
  }
  M->fillComplete(owned_dofs_, owned_dofs_);
  return M;
}

void System::elastic_hessian(const Vector& u, CrsMatrix& K) const {
  if (K.getCrsGraph().get() != mesh_graph_.get()) throw std::logic_error("System::elastic_hessian: K must be on the mesh graph");
  run(u, nullptr, &K, Backend::Default, std::nullopt, {}, elastic_.get(), true);
}
Teuchos::RCP<Vector> System::create_vector() const { return Teuchos::rcp(new Vector(owned_dofs_)); }

void System::set_fixed_dofs(const std::vector<int>& overlap_dofs) {
  auto h = Kokkos::create_mirror_view(fixed_);
  Kokkos::deep_copy(h, 0);
  fixed_owned_.clear();
  any_fixed_ = !overlap_dofs.empty();
  const int n_owned_dofs = static_cast<int>(3 * mesh_.n_owned_nodes);
  const std::size_t n_overlap = 3 * mesh_.local_nodes();
  for (int d : overlap_dofs) {
    if (d < 0 || static_cast<std::size_t>(d) >= n_overlap) throw std::out_of_range("set_fixed_dofs: bad DOF index");
    h(d) = 1;
  }
  for (int d = 0; d < n_owned_dofs; ++d)
    if (h(d)) fixed_owned_.push_back(d);
  Kokkos::deep_copy(fixed_, h);
  refresh_fixed_columns();
}

std::vector<char> System::fixed_owned_mask() const {
  std::vector<char> mask(3 * mesh_.n_owned_nodes, 0);
  for (int d : fixed_owned_) mask[static_cast<std::size_t>(d)] = 1;
  return mask;
}

void System::refresh_fixed_columns() {
  // Columns past the overlap belong to nodes of other ranks' meshes: ask their owners. Collective.
  const std::size_t n_overlap = 3 * mesh_.local_nodes();
  const std::size_t n_columns = column_dofs_->getNodeNumElements();
  int extra = n_columns > n_overlap ? 1 : 0, any_extra = 0;
  Teuchos::reduceAll(*comm_, Teuchos::REDUCE_MAX, extra, Teuchos::outArg(any_extra));
  if (!any_extra) return;
  Vector owned(owned_dofs_), columns(column_dofs_);
  {
    auto v = owned.getLocalViewHost(Tpetra::Access::OverwriteAll);
    for (std::size_t d = 0; d < v.extent(0); ++d) v(d, 0) = 0.0;
    for (int d : fixed_owned_) v(d, 0) = 1.0;
  }
  columns.doImport(owned, *column_importer_, Tpetra::INSERT);
  auto c = columns.getLocalViewHost(Tpetra::Access::ReadOnly);
  auto h = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), fixed_);
  for (std::size_t d = n_overlap; d < n_columns; ++d) {
    h(d) = c(d, 0) != 0.0 ? 1 : 0;
    if (h(d)) any_fixed_ = true;
  }
  Kokkos::deep_copy(fixed_, h);
}

std::size_t System::global_fixed_dofs() const {
  std::size_t local = fixed_owned_.size(), global = 0;
  Teuchos::reduceAll(*comm_, Teuchos::REDUCE_SUM, local, Teuchos::outArg(global));
  return global;
}

void System::set_body_force(const std::array<double, 3>& f) { external_->set_body_force(f); }
void System::set_gravity(const std::array<double, 3>& g) { external_->set_gravity(g); }
void System::set_external_loads(const std::array<double, 3>& f, const std::array<double, 3>& g, bool ramped) {
  external_->set_full(f, g, ramped);
}

EvaluationTotals System::evaluate(const Vector& u, Vector* force, CrsMatrix* K, Backend backend,
                                  std::optional<Projection> projection, bool exact_terms) const {
  return run(u, force, K, backend, projection, {}, nullptr, true, exact_terms);
}

EvaluationTotals System::evaluate_lifted(const Vector& u, const Vector& d, Vector& force, CrsMatrix& K,
                                         std::optional<Projection> projection, bool exact_terms) const {
  const EvaluationTotals t = run(u, &force, &K, Backend::Default, projection, {}, nullptr, false, exact_terms);
  // K still couples the prescribed DOFs here: f + K d is the force linearised along the increment.
  K.apply(d, force, Teuchos::NO_TRANS, 1.0, 1.0);
  K.resumeFill();
  eliminate_dirichlet(&force, &K);
  K.fillComplete(owned_dofs_, owned_dofs_);
  return t;
}

void System::element_fields(const Vector& u, std::vector<double>& psi, std::vector<double>& J) const {
  ElementFields<DeviceMemory> fields{Kokkos::View<double*>("elem_psi", mesh_.n_owned_elements),
                                     Kokkos::View<double*>("elem_J", mesh_.n_owned_elements)};
  run(u, nullptr, nullptr, Backend::Default, std::nullopt, fields);
  auto ph = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), fields.psi);
  auto jh = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), fields.J);
  psi.assign(ph.data(), ph.data() + ph.extent(0));
  J.assign(jh.data(), jh.data() + jh.extent(0));
}

NodeRelaxationTotals System::relax_nodes(Vector& u, const Vector& force, double share, int rings,
                                         const NodeRelaxationSettings& settings) const {
  NodeRelaxationTotals done;
  // Inertia is not linear in a node's displacement, nor is contact at its springs' nodes: their share of
  // the gradient cannot be frozen there. The external-force term's can (it is linear). Each term says
  // which it is, and which nodes it holds.
  const std::size_t n_owned = mesh_.n_owned_nodes, n_local = mesh_.local_nodes();
  std::vector<char> held(n_local, 0);
  const bool allowed = std::all_of(terms_.begin(), terms_.end(), [&](const auto& t) { return t->allows_node_relaxation(held); });
  if (!allowed || !(share > 0.0) || !Kokkos::SpaceAccessibility<Kokkos::HostSpace, DeviceMemory>::accessible)
    return done;
  const double f2 = force.norm2() * force.norm2();
  if (!(f2 > 0.0) || !std::isfinite(f2)) return done;
  auto f = force.getLocalViewHost(Tpetra::Access::ReadOnly);
  auto fixed = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), fixed_);
  auto free_node = [&](std::size_t n) {
    return n < n_owned && !held[n] && !fixed(3 * n) && !fixed(3 * n + 1) && !fixed(3 * n + 2);
  };
  auto force2 = [&](std::size_t n) { return f(3 * n, 0) * f(3 * n, 0) + f(3 * n + 1, 0) * f(3 * n + 1, 0) + f(3 * n + 2, 0) * f(3 * n + 2, 0); };
  std::vector<int> nodes;
  std::vector<char> picked(n_local, 0);
  for (std::size_t n = 0; n < n_owned; ++n)
    if (free_node(n) && force2(n) >= share * f2) {
      nodes.push_back(static_cast<int>(n));
      picked[n] = 1;
    }
  int mine = nodes.empty() ? 0 : 1, any = 0;
  Teuchos::reduceAll(*comm_, Teuchos::REDUCE_MAX, mine, Teuchos::outArg(any));
  if (!any) return done;
  // The largest forces first, then the rings around them (their neighbours take up what they shed).
  std::sort(nodes.begin(), nodes.end(), [&](int a, int b) { return force2(a) > force2(b); });
  const int npe = nodes_per_element(mesh_.type);
  for (int r = 0; r < rings; ++r) {
    std::vector<int> ring;
    for (std::size_t e = 0; e < mesh_.local_elements(); ++e) {
      bool touches = false;
      for (int a = 0; a < npe && !touches; ++a) touches = picked[mesh_.conn(e, a)] == 1;
      if (!touches) continue;
      for (int a = 0; a < npe; ++a) {
        const int m = mesh_.conn(e, a);
        if (!picked[m] && free_node(m)) {
          picked[m] = 2;
          ring.push_back(m);
        }
      }
    }
    for (int m : ring) picked[m] = 1;
    nodes.insert(nodes.end(), ring.begin(), ring.end());
  }
  u_columns_->doImport(u, *column_importer_, Tpetra::INSERT);
  std::vector<double> local(3 * n_local);
  {
    auto c = u_columns_->getLocalViewHost(Tpetra::Access::ReadOnly);
    for (std::size_t d = 0; d < 3 * n_local; ++d) local[d] = c(d, 0);
  }
  std::vector<double> rows(3 * nodes.size());
  for (std::size_t k = 0; k < nodes.size(); ++k)
    for (int i = 0; i < 3; ++i) rows[3 * k + i] = f(3 * nodes[k] + i, 0);
  if (!nodes.empty()) done = elastic_->relax(local, nodes, rows, settings);
  {
    auto v = u.getLocalViewHost(Tpetra::Access::ReadWrite);
    for (int n : nodes)
      for (int i = 0; i < 3; ++i) v(3 * n + i, 0) = local[3 * n + i];
  }
  const long long counts[2] = {done.nodes, done.iterations};
  long long gcounts[2];
  Teuchos::reduceAll(*comm_, Teuchos::REDUCE_SUM, 2, counts, gcounts);
  double decrease = 0.0;
  Teuchos::reduceAll(*comm_, Teuchos::REDUCE_SUM, done.decrease, Teuchos::outArg(decrease));
  return NodeRelaxationTotals{gcounts[0], gcounts[1], decrease};
}

void System::gradient(const Vector& u, Vector& force, const EnergyTerm* only) const {
  run(u, &force, nullptr, Backend::Default, std::nullopt, {}, only, false);
}

EvaluationTotals System::run(const Vector& u, Vector* force, CrsMatrix* K, Backend backend, std::optional<Projection> projection,
                             ElementFields<DeviceMemory> fields, const EnergyTerm* only, bool eliminate,
                             bool exact_terms) const {
  if (K && K->getCrsGraph().get() != graph_.get() && !(only == elastic_.get() && K->getCrsGraph().get() == mesh_graph_.get()))
    throw std::logic_error("System::evaluate: the matrix was made before the pattern changed (create_matrix again)");
  u_columns_->doImport(u, *column_importer_, Tpetra::INSERT);
  if (force) force->putScalar(0.0);
  if (K) {
    K->resumeFill();
    K->setAllToScalar(0.0);
  }
  TermOutput out;
  out.totals.min_J = HUGE_VAL;
  std::vector<std::pair<const char*, double>> shares;
  {
    TermInput in;
    auto u_view = u_columns_->getLocalViewDevice(Tpetra::Access::ReadOnly);
    in.u = Kokkos::subview(u_view, Kokkos::ALL(), 0);
    in.want_force = force != nullptr;
    in.want_matrix = K != nullptr;
    in.backend = backend;
    in.projection = projection;
    in.exact_terms = exact_terms;
    Kokkos::View<double**, Kokkos::LayoutLeft, Vector::device_type> f_view;
    if (force) {
      f_view = force->getLocalViewDevice(Tpetra::Access::ReadWrite);
      out.force = Kokkos::subview(f_view, Kokkos::ALL(), 0);
    }
    if (K) out.matrix = K->getLocalMatrixDevice();
    out.owned_dofs = static_cast<int>(3 * mesh_.n_owned_nodes);
    out.fields = fields;
    shares.reserve(terms_.size());
    for (const auto& term : terms_) {
      if (only && term.get() != only) continue;
      out.energy = 0.0;
      term->add(in, out);
      shares.emplace_back(term->name(), out.energy);
    }
    Kokkos::fence();
  }
  if (eliminate) eliminate_dirichlet(force, K);
  if (K) K->fillComplete(owned_dofs_, owned_dofs_);

  const EvaluationTotals& t = out.totals;
  EvaluationTotals g;
  // One sum over ranks for the volume and each term's share (every rank has the same terms).
  // The total summed locally first, as the terms add up, then over ranks.
  double local_energy = 0.0;
  for (const auto& share : shares) local_energy += share.second;
  std::vector<double> sums{local_energy, t.volume}, gsums(shares.size() + 2);
  for (const auto& share : shares) sums.push_back(share.second);
  Teuchos::reduceAll(*comm_, Teuchos::REDUCE_SUM, static_cast<int>(sums.size()), sums.data(), gsums.data());
  g.energy = gsums[0];
  g.volume = gsums[1];
  g.shares = std::move(shares);
  for (std::size_t k = 0; k < g.shares.size(); ++k) g.shares[k].second = gsums[k + 2];
  Teuchos::reduceAll(*comm_, Teuchos::REDUCE_MIN, t.min_J, Teuchos::outArg(g.min_J));
  Teuchos::reduceAll(*comm_, Teuchos::REDUCE_MAX, t.penetration, Teuchos::outArg(g.penetration));
  const long long counts[3] = {t.inverted, t.undefined, t.contacts};
  long long gcounts[3];
  Teuchos::reduceAll(*comm_, Teuchos::REDUCE_SUM, 3, counts, gcounts);
  g.inverted = gcounts[0];
  g.undefined = gcounts[1];
  g.contacts = gcounts[2];
  return g;
}

void System::eliminate_dirichlet(Vector* force, CrsMatrix* K) const {
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
    // Local column indices are column-map indices (overlap DOFs first), which fixed_ covers.
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

void System::fill_coordinates(MultiVector& X, const Vector* u) const {
  const auto x = owned_positions(mesh_, u);
  auto v = X.getLocalViewHost(Tpetra::Access::OverwriteAll);
  for (std::size_t n = 0; n < mesh_.n_owned_nodes; ++n)
    for (int d = 0; d < 3; ++d) v(n, d) = x(n, d);
}

Teuchos::RCP<MultiVector> System::coordinates() const {
  auto X = Teuchos::rcp(new MultiVector(owned_nodes_, 3));
  fill_coordinates(*X, nullptr);
  return X;
}

void System::fill_rigid_body_modes(MultiVector& modes, const Vector* u) const {
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

Teuchos::RCP<MultiVector> System::rigid_body_modes() const {
  auto modes = Teuchos::rcp(new MultiVector(owned_dofs_, 6));
  fill_rigid_body_modes(*modes, nullptr);
  return modes;
}

}  // namespace sinew
