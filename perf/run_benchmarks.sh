#!/usr/bin/env bash
# Runs a benchmark (default perf/bench_newton) at 1 and 2 OpenMP
# threads and merges both runs into one JSON with the machine's description.
# Builds nothing: build first with  ninja -C build bench_newton
#
#   perf/run_benchmarks.sh [--bench bench_newton|bench_mpm_newton|bench_ccd|bench_assembly|bench_explicit|bench_single_factor] [--build-dir DIR]
#                          [--out FILE] [--threads "1 2"]
#                          [--wait-quiet SECONDS] [-- options passed to the benchmark]
#
# Defaults: --bench bench_newton, --build-dir build, --out build/perf/newton.json
# (bench_mpm_newton: build/perf/mpm_newton.json; bench_ccd: build/perf/ccd.json),
# --threads "1 2" (bench_ccd: "1"; it times one query per call, serially;
# bench_single_factor: "2"; it times 1 thread and OMP_NUM_THREADS itself).
# --wait-quiet S: before each thread count, wait up to S seconds for the CPUs
# to be >= 95% idle for 6 s (the machine is shared; see perf/README.md).
# Compare the result with the stored baseline:
#   python3 perf/compare.py build/perf/newton.json
#   python3 perf/compare.py build/perf/mpm_newton.json --baseline perf/baselines/mpm_newton.json
set -euo pipefail

repo="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
build_dir="$repo/build"
out=""
threads=""
wait_quiet=0
extra=()
bench=bench_newton
while [[ $# -gt 0 ]]; do
  case "$1" in
    --bench) bench="$2"; shift 2 ;;
    --build-dir) build_dir="$(cd "$2" && pwd)"; shift 2 ;;
    --out) out="$2"; shift 2 ;;
    --threads) threads="$2"; shift 2 ;;
    --wait-quiet) wait_quiet="$2"; shift 2 ;;
    --) shift; extra=("$@"); break ;;
    -h|--help) sed -n '2,17p' "${BASH_SOURCE[0]}"; exit 0 ;;
    *) echo "run_benchmarks.sh: unknown argument '$1' (see --help)" >&2; exit 2 ;;
  esac
done
case "$bench" in
  bench_newton) bench_json=newton; bench_name=newton_iteration ;;
  bench_mpm_newton) bench_json=mpm_newton; bench_name=mpm_newton_iteration ;;
  bench_ccd) bench_json=ccd; bench_name=ccd_queries; [[ -n "$threads" ]] || threads="1" ;;
  bench_assembly) bench_json=assembly; bench_name=assembly ;;
  bench_explicit) bench_json=explicit; bench_name=explicit_step ;;
  bench_single_factor) bench_json=single_factor; bench_name=single_factor_solve; [[ -n "$threads" ]] || threads="2" ;;
  *) echo "run_benchmarks.sh: --bench '$bench': expected bench_newton, bench_mpm_newton, bench_ccd, bench_assembly, bench_explicit or bench_single_factor" >&2; exit 2 ;;
esac
[[ -n "$threads" ]] || threads="1 2"
[[ -n "$out" ]] || out="$build_dir/perf/$bench_json.json"
bin="$build_dir/perf/$bench"
if [[ ! -x "$bin" ]]; then
  echo "run_benchmarks.sh: $bin not found; build it first: ninja -C $build_dir $bench" >&2
  exit 2
fi
command -v python3 >/dev/null || { echo "run_benchmarks.sh: python3 is needed" >&2; exit 2; }

# The script builds nothing, so say when the binary is older than the sources it
# measures (the JSON records the git commit of the tree, not of the binary).
stale="$(find "$repo/src" "$repo/kernels" "$repo/perf/$bench.cpp" -newer "$bin" \
         \( -name '*.cpp' -o -name '*.hpp' \) -print -quit 2>/dev/null || true)"
if [[ -n "$stale" ]]; then
  echo "run_benchmarks.sh: warning: $bin is older than ${stale#$repo/} (and maybe more);" \
       "rebuild with: ninja -C $build_dir $bench" >&2
fi

# Percentage of CPU time idle over the next 2 seconds (all CPUs, /proc/stat).
idle_pct() {
  local a b
  read -r -a a < /proc/stat
  sleep 2
  read -r -a b < /proc/stat
  local total=0 idle=$(( (b[4] + b[5]) - (a[4] + a[5]) )) k
  for k in 1 2 3 4 5 6 7 8; do total=$(( total + b[k] - a[k] )); done
  echo $(( total > 0 ? 100 * idle / total : 0 ))
}

