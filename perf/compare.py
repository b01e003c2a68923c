#!/usr/bin/env python3
"""Compare a Newton-benchmark run with the stored baseline.

    python3 perf/compare.py RUN.json [RUN2.json ...] [--baseline perf/baselines/newton.json]
                            [--threshold 0.25] [--min-abs 0.001]
                            [--fields assembly_s,solve_s,line_search_s]
                            [--changed-only]
    python3 perf/compare.py RUN.json --summary     # Markdown table of one run

RUN.json is what perf/run_benchmarks.sh writes (or a single bench_newton
output); with several runs, each timing is the best (minimum) of them, which
filters out most of the noise of a shared machine. Configurations are matched
on (dim, size, solver, threads). For every timing field the table shows the
baseline, the new value and their ratio; a timing regresses when

    now > baseline * (1 + threshold)   and   now - baseline > min_abs

(min_abs keeps sub-millisecond noise on the small cases from failing a run).

Exit status: 0 no regression; 1 at least one regression, or a configuration
that ran in the baseline and failed now; 2 bad usage / unreadable input.
Missing, skipped and changed-mesh configurations are reported as warnings.
"""
import argparse
import json
import os
import sys

DEFAULT_BASELINE = os.path.join(os.path.dirname(os.path.abspath(__file__)),
                                "baselines", "newton.json")
DEFAULT_FIELDS = "assembly_s,solve_s,line_search_s"


def flatten_runs(data):
    """The older per-thread layout of run_contact.sh / run_transfers.sh
    ({"runs": [{"threads": t, "cases": [...]}, ...]}) as a results list:
    dim (2 unless the case says), size = the case's particle count (and facet
    count), solver = the benchmark name, threads from the run."""
    results = []
    for run in data.get("runs", []):
        if not isinstance(run, dict) or "cases" not in run:
            continue
        for case in run["cases"]:
            r = dict(case)
            r["threads"] = run.get("threads", 1)
            r.setdefault("dim", 2)
            size = str(case.get("particles", ""))
            if "facets" in case:
                size += "/" + str(case["facets"])
            r["size"] = size
            r["solver"] = data.get("benchmark", "")
            results.append(r)
    return results


def load(path):
    try:
        with open(path) as f:
            data = json.load(f)
    except (OSError, ValueError) as e:
        print(f"compare.py: cannot read {path}: {e}", file=sys.stderr)
        sys.exit(2)
    if "results" not in data and "runs" in data:
        data["results"] = flatten_runs(data)
    if "results" not in data:
        print(f"compare.py: {path} has no 'results' (not a bench_newton output?)",
              file=sys.stderr)
        sys.exit(2)
    table = {}
    for r in data["results"]:
        key = (r["dim"], r["size"], r["solver"], r["threads"])
        table[key] = r
    return data, table


def best_of(paths):
    """Loads one or more runs of the same benchmark; every timing field (top-level
    key ending in _s) becomes its minimum over the runs (best of N), the rest comes
    from the first run. A configuration that failed in any run counts as failed."""
    loaded = [load(p) for p in paths]
    data, first = loaded[0]
    table = {}
    for key, r in first.items():
        entries = [t[key] for _, t in loaded if key in t]
        merged = dict(r)
        failed = [e for e in entries if "failed" in e]
        if failed:
            merged = dict(failed[0])
        elif "skipped" not in r:
            for field, value in r.items():
                if field.endswith("_s") and isinstance(value, (int, float)):
                    values = [e[field] for e in entries
                              if isinstance(e.get(field), (int, float))]
                    merged[field] = min(values)
        table[key] = merged
    for _, t in loaded[1:]:
        for key, r in t.items():
            table.setdefault(key, r)
    datas = [d for d, _ in loaded]
    combined = dict(data)
    combined["results"] = list(table.values())
    return combined, table, datas


def fmt(v):
    if v is None:
        return "-"
    if v >= 1:
        return f"{v:.3f}"
    if v >= 1e-3:
        return f"{v * 1e3:.2f}m"
    return f"{v * 1e6:.0f}u"


def ms(v):
    """Milliseconds, 3 significant digits (for the Markdown summary)."""
    if v is None:
        return "-"
    v *= 1e3
    return f"{v:.0f}" if v >= 100 else f"{v:.3g}"


def order(key):
    dim, size, solver, threads = key
    sizes = {"small": 0, "medium": 1, "large": 2}
    solvers = {"Cholmod": 0, "KLU2": 1, "CG": 2}
    return (dim, sizes.get(size, 9), solvers.get(solver, 9), solver, threads)


