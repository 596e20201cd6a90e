// Internal: the typed entry points of the element loop on Tpetra's local objects, one translation unit
// per element type so that the per-model instantiations compile in parallel.
#pragma once

#include <sinew/algebra/energy_term.hpp>
#include <sinew/discretization/element_kernel.hpp>
#include <sinew/materials/models.hpp>

#include <Tpetra_CrsMatrix_decl.hpp>

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

// With chunks, one launch per colour and plain adds; without (or on a device, where a chunk per thread
// would leave it idle), one element per work item and atomic adds.
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
    constexpr bool host = Kokkos::SpaceAccessibility<Kokkos::HostSpace, typename Exec::memory_space>::accessible;
    if (!host || chunks.offsets.extent(0) == 0) {
      AssemblyTotals t;
      Kokkos::parallel_reduce("sinew::element_loop", Kokkos::RangePolicy<Exec>(0, static_cast<int>(elements.extent(0))), loop, t);
      return t;
    }
    loop.chunks = chunks.offsets;
    loop.target.atomic = false;
    AssemblyTotals t;
    loop.init(t);  // the reduction's identity: the colours' totals are joined here
    for (std::size_t k = 0; k + 1 < chunks.colour_begin.size(); ++k) {
      loop.chunk_first = chunks.colour_begin[k];
      AssemblyTotals tk;
      Kokkos::parallel_reduce("sinew::element_loop_coloured", Kokkos::RangePolicy<Exec>(0, chunks.colour_begin[k + 1] - chunks.colour_begin[k]),
                              loop, tk);
      t.add(tk);
    }
    return t;
  });
}

}  // namespace sinew::detail

// Instantiations: the default execution space, and Serial when it differs (the backend comparison).
#define SINEW_INSTANTIATE_ASSEMBLY(fn, Exec)                                                                          \
  template sinew::AssemblyTotals fn<Exec>(const sinew::MaterialSpec&, sinew::Projection,                             \
                                          const Kokkos::View<const int*, sinew::detail::MemorySpace>&, \
                                          const sinew::detail::Chunks&, const sinew::detail::AssemblyRequest&);
