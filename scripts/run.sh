#!/usr/bin/env bash
# Build Sinew if needed, then run one scene.
# Usage: scripts/run.sh [--deps-cache DIR] [--np RANKS] [--threads T] SCENE.xml [sinew options]
#   --np RANKS    MPI ranks (default 1; with more, each rank gets --threads threads)
#   --threads T   OpenMP threads per rank (default: all cores / ranks)
set -euo pipefail
here=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
repo=$(cd "$here/.." && pwd)
build_args=()
np=1
threads=
while [ $# -gt 0 ]; do
  case "$1" in
    --deps-cache|--build-dir|--build-type|--trilinos-dir) build_args+=("$1" "${2:?$1 needs a value}"); shift 2 ;;
    --no-apt) build_args+=("$1"); shift ;;
    --np) np=${2:?}; shift 2 ;;
    --threads) threads=${2:?}; shift 2 ;;
    -h|--help) sed -n '2,5p' "$0"; exit 0 ;;
    *) break ;;
  esac
done
[ $# -ge 1 ] || { sed -n '2,5p' "$0" >&2; exit 2; }
"$here/build.sh" "${build_args[@]}" >&2
build_dir=${SINEW_BUILD_DIR:-$repo/build}
for ((i = 0; i < ${#build_args[@]}; i++)); do
  [ "${build_args[$i]}" = --build-dir ] && build_dir=${build_args[$((i + 1))]}
done
[ -n "$threads" ] || threads=$(( $(nproc) / np > 0 ? $(nproc) / np : 1 ))
export OMP_NUM_THREADS=$threads OMP_PROC_BIND=spread OMP_PLACES=threads
if [ "$np" -eq 1 ]; then
  exec "$build_dir/sinew" "$@"
fi
mpi_flags=(--oversubscribe)
[ "$(id -u)" -eq 0 ] && mpi_flags+=(--allow-run-as-root)
# One core per rank unless a rank has several threads: then let the threads spread.
[ "$threads" -gt 1 ] && mpi_flags+=(--bind-to none)
exec mpirun "${mpi_flags[@]}" -np "$np" "$build_dir/sinew" "$@"