# Waits (up to $wait_quiet s) for 3 consecutive quiet samples; warns if the
# machine is busy when the run starts.
check_quiet() {
  local waited=0 ok=0 p
  while :; do
    p=$(idle_pct)
    if (( p >= 95 )); then ok=$((ok + 1)); else ok=0; fi
    if (( ok >= 3 || waited >= wait_quiet )); then break; fi
    waited=$((waited + 2))
  done
  idle_before=$p
  if (( p < 90 )); then
    echo "run_benchmarks.sh: warning: the CPUs are only ${p}% idle; other processes will" \
         "distort the timings (2-thread runs most)" >&2
  fi
}

tmp="$(mktemp -d)"
trap 'rm -rf "$tmp"' EXIT

# Pinned OpenMP threads, one per core; BLAS single-threaded so that Cholmod's
# supernodal BLAS calls do not add threads of their own on top of Kokkos'.
export OMP_PROC_BIND=spread OMP_PLACES=threads OPENBLAS_NUM_THREADS=1
runs=()
status=0
for t in $threads; do
  check_quiet
  echo "== $bench, OMP_NUM_THREADS=$t (load average: $(cut -d' ' -f1-3 /proc/loadavg))"
  start=$(date +%s.%N)
  if ! OMP_NUM_THREADS=$t "$bin" --out "$tmp/threads$t.json" "${extra[@]}"; then
    echo "run_benchmarks.sh: $bench failed at $t thread(s) (see above)" >&2
    status=1
  fi
  end=$(date +%s.%N)
  [[ -f "$tmp/threads$t.json" ]] || continue
  runs+=("$t:$(python3 -c "print(round($end - $start, 1))"):$idle_before:$tmp/threads$t.json")
done
[[ ${#runs[@]} -gt 0 ]] || { echo "run_benchmarks.sh: no run produced output" >&2; exit 1; }

mkdir -p "$(dirname "$out")"
BENCH_NAME="$bench_name" BENCH_BIN="$bin" BENCH_STALE="$stale" python3 - "$out" "$repo" "${runs[@]}" <<'PY'
import datetime, json, os, platform, subprocess, sys

out, repo, runs = sys.argv[1], sys.argv[2], sys.argv[3:]

def sh(*cmd):
    try:
        return subprocess.run(cmd, cwd=repo, capture_output=True, text=True,
                              check=True).stdout.strip()
    except Exception:
        return ""

cpu = ""
try:
    with open("/proc/cpuinfo") as f:
        for line in f:
            if line.startswith("model name"):
                cpu = line.split(":", 1)[1].strip()
                break
except OSError:
    pass
mem_gib = None
try:
    with open("/proc/meminfo") as f:
        mem_gib = round(int(f.readline().split()[1]) / 2**20, 1)
except (OSError, ValueError, IndexError):
    pass
with open("/proc/loadavg") as f:
    load = [float(x) for x in f.read().split()[:3]]
# Read-only git queries (--no-optional-locks: status must not rewrite the index).
dirty = sh("git", "--no-optional-locks", "status", "--porcelain", "--untracked-files=no")

merged = {
    "benchmark": os.environ.get("BENCH_NAME", "newton_iteration"),
    "date": datetime.datetime.now().astimezone().isoformat(timespec="seconds"),
    "machine": {
        "hostname": platform.node(),
        "nproc": os.cpu_count(),
        "nproc_available": len(os.sched_getaffinity(0)),
        "cpu_model": cpu,
        "memory_gib": mem_gib,
        "kernel": platform.release(),
        "loadavg_at_end": load,
    },
    "git": {"commit": sh("git", "rev-parse", "HEAD"), "tracked_changes": bool(dirty)},
    "binary": {"path": os.environ["BENCH_BIN"],
               "built": datetime.datetime.fromtimestamp(
                   os.path.getmtime(os.environ["BENCH_BIN"])).astimezone().isoformat(
                   timespec="seconds"),
               "older_than_sources": os.environ.get("BENCH_STALE", "") != ""},
    "env": {k: os.environ.get(k, "") for k in
            ("OMP_PROC_BIND", "OMP_PLACES", "OPENBLAS_NUM_THREADS")},
    "runs": [],
    "results": [],
}
for spec in runs:
    threads, wall, idle, path = spec.split(":", 3)
    with open(path) as f:
        run = json.load(f)
    for key in ("scene", "cg_preconditioner", "kokkos_backend"):
        merged.setdefault(key, run.get(key))
    merged["runs"].append({"threads": int(threads), "kokkos_threads": run.get("threads"),
                           "wall_s": float(wall), "cpu_idle_pct_before": int(idle)})
    merged["results"].extend(run["results"])
with open(out, "w") as f:
    json.dump(merged, f, indent=1)
    f.write("\n")
print(f"run_benchmarks.sh: wrote {out} "
      f"({len(merged['results'])} results; total {sum(r['wall_s'] for r in merged['runs']):.0f} s)")
PY
exit $status
