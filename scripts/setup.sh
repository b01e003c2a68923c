#!/usr/bin/env bash
# bfemp set-up: Debian packages + Trilinos 13.2 with Kokkos' OpenMP backend
# (the `r2` configuration: + Xpetra, MueLu, Zoltan, Zoltan2 for MPI runs).
# Idempotent; run as root on Debian bookworm.
#   scripts/setup.sh [--prefix DIR] [--archive FILE] [--from-source] [--no-apt] [--with-paraview]
# The prebuilt archive (shared/deps/README.md) is used when --archive or
# BFEMP_TRILINOS_ARCHIVE names it, or when ../shared/deps holds it.
# --with-paraview also installs ParaView 5.11 with pvpython (paraview,
# python3-paraview) and xvfb, xauth for `ctest -L paraview`; not by default
# (about 150 MB to download, 800 MB installed).
set -euo pipefail

PREFIX_ROOT=${BFEMP_DEPS_PREFIX:-/opt/bfemp-deps}
ARCHIVE=${BFEMP_TRILINOS_ARCHIVE:-}
FROM_SOURCE=0
DO_APT=1
WITH_PARAVIEW=0
here=$(cd "$(dirname "$0")/.." && pwd)

while [ $# -gt 0 ]; do
  case "$1" in
    --prefix) PREFIX_ROOT=$2; shift 2;;
    --archive) ARCHIVE=$2; shift 2;;
    --from-source) FROM_SOURCE=1; shift;;
    --no-apt) DO_APT=0; shift;;
    --with-paraview) WITH_PARAVIEW=1; shift;;
    -h|--help) sed -n 2,9p "$0"; exit 0;;
    *) echo "setup.sh: unknown option '$1' (expected --prefix, --archive, --from-source, --no-apt, --with-paraview)" >&2; exit 2;;
  esac
done

TRILINOS_PREFIX=$PREFIX_ROOT/trilinos-13.2.0-omp-r2
default_archive=$here/../shared/deps/trilinos-13.2.0-omp-r2-bookworm-x86_64.tar.xz
if [ -z "$ARCHIVE" ] && [ $FROM_SOURCE -eq 0 ] && [ -f "$default_archive" ]; then
  ARCHIVE=$default_archive
fi

PACKAGES="build-essential cmake ninja-build dpkg-dev xz-utils pkg-config
  libopenmpi-dev openmpi-bin libhdf5-openmpi-dev libopenblas-dev liblapack-dev
  libsuitesparse-dev libeigen3-dev libgtest-dev libbenchmark-dev libcli11-dev
  libgmsh-dev python3-matplotlib python3-h5py"
# pvpython is in python3-paraview (only a Recommends of paraview).
if [ $WITH_PARAVIEW -eq 1 ]; then
  [ $DO_APT -eq 1 ] || { echo "setup.sh: --with-paraview installs Debian packages; it cannot go with --no-apt" >&2; exit 2; }
  PACKAGES="$PACKAGES paraview python3-paraview xvfb xauth"
fi

if [ $DO_APT -eq 1 ]; then
  missing=$(dpkg-query -W -f='${Package} ${Status}\n' $PACKAGES 2>/dev/null | grep -v "install ok installed" | cut -d' ' -f1 || true)
  for p in $PACKAGES; do dpkg-query -W "$p" >/dev/null 2>&1 || missing="$missing $p"; done
  missing=$(echo $missing | tr ' ' '\n' | sort -u | tr '\n' ' ')
  if [ -n "${missing// /}" ]; then
    echo "setup: installing Debian packages: $missing"
    export DEBIAN_FRONTEND=noninteractive
    apt-get update -qq
    apt-get install -y -qq --no-install-recommends $missing
  else
    echo "setup: Debian packages present"
  fi
fi

have_trilinos() {
  local cfg=$TRILINOS_PREFIX/include/KokkosCore_config.h
  [ -f "$TRILINOS_PREFIX/lib/cmake/Trilinos/TrilinosConfig.cmake" ] && [ -f "$cfg" ] && grep -q "KOKKOS_ENABLE_OPENMP" "$cfg" \
    && [ -f "$TRILINOS_PREFIX/include/MueLu_CreateTpetraPreconditioner.hpp" ] \
    && [ -f "$TRILINOS_PREFIX/include/Zoltan2_PartitioningProblem.hpp" ]
}

if have_trilinos; then
  echo "setup: Trilinos with OpenMP Kokkos already at $TRILINOS_PREFIX"
  exit 0
fi

