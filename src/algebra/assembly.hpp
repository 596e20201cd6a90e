// Internal: the typed entry points of the element loop on Tpetra's local objects, one translation unit
// per element type so that the per-model instantiations compile in parallel.
#pragma once

#include <sinew/algebra/energy_term.hpp>
#include <sinew/discretization/element_kernel.hpp>
#include <sinew/discretization/colouring.hpp>
#include <sinew/materials/models.hpp>

#include <Tpetra_CrsMatrix_decl.hpp>

#include <algorithm>
#include <cstdlib>
#include <string>
#include <vector>

namespace sinew::detail {

using MemorySpace = DeviceMemory;
using Target = CrsTarget<LocalMatrix, Kokkos::View<double*, MemorySpace>>;

// Everything one evaluation reads and writes, whatever the law.
struct AssemblyRequest {
  ElementGeometry<MemorySpace> geometry;
  Kokkos::View<const double*, MemorySpace> u;
  Target target;
  bool want_force = false, want_matrix = false;
  ElementFields<MemorySpace> fields;
};

// How `elements` is cut into coloured chunks (discretization/colouring.hpp); offsets empty: none.
struct Chunks {
  Kokkos::View<const int*, MemorySpace> offsets;
  const std::vector<int>& colour_begin;
};

// The element loop over `elements` (local ids, all of one law) on execution space Exec.
template <class Exec>
AssemblyTotals assemble_hex8(const MaterialSpec& law, Projection projection, const Kokkos::View<const int*, MemorySpace>& elements,
                             const Chunks& chunks, const AssemblyRequest& r);
template <class Exec>
AssemblyTotals assemble_tet4(const MaterialSpec& law, Projection projection, const Kokkos::View<const int*, MemorySpace>& elements,
                             const Chunks& chunks, const AssemblyRequest& r);

// The chunk size of the coloured element loops: 32 elements, measured in docs/performance.md
// (SINEW_ASSEMBLY_CHUNK overrides it for benchmarks; 0 gives one element per work item with atomic adds,
// the device's way).
inline int assembly_chunk_size() {
  int chunk = 32;
  if (const char* env = std::getenv("SINEW_ASSEMBLY_CHUNK")) chunk = std::max(0, std::atoi(env));
  return chunk;
}

// The local elements' nodes on the host, row-major element x node (what the colouring reads).
inline std::vector<int> host_connectivity(const Mesh& mesh) {
  auto c = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), mesh.conn);
  const int npe = nodes_per_element(mesh.type);
  std::vector<int> conn(mesh.local_elements() * npe);
  for (std::size_t e = 0; e < mesh.local_elements(); ++e)
    for (int a = 0; a < npe; ++a) conn[e * npe + a] = c(e, a);
  return conn;
}

inline Kokkos::View<int*> int_view(const std::string& label, const std::vector<int>& v) {
  Kokkos::View<int*> d(label, v.size());
  auto h = Kokkos::create_mirror_view(d);
  for (std::size_t k = 0; k < v.size(); ++k) h(k) = v[k];
  Kokkos::deep_copy(d, h);
  return d;
}

// A list of local elements in the order a loop visits them: in coloured chunks of `chunk` elements
// (discretization/colouring.hpp; `conn` from host_connectivity), or as given when chunk is 0 (no chunks:
// one element per work item). elements(k) is ids[position[k]], for data that travels with the elements.
struct ElementOrder {
  Kokkos::View<int*> elements, chunks;
  std::vector<int> colour_begin, position;
};
inline ElementOrder order_elements(const std::vector<int>& ids, const Mesh& mesh, const std::vector<int>& conn, int chunk) {
  ElementOrder o;
  std::vector<int> order = ids;
  if (chunk > 0) {
    ElementChunks c = colour_element_chunks(ids, conn, nodes_per_element(mesh.type), mesh.local_nodes(), chunk);
    order = c.elements;
    o.chunks = int_view("element chunks", c.chunk_begin);
    o.colour_begin = c.colour_begin;
  }
  std::vector<int> at(mesh.local_elements(), -1);
  for (std::size_t k = 0; k < ids.size(); ++k) at[ids[k]] = static_cast<int>(k);
  for (int e : order) o.position.push_back(at[e]);
  o.elements = int_view("elements", order);
  return o;
}

// Runs an element loop (ElementLoop, or a term's own with the same chunks, chunk_first, target,
// init and join) over n elements. With chunks, one launch per colour and plain adds; without (or on a
// device, where a chunk per thread would leave it idle), one element per work item and atomic adds.
template <class Exec, class Loop>
typename Loop::value_type run_element_loop(Loop loop, int n, const Chunks& chunks) {
  constexpr bool host = Kokkos::SpaceAccessibility<Kokkos::HostSpace, typename Exec::memory_space>::accessible;
  typename Loop::value_type t;
  if (!host || chunks.offsets.extent(0) == 0) {
    Kokkos::parallel_reduce("sinew::element_loop", Kokkos::RangePolicy<Exec>(0, n), loop, t);
    return t;
  }
  loop.chunks = chunks.offsets;
  loop.target.atomic = false;
  loop.init(t);  // the reduction's identity: the colours' totals are joined here
  for (std::size_t k = 0; k + 1 < chunks.colour_begin.size(); ++k) {
    loop.chunk_first = chunks.colour_begin[k];
    typename Loop::value_type tk;
    Kokkos::parallel_reduce("sinew::element_loop_coloured", Kokkos::RangePolicy<Exec>(0, chunks.colour_begin[k + 1] - chunks.colour_begin[k]),
                            loop, tk);
    loop.join(t, tk);
  }
  return t;
}

template <class Exec, class Element>
AssemblyTotals assemble_with(const MaterialSpec& law, Projection projection, const Kokkos::View<const int*, MemorySpace>& elements,
                             const Chunks& chunks, const AssemblyRequest& r) {
  return with_material(law, [&](auto model) {
    ElementLoop<Element, decltype(model), Target> loop;
    loop.model = model;
    loop.projection = projection;
    loop.geometry = r.geometry;
    loop.elements = elements;
    loop.u = r.u;
    loop.target = r.target;
    loop.want_force = r.want_force;
    loop.want_matrix = r.want_matrix;
    loop.mean_dilatation = law.mean_dilatation;
    loop.fields = r.fields;
    return run_element_loop<Exec>(loop, static_cast<int>(elements.extent(0)), chunks);
  });
}

}  // namespace sinew::detail

// Instantiations: the default execution space, and Serial when it differs (the backend comparison).
#define SINEW_INSTANTIATE_ASSEMBLY(fn, Exec)                                                                          \
  template sinew::AssemblyTotals fn<Exec>(const sinew::MaterialSpec&, sinew::Projection,                             \
                                          const Kokkos::View<const int*, sinew::detail::MemorySpace>&, \
                                          const sinew::detail::Chunks&, const sinew::detail::AssemblyRequest&);
