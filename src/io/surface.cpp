// Boundary surface extraction and OBJ writing (surface.hpp).
#include <sinew/core/collective.hpp>
#include <sinew/discretization/boundary.hpp>
#include <sinew/discretization/shape_functions.hpp>
#include <sinew/io/surface.hpp>

#include "durable_file.hpp"

#include <Tpetra_Import.hpp>
#include <Tpetra_Map.hpp>
#include <Tpetra_Vector.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <unordered_map>

namespace sinew {

void write_obj_file(const std::string& path, const std::vector<double>& x, const std::vector<std::array<int, 3>>& triangles,
                    const std::string& comment) {
  // Area-weighted vertex normals: the sum of the (unnormalized) cross products of the triangles around.
  std::vector<double> normal(x.size(), 0.0);
  for (const auto& t : triangles) {
    const double* p0 = &x[3 * t[0]];
    const double* p1 = &x[3 * t[1]];
    const double* p2 = &x[3 * t[2]];
    const double a[3] = {p1[0] - p0[0], p1[1] - p0[1], p1[2] - p0[2]}, b[3] = {p2[0] - p0[0], p2[1] - p0[1], p2[2] - p0[2]};
    const double c[3] = {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
    for (int v : t)
      for (int d = 0; d < 3; ++d) normal[3 * v + d] += c[d];
  }
  io_detail::write_durably(path, "w", [&](std::FILE* f) {
    std::fprintf(f, "# Sinew surface: %zu vertices, %zu triangles; %s\n", x.size() / 3, triangles.size(), comment.c_str());
    for (std::size_t v = 0; v < x.size() / 3; ++v) std::fprintf(f, "v %.10g %.10g %.10g\n", x[3 * v], x[3 * v + 1], x[3 * v + 2]);
    for (std::size_t v = 0; v < x.size() / 3; ++v) {
      const double* m = &normal[3 * v];
      const double len = std::sqrt(m[0] * m[0] + m[1] * m[1] + m[2] * m[2]);
      const double s = len > 0.0 ? 1.0 / len : 0.0;
      std::fprintf(f, "vn %.6f %.6f %.6f\n", s * m[0], s * m[1], s * m[2]);
    }
    for (const auto& t : triangles)
      std::fprintf(f, "f %d//%d %d//%d %d//%d\n", t[0] + 1, t[0] + 1, t[1] + 1, t[1] + 1, t[2] + 1, t[2] + 1);
    return true;  // the stream's error flag says the rest
  });
}

EmbeddedSkin::EmbeddedSkin(const Mesh& mesh, const Teuchos::RCP<const Map>& owned_dofs) : mesh_(mesh) {
  // Rank 0 asks for the displacement of every node a skin vertex hangs on; the others ask for none.
  std::vector<GO> want;
  if (mesh.embedded) {
    std::vector<GlobalId> nodes;
    for (const auto& n : mesh.embedded->nodes) nodes.insert(nodes.end(), n.begin(), n.end());
    std::sort(nodes.begin(), nodes.end());
    nodes.erase(std::unique(nodes.begin(), nodes.end()), nodes.end());
    for (GlobalId g : nodes)
      for (int c = 0; c < 3; ++c) want.push_back(3 * static_cast<GO>(g) + c);
    for (std::size_t k = 0; k < nodes.size(); ++k) slot_[nodes[k]] = static_cast<int>(k);
  }
  const Teuchos::ArrayView<const GO> view(want.data(), static_cast<Teuchos::ArrayView<const GO>::size_type>(want.size()));
  gathered_ = Teuchos::rcp(new Map(Teuchos::OrdinalTraits<Tpetra::global_size_t>::invalid(), view, 0, owned_dofs->getComm()));
  import_ = Teuchos::rcp(new Import(owned_dofs, gathered_));
  // The same nodes' reference coordinates, once (for det F at the skin).
  Vector X(owned_dofs), here(gathered_);
  {
    auto Xh = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), mesh.X);
    auto xv = X.getLocalViewHost(Tpetra::Access::OverwriteAll);
    for (std::size_t n = 0; n < mesh.n_owned_nodes; ++n)
      for (int d = 0; d < 3; ++d) xv(3 * n + d, 0) = Xh(n, d);
  }
  here.doImport(X, *import_, Tpetra::INSERT);
  auto h = here.getLocalViewHost(Tpetra::Access::ReadOnly);
  rest_nodes_.assign(h.data(), h.data() + h.extent(0));
}

