#!/usr/bin/env python3
"""B1(b) error curves like paper 001 Fig. 5: (MM - SMM) / SMM of the mean axial
stress (in %) against strain, from the runs' own output written by
tests/scene/test_explicit_b1_strain.cpp into <build>/explicit_b1/*.csv.

usage: scripts/plot_b1.py [build/explicit_b1] [out.png]
"""
import csv
import os
import sys


def read(path):
    with open(path) as f:
        r = csv.DictReader(f)
        rows = [(float(x["strain"]), float(x["stress_yy_Pa"])) for x in r]
    return rows


def main():
    d = sys.argv[1] if len(sys.argv) > 1 else "build/explicit_b1"
    out = sys.argv[2] if len(sys.argv) > 2 else os.path.join(d, "b1_errors.png")
    pairs = [("lr", "smm_flip", "LR"), ("lr_xpic5", "smm_xpic5", "LR-XPIC(5)"),
             ("cp08", "smm_flip", "CP=0.8"), ("lr_once", "smm_flip", "LR once"),
             ("lr_usavg", "smm_flip_usavg", "LR (USAVG)"), ("lr_once_usavg", "smm_flip_usavg", "LR once (USAVG)"),
             ("lr_xpic5_usavg", "smm_xpic5_usavg", "LR-XPIC(5) (USAVG)")]
    try:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:  # no matplotlib: write the curves as CSV instead
        plt = None
    curves = {}
    for mm, smm, label in pairs:
        pm, ps = os.path.join(d, mm + ".csv"), os.path.join(d, smm + ".csv")
        if not (os.path.exists(pm) and os.path.exists(ps)):
            print("skipping", label, "(no", pm, "or", ps + ")")
            continue
        a, b = read(pm), read(ps)
        n = min(len(a), len(b))
        curves[label] = [(100 * a[i][0], 100 * (a[i][1] - b[i][1]) / abs(b[i][1])) for i in range(n) if b[i][1] != 0]
    if plt is None:
        out = os.path.splitext(out)[0] + ".csv"
        with open(out, "w") as f:
            f.write("variant,strain_percent,error_percent\n")
            for label, e in curves.items():
                for x, y in e:
                    f.write("%s,%.6g,%.6g\n" % (label, x, y))
        print("matplotlib missing: wrote", out)
        return
    fig, axes = plt.subplots(1, 2, figsize=(11, 4.2))
    for label, e in curves.items():
        for ax in axes:
            ax.plot([x for x, _ in e], [y for _, y in e], label=label)
    axes[0].set_title("A. all results")
    axes[1].set_title("B. zoom to +-1 %")
    axes[1].set_ylim(-1, 1)
    for ax in axes:
        ax.set_xlabel("strain (%)")
        ax.set_ylabel("(MM - SMM) / SMM (%)")
        ax.axhline(0, color="k", lw=0.5)
        ax.legend()
    fig.tight_layout()
    fig.savefig(out, dpi=120)
    print("wrote", out)


if __name__ == "__main__":
    main()
