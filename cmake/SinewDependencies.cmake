# Finds Trilinos (with its Kokkos), MPI and parallel HDF5 and wraps them as imported targets:
#   sinew::kokkos    Kokkos only (for header-only material code and light tests)
#   sinew::trilinos  every Trilinos package Sinew uses
#   sinew::hdf5      parallel HDF5 (C API)
#   assimp::assimp   Assimp 5.2 (Debian's libassimp-dev, BSD-3): rigged characters
# Stops at configure time when Kokkos lacks the OpenMP backend, unless SINEW_ALLOW_SERIAL_ONLY.

find_package(MPI REQUIRED COMPONENTS C CXX)

set(_sinew_trilinos_components
  Kokkos KokkosKernels Teuchos Tpetra Belos Ifpack2 Amesos2 MueLu Xpetra NOX Thyra Stratimikos Zoltan2)
find_package(Trilinos 13.2 REQUIRED COMPONENTS ${_sinew_trilinos_components})
message(STATUS "Trilinos ${Trilinos_VERSION} from ${Trilinos_DIR}")

# Which Kokkos backends did this Trilinos compile in? Read them from Kokkos' own config header:
# the header is what our code sees, whatever the CMake variables of a given packaging say.
find_file(SINEW_KOKKOS_CONFIG_H KokkosCore_config.h PATHS ${Trilinos_INCLUDE_DIRS} NO_DEFAULT_PATH)
if(NOT SINEW_KOKKOS_CONFIG_H)
  message(FATAL_ERROR "Sinew: KokkosCore_config.h not found in Trilinos' include dirs (${Trilinos_INCLUDE_DIRS}).")
endif()
file(STRINGS ${SINEW_KOKKOS_CONFIG_H} _kokkos_backend_lines REGEX "^#define KOKKOS_ENABLE_(SERIAL|OPENMP|CUDA|THREADS)$")
set(SINEW_KOKKOS_BACKENDS "")
foreach(_l IN LISTS _kokkos_backend_lines)
  string(REGEX REPLACE "^#define KOKKOS_ENABLE_" "" _b "${_l}")
  list(APPEND SINEW_KOKKOS_BACKENDS ${_b})
endforeach()
message(STATUS "Kokkos backends in this Trilinos: ${SINEW_KOKKOS_BACKENDS}")
if(NOT "OPENMP" IN_LIST SINEW_KOKKOS_BACKENDS)
  if(SINEW_ALLOW_SERIAL_ONLY)
    message(WARNING "Sinew: this Trilinos' Kokkos has no OpenMP backend (${SINEW_KOKKOS_BACKENDS}); "
                    "building a Serial-only Sinew because SINEW_ALLOW_SERIAL_ONLY is ON.")
  else()
    message(FATAL_ERROR
      "Sinew: the Trilinos at ${Trilinos_DIR} was built without Kokkos OpenMP "
      "(backends: ${SINEW_KOKKOS_BACKENDS}). Debian's own Trilinos packages are Serial-only. "
      "Use scripts/deps.sh to provision Trilinos 13.2 with OpenMP, or configure with "
      "-DSINEW_ALLOW_SERIAL_ONLY=ON to build a Serial-only Sinew on purpose.")
  endif()
endif()

add_library(sinew::kokkos INTERFACE IMPORTED)
# Trilinos exports plain target names (kokkoscore, tpetra, ...); the Kokkos target carries -fopenmp.
target_link_libraries(sinew::kokkos INTERFACE kokkoscore kokkoscontainers)
target_include_directories(sinew::kokkos SYSTEM INTERFACE ${Trilinos_INCLUDE_DIRS} ${Trilinos_TPL_INCLUDE_DIRS})
if("OPENMP" IN_LIST SINEW_KOKKOS_BACKENDS)
  find_package(OpenMP REQUIRED COMPONENTS CXX)
  target_link_libraries(sinew::kokkos INTERFACE OpenMP::OpenMP_CXX)
endif()

add_library(sinew::trilinos INTERFACE IMPORTED)
target_link_libraries(sinew::trilinos INTERFACE sinew::kokkos ${Trilinos_LIBRARIES} ${Trilinos_TPL_LIBRARIES} MPI::MPI_CXX)

set(HDF5_PREFER_PARALLEL TRUE)
find_package(HDF5 REQUIRED COMPONENTS C)
if(NOT HDF5_IS_PARALLEL)
  message(FATAL_ERROR "Sinew: HDF5 at ${HDF5_INCLUDE_DIRS} is not parallel; install libhdf5-openmpi-dev.")
endif()
add_library(sinew::hdf5 INTERFACE IMPORTED)
target_include_directories(sinew::hdf5 SYSTEM INTERFACE ${HDF5_INCLUDE_DIRS})
target_link_libraries(sinew::hdf5 INTERFACE ${HDF5_C_LIBRARIES} MPI::MPI_C)
target_compile_definitions(sinew::hdf5 INTERFACE ${HDF5_DEFINITIONS})

# mpirun flags for tests: oversubscription is harmless on 2 cores, and root needs an explicit opt-in.
set(SINEW_MPIEXEC ${MPIEXEC_EXECUTABLE})
set(SINEW_MPIEXEC_FLAGS --oversubscribe)
execute_process(COMMAND id -u OUTPUT_VARIABLE _uid OUTPUT_STRIP_TRAILING_WHITESPACE)
if(_uid STREQUAL "0")
  list(APPEND SINEW_MPIEXEC_FLAGS --allow-run-as-root)
endif()

# Rigged characters (glTF, FBX, COLLADA, .x, BVH): Debian's libassimp-dev (scripts/deps.sh).
find_package(assimp 5.2 REQUIRED)