void EmbeddedSkin::deformed(const Vector& u, std::vector<double>& x, std::vector<double>* J) const {
  Vector here(gathered_);
  here.doImport(u, *import_, Tpetra::INSERT);
  x.clear();
  if (J) J->clear();
  if (!mesh_.embedded) return;
  const auto& s = *mesh_.embedded;
  auto h = here.getLocalViewHost(Tpetra::Access::ReadOnly);
  x.resize(3 * s.rest.size());
  if (J) J->resize(s.rest.size());
  for (std::size_t v = 0; v < s.rest.size(); ++v) {
    for (int d = 0; d < 3; ++d) {
      double ud = 0.0;
      for (int a = 0; a < 8; ++a) ud += s.weights[v][a] * h(3 * slot_.at(s.nodes[v][a]) + d, 0);
      x[3 * v + d] = s.rest[v][d] + ud;
    }
    if (!J) continue;
    // The vertex's reference coordinates in its cell (trilinear weights reproduce linear functions),
    // then dx/dxi and dX/dxi there: J = det(dx/dxi) / det(dX/dxi). A vertex beyond its cell (its
    // weights extrapolate) takes the J of the cell's nearest point: the map extrapolated past the cell
    // is no material's.
    double xi[3] = {0.0, 0.0, 0.0};
    for (int a = 0; a < 8; ++a)
      for (int d = 0; d < 3; ++d) xi[d] += s.weights[v][a] * Hex8::corner(a, d);
    for (double& c : xi) c = std::clamp(c, -1.0, 1.0);
    double dN[8][3];
    Hex8::gradients_at(xi, dN);
    Mat3 dX = Mat3::zero(), dx = Mat3::zero();
    for (int a = 0; a < 8; ++a) {
      const int k = slot_.at(s.nodes[v][a]);
      for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) {
          dX(i, j) += rest_nodes_[3 * k + i] * dN[a][j];
          dx(i, j) += (rest_nodes_[3 * k + i] + h(3 * k + i, 0)) * dN[a][j];
        }
    }
    (*J)[v] = det(dx) / det(dX);
  }
}

void EmbeddedSkin::write_obj(const std::string& path, const Vector& u, const std::string& comment) const {
  std::vector<double> x;
  deformed(u, x);
  collectively(raw_comm(*gathered_->getComm()), [&] {
    if (mesh_.embedded) write_obj_file(path, x, mesh_.embedded->triangles, comment);
  });
}

BoundarySurface::BoundarySurface(const Mesh& mesh, const Teuchos::Comm<int>& comm)
    : mesh_(mesh), comm_(raw_comm(comm)), root_(comm.getRank() == 0) {
  const LocalBoundary boundary = local_boundary(mesh);
  owned_vertices_ = boundary.owned_vertices;
  std::vector<GlobalId> tri_gids, vertex_gids;  // faces this rank counts: 3 global ids per triangle
  for (const auto& t : boundary.triangles) tri_gids.insert(tri_gids.end(), t.begin(), t.end());
  for (int n : owned_vertices_) vertex_gids.push_back(mesh.node_gid[n]);

  // Rank 0 gathers the topology once.
  int P = 1;
  MPI_Comm_size(comm_, &P);
  auto gather = [&](const std::vector<GlobalId>& mine, std::vector<int>& counts, std::vector<int>& offsets) {
    int n = static_cast<int>(mine.size());
    counts.assign(P, 0);
    MPI_Gather(&n, 1, MPI_INT, counts.data(), 1, MPI_INT, 0, comm_);
    offsets.assign(P + 1, 0);
    for (int r = 0; r < P; ++r) offsets[r + 1] = offsets[r] + counts[r];
    std::vector<GlobalId> all(root_ ? offsets[P] : 0);
    MPI_Gatherv(mine.data(), n, MPI_LONG_LONG, all.data(), counts.data(), offsets.data(), MPI_LONG_LONG, 0, comm_);
    return all;
  };
  static_assert(sizeof(GlobalId) == sizeof(long long), "global ids travel as MPI_LONG_LONG");
  std::vector<int> tcounts, toffsets;
  const std::vector<GlobalId> all_vertices = gather(vertex_gids, counts_, offsets_);
  const std::vector<GlobalId> all_tris = gather(tri_gids, tcounts, toffsets);
  long long n[2] = {static_cast<long long>(all_vertices.size()), static_cast<long long>(all_tris.size() / 3)};
  MPI_Bcast(n, 2, MPI_LONG_LONG, 0, comm_);
  n_vertices_ = n[0];
  n_triangles_ = n[1];
  if (!root_) return;
  std::unordered_map<GlobalId, int> index;
  for (std::size_t k = 0; k < all_vertices.size(); ++k) index[all_vertices[k]] = static_cast<int>(k);
  triangles_.resize(all_tris.size() / 3);
  for (std::size_t t = 0; t < triangles_.size(); ++t)
    for (int a = 0; a < 3; ++a) triangles_[t][a] = index.at(all_tris[3 * t + a]);
}

void BoundarySurface::write_obj(const std::string& path, const Vector& u, const std::string& comment) const {
  auto X = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), mesh_.X);
  auto uv = u.getLocalViewHost(Tpetra::Access::ReadOnly);
  std::vector<double> mine(3 * owned_vertices_.size());
  for (std::size_t k = 0; k < owned_vertices_.size(); ++k)
    for (int d = 0; d < 3; ++d) mine[3 * k + d] = X(owned_vertices_[k], d) + uv(3 * owned_vertices_[k] + d, 0);
  int P = 1;
  MPI_Comm_size(comm_, &P);
  std::vector<int> counts(P), offsets(P);
  for (int r = 0; root_ && r < P; ++r) {
    counts[r] = 3 * counts_[r];
    offsets[r] = 3 * offsets_[r];
  }
  std::vector<double> x(root_ ? 3 * n_vertices_ : 0);
  MPI_Gatherv(mine.data(), static_cast<int>(mine.size()), MPI_DOUBLE, x.data(), counts.data(), offsets.data(), MPI_DOUBLE, 0, comm_);
  collectively(comm_, [&] {
    if (root_) write_obj_file(path, x, triangles_, comment);
  });
}

}  // namespace sinew
