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
  GroupMask groups;
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
  std::vector<std::string> element_groups, node_groups, notes;
  std::string source;
  std::string error;  // rank 0's verdict on the file, so that every rank throws it together
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
  strings(h.notes);
  std::vector<std::string> src{h.source, h.error};
  strings(src);
  h.source = src[0];
  h.error = src[1];
}

// The four stages of distribute_mesh, sharing the rank's view of the directory.
class Distribution {
 public:
  Distribution(const Teuchos::Comm<int>& tcomm) : tcomm_(tcomm), comm_(raw_comm(tcomm)) {
    MPI_Comm_rank(comm_, &me_);
    MPI_Comm_size(comm_, &P_);
  }

  // Rank 0 describes the mesh to everybody.
  void share_header(const MeshFile& file) {
    if (me_ == 0) {
      h_.type = static_cast<int>(file.type);
      h_.npe = nodes_per_element(file.type);
      h_.nodes = static_cast<GlobalId>(file.nodes());
      h_.elements = static_cast<GlobalId>(file.elements());
      h_.reoriented = file.reoriented;
      h_.element_groups = file.element_group_names;
      h_.node_groups = file.node_group_names;
      h_.notes = file.notes;
      h_.source = file.format + " " + file.path;
      if (h_.node_groups.size() > 64 * kGroupWords)
        h_.error = file.path + ": more than " + std::to_string(64 * kGroupWords) + " node groups";
    }
    broadcast_header(h_, comm_);
    if (!h_.error.empty()) throw InputError(h_.error, InputErrorKind::BadMesh);
    npe_ = h_.npe;
    dir0_ = block_begin(me_, h_.nodes, P_);
    if (h_.elements < P_)
      throw InputError("Mesh: " + std::to_string(h_.elements) + " elements cannot be split over " + std::to_string(P_) + " ranks",
                       InputErrorKind::BadMesh);
  }

  // 1. Rank 0 sends blocks of elements (file order, with centroids) and of node data (by node id) to
  //    every rank, then drops the file.
  void scatter(MeshFile& file) {
    std::vector<std::vector<ElementRecord>> send_e(P_);
    std::vector<std::vector<double>> send_c(P_);
    std::vector<std::vector<NodeRecord>> send_n(P_);
    if (me_ == 0) {
      for (int r = 0; r < P_; ++r)
        for (GlobalId e = block_begin(r, h_.elements, P_); e < block_begin(r + 1, h_.elements, P_); ++e) {
          ElementRecord rec{e, file.element_tag[e], file.element_groups[e], {}};
          double c[3] = {0.0, 0.0, 0.0};
          for (int a = 0; a < npe_; ++a) {
            const int n = file.conn[npe_ * e + a];
            rec.nodes[a] = n;
            for (int d = 0; d < 3; ++d) c[d] += file.xyz[3 * static_cast<std::size_t>(n) + d] / npe_;
          }
          send_e[r].push_back(rec);
          send_c[r].insert(send_c[r].end(), c, c + 3);
        }
      std::vector<NodeRecord> all(file.nodes());
      for (std::size_t n = 0; n < file.nodes(); ++n) {
        for (int d = 0; d < 3; ++d) all[n].x[d] = file.xyz[3 * n + d];
        all[n].tag = file.node_tag[n];
        for (auto& w : all[n].groups) w = 0;
      }
      for (std::size_t g = 0; g < file.node_group_nodes.size(); ++g)
        for (int n : file.node_group_nodes[g]) all[n].groups[g / 64] |= std::uint64_t(1) << (g % 64);
      file = MeshFile();  // rank 0 no longer needs the whole mesh
      for (int r = 0; r < P_; ++r)
        send_n[r].assign(all.begin() + block_begin(r, h_.nodes, P_), all.begin() + block_begin(r + 1, h_.nodes, P_));
    }
    mine_ = std::move(alltoallv(comm_, send_e)[0]);
    centroid_ = std::move(alltoallv(comm_, send_c)[0]);
    dir_ = std::move(alltoallv(comm_, send_n)[0]);
  }