def summary(data):
    """Markdown table of one run: per-iteration figures at each thread count."""
    by = {}
    threads = sorted({r["threads"] for r in data["results"]})
    for r in data["results"]:
        by.setdefault((r["dim"], r["size"], r["solver"]), {})[r["threads"]] = r
    t0 = threads[0]
    cols = ["config", "DOFs", "elements", "Newton its"]
    for f in ("assembly", "solve", "line search"):
        cols += [f"{f} {t}t" for t in threads]
        if f == "assembly" and len(threads) > 1:
            cols += [f"assembly speed-up {t0}->{t}t" for t in threads[1:]]
    cols += [f"set-up {t0}t"]
    print("| " + " | ".join(cols) + " |")
    print("|" + "|".join("---" if i == 0 else "---:" for i in range(len(cols))) + "|")
    for key in sorted(by, key=lambda k: order(k + (0,))):
        runs = by[key]
        first = runs.get(t0) or next(iter(runs.values()))
        name = "{}D {} {}".format(*key)
        if "skipped" in first or "failed" in first:
            why = "skipped" if "skipped" in first else "FAILED"
            print(f"| {name} | {first.get('dofs', '')} | {first.get('elements', '')} | {why} |"
                  + " |" * (len(cols) - 4))
            continue
        its = "/".join(str(runs[t].get("iterations", "-")) for t in threads if t in runs)
        row = [name, str(first["dofs"]), str(first["elements"]), its]
        for f in ("assembly_s", "solve_s", "line_search_s"):
            row += [ms(runs[t].get(f)) if t in runs else "-" for t in threads]
            if f == "assembly_s" and len(threads) > 1:
                for t in threads[1:]:
                    a0, a1 = first.get("assembly_s"), runs.get(t, {}).get("assembly_s")
                    row.append(f"{a0 / a1:.2f}x" if a0 and a1 else "-")
        row.append(ms(first.get("setup_total_s")))
        print("| " + " | ".join(row) + " |")
    print("\ntimes in milliseconds per Newton iteration; Newton its: total over "
          "the measured steps at each thread count; set-up: construction + one-time "
          "first-iteration cost (ms)")


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("run", nargs="+",
                    help="JSON written by perf/run_benchmarks.sh or bench_newton; with several "
                         "files (repeated runs) every timing is the best of them")
    ap.add_argument("--baseline", default=DEFAULT_BASELINE,
                    help="baseline JSON (default: perf/baselines/newton.json)")
    ap.add_argument("--threshold", type=float, default=0.25,
                    help="relative slow-down that counts as a regression (default 0.25 = 25%%)")
    ap.add_argument("--min-abs", type=float, default=1e-3,
                    help="ignore slow-downs smaller than this many seconds (default 0.001)")
    ap.add_argument("--fields", default=DEFAULT_FIELDS,
                    help=f"comma-separated timing fields to compare (default {DEFAULT_FIELDS}; "
                         "also: iteration_s, setup_s, setup_total_s, step_s)")
    ap.add_argument("--changed-only", action="store_true",
                    help="print only the rows flagged faster or REGRESSION")
    ap.add_argument("--summary", action="store_true",
                    help="print a Markdown table of RUN alone (1 vs 2 threads, speed-up) and exit")
    args = ap.parse_args()
    if args.summary:
        summary(best_of(args.run)[0])
        return 0
    if args.threshold < 0 or args.min_abs < 0:
        ap.error("--threshold and --min-abs must be >= 0")
    fields = [f for f in args.fields.split(",") if f]

    base_data, base = load(args.baseline)
    run_data, run, run_datas = best_of(args.run)

    warnings, regressions, failures, missing = [], [], [], []
    rows = []
    for key in sorted(set(base) | set(run), key=order):
        name = "{}d/{}/{} t={}".format(*key)
        b, r = base.get(key), run.get(key)
        if b is None:
            warnings.append(f"{name}: not in the baseline (new configuration)")
            continue
        if r is None:
            missing.append(name)
            continue
        if "failed" in r:
            if "failed" not in b:
                failures.append(f"{name}: FAILED now: {r['failed']}")
            continue
        if "skipped" in r or "skipped" in b:
            if ("skipped" in r) != ("skipped" in b):
                warnings.append(f"{name}: skipped in {'this run' if 'skipped' in r else 'the baseline'}")
            continue
        if "failed" in b:
            warnings.append(f"{name}: failed in the baseline, runs now")
            continue
        if r.get("dofs") != b.get("dofs"):
            warnings.append(f"{name}: mesh changed ({b.get('dofs')} -> {r.get('dofs')} DOFs); "
                            "timings are not comparable")
        if r.get("iterations") != b.get("iterations") or r.get("steps") != b.get("steps"):
            warnings.append(f"{name}: Newton iterations {b.get('iterations')} in "
                            f"{b.get('steps')} step(s) -> {r.get('iterations')} in "
                            f"{r.get('steps')} (per-iteration figures still compare)")
        lb, lr = b.get("linear_iterations_per_newton"), r.get("linear_iterations_per_newton")
        if lb and lr and key[2] == "CG" and abs(lr - lb) > 0.1 * lb:
            warnings.append(f"{name}: CG iterations per Newton iteration {lb:.1f} -> {lr:.1f}")
        for field in fields:
            vb, vr = b.get(field), r.get(field)
            if vb is None or vr is None:
                continue
            ratio = vr / vb if vb > 0 else float("inf") if vr > 0 else 1.0
            regressed = vr > vb * (1 + args.threshold) and vr - vb > args.min_abs
            improved = vr < vb / (1 + args.threshold) and vb - vr > args.min_abs
            flag = "REGRESSION" if regressed else "faster" if improved else ""
            if regressed:
                regressions.append(f"{name} {field}: {ms(vb)} -> {ms(vr)} ms ({ratio:.2f}x)")
            rows.append((name, field, fmt(vb), fmt(vr), f"{ratio:.2f}", flag))

    if missing:
        warnings.append(f"{len(missing)} baseline configuration(s) not in this run: "
                        + ", ".join(missing[:4]) + (" ..." if len(missing) > 4 else ""))
    # Results are only as good as the machine was quiet: say so.
    labelled = [("baseline", base_data)] + [
        (f"run {p}" if len(args.run) > 1 else "run", d) for p, d in zip(args.run, run_datas)]
    for label, data in labelled:
        m = data.get("machine", {})
        la = m.get("loadavg_at_end")
        nproc = m.get("nproc")
        if la and nproc and la[0] > nproc:
            warnings.append(f"{label}: load average {la[0]} on {nproc} CPUs at the end of the "
                            "run; other processes competed for the cores")
        if data.get("binary", {}).get("older_than_sources"):
            warnings.append(f"{label}: bench_newton was older than the sources when it ran "
                            f"(built {data['binary'].get('built')}); the git commit "
                            "does not describe the measured code")
        for run in data.get("runs", []):
            idle = run.get("cpu_idle_pct_before")
            if idle is not None and idle < 90:
                warnings.append(f"{label}: the CPUs were only {idle}% idle when the "
                                f"{run['threads']}-thread run started")
        low = [f"{r['dim']}d/{r['size']}/{r['solver']}"
               for r in data["results"] if r.get("threads") == 1 and
               r.get("cpu_utilisation", 1) < 0.8]
        if low:
            warnings.append(f"{label}: 1-thread configurations that got < 80% of a core "
                            "(starved by other processes): "
                            + ", ".join(low[:6]) + (" ..." if len(low) > 6 else ""))

    shown = [x for x in rows if x[5]] if args.changed_only else rows
    header = ("config", "field", "baseline", "now", "ratio", "")
    widths = [max(len(str(x[i])) for x in shown + [header]) for i in range(len(header))]
    print(f"baseline: {args.baseline} ({base_data.get('date', '?')}, "
          f"commit {base_data.get('git', {}).get('commit', '?')[:10]})")
    for p, d in zip(args.run, run_datas):
        print(f"run:      {p} ({d.get('date', '?')}, "
              f"commit {d.get('git', {}).get('commit', '?')[:10]})")
    if len(args.run) > 1:
        print(f"          timings: best of the {len(args.run)} runs")
    print(f"threshold +{args.threshold:.0%}, min_abs {args.min_abs} s; seconds per Newton "
          "iteration (m = milli, u = micro)"
          + (f"; {len(rows) - len(shown)} unchanged rows hidden" if args.changed_only else ""))
    for row in [header] + shown:
        print("  ".join(str(c).ljust(w) if i < 2 else str(c).rjust(w)
                        for i, (c, w) in enumerate(zip(row, widths))).rstrip())
    for w in warnings:
        print(f"warning: {w}")
    for f in failures:
        print(f"error: {f}")
    if regressions:
        print(f"{len(regressions)} regression(s) over +{args.threshold:.0%}:")
        for x in regressions:
            print(f"  {x}")
    if regressions or failures:
        return 1
    print("no regressions")
    return 0


if __name__ == "__main__":
    sys.exit(main())
