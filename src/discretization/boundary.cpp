// Boundary faces of a distributed mesh, and the surface replicated on every rank (boundary.hpp).
#include <sinew/core/collective.hpp>
#include <sinew/discretization/boundary.hpp>

#include <algorithm>
#include <unordered_map>

namespace sinew {

namespace {

// Outward faces of a positively oriented element in Gmsh/VTK node order (counter-clockwise seen from
// outside). tet4: the faces opposite nodes 3, 2, 1, 0; hex8: bottom 0-1-2-3, top 4-7.
constexpr int kTetFaces[4][4] = {{0, 2, 1, -1}, {0, 1, 3, -1}, {0, 3, 2, -1}, {1, 2, 3, -1}};

struct Face {
  std::array<GlobalId, 4> key;  // sorted global node ids (-1 pad for triangles)
  int element, face;
};

}  // namespace

LocalBoundary local_boundary(const Mesh& mesh) {
  const bool hex = mesh.type == ElementType::Hex8;
  const int nf = hex ? 6 : 4, nv = hex ? 4 : 3;
  auto conn = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), mesh.conn);
  const auto owned = [&](int local) { return static_cast<std::size_t>(local) < mesh.n_owned_nodes; };
  const auto corner = [&](int e, int f, int a) { return hex ? conn(e, kHexFaces[f][a]) : conn(e, kTetFaces[f][a]); };

  // Faces touching an owned node: every element sharing such a face is on this rank.
  std::vector<Face> faces;
  for (int e = 0; e < static_cast<int>(mesh.local_elements()); ++e)
    for (int f = 0; f < nf; ++f) {
      bool touches = false;
      Face face{{-1, -1, -1, -1}, e, f};
      for (int a = 0; a < nv; ++a) {
        touches |= owned(corner(e, f, a));
        face.key[a] = mesh.node_gid[corner(e, f, a)];
      }
      if (!touches) continue;
      std::sort(face.key.begin(), face.key.begin() + nv);
      faces.push_back(face);
    }
  std::sort(faces.begin(), faces.end(), [](const Face& a, const Face& b) { return a.key < b.key; });

  LocalBoundary out;
  std::vector<char> on_surface(mesh.local_nodes(), 0);
  for (std::size_t i = 0; i < faces.size();) {
    std::size_t j = i + 1;
    while (j < faces.size() && faces[j].key == faces[i].key) ++j;
    if (j - i == 1) {  // on one element only: the boundary
      const Face& F = faces[i];
      GlobalId g[4];
      int lowest = 0;  // the corner with the lowest global id: its owner counts the face
      for (int a = 0; a < nv; ++a) {
        on_surface[corner(F.element, F.face, a)] = 1;
        g[a] = mesh.node_gid[corner(F.element, F.face, a)];
        if (g[a] < g[lowest]) lowest = a;
      }
      if (owned(corner(F.element, F.face, lowest))) {
        // A hex face is split along the diagonal its element's six tets cut it along (kHexTets), so
        // that the triangles are the tets' own faces and inside a tet is behind the surface. Split along
        // corners 0-2 everywhere, faces 4 and 5 disagreed with the tets, and a bent face's tets bulged
        // in front of its triangles: on BCN_Epileptic's steps 31-40, 393 of 1,270 samples found inside
        // an element lay in front of the nearest face (a median 0.0014, the thickness 0.0015), each
        // refrozen to a spring that hardly pushed at every detection and reported as a change, so that
        // the regroups and rounds of the crease never settled.
        if (!hex)
          out.triangles.push_back({g[0], g[1], g[2]});
        else if (hex_face_diagonal(F.face) == 1) {
          out.triangles.push_back({g[0], g[1], g[3]});
          out.triangles.push_back({g[1], g[2], g[3]});
        } else {
          out.triangles.push_back({g[0], g[1], g[2]});
          out.triangles.push_back({g[0], g[2], g[3]});
        }
      }
    }
    i = j;
  }
  for (std::size_t n = 0; n < mesh.n_owned_nodes; ++n)
    if (on_surface[n]) out.owned_vertices.push_back(static_cast<int>(n));
  return out;
}

int SurfaceMesh::vertex_of(GlobalId g) const {
  const auto it = std::lower_bound(gid.begin(), gid.end(), g);
  return it != gid.end() && *it == g ? static_cast<int>(it - gid.begin()) : -1;
}

bool SurfaceMesh::in_ring(int v, GlobalId g) const {
  return std::binary_search(ring.begin() + ring_offsets[v], ring.begin() + ring_offsets[v + 1], g);
}

bool SurfaceMesh::touches_ring(int t, int v) const {
  for (int m : triangles[t])
    if (in_ring(v, gid[m])) return true;
  return false;
}

std::vector<geom::Vec> gather_surface_positions(const SurfaceMesh& s, const Teuchos::Comm<int>& comm, const std::vector<int>& owned,
                                                const std::vector<int>& vertex, const std::function<geom::Vec(int)>& position) {
  struct Position {
    int vertex;
    double x[3];
  };
  std::vector<Position> mine;
  mine.reserve(owned.size());
  for (std::size_t i = 0; i < owned.size(); ++i) {
    const geom::Vec p = position(owned[i]);
    mine.push_back({vertex[i], {p[0], p[1], p[2]}});
  }
  std::vector<geom::Vec> x(s.vertices(), geom::Vec{});
  for (const Position& p : allgatherv(raw_comm(comm), mine)) x[p.vertex] = {p.x[0], p.x[1], p.x[2]};
  return x;
}

