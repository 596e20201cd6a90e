#!/usr/bin/env bash
# Provision everything Sinew builds against, on Debian 12:
#   1. Debian packages (Open MPI, parallel HDF5, BLAS/LAPACK, GoogleTest, Google Benchmark, tools; gmsh to
#      make meshes, meshio and ParaView's Python with Xvfb to read and render results);
#   2. Trilinos 13.2 with Kokkos Serial + OpenMP, restored from a prebuilt archive found in a cache
#      directory, or built from Debian's own source package when no archive is there;
#   3. for the skin's caches (issue 43): Blender and Chromium (Debian's), and from npm into
#      <repo>/.deps/viewer the versions pinned in scripts/viewer/package-lock.json of three.js (which
#      scripts/sinew-view copies into its pages, so they work offline) and the Khronos glTF-Validator.
#
# Usage: scripts/deps.sh [--deps-cache DIR] [--prefix DIR] [--jobs N] [--no-apt]
#   --deps-cache DIR  folder holding trilinos-13.2.0-openmp-debian12-x86_64.tar.xz (CI passes ../shared/deps)
#   --prefix DIR  where Trilinos goes (default: <repo>/.deps); it ends up in DIR/trilinos-omp
#   --jobs N      parallel jobs for a source build (default: nproc)
#   --no-apt      skip the Debian package step (packages already there, or no root)
# Prints the Trilinos CMake directory on its last line (for scripts/build.sh).
set -euo pipefail

here=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
repo=$(cd "$here/.." && pwd)
cache=${SINEW_DEPS_CACHE:-}
prefix=${SINEW_DEPS_PREFIX:-$repo/.deps}
jobs=${JOBS:-$(nproc)}
do_apt=1

while [ $# -gt 0 ]; do
  case "$1" in
    --cache|--deps-cache) cache=${2:?--deps-cache needs a directory}; shift 2 ;;
    --prefix) prefix=${2:?--prefix needs a directory}; shift 2 ;;
    --jobs) jobs=${2:?--jobs needs a number}; shift 2 ;;
    --no-apt) do_apt=0; shift ;;
    -h|--help) sed -n '2,13p' "$0"; exit 0 ;;
    *) echo "deps.sh: unknown argument '$1' (see --help)" >&2; exit 2 ;;
  esac
done

archive_name=trilinos-13.2.0-openmp-debian12-x86_64.tar.xz
archive_sha256=e1b208f8c5d2249e244f293a5a53756eade1cab5f051fdb7099aa630ac03a8e9
trilinos_dir=$prefix/trilinos-omp
trilinos_cmake=$trilinos_dir/lib/cmake/Trilinos

log() { printf '[deps] %s\n' "$*" >&2; }

as_root() {
  if [ "$(id -u)" -eq 0 ]; then "$@"
  elif command -v sudo >/dev/null 2>&1; then sudo "$@"
  else log "need root for: $*  (rerun as root, or install the packages and pass --no-apt)"; exit 1
  fi
}

packages=(build-essential cmake ninja-build ccache pkg-config xz-utils
  libopenmpi-dev openmpi-bin libhdf5-openmpi-dev hdf5-tools
  libblas-dev liblapack-dev libgtest-dev libgmock-dev libbenchmark-dev
  python3 python3-numpy python3-h5py python3-matplotlib python3-pil
  gmsh python3-meshio python3-paraview xvfb xauth libassimp-dev assimp-testmodels
  blender chromium)