if [ -n "$ARCHIVE" ] && [ $FROM_SOURCE -eq 0 ]; then
  if [ "$TRILINOS_PREFIX" != /opt/bfemp-deps/trilinos-13.2.0-omp-r2 ]; then
    echo "setup: the archive hard-codes /opt/bfemp-deps/trilinos-13.2.0-omp-r2; use --from-source for prefix $PREFIX_ROOT" >&2
    exit 2
  fi
  if [ -f "$ARCHIVE.sha256" ]; then
    want=$(cut -d' ' -f1 < "$ARCHIVE.sha256")
    got=$(sha256sum "$ARCHIVE" | cut -d' ' -f1)
    [ "$want" = "$got" ] || { echo "setup: $ARCHIVE: sha256 $got, expected $want (from $ARCHIVE.sha256)" >&2; exit 1; }
  fi
  echo "setup: unpacking $ARCHIVE"
  mkdir -p /opt/bfemp-deps
  tar -xJf "$ARCHIVE" -C /opt/bfemp-deps
  have_trilinos || { echo "setup: archive did not yield an OpenMP Trilinos at $TRILINOS_PREFIX" >&2; exit 1; }
  echo "setup: Trilinos ready at $TRILINOS_PREFIX"
  exit 0
fi

# Build from Debian's source package (about 70 minutes on 2 cores).
work=${BFEMP_BUILD_DIR:-/tmp/bfemp-trilinos-build}
mkdir -p "$work/sources.list.d" "$work/lists/partial"
cd "$work"
if [ ! -f trilinos_13.2.0.orig.tar.gz ]; then
  echo "deb-src http://deb.debian.org/debian bookworm main" > sources.list.d/src.list
  opts="-o Dir::Etc::SourceParts=$work/sources.list.d -o Dir::Etc::SourceList=/dev/null -o Dir::State::Lists=$work/lists"
  apt-get $opts update -qq
  apt-get $opts source --download-only trilinos=13.2.0-4
fi
src=$work/Trilinos-trilinos-release-13-2-0
[ -d "$src" ] || tar -xzf trilinos_13.2.0.orig.tar.gz
cmake -S "$src" -B "$work/build" -G Ninja \
  -DCMAKE_BUILD_TYPE=Release -DCMAKE_INSTALL_PREFIX="$TRILINOS_PREFIX" \
  -DCMAKE_CXX_STANDARD=17 -DKokkos_CXX_STANDARD=17 -DBUILD_SHARED_LIBS=ON \
  -DTrilinos_ENABLE_ALL_OPTIONAL_PACKAGES=OFF -DTrilinos_ENABLE_ALL_PACKAGES=OFF \
  -DTrilinos_ENABLE_TESTS=OFF -DTrilinos_ENABLE_EXAMPLES=OFF -DTrilinos_ENABLE_Fortran=OFF \
  -DTrilinos_ENABLE_OpenMP=ON -DKokkos_ENABLE_OPENMP=ON -DKokkos_ENABLE_SERIAL=ON \
  -DTrilinos_ENABLE_Kokkos=ON -DTrilinos_ENABLE_KokkosKernels=ON -DTrilinos_ENABLE_Teuchos=ON \
  -DTrilinos_ENABLE_Tpetra=ON -DTrilinos_ENABLE_Belos=ON -DTrilinos_ENABLE_Ifpack2=ON -DTrilinos_ENABLE_Amesos2=ON \
  -DAmesos2_ENABLE_KLU2=ON -DAmesos2_ENABLE_Experimental=ON \
  -DTPL_ENABLE_MPI=ON -DTPL_ENABLE_BLAS=ON -DTPL_ENABLE_LAPACK=ON \
  -DTPL_ENABLE_Cholmod=ON -DCholmod_INCLUDE_DIRS=/usr/include/suitesparse \
  "-DCholmod_LIBRARY_NAMES=cholmod;amd;colamd;ccolamd;camd;suitesparseconfig" \
  -DTpetra_INST_SERIAL=OFF -DTpetra_INST_OPENMP=ON -DTpetra_INST_DOUBLE=ON \
  -DTpetra_INST_FLOAT=OFF -DTpetra_INST_COMPLEX_DOUBLE=OFF \
  -DTpetra_INST_INT_INT=OFF -DTpetra_INST_INT_LONG_LONG=ON \
  -DTrilinos_ENABLE_EXPLICIT_INSTANTIATION=ON \
  -DTrilinos_ENABLE_Epetra=OFF \
  -DTrilinos_ENABLE_Xpetra=ON -DTrilinos_ENABLE_MueLu=ON \
  -DTrilinos_ENABLE_Zoltan=ON -DTrilinos_ENABLE_Zoltan2=ON \
  -DMueLu_ENABLE_Epetra=OFF -DXpetra_ENABLE_Epetra=OFF \
  -DXpetra_ENABLE_EpetraExt=OFF -DZoltan2_ENABLE_Epetra=OFF \
  "-DCMAKE_CXX_FLAGS=-O2 -w"
ninja -C "$work/build" -j"$(nproc)" install
have_trilinos || { echo "setup: build finished but no OpenMP Trilinos at $TRILINOS_PREFIX" >&2; exit 1; }
echo "setup: Trilinos built and installed at $TRILINOS_PREFIX"