  // 2. Zoltan2 multi-jagged on the centroids, one part per rank; elements move to their part.
  void partition() {
    if (P_ > 1) {
      using Types = Zoltan2::BasicUserTypes<double, int, GlobalId>;
      using Adapter = Zoltan2::BasicVectorAdapter<Types>;
      std::vector<GlobalId> ids(mine_.size());
      for (std::size_t k = 0; k < mine_.size(); ++k) ids[k] = mine_[k].gid;
      const double* c = centroid_.data();
      Adapter adapter(static_cast<int>(mine_.size()), ids.data(), c, c + 1, c + 2, 3, 3, 3);
      Teuchos::ParameterList params("Zoltan2");
      params.set("algorithm", "multijagged");
      params.set("num_global_parts", P_);
      params.set("imbalance_tolerance", 1.03);
      Zoltan2::PartitioningProblem<Adapter> problem(&adapter, &params, Teuchos::rcpFromRef(tcomm_));
      problem.solve();
      const auto* parts = problem.getSolution().getPartListView();
      std::vector<std::vector<ElementRecord>> send(P_);
      for (std::size_t k = 0; k < mine_.size(); ++k) send[static_cast<int>(parts[k])].push_back(mine_[k]);
      mine_.clear();
      for (auto& from : alltoallv(comm_, send)) mine_.insert(mine_.end(), from.begin(), from.end());
    }
    std::sort(mine_.begin(), mine_.end(), [](const ElementRecord& a, const ElementRecord& b) { return a.gid < b.gid; });
    centroid_.clear();
  }

  // 3. Node owners: the directory hears which ranks touch each node and picks the lowest; each element
  //    then goes, as a ghost, to the owners of its nodes other than this rank.
  void own_and_ghost() {
    touched_ = touched_by(mine_);
    owner_of_.assign(dir_.size(), P_);
    std::vector<std::vector<GlobalId>> ask(P_);
    for (GlobalId n : touched_) ask[directory(n, h_.nodes, P_)].push_back(n);
    const auto heard = alltoallv(comm_, ask);
    for (int r = 0; r < P_; ++r)
      for (GlobalId n : heard[r]) owner_of_[n - dir0_] = std::min(owner_of_[n - dir0_], r);
    const std::vector<Answer> first = lookup(touched_);
    std::vector<std::vector<ElementRecord>> send(P_);
    std::vector<int> dest;
    for (const auto& e : mine_) {
      dest.clear();
      for (int a = 0; a < npe_; ++a) {
        const auto k = std::lower_bound(touched_.begin(), touched_.end(), e.nodes[a]) - touched_.begin();
        const int o = first[k].owner;
        if (o != me_ && std::find(dest.begin(), dest.end(), o) == dest.end()) dest.push_back(o);
      }
      for (int o : dest) send[o].push_back(e);
    }
    for (auto& from : alltoallv(comm_, send)) ghosts_.insert(ghosts_.end(), from.begin(), from.end());
    std::sort(ghosts_.begin(), ghosts_.end(), [](const ElementRecord& a, const ElementRecord& b) { return a.gid < b.gid; });
  }

  // 4. All local nodes (of this rank's elements and ghosts) with their data; the Mesh: owned nodes first
  //    (ascending id), then ghosts; owned elements, then ghosts.
  Mesh assemble() {
    std::vector<GlobalId> all_nodes;
    const auto more = touched_by(ghosts_);
    std::set_union(touched_.begin(), touched_.end(), more.begin(), more.end(), std::back_inserter(all_nodes));
    const std::vector<Answer> data = lookup(all_nodes);
    Mesh m;
    m.type = static_cast<ElementType>(h_.type);
    m.global_nodes = h_.nodes;
    m.global_elements = h_.elements;
    m.source = h_.source;
    m.reoriented = h_.reoriented;
    m.notes = h_.notes;
    m.element_group_names = h_.element_groups;
    m.node_group_names = h_.node_groups;
    const std::vector<int> local_of = fill_nodes(m, all_nodes, data);
    fill_elements(m, all_nodes, local_of);
    set_bounding_box(m);
    number_for_output(m, tcomm_);
    return m;
  }

 private:
  struct Answer {
    NodeRecord node;
    int owner;
    int pad;
  };

  std::vector<GlobalId> touched_by(const std::vector<ElementRecord>& els) const {
    std::vector<GlobalId> ns;
    for (const auto& e : els) ns.insert(ns.end(), e.nodes, e.nodes + npe_);
    std::sort(ns.begin(), ns.end());
    ns.erase(std::unique(ns.begin(), ns.end()), ns.end());
    return ns;
  }

  // The directory answers owner and node data for any list of nodes (collective).
  std::vector<Answer> lookup(const std::vector<GlobalId>& nodes) const {
    std::vector<std::vector<GlobalId>> ask(P_);
    for (GlobalId n : nodes) ask[directory(n, h_.nodes, P_)].push_back(n);
    const auto asked = alltoallv(comm_, ask);
    std::vector<std::vector<Answer>> answer(P_);
    for (int r = 0; r < P_; ++r)
      for (GlobalId n : asked[r]) answer[r].push_back({dir_[n - dir0_], owner_of_[n - dir0_], 0});
    const auto got = alltoallv(comm_, answer);
    std::vector<Answer> out(nodes.size());
    std::vector<std::size_t> next(P_, 0);
    for (std::size_t k = 0; k < nodes.size(); ++k) {
      const int d = directory(nodes[k], h_.nodes, P_);
      out[k] = got[d][next[d]++];
    }
    return out;
  }

