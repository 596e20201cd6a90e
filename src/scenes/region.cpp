// Region resolution: geometric predicates on reference positions (the same verdict wherever a node is
// held), node groups from the mesh file (distributed with the nodes), and volume groups, whose verdict
// on a ghost node comes from its owner (only the owner sees every element around it).
#include <sinew/core/collective.hpp>
#include <sinew/core/parameters.hpp>
#include <sinew/discretization/mesh_file.hpp>
#include <sinew/discretization/triangle_surface.hpp>
#include <sinew/scenes/region.hpp>

#include <algorithm>
#include <cmath>
#include <functional>
#include <memory>

namespace sinew {

double segment_distance(const double* X, const std::array<double, 3>& a, const std::array<double, 3>& b) {
  double ab[3], ax[3], len2 = 0.0, t = 0.0;
  for (int k = 0; k < 3; ++k) {
    ab[k] = b[k] - a[k];
    ax[k] = X[k] - a[k];
    len2 += ab[k] * ab[k];
    t += ab[k] * ax[k];
  }
  t = len2 > 0.0 ? std::clamp(t / len2, 0.0, 1.0) : 0.0;
  double d2 = 0.0;
  for (int k = 0; k < 3; ++k) d2 += (ax[k] - t * ab[k]) * (ax[k] - t * ab[k]);
  return std::sqrt(d2);
}

namespace {

std::function<bool(const std::array<double, 3>&)> predicate(const Mesh& mesh, const RegionParameters& p, const std::string& where) {
  const std::string& region = p.region;
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
  if (region == "segment") {
    const auto a = p.segment_start, b = p.segment_end;
    const double r = p.radius;
    return [a, b, r](const std::array<double, 3>& X) { return segment_distance(X.data(), a, b) <= r; };
  }
  if (region == "all") return [](const std::array<double, 3>&) { return true; };
  if (region == "inside") {  // every rank reads the (small) surface and tests its own nodes
    std::shared_ptr<const TriangleSurface> surface;
    try {
      surface = std::make_shared<const TriangleSurface>(read_triangle_surface(p.surface));
    } catch (const InputError& e) {
      throw e.prefixed(where + ": ");
    }
    auto test = std::make_shared<const InsideTest>(*surface);
    return [surface, test](const std::array<double, 3>& X) { return test->inside(X); };
  }
  throw InputError(where + ": unknown 'Region' \"" + region + "\"");
}

}  // namespace

namespace {

// The local nodes of one group: a node group's, or those of a volume group's elements. A ghost node
// may belong to a volume group through an element this rank does not hold: its owner decides.
std::vector<char> group_nodes(const Mesh& mesh, const Teuchos::Comm<int>& comm, const std::string& group, const std::string& where) {
  std::vector<char> in(mesh.local_nodes(), 0);
  const auto& ng = mesh.node_group_names;
  if (const auto it = std::find(ng.begin(), ng.end(), group); it != ng.end()) {
    for (int n : mesh.node_group_nodes[it - ng.begin()]) in[n] = 1;
    return in;
  }
  const auto& eg = mesh.element_group_names;
  const auto it = std::find(eg.begin(), eg.end(), group);
  if (it == eg.end()) throw unknown_group(where, group, ng, eg);
  const int g = static_cast<int>(it - eg.begin());
  auto conn = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), mesh.conn);
  const int npe = nodes_per_element(mesh.type);
  for (std::size_t e = 0; e < mesh.local_elements(); ++e)
    if (mesh.in_group(e, g))
      for (int a = 0; a < npe; ++a) in[conn(e, a)] = 1;
  MPI_Comm c = raw_comm(comm);
  int P = 1;
  MPI_Comm_size(c, &P);
  std::vector<std::vector<GlobalId>> ask(P);
  for (std::size_t n = mesh.n_owned_nodes; n < mesh.local_nodes(); ++n) ask[mesh.node_owner[n]].push_back(mesh.node_gid[n]);
  const auto asked = alltoallv(c, ask);
  std::vector<std::vector<char>> answer(P);
  const auto owned_end = mesh.node_gid.begin() + static_cast<std::ptrdiff_t>(mesh.n_owned_nodes);
  for (int r = 0; r < P; ++r)
    for (GlobalId gid : asked[r]) answer[r].push_back(in[std::lower_bound(mesh.node_gid.begin(), owned_end, gid) - mesh.node_gid.begin()]);
  const auto answered = alltoallv(c, answer);
  std::vector<std::size_t> next(P, 0);
  for (std::size_t n = mesh.n_owned_nodes; n < mesh.local_nodes(); ++n) in[n] = answered[mesh.node_owner[n]][next[mesh.node_owner[n]]++];
  return in;
}

}  // namespace

std::vector<int> select_region(const Mesh& mesh, const Teuchos::Comm<int>& comm, const RegionParameters& p,
                               const std::string& where) {
  const auto groups = p.groups();
  if (groups.empty()) {
    // A surface file that one rank cannot read (or parse) is an error on every rank, not a hang in
    // the next collective.
    std::function<bool(const std::array<double, 3>&)> test;
    collectively(raw_comm(comm), [&] { test = predicate(mesh, p, where); });
    return select_nodes(mesh, test);
  }
  std::vector<char> in(mesh.local_nodes(), 0);
  for (const auto& g : groups) {
    const auto one = group_nodes(mesh, comm, g, where);
    for (std::size_t n = 0; n < in.size(); ++n) in[n] |= one[n];
  }
  std::vector<int> out;
  for (std::size_t n = 0; n < in.size(); ++n)
    if (in[n]) out.push_back(static_cast<int>(n));
  return out;
}

}  // namespace sinew
