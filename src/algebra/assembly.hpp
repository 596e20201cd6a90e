// Internal: the typed entry points of the element kernels, one translation unit per element type so
// that the per-model instantiations compile in parallel.
#pragma once

#include <sinew/algebra/elastic_system.hpp>
#include <sinew/discretization/element_kernels.hpp>

#include <Tpetra_CrsMatrix_decl.hpp>

namespace sinew::detail {

using LocalMatrix = CrsMatrix::local_matrix_device_type;
using Views = AssemblyViews<LocalMatrix>;

template <class Exec>
AssemblyTotals assemble_hex8(const MaterialSpec& spec, const Views& v, int n_elements);
template <class Exec>
AssemblyTotals assemble_tet4(const MaterialSpec& spec, const Views& v, int n_elements);

template <class Exec, int NPE, int NQP>
AssemblyTotals assemble_with(const MaterialSpec& spec, const Views& v, int n_elements) {
  return with_material(spec, [&](auto model) {
    ElasticKernel<decltype(model), NPE, NQP, LocalMatrix> kernel{model, v};
    AssemblyTotals t;
    Kokkos::parallel_reduce("sinew::element_kernel", Kokkos::RangePolicy<Exec>(0, n_elements), kernel, t);
    return t;
  });
}

}  // namespace sinew::detail

// Explicit instantiation for the default execution space and, when it differs, Serial.
#if defined(KOKKOS_ENABLE_SERIAL)
#define SINEW_INSTANTIATE_SERIAL(fn)                                                                    \
  template sinew::AssemblyTotals fn<Kokkos::Serial>(const sinew::MaterialSpec&, const sinew::detail::Views&, int);
#else
#define SINEW_INSTANTIATE_SERIAL(fn)
#endif
