#!/usr/bin/env bash
# The validation report of the BFEMP scenes (VALIDATION.md section A):
#   scripts/validate.sh [--size ci|paper] [--scenes A1,A2,A3,A4,A6[,A7]] [--out DIR]
# runs each scene with build/drivers/bfemp, evaluates its bands with
# `bfemp probe` and writes DIR/report.md plus a PNG per scene (see
# scripts/validate.py --help). Build first: ninja -C build bfemp.
set -euo pipefail
repo="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
py=/usr/bin/python3   # Debian's, with python3-matplotlib
[[ -x "$py" ]] || py=python3
export OMP_PROC_BIND=${OMP_PROC_BIND:-spread} OMP_PLACES=${OMP_PLACES:-threads}
exec "$py" "$repo/scripts/validate.py" "$@"
