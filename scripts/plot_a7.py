#!/usr/bin/env python3
"""VALIDATION A7 (paper 000 section 6.7, Fig. 17): the mean rotation about z
of the MPM cube's top centre against time, one curve per friction mu, with
the twist of the shell's prescribed cap (pi/5 rad/s from t = 1 s).

Reads each run's bfemp.h5 (frames of `bfemp run inputs/a7_twist.yaml -o DIR
--set Contact/friction=MU`). The top centre: the particles with |x|, |y| <
0.25 and z > 0.85 at t = 0 (the same set as the `peak_rotation` probe of
scripts/validate.py). While the cube's top sticks to the shell it turns with
the cap; where it slips its rotation stops following (the peak is the slip
angle).

usage: plot_a7.py OUT.png MU=DIR [MU=DIR ...] [--title TEXT]   (needs h5py, numpy, matplotlib)
"""
import sys

import matplotlib
matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np

from h5frames import parse_args, particle_frames


def top_rotation(path):
    frames = particle_frames(path)
    x0 = frames[0][1]
    top = (np.abs(x0[:, 0]) < 0.25) & (np.abs(x0[:, 1]) < 0.25) & (x0[:, 2] > 0.85)
    top &= np.hypot(x0[:, 0], x0[:, 1]) > 1e-12
    a0 = np.arctan2(x0[top, 1], x0[top, 0])
    t, rot = [], []
    for time, x in frames:
        d = np.arctan2(x[top, 1], x[top, 0]) - a0
        d = (d + np.pi) % (2 * np.pi) - np.pi  # each angle in [-pi, pi), as the probe
        t.append(time)
        rot.append(d.mean())
    return np.array(t), np.array(rot)


def main():
    out, runs, title = parse_args(sys.argv[1:])
    fig, ax = plt.subplots(figsize=(6.5, 4.2))
    tmax = 0.0
    for mu, d in runs:
        t, rot = top_rotation(d)
        tmax = max(tmax, t[-1])
        k = int(np.argmax(np.abs(rot)))
        print(f"mu {mu}: frames to t = {t[-1]:.2f} s; peak rotation {rot[k] / np.pi:.3f} pi at t = {t[k]:.2f} s")
        ax.plot(t, rot / np.pi, label=f"mu = {mu} (peak {rot[k] / np.pi:.2f} pi)")
    tc = np.linspace(0, max(tmax, 1.0), 200)
    ax.plot(tc, np.clip(tc - 1.0, 0, 4.5) / 5.0, "k--", lw=0.8, label="shell cap twist")
    ax.set_xlabel("t (s)")
    ax.set_ylabel("rotation of the cube's top centre / pi")
    ax.set_title("A7: 3D twist with friction (paper Fig. 17)" + (f", {title}" if title else ""))
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(out, dpi=120)


if __name__ == "__main__":
    main()
