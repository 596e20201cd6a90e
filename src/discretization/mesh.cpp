// Lattice meshes: the extruded 2D mask (box, voxelized cylinder), its z-slab distribution with one ghost
// layer, hex8 or Kuhn-split tet4 cells, node selection by predicate.
#include <sinew/core/errors.hpp>
#include <sinew/core/hash.hpp>
#include <sinew/discretization/mesh.hpp>

#include <sinew/core/collective.hpp>

#include <algorithm>

#include <cmath>
#include <sstream>

namespace sinew {

std::string to_string(ElementType t) { return t == ElementType::Hex8 ? "hex8" : "tet4"; }

std::string to_string(MeshType t) {
  for (const auto& [name, value] : mesh_type_choices())
    if (value == t) return name;
  return "?";
}

MeshSpec lattice_spec(const MeshParameters& p) {
  MeshSpec s;
  s.shape = p.type;
  s.element = p.element;
  s.cells = p.cells;
  s.jitter = p.jitter;
  s.jitter_seed = p.jitter_seed;
  if (p.type == MeshType::Box) {
    s.lower = p.lower;
    s.upper = p.upper;
  } else {
    s.lower = {-p.radius, -p.radius, 0.0};
    s.upper = {p.radius, p.radius, p.length};
  }
  return s;
}

namespace {

// Active cells and nodes of one x-y layer, with compact numbering.
struct Pattern {
  int nx = 0, ny = 0;
  std::vector<int> cell_index;  // nx*ny, -1 where inactive
  std::vector<int> node_index;  // (nx+1)*(ny+1), -1 where no active cell touches the node
  int cells = 0, nodes = 0;
  int node(int i, int j) const { return node_index[i + (nx + 1) * j]; }
};

Pattern make_pattern(const MeshSpec& s) {
  Pattern p;
  p.nx = s.cells[0];
  p.ny = s.cells[1];
  p.cell_index.assign(static_cast<std::size_t>(p.nx) * p.ny, -1);
  p.node_index.assign(static_cast<std::size_t>(p.nx + 1) * (p.ny + 1), -1);
  for (int j = 0; j < p.ny; ++j) {
    for (int i = 0; i < p.nx; ++i) {
      bool active = true;
      if (s.shape == MeshType::Cylinder) {  // cell centre inside the inscribed ellipse of the x-y box
        const double u = (i + 0.5) / p.nx * 2.0 - 1.0, v = (j + 0.5) / p.ny * 2.0 - 1.0;
        active = u * u + v * v <= 1.0;
      }
      if (active) p.cell_index[i + p.nx * j] = 0;
    }
  }
  for (int j = 0; j < p.ny; ++j)
    for (int i = 0; i < p.nx; ++i) {
      int& c = p.cell_index[i + p.nx * j];
      if (c < 0) continue;
      c = p.cells++;
      for (int dj = 0; dj < 2; ++dj)
        for (int di = 0; di < 2; ++di) p.node_index[(i + di) + (p.nx + 1) * (j + dj)] = 0;
    }
  for (auto& n : p.node_index)
    if (n >= 0) n = p.nodes++;
  return p;
}

}  // namespace

Mesh build_mesh(const MeshSpec& spec, const Teuchos::Comm<int>& comm) {
  const int P = comm.getSize(), r = comm.getRank();
  const int nz = spec.cells[2];
  if (nz < P)
    throw InputError("Mesh: " + std::to_string(nz) + " element layers along z cannot be split over " +
                     std::to_string(P) + " MPI ranks (need at least one layer per rank)",
                     InputErrorKind::BadMesh);
  const Pattern pat = make_pattern(spec);
  if (pat.cells == 0) throw InputError("Mesh: the shape has no active cells; increase 'Elements'", InputErrorKind::BadMesh);

  Mesh m;
  m.type = spec.element;
  m.lower = spec.lower;
  m.upper = spec.upper;
  m.global_nodes = static_cast<GlobalId>(pat.nodes) * (nz + 1);
  const GlobalId hexes = static_cast<GlobalId>(pat.cells) * nz;
  m.global_elements = spec.element == ElementType::Hex8 ? hexes : 6 * hexes;

  const int k0 = static_cast<int>(static_cast<long long>(r) * nz / P);
  const int k1 = static_cast<int>(static_cast<long long>(r + 1) * nz / P);
  const bool last = r == P - 1;
  // Node layers: owned [k0, k1) (and nz on the last rank); ghosts k0-1 (below) and k1 (above).
  std::vector<int> layers;
  for (int k = k0; k < k1; ++k) layers.push_back(k);
  if (last) layers.push_back(nz);
  const std::size_t owned_layers = layers.size();
  if (r > 0) layers.push_back(k0 - 1);
  if (!last) layers.push_back(k1);
  std::vector<int> layer_slot(nz + 1, -1);
  for (std::size_t s = 0; s < layers.size(); ++s) layer_slot[layers[s]] = static_cast<int>(s);

  const std::size_t nloc = layers.size() * pat.nodes;
  m.node_gid.resize(nloc);
  // Ghost layers: k0 - 1 belongs to the rank below, k1 to the rank above.
  m.node_owner.assign(nloc, r);
  for (std::size_t s = owned_layers; s < layers.size(); ++s)
    for (int n2 = 0; n2 < pat.nodes; ++n2) m.node_owner[s * pat.nodes + n2] = layers[s] < k0 ? r - 1 : r + 1;
  m.n_owned_nodes = owned_layers * pat.nodes;
  m.X = Kokkos::View<double* [3]>("X", nloc);
  auto Xh = Kokkos::create_mirror_view(m.X);
  const double dx[3] = {(spec.upper[0] - spec.lower[0]) / spec.cells[0], (spec.upper[1] - spec.lower[1]) / spec.cells[1],
                        (spec.upper[2] - spec.lower[2]) / nz};
  for (std::size_t s = 0; s < layers.size(); ++s) {
    const int k = layers[s];
    for (int j = 0; j <= pat.ny; ++j)
      for (int i = 0; i <= pat.nx; ++i) {
        const int n2 = pat.node(i, j);
        if (n2 < 0) continue;
        const std::size_t l = s * pat.nodes + n2;
        m.node_gid[l] = static_cast<GlobalId>(k) * pat.nodes + n2;
        Xh(l, 0) = spec.lower[0] + i * dx[0];
        Xh(l, 1) = spec.lower[1] + j * dx[1];
        Xh(l, 2) = spec.lower[2] + k * dx[2];
        const bool on_box = i == 0 || i == pat.nx || j == 0 || j == pat.ny || k == 0 || k == nz;
        if (spec.jitter > 0.0 && !on_box) {
          for (int d = 0; d < 3; ++d)  // deterministic in the global id: the same on every rank
            Xh(l, d) += spec.jitter * dx[d] * (2.0 * unit_hash(m.node_gid[l], d, spec.jitter_seed) - 1.0);
        }
      }
  }
  Kokkos::deep_copy(m.X, Xh);
  auto local_node = [&](int i, int j, int k) { return layer_slot[k] * pat.nodes + pat.node(i, j); };

  // Element layers: owned [k0, k1), ghost k0-1.
  std::vector<int> elayers;
  for (int k = k0; k < k1; ++k) elayers.push_back(k);
  const std::size_t owned_elayers = elayers.size();
  if (r > 0) elayers.push_back(k0 - 1);
  const int per_hex = spec.element == ElementType::Hex8 ? 1 : 6;
  const int npe = nodes_per_element(spec.element);
  const std::size_t ne = elayers.size() * pat.cells * per_hex;
  m.n_owned_elements = owned_elayers * pat.cells * per_hex;
  m.element_gid.resize(ne);
  m.conn = Kokkos::View<int**>("conn", ne, npe);
  auto Ch = Kokkos::create_mirror_view(m.conn);
  std::size_t e = 0;
  for (int k : elayers) {
    for (int j = 0; j < pat.ny; ++j)
      for (int i = 0; i < pat.nx; ++i) {
        const int c2 = pat.cell_index[i + pat.nx * j];
        if (c2 < 0) continue;
        const int hex[8] = {local_node(i, j, k),         local_node(i + 1, j, k),     local_node(i + 1, j + 1, k),
                            local_node(i, j + 1, k),     local_node(i, j, k + 1),     local_node(i + 1, j, k + 1),
                            local_node(i + 1, j + 1, k + 1), local_node(i, j + 1, k + 1)};
        const GlobalId hex_gid = static_cast<GlobalId>(k) * pat.cells + c2;
        if (spec.element == ElementType::Hex8) {
          for (int a = 0; a < 8; ++a) Ch(e, a) = hex[a];
          m.element_gid[e++] = hex_gid;
        } else {
          for (int t = 0; t < 6; ++t) {
            for (int a = 0; a < 4; ++a) Ch(e, a) = hex[kHexTets[t][a]];
            m.element_gid[e++] = 6 * hex_gid + t;
          }
        }
      }
  }
  Kokkos::deep_copy(m.conn, Ch);
  m.source = to_string(spec.shape) + " lattice";
  number_for_output(m, comm);
  return m;
}

void number_for_output(Mesh& m, const Teuchos::Comm<int>& comm) {
  MPI_Comm c = raw_comm(comm);
  long long counts[2] = {static_cast<long long>(m.n_owned_nodes), static_cast<long long>(m.n_owned_elements)}, first[2] = {0, 0};
  MPI_Exscan(counts, first, 2, MPI_LONG_LONG, MPI_SUM, c);
  int rank = 0, P = 1;
  MPI_Comm_rank(c, &rank);
  MPI_Comm_size(c, &P);
  if (rank == 0) first[0] = first[1] = 0;  // MPI_Exscan leaves rank 0's result undefined
  m.first_output_node = first[0];
  m.first_output_element = first[1];
  m.node_output_id.assign(m.local_nodes(), -1);
  for (std::size_t n = 0; n < m.n_owned_nodes; ++n) m.node_output_id[n] = first[0] + static_cast<GlobalId>(n);
  // Ghosts: ask each owner for the row of each of its nodes (owned nodes are sorted by global id).
  std::vector<std::vector<GlobalId>> ask(P);
  for (std::size_t n = m.n_owned_nodes; n < m.local_nodes(); ++n) ask[m.node_owner[n]].push_back(m.node_gid[n]);
  const auto asked = alltoallv(c, ask);
  std::vector<std::vector<GlobalId>> answer(P);
  const auto owned_end = m.node_gid.begin() + static_cast<std::ptrdiff_t>(m.n_owned_nodes);
  for (int r = 0; r < P; ++r)
    for (GlobalId g : asked[r]) {
      const auto it = std::lower_bound(m.node_gid.begin(), owned_end, g);
      if (it == owned_end || *it != g) throw std::logic_error("number_for_output: a ghost's owner does not own it");
      answer[r].push_back(first[0] + (it - m.node_gid.begin()));
    }
  const auto answered = alltoallv(c, answer);
  std::vector<std::size_t> next(P, 0);
  for (std::size_t n = m.n_owned_nodes; n < m.local_nodes(); ++n) {
    const int o = m.node_owner[n];
    m.node_output_id[n] = answered[o][next[o]++];
  }
}

std::vector<int> select_nodes(const Mesh& mesh, const std::function<bool(const std::array<double, 3>&)>& pred) {
  auto Xh = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), mesh.X);
  std::vector<int> out;
  for (std::size_t n = 0; n < mesh.local_nodes(); ++n)
    if (pred({Xh(n, 0), Xh(n, 1), Xh(n, 2)})) out.push_back(static_cast<int>(n));
  return out;
}

std::function<bool(const std::array<double, 3>&)> face_predicate(const Mesh& mesh, const std::string& face) {
  if (face.size() != 2 || face[0] < 'x' || face[0] > 'z' || (face[1] != '-' && face[1] != '+'))
    throw InputError("face '" + face + "' is not one of x-, x+, y-, y+, z-, z+");
  const int axis = face[0] - 'x';
  const bool upper = face[1] == '+';
  const double target = upper ? mesh.upper[axis] : mesh.lower[axis];
  const double tol = 1e-9 * (mesh.upper[axis] - mesh.lower[axis]);
  return [=](const std::array<double, 3>& X) { return std::fabs(X[axis] - target) <= tol; };
}

}  // namespace sinew
