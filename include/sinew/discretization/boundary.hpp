// The boundary surface of a distributed mesh: faces that belong to exactly one element, oriented
// outward (counter-clockwise seen from outside), hex8 quads split in two along the diagonal the
// element's six tets cut them along (hex_face_diagonal): the triangles are the tets' own faces.
//
// Found without communicating the volume mesh: a face is counted by the rank that owns its
// lowest-numbered node, which holds every element around that node (the ghost layer), so it sees every
// element sharing the face. Renderers gather it on rank 0 (io/surface.hpp); contact needs all of it on
// every rank (replicate_boundary), which costs memory in proportion to the surface, not the volume.
#pragma once

#include <sinew/discretization/geometry.hpp>
#include <sinew/discretization/mesh.hpp>

#include <array>
#include <functional>
#include <vector>

namespace sinew {

// This rank's share of the boundary.
struct LocalBoundary {
  std::vector<std::array<GlobalId, 3>> triangles;  // the faces this rank counts, as global node ids
  std::vector<int> owned_vertices;                  // local owned nodes on the surface
};
LocalBoundary local_boundary(const Mesh& mesh);

// The corners (counter-clockwise seen from outside) of the hex face whose split are the consecutive
// boundary triangles t0, t1: (a, b, c), (a, c, d) or (a, b, d), (b, c, d). False when they are not one
// face's split.
template <class Id>
bool quad_of_triangles(const std::array<Id, 3>& t0, const std::array<Id, 3>& t1, std::array<Id, 4>& quad) {
  if (t1[0] == t0[0] && t1[1] == t0[2]) {
    quad = {t0[0], t0[1], t0[2], t1[2]};
    return true;
  }
  if (t1[0] == t0[1] && t1[2] == t0[2]) {
    quad = {t0[0], t0[1], t1[1], t0[2]};
    return true;
  }
  return false;
}

// The whole boundary surface, the same on every rank.
struct SurfaceMesh {
  std::vector<GlobalId> gid;                  // vertex -> global node id, ascending
  std::vector<int> owner;                     // vertex -> the rank owning the node
  std::vector<geom::Vec> X;                  // reference positions
  std::vector<std::array<int, 3>> triangles;  // vertex indices, outward
  std::vector<double> area;                   // per vertex: a third of the reference area of its triangles
  std::vector<int> tri_offsets, vertex_tris;  // the triangles around each vertex (CSR)
  // Per vertex, the global ids of the nodes that share an element with it, itself included (CSR,
  // ascending): its neighbours at rest, which contact never pairs it with.
  std::vector<int> ring_offsets;
  std::vector<GlobalId> ring;

  std::size_t vertices() const { return gid.size(); }
  // The vertex of a global node id, -1 when the node is not on the surface.
  int vertex_of(GlobalId g) const;
  // Whether global node g shares an element with vertex v (or is v).
  bool in_ring(int v, GlobalId g) const;
  // Whether triangle t has a vertex in v's ring: a face next to v at rest, which contact and
  // attachments never pair v with.
  bool touches_ring(int t, int v) const;
};

// Every surface vertex's current position, on every rank (collective): each rank sends those of its
// owned surface nodes (`owned`: local nodes, `vertex`: their surface vertices, `position`: a local
// node's current position). Surface-sized.
std::vector<geom::Vec> gather_surface_positions(const SurfaceMesh& s, const Teuchos::Comm<int>& comm, const std::vector<int>& owned,
                                                const std::vector<int>& vertex, const std::function<geom::Vec(int)>& position);

// Collective.
SurfaceMesh replicate_boundary(const Mesh& mesh, const Teuchos::Comm<int>& comm);

}  // namespace sinew
