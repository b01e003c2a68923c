#!/usr/bin/env python3
"""VALIDATION A6 (paper 000 section 6.6, Fig. 15): the inner MPM semi-ring's
crown against the plate's travel, one curve per inner-outer friction mu.

Reads each run's bfemp.h5 (frames of `bfemp run inputs/a6_semiring_buckling.yaml
-o DIR --set 'Contact/Friction Pairs/inner : outer=MU' --set 'Time/end time=8'`).
The crown: the particles with |x| < 1 and y > 9.5 at t = 0. While the rings
are pressed together the crown follows the plate (plate travel = t x 1 m/s);
when the inner ring buckles it falls away from the outer ring and its crown
runs ahead of the plate. The onset is taken where the crown's lead over the
plate first exceeds 0.15 m (the gaps the plate closes before pressing are
about 0.05-0.09 m of lag).

usage: plot_a6.py OUT.png MU=DIR [MU=DIR ...] [--title TEXT]   (needs h5py, numpy, matplotlib)
"""
import sys

import matplotlib
matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np

from h5frames import parse_args, particle_frames


def crown_lead(path):
    frames = particle_frames(path)
    x0 = frames[0][1]
    crown = (np.abs(x0[:, 0]) < 1.0) & (x0[:, 1] > 9.5)
    t, lead = [], []
    for time, x in frames:
        uy = x[crown, 1].mean() - x0[crown, 1].mean()
        t.append(time)
        lead.append(-(uy + time))  # crown travel beyond the plate's (m)
    return np.array(t), np.array(lead)


def main():
    out, runs, title = parse_args(sys.argv[1:])
    fig, ax = plt.subplots(figsize=(6, 4))
    for mu, d in runs:
        t, lead = crown_lead(d)
        over = np.nonzero(lead > 0.15)[0]
        onset = t[over[0]] if len(over) else None
        print(f"mu {mu}: frames to plate travel {t[-1]:.2f} m; onset (crown 0.15 m ahead of the plate) at "
              + (f"{onset:.2f} m" if onset is not None else "none"))
        ax.plot(t, lead, label=f"mu = {mu}" + (f" (onset {onset:.1f} m)" if onset is not None else " (no onset)"))
    ax.axhline(0.15, color="grey", lw=0.8, ls="--")
    ax.set_xlabel("plate travel (m)")
    ax.set_ylabel("inner crown travel beyond the plate (m)")
    ax.set_title("A6: inner semi-ring buckling vs friction" + (f" ({title})" if title else ""))
    ax.legend()
    fig.tight_layout()
    fig.savefig(out, dpi=120)


if __name__ == "__main__":
    main()
