#!/usr/bin/env bash
# Configure and build Sinew (and its tests and benchmarks), provisioning dependencies first.
# Usage: scripts/build.sh [--deps-cache DIR] [--build-dir DIR] [--build-type Release|Debug|RelWithDebInfo]
#                         [--trilinos-dir DIR] [--no-apt] [-- extra cmake arguments]
#   --deps-cache DIR    folder with the prebuilt Trilinos archive (see scripts/deps.sh); without it,
#                       and with no Trilinos in .deps/ yet, Trilinos is built from Debian's source (~40 min)
#   --trilinos-dir DIR  use this Trilinos (its lib/cmake/Trilinos folder) instead of provisioning one
set -euo pipefail
here=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
repo=$(cd "$here/.." && pwd)
build_dir=${SINEW_BUILD_DIR:-$repo/build}
build_type=Release
trilinos_dir=
deps_args=()
cmake_extra=()
cmake_cache=()
while [ $# -gt 0 ]; do
  case "$1" in
    --deps-cache) deps_args+=(--deps-cache "${2:?--deps-cache needs a directory}")
                  cmake_cache=(-DSINEW_DEPS_CACHE="$(cd "$2" && pwd)"); shift 2 ;;
    --no-apt) deps_args+=(--no-apt); shift ;;
    --build-dir) build_dir=${2:?}; shift 2 ;;
    --build-type) build_type=${2:?}; shift 2 ;;
    --trilinos-dir) trilinos_dir=${2:?}; shift 2 ;;
    --) shift; cmake_extra=("$@"); break ;;
    -h|--help) sed -n '2,8p' "$0"; exit 0 ;;
    *) echo "build.sh: unknown argument '$1' (see --help)" >&2; exit 2 ;;
  esac
done
if [ -z "$trilinos_dir" ]; then
  trilinos_dir=$("$here/deps.sh" "${deps_args[@]}" | tail -n 1)
fi
jobs=${JOBS:-2}
launcher=()
command -v ccache >/dev/null 2>&1 && launcher=(-DCMAKE_CXX_COMPILER_LAUNCHER=ccache)
t0=$SECONDS
mkdir -p "$build_dir"
cmake -S "$repo" -B "$build_dir" -G Ninja -DCMAKE_BUILD_TYPE="$build_type" \
  -DTrilinos_DIR="$trilinos_dir" "${launcher[@]}" "${cmake_cache[@]}" "${cmake_extra[@]}" >"$build_dir/configure.log" 2>&1 \
  || { cat "$build_dir/configure.log" >&2; exit 1; }
cmake --build "$build_dir" -j "$jobs"
echo "[build] $build_dir ready ($(( SECONDS - t0 )) s)" >&2
