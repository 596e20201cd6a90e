#include "assembly.hpp"

namespace sinew::detail {
template <class Exec>
AssemblyTotals assemble_tet4(const MaterialSpec& spec, const Views& v, int n_elements) {
  return assemble_with<Exec, 4, 1>(spec, v, n_elements);
}
template AssemblyTotals assemble_tet4<Kokkos::DefaultExecutionSpace>(const MaterialSpec&, const Views&, int);
}  // namespace sinew::detail
#if !defined(KOKKOS_ENABLE_SERIAL) || !defined(KOKKOS_ENABLE_OPENMP)
// Serial is the default execution space, already instantiated.
#else
SINEW_INSTANTIATE_SERIAL(sinew::detail::assemble_tet4)
#endif