apt_install() {
  local missing=()
  for p in "$@"; do
    dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q 'install ok installed' || missing+=("$p")
  done
  [ ${#missing[@]} -eq 0 ] && return 0
  log "installing Debian packages: ${missing[*]}"
  export DEBIAN_FRONTEND=noninteractive
  as_root apt-get update -qq
  as_root apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
}

# Trilinos from Debian's source package, with the configuration of the prebuilt archive
# (Kokkos Serial + OpenMP, Tpetra ETI double/int/long long on the OpenMP node).
build_trilinos_from_source() {
  local work=$prefix/trilinos-src
  log "no Trilinos archive found: building Trilinos 13.2 from Debian's source package in $work"
  log "this takes about 40 minutes on 2 cores (-j$jobs)"
  if ! grep -rqs '^Types: deb-src' /etc/apt/sources.list.d/ && ! grep -qs '^deb-src' /etc/apt/sources.list; then
    printf 'Types: deb-src\nURIs: http://deb.debian.org/debian\nSuites: bookworm\nComponents: main\nSigned-By: /usr/share/keyrings/debian-archive-keyring.gpg\n' \
      | as_root tee /etc/apt/sources.list.d/debian-src.sources >/dev/null
    as_root apt-get update -qq
  fi
  apt_install dpkg-dev gfortran patchelf
  mkdir -p "$work" && cd "$work"
  [ -f trilinos_13.2.0.orig.tar.gz ] || apt-get source --download-only trilinos=13.2.0-4
  [ -d Trilinos-trilinos-release-13-2-0 ] || tar xzf trilinos_13.2.0.orig.tar.gz
  mkdir -p build && cd build
  local t0=$SECONDS
  cmake -G Ninja ../Trilinos-trilinos-release-13-2-0 \
    -DCMAKE_BUILD_TYPE=Release -DCMAKE_INSTALL_PREFIX="$trilinos_dir" \
    -DBUILD_SHARED_LIBS=ON -DCMAKE_CXX_FLAGS="-O2 -w" -DCMAKE_CXX_FLAGS_RELEASE="-O2 -DNDEBUG" \
    -DTPL_ENABLE_MPI=ON -DTrilinos_ENABLE_OpenMP=ON \
    -DTrilinos_ENABLE_ALL_OPTIONAL_PACKAGES=OFF -DTrilinos_ENABLE_TESTS=OFF -DTrilinos_ENABLE_EXAMPLES=OFF \
    -DTrilinos_ENABLE_EXPLICIT_INSTANTIATION=ON \
    -DTrilinos_ENABLE_Kokkos=ON -DKokkos_ENABLE_SERIAL=ON -DKokkos_ENABLE_OPENMP=ON \
    -DTrilinos_ENABLE_KokkosKernels=ON -DTrilinos_ENABLE_Teuchos=ON -DTrilinos_ENABLE_Tpetra=ON \
    -DTrilinos_ENABLE_Belos=ON -DTrilinos_ENABLE_Ifpack2=ON -DTrilinos_ENABLE_Amesos2=ON \
    -DTrilinos_ENABLE_MueLu=ON -DTrilinos_ENABLE_Xpetra=ON -DTrilinos_ENABLE_NOX=ON \
    -DTrilinos_ENABLE_Thyra=ON -DTrilinos_ENABLE_Stratimikos=ON -DTrilinos_ENABLE_Zoltan2=ON -DTrilinos_ENABLE_Zoltan=ON \
    -DTrilinos_ENABLE_Epetra=OFF -DTrilinos_ENABLE_EpetraExt=OFF -DTrilinos_ENABLE_Triutils=OFF \
    -DTrilinos_ENABLE_Sacado=OFF -DTrilinos_ENABLE_Galeri=OFF -DTrilinos_ENABLE_Isorropia=OFF \
    -DTpetra_INST_SERIAL=OFF -DTpetra_INST_OPENMP=ON -DTpetra_INST_INT_LONG_LONG=ON -DTpetra_INST_INT_INT=OFF \
    -DTpetra_INST_DOUBLE=ON -DTpetra_INST_FLOAT=OFF -DTpetra_INST_COMPLEX_DOUBLE=OFF -DTpetra_INST_COMPLEX_FLOAT=OFF \
    -DTpetra_ENABLE_TSQR=OFF \
    -DKokkosKernels_INST_EXECSPACE_SERIAL=OFF -DKokkosKernels_INST_OFFSET_INT=OFF \
    -DNOX_ENABLE_LOCA=OFF -DMueLu_ENABLE_Kokkos_Refactor=ON \
    -DTPL_ENABLE_BLAS=ON -DTPL_ENABLE_LAPACK=ON -DTPL_ENABLE_Boost=OFF -DTPL_ENABLE_Matio=OFF -DTPL_ENABLE_X11=OFF \
    -DTPL_ENABLE_DLlib=ON -DTPL_ENABLE_Pthread=ON \
    -DCMAKE_CXX_COMPILER_LAUNCHER=ccache -DCMAKE_C_COMPILER_LAUNCHER=ccache
  ninja -j"$jobs" install
  # Relocatable install: each library finds its siblings next to itself.
  for f in "$trilinos_dir"/lib/*.so.*; do [ -L "$f" ] || patchelf --set-rpath '$ORIGIN' "$f"; done
  log "Trilinos source build took $(( (SECONDS - t0) / 60 )) min"
}

restore_trilinos() {
  local archive=$1
  log "restoring Trilinos from $archive"
  local sum
  sum=$(sha256sum "$archive" | cut -d' ' -f1)
  if [ "$sum" != "$archive_sha256" ]; then
    log "checksum mismatch for $archive: got $sum, expected $archive_sha256"; exit 1
  fi
  mkdir -p "$prefix"
  rm -rf "$trilinos_dir.partial" && mkdir -p "$trilinos_dir.partial"
  tar -xJf "$archive" -C "$trilinos_dir.partial"
  rm -rf "$trilinos_dir" && mv "$trilinos_dir.partial/trilinos-omp" "$trilinos_dir" && rm -rf "$trilinos_dir.partial"
}

[ "$do_apt" -eq 1 ] && apt_install "${packages[@]}"

# The viewer's and the tests' npm packages, at the lock file's versions (npm ci: nothing else, no
# resolution). A machine without npm gets Debian's; without a registry the viewer tests say they skip.
setup_viewer() {
  local dir=$prefix/viewer
  if [ -f "$dir/package-lock.json" ] && cmp -s "$dir/package-lock.json" "$here/viewer/package-lock.json" &&
     [ -d "$dir/node_modules/three" ] && [ -d "$dir/node_modules/gltf-validator" ]; then
    return
  fi
  if ! command -v npm >/dev/null 2>&1; then
    [ "$do_apt" -eq 1 ] && apt_install npm || { log "no npm: the viewer's packages are not installed"; return; }
  fi
  mkdir -p "$dir"
  cp "$here/viewer/package.json" "$here/viewer/package-lock.json" "$dir/"
  log "installing the viewer's npm packages (three, gltf-validator) into $dir"
  (cd "$dir" && npm ci --no-audit --no-fund --loglevel=error >&2) || log "npm ci failed: sinew-view and its tests will say so"
}
setup_viewer

if [ -f "$trilinos_cmake/TrilinosConfig.cmake" ]; then
  log "Trilinos already in $trilinos_dir"
elif [ -n "$cache" ] && [ -f "$cache/$archive_name" ]; then
  restore_trilinos "$cache/$archive_name"
else
  [ -n "$cache" ] && log "cache '$cache' has no $archive_name"
  build_trilinos_from_source
fi
echo "$trilinos_cmake"
