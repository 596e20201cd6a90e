// The tet4 element loop, instantiated for every material model (see assembly.hpp).
#include "assembly.hpp"

namespace sinew::detail {
template <class Exec>
AssemblyTotals assemble_tet4(const MaterialSpec& law, Projection projection, const Kokkos::View<const int*, MemorySpace>& elements,
                             const Chunks& chunks, const AssemblyRequest& r) {
  return assemble_with<Exec, Tet4>(law, projection, elements, chunks, r);
}
}  // namespace sinew::detail

SINEW_INSTANTIATE_ASSEMBLY(sinew::detail::assemble_tet4, Kokkos::DefaultExecutionSpace)
#if defined(KOKKOS_ENABLE_SERIAL) && defined(KOKKOS_ENABLE_OPENMP)
SINEW_INSTANTIATE_ASSEMBLY(sinew::detail::assemble_tet4, Kokkos::Serial)
#endif
