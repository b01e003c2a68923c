#!/usr/bin/env bash
# Runs bench_contact at 1 and 2 threads; writes build/perf/contact.json (or the
# file given as $1; pass perf/baselines/contact.json to record a new baseline,
# on a quiet machine). Needs a build in ./build. Compare with the baseline:
#   python3 perf/compare.py build/perf/contact.json --baseline perf/baselines/contact.json --fields eval_s,friction_s
set -euo pipefail
cd "$(dirname "$0")/.."
out=${1:-build/perf/contact.json}
mkdir -p "$(dirname "$out")"
tmp=$(mktemp -d)
for t in 1 2; do
  OMP_NUM_THREADS=$t OMP_PROC_BIND=spread OMP_PLACES=threads build/perf/bench_contact --out "$tmp/t$t.json"
done
/usr/bin/python3 - "$tmp" "$out" <<'PY'
import json, sys, subprocess
tmp, out = sys.argv[1], sys.argv[2]
runs = [json.load(open(f"{tmp}/t{t}.json")) for t in (1, 2)]
commit = subprocess.run(["git", "rev-parse", "--short", "HEAD"], capture_output=True, text=True).stdout.strip()
json.dump({"benchmark": "barrier_contact", "commit": commit, "runs": runs}, open(out, "w"), indent=1)
print(out)
PY
