#!/usr/bin/env bash
# The 3D twist (VALIDATION A7, inputs/a7_twist.yaml: ci size, 4096 particles,
# 756 FEM nodes; friction mu 0.5) for its first N steps (default 15: the shell
# lands on the cube at step 8) on 1 and 2 MPI ranks: 1 rank x 1 thread and
# 1 x 2 with Cholmod (the default), 2 ranks x 1 thread with CG and each
# preconditioner in --precs (direct solvers are refused on 2 ranks). Writes
# the mean per contact step of step_s, assembly_s, solve_s, the Newton and CG
# iterations from each run's diagnostics.csv, and from the run's summary the
# share of the whole run's step time spent in MPI exchanges (DOF export and
# import, particle migration: comm_share) and in output, as JSON that
# perf/compare.py reads (solver = the configuration, threads = ranks x threads):
#   perf/run_twist_ranks.sh [--build-dir DIR] [--out FILE] [--steps N] [--precs "RELAXATION BLOCK_CHOLMOD"]
# (--precs: Ifpack2 names, MUELU, BLOCK_CHOLMOD (its defaults: 'block overlap' 1, 'block reuse'),
# BLOCK_CHOLMOD_NOREUSE ('block reuse' false), BLOCK_CHOLMOD_OV0 (overlap 0, no reuse: before 2026-12-04))
#                           [--size NAME --set KEY=VALUE ...]
# --set changes the scene for every run (e.g. a refined twist for weak
# scaling: --size twist_weak2 --set 'MPM/grid spacing=0.1'
# --set 'FEM Bodies/shell/Mesh/element size=0.08'); --size names it in the JSON
# (default twist_ci).
#   python3 perf/compare.py build/perf/twist_ranks.json --baseline perf/baselines/twist_ranks.json \
#       --fields step_s,assembly_s,solve_s
# Goals (MPI issue, paper size): 2 ranks >= 1.6x over 1 x 1; comm_share <= 0.1.
set -euo pipefail
repo="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
build_dir="$repo/build"
out=""
steps=15
precs="RELAXATION BLOCK_CHOLMOD"
size=twist_ci
extra=()
while [[ $# -gt 0 ]]; do
  case "$1" in
    --build-dir) build_dir="$(cd "$2" && pwd)"; shift 2 ;;
    --out) out="$2"; shift 2 ;;
    --steps) steps="$2"; shift 2 ;;
    --precs) precs="$2"; shift 2 ;;
    --size) size="$2"; shift 2 ;;
    --set) extra+=(--set "$2"); shift 2 ;;
    -h|--help) sed -n '2,20p' "${BASH_SOURCE[0]}"; exit 0 ;;
    *) echo "run_twist_ranks.sh: unknown argument '$1' (see --help)" >&2; exit 2 ;;
  esac
