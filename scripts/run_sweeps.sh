#!/usr/bin/env bash
# The speed-accuracy sweeps of VALIDATION section C, one knob at a time, with
# `bfemp sweep` (real runs; threads from OMP_NUM_THREADS, default 2). Each
# sweep's sweep.csv, sweep.json and sweep.png go to validation/sweeps/<name>/;
# the runs themselves to a scratch directory (--work, default a temp dir).
#   scripts/run_sweeps.sh [--only a4,a5,a1] [--work DIR] [--build-dir DIR]
#  a4: box on a slope, mu = 0.1 (0.3 s): error of the fitted acceleration
#      against g (sin - mu cos) over dhat, kappa, eps_v, dt, eps_d;
#  a5: refinement: equilibrium height over N = 2..12 against N = 16, for
#      PPC 4, 9 and 16;
#  a1: rings at the ci size run to 0.4 s: the energy lost during contact
#      against the paper's 8.57 % over dt, transfer scheme and linear solver.
set -euo pipefail
repo="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
build_dir="$repo/build"
only="a4,a5,a1"
work=""
while [[ $# -gt 0 ]]; do
  case "$1" in
    --only) only="$2"; shift 2 ;;
    --work) work="$2"; shift 2 ;;
    --build-dir) build_dir="$(cd "$2" && pwd)"; shift 2 ;;
    -h|--help) sed -n '2,14p' "${BASH_SOURCE[0]}"; exit 0 ;;
    *) echo "run_sweeps.sh: unknown argument '$1' (see --help)" >&2; exit 2 ;;
  esac
done
bin="$build_dir/drivers/bfemp"
[[ -x "$bin" ]] || { echo "run_sweeps.sh: $bin not found; build it first" >&2; exit 2; }
[[ -n "$work" ]] || { work="$(mktemp -d)"; trap 'rm -rf "$work"' EXIT; }
export OMP_NUM_THREADS=${OMP_NUM_THREADS:-2} OMP_PROC_BIND=${OMP_PROC_BIND:-spread} OMP_PLACES=${OMP_PLACES:-threads}
out="$repo/validation/sweeps"

sweep() {  # name, then bfemp sweep arguments
  local name="$1"; shift
  echo "== sweep $name"
  "$bin" sweep "$@" --out "$work/$name" | grep '^sweep:'
  mkdir -p "$out/$name"
  cp "$work/$name"/sweep.csv "$work/$name"/sweep.json "$out/$name/"
  [[ -f "$work/$name/sweep.png" ]] && cp "$work/$name/sweep.png" "$out/$name/" || true
}

if [[ ",$only," == *",a4,"* ]]; then
  a4="$repo/inputs/contact_slope.yaml"
  a_exact=$(python3 -c "import math; t=0.2; print(repr(5.10*(t-0.1)/math.sqrt(1+t*t)))")
  probe=(--probe "acceleration:body=box,axis=x,from=0.1,to=0.3" --probe "sum:column=newton_iters" --reference "$a_exact")
  sweep a4_dhat "$a4" --set Contact/friction=0.1 --vary "Contact/dhat=2.0e-3,1.0e-3,5.0e-4,2.5e-4" "${probe[@]}"
  sweep a4_kappa "$a4" --set Contact/friction=0.1 --vary "Contact/kappa=1.0e5,1.0e6,1.0e7,1.0e8" "${probe[@]}"
  sweep a4_eps_v "$a4" --set Contact/friction=0.1 --vary "Contact/eps_v=1.0e-3,1.0e-4,1.0e-5,1.0e-6" "${probe[@]}"
  sweep a4_dt "$a4" --set Contact/friction=0.1 --vary "Time/dt=4.0e-3,2.0e-3,1.0e-3,5.0e-4" "${probe[@]}"
  sweep a4_eps_d "$a4" --set Contact/friction=0.1 --vary "Newton/eps_d=1.0e-5,1.0e-6,1.0e-7,1.0e-8,1.0e-9" "${probe[@]}"
fi
if [[ ",$only," == *",a5,"* ]]; then
  a5="$repo/inputs/a5_refinement.yaml"
  levels=""
  for N in 2 4 6 8 10 12; do
    levels+=$(python3 -c "N=$N; h=1.0/N; print('%r&%r&%r' % (h, h, h*h), end='')"),
  done
  ref=(--reference-run "MPM/grid spacing=0.0625" --reference-run "FEM Bodies/base/Mesh/element size=0.0625"
       --reference-run "Contact/dhat=0.00390625")
  for ppc in 4 9 16; do
    sweep "a5_N_ppc$ppc" "$a5" --set "MPM/particles per cell=$ppc" \
      --vary "MPM/grid spacing&FEM Bodies/base/Mesh/element size&Contact/dhat=${levels%,}" \
      --probe "equilibrium_height:bodies=box+base" --probe "max_speed:body=box,axis=y,from=4" "${ref[@]}"
  done
fi
if [[ ",$only," == *",a1,"* ]]; then
  a1="$repo/inputs/contact_rings.yaml"
  probe=(--probe energy_lost_pct --probe "momentum_drift:axis=x,relative_to=left" --reference 8.57)
  sweep a1_dt "$a1" --set "Time/end time=0.4" --set "MPM/when particles leave=extend" --vary "Time/dt=2.0e-3,1.0e-3,5.0e-4" "${probe[@]}"
  sweep a1_transfer "$a1" --set "Time/end time=0.4" --set "MPM/when particles leave=extend" --vary "MPM/transfer=APIC,FLIP,PIC" "${probe[@]}"
  sweep a1_solver "$a1" --set "Time/end time=0.4" --set "MPM/when particles leave=extend" --vary "Linear Solver/type=Cholmod,KLU2,CG" "${probe[@]}"
fi
echo "run_sweeps.sh: wrote $out"
