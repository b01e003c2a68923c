#!/usr/bin/env python3
"""VALIDATION A7 (paper 000 section 6.7, Fig. 17): the mean rotation about z
of the MPM cube's top centre against time, one curve per friction mu, with
the twist of the shell's prescribed cap (pi/5 rad/s from t = 1 s).

Reads each run's bfemp.h5 (frames of `bfemp run inputs/a7_twist.yaml -o DIR
--set Contact/friction=MU`). The top centre: the particles with |x|, |y| <
0.25 and z > 0.95 at t = 0, the top face's particles (the same set as the
`peak_rotation` band of scripts/validate.py); a thin dotted line of the same
colour shows the deeper set used before 2026-12-07 (z > 0.85), which turns
less because the twist falls off with depth under the press. While the cube's top sticks to the shell it turns with
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


def top_rotation(path, zmin=0.95, frames=None):
    frames = frames or particle_frames(path)
    x0 = frames[0][1]
    top = (np.abs(x0[:, 0]) < 0.25) & (np.abs(x0[:, 1]) < 0.25) & (x0[:, 2] > zmin)
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
        frames = particle_frames(d)
        t, rot = top_rotation(d, 0.95, frames)
        _, deep = top_rotation(d, 0.85, frames)
        tmax = max(tmax, t[-1])
        k = int(np.argmax(np.abs(rot)))
        kd = int(np.argmax(np.abs(deep)))
        print(f"mu {mu}: frames to t = {t[-1]:.2f} s; peak rotation {rot[k] / np.pi:.3f} pi at t = {t[k]:.2f} s "
              f"(z0 > 0.85: {deep[kd] / np.pi:.3f} pi at t = {t[kd]:.2f} s)")
        line, = ax.plot(t, rot / np.pi, label=f"mu = {mu} (peak {rot[k] / np.pi:.2f} pi)")
        ax.plot(t, deep / np.pi, ":", lw=0.9, color=line.get_color(), label=f"mu = {mu}, set z0 > 0.85 (before)")
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
