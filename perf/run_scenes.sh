#!/usr/bin/env bash
# Whole-scene benchmark: the colliding rings (VALIDATION A1) at the paper's
# size -- dx 0.1 with 9 particles per cell (about 20000 particles), FEM element
# size 0.13 (about 1830 vertices), dt 2e-4, Newmark -- for 50 steps in contact.
# The rings start 0.02 m apart (centres at -/+4.01 instead of -/+5) so that
# every timed step is a contact step. Runs bfemp at 1 and 2 threads and writes
# the mean per contact step of step_s, assembly_s, solve_s and the Newton
# iterations from each run's diagnostics.csv, plus graph builds and the peak
# resident memory, as JSON that perf/compare.py reads:
#   perf/run_scenes.sh [--build-dir DIR] [--out FILE] [--threads "1 2"] [--steps N] [--set KEY=VALUE ...]
# (--set: passed on to bfemp, e.g. an A/B of a Newton or linear-solver key on one binary)
#   python3 perf/compare.py build/perf/scenes.json --baseline perf/baselines/scenes.json \
#       --fields step_s,assembly_s,solve_s
# Goal (speed issue): <= 0.25 s per contact step at 2 threads.
set -euo pipefail
repo="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
build_dir="$repo/build"
out=""
threads="1 2"
steps=50
extra=()
while [[ $# -gt 0 ]]; do
  case "$1" in
    --build-dir) build_dir="$(cd "$2" && pwd)"; shift 2 ;;
    --out) out="$2"; shift 2 ;;
    --threads) threads="$2"; shift 2 ;;
    --steps) steps="$2"; shift 2 ;;
    --set) extra+=(--set "$2"); shift 2 ;;
    -h|--help) sed -n '2,16p' "${BASH_SOURCE[0]}"; exit 0 ;;
    *) echo "run_scenes.sh: unknown argument '$1' (see --help)" >&2; exit 2 ;;
  esac
done
[[ -n "$out" ]] || out="$build_dir/perf/scenes.json"
bin="$build_dir/drivers/bfemp"
[[ -x "$bin" ]] || { echo "run_scenes.sh: $bin not found; build it first: ninja -C $build_dir bfemp" >&2; exit 2; }
tmp="$(mktemp -d)"
trap 'rm -rf "$tmp"' EXIT
export OMP_PROC_BIND=spread OMP_PLACES=threads  # bfemp runs the BLAS on one thread
end_time=$(python3 -c "print(($steps + 0.5) * 2e-4)")
runs=()
for t in $threads; do
  echo "== rings (paper size), OMP_NUM_THREADS=$t, $steps steps"
  /usr/bin/time -f "%M" -o "$tmp/mem$t" env OMP_NUM_THREADS=$t "$bin" run "$repo/inputs/contact_rings.yaml" \
    --output "$tmp/rings$t" \
    --set "MPM/grid spacing=0.1" --set "MPM/particles per cell=9" \
    --set "FEM Bodies/right/Mesh/element size=0.13" \
    --set "MPM Bodies/left/center=[-4.01, 0.0]" --set "FEM Bodies/right/Mesh/center=[4.01, 0.0]" \
    --set "Time/dt=2.0e-4" --set "Time/end time=$end_time" \
    --set "Output/frame every=1000000" --set "Output/progress every=10" ${extra[@]+"${extra[@]}"} > "$tmp/log$t" 2>&1 \
    || { cat "$tmp/log$t" >&2; echo "run_scenes.sh: the run failed at $t thread(s)" >&2; exit 1; }
  grep -E "^(FEM|energy terms)|graph builds|assembly time|^    " "$tmp/log$t" || true
  runs+=("$t:$tmp/rings$t/diagnostics.csv:$tmp/mem$t:$tmp/log$t")
done
mkdir -p "$(dirname "$out")"
python3 - "$out" "$repo" "${runs[@]}" <<'PY'
import re, sys
out, repo, runs = sys.argv[1], sys.argv[2], sys.argv[3:]
sys.path.insert(0, repo + "/perf")
from scene_stats import contact_step_means, write_results
results = []
for spec in runs:
    t, diag, mem, log = spec.split(":", 3)
    n, m = contact_step_means(diag, ("step_s", "assembly_s", "solve_s", "newton_iters"))
    text = open(log).read()
    gb = re.search(r"graph builds\s+(\d+)", text)
    parts = re.search(r"FEM: (\d+) nodes.*MPM: (\d+) particles", text)
    results.append({"dim": 2, "size": "rings_paper", "solver": "Cholmod", "threads": int(t),
                    "contact_steps": n, **m,
                    "graph_builds": int(gb.group(1)) if gb else None,
                    "fem_nodes": int(parts.group(1)) if parts else None,
                    "particles": int(parts.group(2)) if parts else None,
                    "peak_rss_mib": round(int(open(mem).read().split()[-1]) / 1024, 1)})
    r = results[-1]
    print(f"  {t} thread(s): {n} contact steps, {r['step_s']:.3f} s per step (assembly {r['assembly_s']:.3f}, "
          f"solve {r['solve_s']:.3f}), {r['newton_iters']:.1f} Newton iterations, peak {r['peak_rss_mib']} MiB"
          f" (goal <= 0.25 s per step at 2 threads)")
write_results(out, "scenes", repo, results)
print(f"run_scenes.sh: wrote {out}")
PY
