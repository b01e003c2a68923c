#!/usr/bin/env bash
# The 3D twist at the paper's size (inputs/paper/a7_twist.yaml: 110592
# particles, the shell at element size 0.07; mu 0.5) for N steps of its
# twisting phase (default 5: t = 1.00 .. 1.05), from a checkpoint at t = 1.0,
# the end of the down phase. Each configuration restarts from that
# checkpoint (`bfemp restart --output`): 1 rank x 2 threads and 1 x 1 with
# Cholmod (the default), 2 ranks x 1 thread with CG + BLOCK_CHOLMOD (the
# 1-rank checkpoint is cut into the 2 ranks' slabs at the restart). Writes
# the mean per step of step_s, assembly_s, solve_s, the Newton and linear
# iterations and friction passes, and from the summary the graph builds,
# symbolic and numeric factorisations and MPI exchanges per step, the time
# of a Newton iteration split into assembly, DOF export/import, solve,
# contact, line search, particle migration and output (per_newton_*), with the
# peak resident memory (the largest rank's), as JSON that perf/compare.py reads
# (each run's log and diagnostics.csv are kept beside it, in FILE without .json + _logs/):
#   perf/run_twist_paper.sh [--build-dir DIR] [--out FILE] [--checkpoint DIR] [--steps N]
#                           [--configs "1x2 1x1 2x1"] [--set KEY=VALUE ...]
#   python3 perf/compare.py build/perf/twist_paper.json --baseline perf/baselines/twist_paper.json \
#       --fields step_s,assembly_s,solve_s
# --checkpoint (default BUILD/perf/twist_paper_t1): a directory whose
# checkpoint.h5 is the twist at step 100 (t = 1.0), or at a later step of the
# twisting phase (a later window: the N steps after the checkpoint's; e.g. a
# checkpoint of a long run, copied with its scene.yaml). When it is missing, it is
# made first: the down phase, 100 steps at 2 threads, about 45 minutes on
# the 2-core VM (kept for later runs; it is not a timing). Any run of
# inputs/paper/a7_twist.yaml checkpointed at step 100 will do (checkpoint.h5
# and scene.yaml in the directory). --set changes the
# timed restarts (keys `bfemp restart` accepts: Newton/*, Linear Solver/*,
# Contact/friction iterations, ...), e.g. an A/B of a solver key.
# Goals (speed issue): <= 10 s per twisting step at 2 threads;
# (MPI issue): 2 ranks >= 1.6x over 1 x 1.
set -euo pipefail
repo="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
build_dir="$repo/build"
out=""
ckpt=""
steps=5
configs="1x2 1x1 2x1"
extra=()
while [[ $# -gt 0 ]]; do
  case "$1" in
    --build-dir) build_dir="$(cd "$2" && pwd)"; shift 2 ;;
    --out) out="$2"; shift 2 ;;
    --checkpoint) ckpt="$2"; shift 2 ;;
    --steps) steps="$2"; shift 2 ;;
    --configs) configs="$2"; shift 2 ;;
    --set) extra+=(--set "$2"); shift 2 ;;
    -h|--help) sed -n '2,26p' "${BASH_SOURCE[0]}"; exit 0 ;;
    *) echo "run_twist_paper.sh: unknown argument '$1' (see --help)" >&2; exit 2 ;;
  esac
