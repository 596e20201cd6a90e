// Internal: the typed entry points of the element loop on Tpetra's local objects, one translation unit
// per element type so that the per-model instantiations compile in parallel.
#pragma once

#include <sinew/algebra/energy_term.hpp>
#include <sinew/discretization/element_kernel.hpp>
#include <sinew/materials/models.hpp>

#include <Tpetra_CrsMatrix_decl.hpp>

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

// The element loop over `elements` (local ids, all of one law) on execution space Exec.
template <class Exec>
AssemblyTotals assemble_hex8(const MaterialSpec& law, Projection projection, const Kokkos::View<const int*, MemorySpace>& elements,
                             const AssemblyRequest& r);
template <class Exec>
AssemblyTotals assemble_tet4(const MaterialSpec& law, Projection projection, const Kokkos::View<const int*, MemorySpace>& elements,
                             const AssemblyRequest& r);

template <class Exec, class Element>
AssemblyTotals assemble_with(const MaterialSpec& law, Projection projection, const Kokkos::View<const int*, MemorySpace>& elements,
                             const AssemblyRequest& r) {
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
    AssemblyTotals t;
    Kokkos::parallel_reduce("sinew::element_loop", Kokkos::RangePolicy<Exec>(0, static_cast<int>(elements.extent(0))), loop, t);
    return t;
  });
}

}  // namespace sinew::detail

// Instantiations: the default execution space, and Serial when it differs (the backend comparison).
#define SINEW_INSTANTIATE_ASSEMBLY(fn, Exec)                                                                          \
  template sinew::AssemblyTotals fn<Exec>(const sinew::MaterialSpec&, sinew::Projection,                             \
                                          const Kokkos::View<const int*, sinew::detail::MemorySpace>&, \
                                          const sinew::detail::AssemblyRequest&);
