// distribute_mesh: scatter from rank 0, Zoltan2 multi-jagged on element centroids, migration, node
// ownership by a directory, ghost elements, node data. The only translation unit with Zoltan2 headers.
#include <sinew/core/errors.hpp>
#include <sinew/discretization/partition.hpp>

#include <sinew/core/collective.hpp>

#include <Teuchos_DefaultMpiComm.hpp>
#include <Zoltan2_BasicVectorAdapter.hpp>
#include <Zoltan2_PartitioningProblem.hpp>

#include <algorithm>
#include <numeric>

namespace sinew {

namespace {


// One element in transit: global id, file tag, volume group and its nodes' global ids.
struct ElementRecord {
  GlobalId gid;
  long long tag;
  int group;
  int pad;
  GlobalId nodes[8];
};

// What the directory knows of a node: coordinates, file tag, node groups (a bit per group, up to 256).
constexpr int kGroupWords = 4;
struct NodeRecord {
  double x[3];
  long long tag;
  std::uint64_t groups[kGroupWords];
};

// The directory rank of a node id: nodes are split in P contiguous blocks.
int directory(GlobalId n, GlobalId N, int P) {
  int r = static_cast<int>((static_cast<__int128>(n) * P) / std::max<GlobalId>(N, 1));
  while (r > 0 && n < static_cast<GlobalId>((static_cast<__int128>(r) * N) / P)) --r;
  while (r + 1 < P && n >= static_cast<GlobalId>((static_cast<__int128>(r + 1) * N) / P)) ++r;
  return r;
}
GlobalId block_begin(int r, GlobalId N, int P) { return static_cast<GlobalId>((static_cast<__int128>(r) * N) / P); }

// Scalars and names every rank needs before the data moves.
struct Header {
  int type = 0, npe = 0;
  GlobalId nodes = 0, elements = 0;
  long long reoriented = 0;
  std::vector<std::string> element_groups, node_groups;
  std::string source;
};

void broadcast_header(Header& h, MPI_Comm comm) {
  long long v[5] = {h.type, h.npe, h.nodes, h.elements, h.reoriented};
  MPI_Bcast(v, 5, MPI_LONG_LONG, 0, comm);
  h.type = static_cast<int>(v[0]);
  h.npe = static_cast<int>(v[1]);
  h.nodes = v[2];
  h.elements = v[3];
  h.reoriented = v[4];
  auto strings = [&](std::vector<std::string>& list) {
    int n = static_cast<int>(list.size());
    MPI_Bcast(&n, 1, MPI_INT, 0, comm);
    list.resize(n);
    for (auto& s : list) {
      int len = static_cast<int>(s.size());
      MPI_Bcast(&len, 1, MPI_INT, 0, comm);
      s.resize(len);
      MPI_Bcast(s.data(), len, MPI_CHAR, 0, comm);
    }
  };
  strings(h.element_groups);
  strings(h.node_groups);
  std::vector<std::string> src{h.source};
  strings(src);
  h.source = src[0];
}

}  // namespace

Mesh distribute_mesh(MeshFile&& file, const Teuchos::Comm<int>& tcomm) {
  MPI_Comm comm = raw_comm(tcomm);
  int me = 0, P = 1;
  MPI_Comm_rank(comm, &me);
  MPI_Comm_size(comm, &P);
  Header h;
  if (me == 0) {
    h.type = static_cast<int>(file.type);
    h.npe = nodes_per_element(file.type);
    h.nodes = static_cast<GlobalId>(file.nodes());
    h.elements = static_cast<GlobalId>(file.elements());
    h.reoriented = file.reoriented;
    h.element_groups = file.element_group_names;
    h.node_groups = file.node_group_names;
    h.source = file.format + " " + file.path;
    if (h.node_groups.size() > 64 * kGroupWords)
      throw InputError(file.path + ": more than " + std::to_string(64 * kGroupWords) + " node groups", InputErrorKind::BadMesh);
  }
  broadcast_header(h, comm);
  const int npe = h.npe;
  if (h.elements < P)
    throw InputError("Mesh: " + std::to_string(h.elements) + " elements cannot be split over " + std::to_string(P) + " ranks",
                     InputErrorKind::BadMesh);

  // 1. Rank 0 sends blocks of elements (file order) and of node data (by node id) to every rank.
  std::vector<ElementRecord> mine;  // elements this rank holds (first its block, then its partition)
  std::vector<double> centroid;     // 3 per element of the block
  std::vector<NodeRecord> dir;      // this rank's block of the node directory
  {
    std::vector<std::vector<ElementRecord>> send_e(P);
    std::vector<std::vector<double>> send_c(P);
    std::vector<std::vector<NodeRecord>> send_n(P);
    if (me == 0) {
      for (int r = 0; r < P; ++r) {
        const GlobalId e0 = block_begin(r, h.elements, P), e1 = block_begin(r + 1, h.elements, P);
        for (GlobalId e = e0; e < e1; ++e) {
          ElementRecord rec{e, file.element_tag[e], file.element_group[e], 0, {}};
          double c[3] = {0.0, 0.0, 0.0};
          for (int a = 0; a < npe; ++a) {
            const int n = file.conn[npe * e + a];
            rec.nodes[a] = n;
            for (int d = 0; d < 3; ++d) c[d] += file.xyz[3 * static_cast<std::size_t>(n) + d] / npe;
          }
          send_e[r].push_back(rec);
          send_c[r].insert(send_c[r].end(), c, c + 3);
        }
      }
      std::vector<NodeRecord> all(file.nodes());
      for (std::size_t n = 0; n < file.nodes(); ++n) {
        NodeRecord& rec = all[n];
        for (int d = 0; d < 3; ++d) rec.x[d] = file.xyz[3 * n + d];
        rec.tag = file.node_tag[n];
        for (auto& w : rec.groups) w = 0;
      }
      for (std::size_t g = 0; g < file.node_group_nodes.size(); ++g)
        for (int n : file.node_group_nodes[g]) all[n].groups[g / 64] |= std::uint64_t(1) << (g % 64);
      file = MeshFile();  // rank 0 no longer needs the whole mesh
      for (int r = 0; r < P; ++r)
        send_n[r].assign(all.begin() + block_begin(r, h.nodes, P), all.begin() + block_begin(r + 1, h.nodes, P));
    }
    mine = std::move(alltoallv(comm, send_e)[0]);
    centroid = std::move(alltoallv(comm, send_c)[0]);
    dir = std::move(alltoallv(comm, send_n)[0]);
  }

  // 2. Zoltan2 multi-jagged on the centroids: one part per rank.
  std::vector<int> part(mine.size(), me);
  if (P > 1) {
    using Types = Zoltan2::BasicUserTypes<double, int, GlobalId>;
    using Adapter = Zoltan2::BasicVectorAdapter<Types>;
    std::vector<GlobalId> ids(mine.size());
    for (std::size_t k = 0; k < mine.size(); ++k) ids[k] = mine[k].gid;
    const double* c = centroid.data();
    Adapter adapter(static_cast<int>(mine.size()), ids.data(), c, c + 1, c + 2, 3, 3, 3);
    Teuchos::ParameterList params("Zoltan2");
    params.set("algorithm", "multijagged");
    params.set("num_global_parts", P);
    params.set("imbalance_tolerance", 1.03);
    Zoltan2::PartitioningProblem<Adapter> problem(&adapter, &params, Teuchos::rcpFromRef(tcomm));
    problem.solve();
    const auto* parts = problem.getSolution().getPartListView();
    for (std::size_t k = 0; k < mine.size(); ++k) part[k] = static_cast<int>(parts[k]);
    std::vector<std::vector<ElementRecord>> send(P);
    for (std::size_t k = 0; k < mine.size(); ++k) send[part[k]].push_back(mine[k]);
    mine.clear();
    for (auto& from : alltoallv(comm, send)) mine.insert(mine.end(), from.begin(), from.end());
  }
  std::sort(mine.begin(), mine.end(), [](const ElementRecord& a, const ElementRecord& b) { return a.gid < b.gid; });

  // 3. Node owners: the directory hears which ranks touch each node and picks the lowest.
  auto touched_by = [&](const std::vector<ElementRecord>& els) {
    std::vector<GlobalId> ns;
    for (const auto& e : els) ns.insert(ns.end(), e.nodes, e.nodes + npe);
    std::sort(ns.begin(), ns.end());
    ns.erase(std::unique(ns.begin(), ns.end()), ns.end());
    return ns;
  };
  const std::vector<GlobalId> touched = touched_by(mine);
  const GlobalId dir0 = block_begin(me, h.nodes, P);
  std::vector<int> owner_of(dir.size(), P);
  {
    std::vector<std::vector<GlobalId>> ask(P);
    for (GlobalId n : touched) ask[directory(n, h.nodes, P)].push_back(n);
    const auto heard = alltoallv(comm, ask);
    for (int r = 0; r < P; ++r)
      for (GlobalId n : heard[r]) owner_of[n - dir0] = std::min(owner_of[n - dir0], r);
  }
  // The directory answers owner and node data for any list of nodes.
  struct Answer {
    NodeRecord node;
    int owner;
    int pad;
  };
  auto lookup = [&](const std::vector<GlobalId>& nodes) {
    std::vector<std::vector<GlobalId>> ask(P);
    for (GlobalId n : nodes) ask[directory(n, h.nodes, P)].push_back(n);
    const auto asked = alltoallv(comm, ask);
    std::vector<std::vector<Answer>> answer(P);
    for (int r = 0; r < P; ++r)
      for (GlobalId n : asked[r]) answer[r].push_back({dir[n - dir0], owner_of[n - dir0], 0});
    const auto got = alltoallv(comm, answer);
    std::vector<Answer> out(nodes.size());
    std::vector<std::size_t> next(P, 0);
    for (std::size_t k = 0; k < nodes.size(); ++k) {
      const int d = directory(nodes[k], h.nodes, P);
      out[k] = got[d][next[d]++];
    }
    return out;
  };
  const std::vector<Answer> first = lookup(touched);

  // Ghost elements: each element goes to the owners of its nodes (other than this rank).
  std::vector<ElementRecord> ghosts;
  {
    std::vector<std::vector<ElementRecord>> send(P);
    std::vector<int> dest;
    for (const auto& e : mine) {
      dest.clear();
      for (int a = 0; a < npe; ++a) {
        const auto k = std::lower_bound(touched.begin(), touched.end(), e.nodes[a]) - touched.begin();
        const int o = first[k].owner;
        if (o != me && std::find(dest.begin(), dest.end(), o) == dest.end()) dest.push_back(o);
      }
      for (int o : dest) send[o].push_back(e);
    }
    for (auto& from : alltoallv(comm, send)) ghosts.insert(ghosts.end(), from.begin(), from.end());
    std::sort(ghosts.begin(), ghosts.end(), [](const ElementRecord& a, const ElementRecord& b) { return a.gid < b.gid; });
  }

  // 4. All local nodes: those of this rank's elements and of its ghost elements, with their data.
  std::vector<GlobalId> all_nodes = touched;
  {
    const auto more = touched_by(ghosts);
    std::vector<GlobalId> merged;
    std::set_union(all_nodes.begin(), all_nodes.end(), more.begin(), more.end(), std::back_inserter(merged));
    all_nodes.swap(merged);
  }
  const std::vector<Answer> data = lookup(all_nodes);

  // Assemble: owned nodes first (ascending id), then ghosts; owned elements, then ghosts.
  Mesh m;
  m.type = static_cast<ElementType>(h.type);
  m.global_nodes = h.nodes;
  m.global_elements = h.elements;
  m.source = h.source;
  m.reoriented = h.reoriented;
  m.element_group_names = h.element_groups;
  m.node_group_names = h.node_groups;
  std::vector<std::size_t> order;  // indices into all_nodes: owned, then ghosts
  for (std::size_t k = 0; k < all_nodes.size(); ++k)
    if (data[k].owner == me) order.push_back(k);
  m.n_owned_nodes = order.size();
  for (std::size_t k = 0; k < all_nodes.size(); ++k)
    if (data[k].owner != me) order.push_back(k);
  const std::size_t nloc = order.size();
  std::vector<int> local_of(all_nodes.size());
  m.node_gid.resize(nloc);
  m.node_owner.resize(nloc);
  m.node_tag.resize(nloc);
  m.X = Kokkos::View<double* [3]>("X", nloc);
  auto Xh = Kokkos::create_mirror_view(m.X);
  m.node_group_nodes.assign(h.node_groups.size(), {});
  for (std::size_t l = 0; l < nloc; ++l) {
    const std::size_t k = order[l];
    local_of[k] = static_cast<int>(l);
    m.node_gid[l] = all_nodes[k];
    m.node_owner[l] = data[k].owner;
    m.node_tag[l] = data[k].node.tag;
    for (int d = 0; d < 3; ++d) Xh(l, d) = data[k].node.x[d];
    for (std::size_t g = 0; g < h.node_groups.size(); ++g)
      if (data[k].node.groups[g / 64] >> (g % 64) & 1) m.node_group_nodes[g].push_back(static_cast<int>(l));
  }
  Kokkos::deep_copy(m.X, Xh);
  const std::size_t ne = mine.size() + ghosts.size();
  m.n_owned_elements = mine.size();
  m.element_gid.resize(ne);
  m.element_tag.resize(ne);
  m.element_group.resize(ne);
  m.conn = Kokkos::View<int**>("conn", ne, npe);
  auto Ch = Kokkos::create_mirror_view(m.conn);
  for (std::size_t e = 0; e < ne; ++e) {
    const ElementRecord& rec = e < mine.size() ? mine[e] : ghosts[e - mine.size()];
    m.element_gid[e] = rec.gid;
    m.element_tag[e] = rec.tag;
    m.element_group[e] = rec.group;
    for (int a = 0; a < npe; ++a) {
      const auto k = std::lower_bound(all_nodes.begin(), all_nodes.end(), rec.nodes[a]) - all_nodes.begin();
      Ch(e, a) = local_of[k];
    }
  }
  Kokkos::deep_copy(m.conn, Ch);
  // Bounding box over all ranks.
  double lo[3] = {HUGE_VAL, HUGE_VAL, HUGE_VAL}, hi[3] = {-HUGE_VAL, -HUGE_VAL, -HUGE_VAL};
  for (std::size_t l = 0; l < nloc; ++l)
    for (int d = 0; d < 3; ++d) {
      lo[d] = std::min(lo[d], Xh(l, d));
      hi[d] = std::max(hi[d], Xh(l, d));
    }
  MPI_Allreduce(MPI_IN_PLACE, lo, 3, MPI_DOUBLE, MPI_MIN, comm);
  MPI_Allreduce(MPI_IN_PLACE, hi, 3, MPI_DOUBLE, MPI_MAX, comm);
  for (int d = 0; d < 3; ++d) {
    m.lower[d] = lo[d];
    m.upper[d] = hi[d];
  }
  number_for_output(m, tcomm);
  return m;
}

}  // namespace sinew