done
[[ -n "$out" ]] || out="$build_dir/perf/twist_paper.json"
[[ -n "$ckpt" ]] || ckpt="$build_dir/perf/twist_paper_t1"
bin="$build_dir/drivers/bfemp"
[[ -x "$bin" ]] || { echo "run_twist_paper.sh: $bin not found; build it first: ninja -C $build_dir bfemp" >&2; exit 2; }
scene="$repo/inputs/paper/a7_twist.yaml"
ckpt_step() {  # the step of DIR/checkpoint.h5 ("none" when there is no file)
  [[ -f "$1/checkpoint.h5" ]] || { echo none; return; }
  /usr/bin/python3 -c "import h5py,sys; print(int(h5py.File(sys.argv[1],'r')['checkpoint'].attrs['step']))" "$1/checkpoint.h5"
}
have=$(ckpt_step "$ckpt")
if [[ "$have" == none ]]; then
  # Only a directory this script made (or none) is written: a run directory
  # given by mistake is refused, not overwritten.
  if [[ -e "$ckpt" && ! -f "$ckpt/.twist_paper_checkpoint" ]]; then
    echo "run_twist_paper.sh: $ckpt exists and is not a checkpoint this script made; remove it or pick another --checkpoint" >&2
    exit 2
  fi
  echo "== making the checkpoint at t = 1.0 in $ckpt (100 steps of the down phase at 2 threads; ~45 min here)"
  mkdir -p "$(dirname "$ckpt")"
  OMP_NUM_THREADS=2 OMP_PROC_BIND=spread OMP_PLACES=threads "$bin" run "$scene" --output "$ckpt" \
    --set 'Time/end time=1.0' --set 'Output/frame every=1000000' --set 'Output/progress every=10' \
    > "$ckpt.log" 2>&1 || { tail -20 "$ckpt.log" >&2; echo "run_twist_paper.sh: the down phase failed" >&2; exit 1; }
  touch "$ckpt/.twist_paper_checkpoint"
  have=$(ckpt_step "$ckpt")
fi
[[ "$have" -ge 100 ]] || { echo "run_twist_paper.sh: $ckpt/checkpoint.h5 is at step $have, before the twist (step 100, t = 1.0)" >&2; exit 1; }
t0=$(python3 -c "print($have * 1e-2)")  # dt = 1e-2 (inputs/paper/a7_twist.yaml)
tmp="$(mktemp -d)"
trap 'rm -rf "$tmp"' EXIT
end_time=$(python3 -c "print($t0 + ($steps - 0.5) * 1e-2)")  # bfemp runs ceil(end time / dt) steps
common=(--set "Time/end time=$end_time" --set "Output/frame every=1000000" --set "Output/progress every=1"
        ${extra[@]+"${extra[@]}"})