  // Returns each of all_nodes' local index.
  std::vector<int> fill_nodes(Mesh& m, const std::vector<GlobalId>& all_nodes, const std::vector<Answer>& data) const {
    std::vector<std::size_t> order;  // indices into all_nodes: owned, then ghosts
    for (std::size_t k = 0; k < all_nodes.size(); ++k)
      if (data[k].owner == me_) order.push_back(k);
    m.n_owned_nodes = order.size();
    for (std::size_t k = 0; k < all_nodes.size(); ++k)
      if (data[k].owner != me_) order.push_back(k);
    const std::size_t nloc = order.size();
    std::vector<int> local_of(all_nodes.size());
    m.node_gid.resize(nloc);
    m.node_owner.resize(nloc);
    m.node_tag.resize(nloc);
    m.X = Kokkos::View<double* [3]>("X", nloc);
    auto Xh = Kokkos::create_mirror_view(m.X);
    m.node_group_nodes.assign(h_.node_groups.size(), {});
    for (std::size_t l = 0; l < nloc; ++l) {
      const std::size_t k = order[l];
      local_of[k] = static_cast<int>(l);
      m.node_gid[l] = all_nodes[k];
      m.node_owner[l] = data[k].owner;
      m.node_tag[l] = data[k].node.tag;
      for (int d = 0; d < 3; ++d) Xh(l, d) = data[k].node.x[d];
      for (std::size_t g = 0; g < h_.node_groups.size(); ++g)
        if (data[k].node.groups[g / 64] >> (g % 64) & 1) m.node_group_nodes[g].push_back(static_cast<int>(l));
    }
    Kokkos::deep_copy(m.X, Xh);
    return local_of;
  }

  void fill_elements(Mesh& m, const std::vector<GlobalId>& all_nodes, const std::vector<int>& local_of) const {
    const std::size_t ne = mine_.size() + ghosts_.size();
    m.n_owned_elements = mine_.size();
    m.element_gid.resize(ne);
    m.element_tag.resize(ne);
    m.element_groups.resize(ne);
    m.conn = Kokkos::View<int**>("conn", ne, npe_);
    auto Ch = Kokkos::create_mirror_view(m.conn);
    for (std::size_t e = 0; e < ne; ++e) {
      const ElementRecord& rec = e < mine_.size() ? mine_[e] : ghosts_[e - mine_.size()];
      m.element_gid[e] = rec.gid;
      m.element_tag[e] = rec.tag;
      m.element_groups[e] = rec.groups;
      for (int a = 0; a < npe_; ++a)
        Ch(e, a) = local_of[std::lower_bound(all_nodes.begin(), all_nodes.end(), rec.nodes[a]) - all_nodes.begin()];
    }
    Kokkos::deep_copy(m.conn, Ch);
  }

  void set_bounding_box(Mesh& m) const {
    auto Xh = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), m.X);
    double lo[3] = {HUGE_VAL, HUGE_VAL, HUGE_VAL}, hi[3] = {-HUGE_VAL, -HUGE_VAL, -HUGE_VAL};
    for (std::size_t l = 0; l < m.local_nodes(); ++l)
      for (int d = 0; d < 3; ++d) {
        lo[d] = std::min(lo[d], Xh(l, d));
        hi[d] = std::max(hi[d], Xh(l, d));
      }
    MPI_Allreduce(MPI_IN_PLACE, lo, 3, MPI_DOUBLE, MPI_MIN, comm_);
    MPI_Allreduce(MPI_IN_PLACE, hi, 3, MPI_DOUBLE, MPI_MAX, comm_);
    for (int d = 0; d < 3; ++d) {
      m.lower[d] = lo[d];
      m.upper[d] = hi[d];
    }
  }

  const Teuchos::Comm<int>& tcomm_;
  MPI_Comm comm_;
  int me_ = 0, P_ = 1, npe_ = 0;
  Header h_;
  GlobalId dir0_ = 0;                    // the first node id of this rank's directory block
  std::vector<ElementRecord> mine_;      // elements this rank holds (first its block, then its part)
  std::vector<double> centroid_;         // 3 per element of the block (until partitioned)
  std::vector<NodeRecord> dir_;          // this rank's block of the node directory
  std::vector<int> owner_of_;            // per directory node: its owner
  std::vector<GlobalId> touched_;        // nodes of this rank's elements, sorted
  std::vector<ElementRecord> ghosts_;    // elements other ranks hold that this rank's owned nodes need
};

}  // namespace

Mesh distribute_mesh(MeshFile&& file, const Teuchos::Comm<int>& comm) {
  Distribution d(comm);
  d.share_header(file);
  d.scatter(file);
  d.partition();
  d.own_and_ghost();
  return d.assemble();
}

}  // namespace sinew
