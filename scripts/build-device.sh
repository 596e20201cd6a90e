#!/usr/bin/env bash
# Builds perf/device (Sinew's material and element kernels for CUDA) with nvcc against the standalone
# CUDA Kokkos: restored from the archive in a cache folder (CI passes ../shared/deps), or built there
# from its source with the cache's recipe. Compiling needs no GPU; running needs one.
# Usage: scripts/build-device.sh [--deps-cache DIR] [--build-dir DIR] [--arch HOPPER90]
# Prints the program's path on its last line.
set -euo pipefail
here=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
repo=$(cd "$here/.." && pwd)
cache=${SINEW_DEPS_CACHE:-}
build=$repo/build-device
arch=HOPPER90
while [ $# -gt 0 ]; do
  case "$1" in
    --deps-cache) cache=${2:?--deps-cache needs a folder}; shift 2 ;;
    --build-dir) build=${2:?--build-dir needs a folder}; shift 2 ;;
    --arch) arch=${2:?--arch needs a Kokkos architecture}; shift 2 ;;
    -h|--help) sed -n '2,6p' "$0"; exit 0 ;;
    *) echo "build-device.sh: unknown argument '$1'" >&2; exit 2 ;;
  esac
done
log() { printf '[device] %s\n' "$*" >&2; }
export CUDA_HOME=${CUDA_HOME:-/usr/local/cuda}
export PATH=$CUDA_HOME/bin:$PATH
export LIBRARY_PATH=$CUDA_HOME/lib64/stubs${LIBRARY_PATH:+:$LIBRARY_PATH}  # libcuda stub: link without a driver
command -v nvcc >/dev/null || { log "nvcc not found in $CUDA_HOME/bin: the CUDA toolkit is needed"; exit 3; }
prefix=$repo/.deps
kokkos=$prefix/kokkos-cuda
archive=kokkos-4.6.99-cuda13-sm90-openmp-install.tar.xz
if [ ! -f "$kokkos/lib/cmake/Kokkos/KokkosConfig.cmake" ] && [ ! -f "$kokkos/lib64/cmake/Kokkos/KokkosConfig.cmake" ]; then
  mkdir -p "$prefix"
  if [ -n "$cache" ] && [ -f "$cache/$archive" ] && [ "$arch" = HOPPER90 ]; then
    log "restoring the CUDA Kokkos from $cache/$archive"
    echo "f70627f6b3fcee5db8697de8b798adbe516c5736319e7449047d7bd090c8d23d  $cache/$archive" | sha256sum -c --quiet -
    tar -xJf "$cache/$archive" -C "$prefix"
  elif [ -n "$cache" ] && [ -x "$cache/build-kokkos-cuda.sh" ]; then
    log "building the CUDA Kokkos for $arch with $cache/build-kokkos-cuda.sh (about 6 minutes on 2 cores)"
    (cd "$cache" && ./build-kokkos-cuda.sh "$kokkos" "$arch")
  else
    log "no CUDA Kokkos: pass --deps-cache DIR with $archive or build-kokkos-cuda.sh (see ../shared/deps/README.md)"
    exit 3
  fi
fi
cmake_dir=$(dirname "$(find "$kokkos" -name KokkosConfig.cmake | head -1)")
command -v ccache >/dev/null && launcher=(-DCMAKE_CXX_COMPILER_LAUNCHER=ccache) || launcher=()
cmake -S "$repo/perf/device" -B "$build" -G Ninja -DCMAKE_BUILD_TYPE=Release -DKokkos_DIR="$cmake_dir" \
  -DCMAKE_CXX_COMPILER="$kokkos/bin/nvcc_wrapper" "${launcher[@]}" >/dev/null
t0=$SECONDS
cmake --build "$build" -j "${JOBS:-2}"
log "compiled for CUDA ($arch) in $((SECONDS - t0)) s"
echo "$build/device_kernels"