mpi=(mpirun --oversubscribe --allow-run-as-root --bind-to none)  # bfemp sets the BLAS threads (solver/blas_threads.hpp)
runs=()
for c in $configs; do
  np=${c%x*}; nt=${c#*x}
  args=()
  if [[ "$np" == 1 ]]; then name="cholmod_$c"; binding=(-x OMP_PROC_BIND=spread -x OMP_PLACES=threads)
  else name="cg_block_cholmod_$c"; binding=(-x OMP_PROC_BIND=false); args=(--set 'Linear Solver/type=CG'); fi
  echo "== twist_paper, $name: $np rank(s) x $nt thread(s), $steps twisting steps from t = $t0"
  /usr/bin/time -f "%M" -o "$tmp/mem_$name" "${mpi[@]}" "${binding[@]}" -x OMP_NUM_THREADS="$nt" -np "$np" \
    "$bin" restart "$ckpt" --output "$tmp/$name" "${common[@]}" ${args[@]+"${args[@]}"} > "$tmp/$name.log" 2>&1 \
    || { tail -30 "$tmp/$name.log" >&2; echo "run_twist_paper.sh: the run $name failed" >&2; exit 1; }
  mkdir -p "${out%.json}_logs" && cp "$tmp/$name.log" "${out%.json}_logs/$name.log" \
    && cp "$tmp/$name/diagnostics.csv" "${out%.json}_logs/$name.diagnostics.csv"
  grep -E "Newton iterations|linear iterations|assembly time|linear-solve|factorisations|graph builds|MPI exchanges|wall time" \
    "$tmp/$name.log" || true
  runs+=("$name:$np:$nt:$tmp/$name.log:$tmp/$name/diagnostics.csv:$tmp/mem_$name")
done
mkdir -p "$(dirname "$out")"
python3 - "$out" "$repo" "$steps" "$t0" "${runs[@]}" <<'PY'
import csv, re, sys
out, repo, steps, t0, runs = sys.argv[1], sys.argv[2], int(sys.argv[3]), float(sys.argv[4]), sys.argv[5:]
sys.path.insert(0, repo + "/perf")
from scene_stats import write_results
keys = ("step_s", "assembly_s", "solve_s", "newton_iters", "linear_iters", "friction_iters", "contact_pairs")
results = []
for spec in runs:
    name, np_, nt, log, diag, mem = spec.split(":", 5)
    rows = [r for r in csv.DictReader(open(diag)) if float(r["time"]) > t0 + 1e-9]
    n = len(rows)
    m = {k: sum(float(r[k]) for r in rows) / n for k in keys} if n else {k: float("nan") for k in keys}
    text = open(log).read()
    def total(pattern):
        g = re.search(pattern, text)
        return float(g.group(1)) if g else float("nan")
    ex = re.search(r"MPI exchanges\s+([0-9.eE+-]+) s DOF export/import \(within the times above; ([0-9.eE+-]+) MB sent\), "
                   r"([0-9.eE+-]+) s particle migration", text)
    exchange, exchange_mb, migration = (float(ex.group(i)) for i in (1, 2, 3)) if ex else (0.0, 0.0, 0.0)
    steps_total = sum(float(r["step_s"]) for r in rows)
    # The MPI issue's split of a Newton iteration (the restart's summary
    # covers only the timed steps): assembly, DOF export/import, linear
    # solve, contact (broad phase, pair evaluation, CCD: within assembly and
    # the line search), particle migration and output, each over the run's
    # Newton iterations; per_newton_s = step_s / newton_iters.
    its = total(r"Newton iterations\s+(\d+)")
    cont = re.search(r"contact: broad phase ([0-9.eE+-]+) s, pair evaluation ([0-9.eE+-]+) s, CCD ([0-9.eE+-]+) s", text)
    contact = sum(float(cont.group(i)) for i in (1, 2, 3)) if cont else 0.0
    per_it = lambda v: v / its if its > 0 else float("nan")
    split = {"per_newton_s": per_it(steps_total),
             "per_newton_assembly_s": per_it(total(r"assembly time\s+([0-9.eE+-]+) s")),
             "per_newton_export_s": per_it(exchange),
             "per_newton_solve_s": per_it(total(r"linear-solve time\s+([0-9.eE+-]+) s")),
             "per_newton_contact_s": per_it(contact),
             "per_newton_line_search_s": per_it(total(r"line-search time\s+([0-9.eE+-]+) s")),
             "per_newton_migration_s": per_it(migration),
             "per_newton_output_s": per_it(total(r"output time\s+([0-9.eE+-]+) s"))}
    results.append({"dim": 3, "size": "twist_paper" if abs(t0 - 1.0) < 1e-9 else f"twist_paper_t{t0:g}", "solver": name, "threads": int(np_) * int(nt),
                    "ranks": int(np_), "threads_per_rank": int(nt), "twisting_steps": n, **m,
                    "graph_builds_per_step": total(r"graph builds\s+(\d+)") / max(n, 1),
                    "symbolic_factorisations_per_step": total(r"symbolic factorisations (\d+)") / max(n, 1),
                    "numeric_factorisations_per_step": total(r"factorisations\s+(\d+) numeric") / max(n, 1),
                    "comm_share": (exchange + migration) / steps_total if steps_total > 0 else float("nan"),
                    "exchange_mb": exchange_mb, **split,
                    "peak_rss_mib": round(int(open(mem).read().split()[-1]) / 1024, 1)})
    r = results[-1]
    print(f"  {name}: {n} twisting steps, {r['step_s']:.2f} s per step (assembly {r['assembly_s']:.2f}, "
          f"solve {r['solve_s']:.2f}), {r['newton_iters']:.1f} Newton, {r['linear_iters']:.0f} linear iterations, "
          f"{r['friction_iters']:.1f} friction passes, {r['contact_pairs']:.0f} pairs; peak {r['peak_rss_mib']} MiB"
          + (f"; MPI exchanges {100 * r['comm_share']:.1f} % of the step time" if int(np_) > 1 else ""))
    if n != steps:
        sys.exit(f"run_twist_paper.sh: {name} has {n} twisting steps in its diagnostics, expected {steps}")
write_results(out, "twist_paper", repo, results)
print(f"run_twist_paper.sh: wrote {out}   (goals: <= 10 s per step at 1 x 2; 2 x 1 >= 1.6x over 1 x 1)")
PY