SurfaceMesh replicate_boundary(const Mesh& mesh, const Teuchos::Comm<int>& comm) {
  using namespace geom;
  const MPI_Comm c = raw_comm(comm);
  const int rank = comm.getRank();
  const LocalBoundary local = local_boundary(mesh);
  auto X = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), mesh.X);
  auto conn = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), mesh.conn);
  const int npe = nodes_per_element(mesh.type);

  // Each owned surface vertex: its id, owner, position, and the nodes sharing an element with it (all
  // elements around an owned node are on its owner).
  struct VertexRecord {
    GlobalId gid;
    int owner, ring_size;
    double X[3];
  };
  std::vector<VertexRecord> mine;
  std::vector<char> is_vertex(mesh.local_nodes(), 0);
  for (int n : local.owned_vertices) is_vertex[n] = 1;
  std::vector<std::vector<GlobalId>> rings(mesh.local_nodes());
  for (std::size_t e = 0; e < mesh.local_elements(); ++e)
    for (int a = 0; a < npe; ++a) {
      const int n = conn(e, a);
      if (!is_vertex[n]) continue;
      for (int b = 0; b < npe; ++b) rings[n].push_back(mesh.node_gid[conn(e, b)]);
    }
  std::vector<GlobalId> my_rings;
  for (int n : local.owned_vertices) {
    auto& r = rings[n];
    std::sort(r.begin(), r.end());
    r.erase(std::unique(r.begin(), r.end()), r.end());
    mine.push_back({mesh.node_gid[n], rank, static_cast<int>(r.size()), {X(n, 0), X(n, 1), X(n, 2)}});
    my_rings.insert(my_rings.end(), r.begin(), r.end());
  }
  const std::vector<VertexRecord> all = allgatherv(c, mine);
  const std::vector<GlobalId> all_rings = allgatherv(c, my_rings);
  const std::vector<std::array<GlobalId, 3>> all_tris = allgatherv(c, local.triangles);

  // Vertices in ascending global id (the order does not depend on the number of ranks).
  std::vector<std::size_t> order(all.size()), ring_start(all.size() + 1, 0);
  for (std::size_t k = 0; k < all.size(); ++k) {
    order[k] = k;
    ring_start[k + 1] = ring_start[k] + static_cast<std::size_t>(all[k].ring_size);
  }
  std::sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) { return all[a].gid < all[b].gid; });
  SurfaceMesh s;
  const std::size_t nv = all.size();
  s.gid.resize(nv);
  s.owner.resize(nv);
  s.X.resize(nv);
  s.ring_offsets.assign(nv + 1, 0);
  for (std::size_t v = 0; v < nv; ++v) {
    const VertexRecord& r = all[order[v]];
    s.gid[v] = r.gid;
    s.owner[v] = r.owner;
    s.X[v] = {r.X[0], r.X[1], r.X[2]};
    s.ring_offsets[v + 1] = s.ring_offsets[v] + r.ring_size;
    s.ring.insert(s.ring.end(), all_rings.begin() + static_cast<long>(ring_start[order[v]]),
                  all_rings.begin() + static_cast<long>(ring_start[order[v] + 1]));
  }
  // Triangles in a rank-independent order too.
  std::vector<std::array<GlobalId, 3>> tris = all_tris;
  std::sort(tris.begin(), tris.end(), [](const auto& a, const auto& b) {
    auto sa = a, sb = b;
    std::sort(sa.begin(), sa.end());
    std::sort(sb.begin(), sb.end());
    return sa < sb;
  });
  s.triangles.resize(tris.size());
  s.area.assign(nv, 0.0);
  std::vector<int> count(nv, 0);
  for (std::size_t t = 0; t < tris.size(); ++t) {
    for (int a = 0; a < 3; ++a) {
      s.triangles[t][a] = s.vertex_of(tris[t][a]);
      ++count[s.triangles[t][a]];
    }
    const auto& T = s.triangles[t];
    const double A = 0.5 * geom::norm(geom::cross(s.X[T[1]] - s.X[T[0]], s.X[T[2]] - s.X[T[0]]));
    for (int a = 0; a < 3; ++a) s.area[T[a]] += A / 3.0;
  }
  s.tri_offsets.assign(nv + 1, 0);
  for (std::size_t v = 0; v < nv; ++v) s.tri_offsets[v + 1] = s.tri_offsets[v] + count[v];
  s.vertex_tris.resize(s.tri_offsets[nv]);
  std::vector<int> fill(s.tri_offsets.begin(), s.tri_offsets.end() - 1);
  for (std::size_t t = 0; t < s.triangles.size(); ++t)
    for (int a = 0; a < 3; ++a) s.vertex_tris[fill[s.triangles[t][a]]++] = static_cast<int>(t);
  return s;
}

}  // namespace sinew
