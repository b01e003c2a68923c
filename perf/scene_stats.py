"""Shared by the whole-scene benchmarks (run_scenes.sh, run_twist_ranks.sh):
the mean per contact step of a run's diagnostics.csv columns, and the JSON
file perf/compare.py reads."""
import csv
import datetime
import json
import subprocess


def contact_step_means(diagnostics, keys):
    """(number of contact steps, {key: mean over them}) of a diagnostics.csv;
    a contact step is a step after the first with contact pairs."""
    rows = [r for r in csv.DictReader(open(diagnostics)) if int(r["step"]) > 0 and int(r["contact_pairs"]) > 0]
    n = len(rows)
    return n, {k: (sum(float(r[k]) for r in rows) / n if n else float("nan")) for k in keys}


def write_results(out, benchmark, repo, results):
    try:
        commit = subprocess.run(["git", "rev-parse", "HEAD"], cwd=repo, capture_output=True, text=True,
                                check=True).stdout.strip()
    except Exception:
        commit = ""
    json.dump({"benchmark": benchmark, "date": datetime.datetime.now().astimezone().isoformat(timespec="seconds"),
               "git": {"commit": commit}, "results": results}, open(out, "w"), indent=1)
