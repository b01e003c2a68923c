#!/usr/bin/env bash
# Sets everything up on a fresh machine (packages, Trilinos), builds bfemp and
# runs the whole test suite (labels unit, scene, extreme, mpi, paraview).   Usage: scripts/test.sh
set -euo pipefail
cd "$(dirname "$0")/.."
if [ "$(id -u)" = 0 ]; then scripts/setup.sh; else sudo scripts/setup.sh; fi
cmake -S . -B build -G Ninja -DCMAKE_BUILD_TYPE=Release
cmake --build build -j"$(nproc)"
cd build
OMP_PROC_BIND=false OPENBLAS_NUM_THREADS=1 ctest --output-on-failure -j"$(nproc)" "$@"
