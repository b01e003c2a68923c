#!/usr/bin/env bash
# Sets everything up on a fresh machine, builds bfemp and runs the default
# scene (inputs/block_drop.yaml) into out/.   Usage: scripts/run_default.sh [bfemp options]
set -euo pipefail
cd "$(dirname "$0")/.."
if [ "$(id -u)" = 0 ]; then scripts/setup.sh; else sudo scripts/setup.sh; fi
cmake -S . -B build -G Ninja -DCMAKE_BUILD_TYPE=Release
cmake --build build -j"$(nproc)" --target bfemp
OMP_PROC_BIND=${OMP_PROC_BIND:-spread} OMP_PLACES=${OMP_PLACES:-threads} OPENBLAS_NUM_THREADS=1 \
  ./build/drivers/bfemp run inputs/block_drop.yaml --output out "$@"
/usr/bin/python3 scripts/plot_diagnostics.py out || echo "(plot skipped: python3-matplotlib missing)"