done
[[ -n "$out" ]] || out="$build_dir/perf/twist_ranks.json"
bin="$build_dir/drivers/bfemp"
[[ -x "$bin" ]] || { echo "run_twist_ranks.sh: $bin not found; build it first: ninja -C $build_dir bfemp" >&2; exit 2; }
tmp="$(mktemp -d)"
trap 'rm -rf "$tmp"' EXIT
end_time=$(python3 -c "print(($steps + 0.5) * 1e-2)")
common=(--set "Time/end time=$end_time" --set "Output/frame every=1000000" --set "Output/progress every=5" "${extra[@]}")
mpi=(mpirun --oversubscribe --allow-run-as-root --bind-to none -x OMP_PROC_BIND=false -x OPENBLAS_NUM_THREADS=1)
runs=()
run() {  # name ranks threads [bfemp args...]
  local name=$1 np=$2 nt=$3; shift 3
  echo "== $size, $name: $np rank(s) x $nt thread(s), $steps steps"
  "${mpi[@]}" -x OMP_NUM_THREADS="$nt" -np "$np" "$bin" run "$repo/inputs/a7_twist.yaml" --output "$tmp/$name" \
    "${common[@]}" "$@" > "$tmp/$name.log" 2>&1 \
    || { cat "$tmp/$name.log" >&2; echo "run_twist_ranks.sh: the run $name failed" >&2; exit 1; }
  grep -E "Newton iterations|linear iterations|assembly time|linear-solve|MPI exchanges|output time|wall time" "$tmp/$name.log" || true
  runs+=("$name:$np:$nt:$tmp/$name.log:$tmp/$name/diagnostics.csv")
}
run cholmod_1x1 1 1
run cholmod_1x2 1 2
for p in $precs; do
  case "$p" in  # BLOCK_CHOLMOD variants: the defaults (overlap 1, reuse) or one of them off
    BLOCK_CHOLMOD_OV0) run "cg_$p" 2 1 --set 'Linear Solver/type=CG' --set "Linear Solver/CG/preconditioner=BLOCK_CHOLMOD" \
      --set "Linear Solver/CG/block overlap=0" --set "Linear Solver/CG/block reuse=false" ;;
    BLOCK_CHOLMOD_NOREUSE) run "cg_$p" 2 1 --set 'Linear Solver/type=CG' --set "Linear Solver/CG/preconditioner=BLOCK_CHOLMOD" \
      --set "Linear Solver/CG/block reuse=false" ;;
    *) run "cg_$p" 2 1 --set 'Linear Solver/type=CG' --set "Linear Solver/CG/preconditioner=$p" ;;
  esac
done
mkdir -p "$(dirname "$out")"
python3 - "$out" "$repo" "$size" "${runs[@]}" <<'PY'
import csv, re, sys
out, repo, size, runs = sys.argv[1], sys.argv[2], sys.argv[3], sys.argv[4:]
sys.path.insert(0, repo + "/perf")
from scene_stats import contact_step_means, write_results
results = []
for spec in runs:
    name, np_, nt, log, diag = spec.split(":", 4)
    n, m = contact_step_means(diag, ("step_s", "assembly_s", "solve_s", "newton_iters", "linear_iters"))
    # Whole-run totals from the summary (rank 0 prints the slowest rank's).
    text = open(log).read()
    ex = re.search(r"MPI exchanges\s+([0-9.eE+-]+) s DOF export/import \(within the times above; ([0-9.eE+-]+) MB sent\), "
                   r"([0-9.eE+-]+) s particle migration", text)
    outp = re.search(r"output time\s+([0-9.eE+-]+) s", text)
    steps_total = sum(float(r["step_s"]) for r in csv.DictReader(open(diag)))
    exchange, exchange_mb, migration = (float(ex.group(i)) for i in (1, 2, 3)) if ex else (0.0, 0.0, 0.0)
    particles = re.search(r"MPM: (\d+) particles", text)
    dofs = re.search(r"FEM: \d+ nodes, \d+ elements, (\d+) DOFs", text)
    results.append({"dim": 3, "size": size,
                    "particles": int(particles.group(1)) if particles else 0,
                    "fem_dofs": int(dofs.group(1)) if dofs else 0, "solver": name, "threads": int(np_) * int(nt),
                    "ranks": int(np_), "threads_per_rank": int(nt), "contact_steps": n, **m,
                    "run_step_s": steps_total, "exchange_s": exchange, "exchange_mb": exchange_mb, "migration_s": migration,
                    "comm_share": (exchange + migration) / steps_total if steps_total > 0 else float("nan"),
                    "output_s": float(outp.group(1)) if outp else float("nan")})
    r = results[-1]
    print(f"  {name} {np_}x{nt}: {n} contact steps, {r['step_s']:.2f} s per step (assembly {r['assembly_s']:.2f}, "
          f"solve {r['solve_s']:.2f}), {r['newton_iters']:.1f} Newton, {r['linear_iters']:.0f} linear iterations; "
          f"MPI exchanges {100 * r['comm_share']:.1f} % of the step time, output {r['output_s']:.2f} s")
write_results(out, "twist_ranks", repo, results)
print(f"run_twist_ranks.sh: wrote {out}")
PY
