#!/usr/bin/env python3
"""Draws a bfemp sweep: error of the first probe against wall time, one marker
per run (labelled with its --vary values), the Pareto front as a line.

    plot_sweep.py SWEEP_JSON OUT_PNG

Needs matplotlib (Debian: python3-matplotlib, i.e. /usr/bin/python3 here).
Runs that failed are listed under the axes, not drawn."""
import json
import sys


def short_label(label):
    """'MPM/grid spacing=0.1666; Contact/dhat=0.0277' -> 'grid spacing=0.1667, dhat=0.02778'."""
    parts = []
    for item in label.split("; "):
        key, _, value = item.partition("=")
        try:
            value = "%.4g" % float(value)
        except ValueError:
            pass
        parts.append("%s=%s" % (key.rsplit("/", 1)[-1], value))
    return ", ".join(parts)


def main():
    if len(sys.argv) != 3:
        print(__doc__, file=sys.stderr)
        return 2
    with open(sys.argv[1]) as f:
        sweep = json.load(f)
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    runs = sweep["runs"]
    ok = [r for r in runs if r["ok"] and r["error"] is not None and r["wall_s"] is not None]
    failed = [r for r in runs if not r["ok"]]
    fig, ax = plt.subplots(figsize=(8, 5.5))
    positive = [r for r in ok if r["error"] > 0]
    zero = [r for r in ok if r["error"] == 0]
    if positive:
        ax.scatter([r["wall_s"] for r in positive], [r["error"] for r in positive], c="tab:blue", zorder=3)
        for r in positive:
            ax.annotate(short_label(r["label"]), (r["wall_s"], r["error"]), fontsize=7, xytext=(4, 4),
                        textcoords="offset points")
        front = sorted([r for r in positive if r["pareto"]], key=lambda r: r["wall_s"])
        if front:
            ax.plot([r["wall_s"] for r in front], [r["error"] for r in front], "-", c="tab:orange",
                    label="Pareto front", zorder=2)
            ax.legend()
        ax.set_yscale("log")
    for r in zero:  # the reference itself: no error to draw on a log axis
        ax.axvline(r["wall_s"], ls=":", c="gray")
        ax.annotate("reference: " + short_label(r["label"]), (r["wall_s"], 0.5), xycoords=("data", "axes fraction"),
                    rotation=90, fontsize=7, va="center")
    ax.set_xscale("log")
    ax.set_xlabel("wall time per run (s), OMP_NUM_THREADS=%s" % (sweep.get("threads") or "?"))
    ax.set_ylabel("|%s - reference|" % sweep["probes"][0])
    ref = sweep["reference_source"]
    if ref.startswith("reference run [") or ref.startswith("last run of the grid ["):
        head, _, rest = ref.partition("[")
        ref = head + "[" + short_label(rest.rstrip("]")) + "]"
    ax.set_title("bfemp sweep: %s\nreference %.8g: %s" % (sweep["scene"].split("/")[-1], sweep["reference"] or
                                                           float("nan"), ref), fontsize=8)
    if failed:
        fig.text(0.01, 0.01, "failed: " + "; ".join("[%s] %s" % (r["label"], r["message"][:60]) for r in failed),
                 fontsize=6)
    ax.grid(True, which="both", alpha=0.3)
    fig.tight_layout()
    fig.savefig(sys.argv[2], dpi=120)
    return 0


if __name__ == "__main__":
    sys.exit(main())
