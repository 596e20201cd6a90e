#!/usr/bin/env bash
# Build Sinew with its tests, then run the whole CTest suite (unit, OpenMP 2-thread and 2-rank MPI tests).
# Usage: scripts/test.sh [--deps-cache DIR] [build.sh options] [-- ctest options, e.g. -L unit]
set -euo pipefail
here=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
repo=$(cd "$here/.." && pwd)
build_args=()
ctest_args=()
while [ $# -gt 0 ]; do
  case "$1" in
    --) shift; ctest_args=("$@"); break ;;
    --no-apt) build_args+=("$1"); shift ;;
    -h|--help) sed -n '2,3p' "$0"; exit 0 ;;
    *) build_args+=("$1" "${2:?$1 needs a value}"); shift 2 ;;
  esac
done
"$here/build.sh" "${build_args[@]}"
build_dir=${SINEW_BUILD_DIR:-$repo/build}
for ((i = 0; i < ${#build_args[@]}; i++)); do
  [ "${build_args[$i]}" = --build-dir ] && build_dir=${build_args[$((i + 1))]}
done
cd "$build_dir"
ctest --output-on-failure -j "${JOBS:-2}" "${ctest_args[@]}"
