#!/usr/bin/python3
"""Plots a run's diagnostics.csv: energies, momentum, Newton iterations, min J.

Usage: scripts/plot_diagnostics.py OUT_DIR [--output FILE.png]
"""
import argparse
import csv
import os

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


def main():
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("run_dir")
    ap.add_argument("--output", default=None, help="PNG file (default RUN_DIR/diagnostics.png)")
    args = ap.parse_args()
    path = os.path.join(args.run_dir, "diagnostics.csv")
    with open(path, newline="") as f:
        rows = list(csv.DictReader(f))
    if not rows:
        raise SystemExit(f"{path}: no rows")
    col = {k: [float(r[k]) for r in rows] for k in rows[0]}
    t = col["time"]
    fig, ax = plt.subplots(2, 2, figsize=(11, 7), sharex=True)
    for k in ("kinetic", "elastic", "potential", "total_energy"):
        ax[0, 0].plot(t, col[k], label=k)
    ax[0, 0].set_ylabel("energy (J)")
    ax[0, 0].legend()
    for k in ("momentum_x", "momentum_y", "momentum_z"):
        ax[0, 1].plot(t, col[k], label=k)
    ax[0, 1].set_ylabel("linear momentum")
    ax[0, 1].legend()
    ax[1, 0].plot(t, col["newton_iters"], ".-")
    ax[1, 0].set_ylabel("Newton iterations")
    ax[1, 1].plot(t, col["min_J"])
    ax[1, 1].set_ylabel("min J")
    for a in ax[1]:
        a.set_xlabel("time (s)")
    fig.tight_layout()
    out = args.output or os.path.join(args.run_dir, "diagnostics.png")
    fig.savefig(out, dpi=110)
    print(out)


if __name__ == "__main__":
    main()
