#!/usr/bin/env python3
"""A7 (3D twist): is the friction law or the cube's stiffness behind the slip angle?

    scripts/a7_friction_check.py RUN_DIR[+CONTINUATION_DIR] MU [--every N] [--zmin Z]

Reads RUN_DIR/bfemp.h5 (h5py) and prints per frame, from the cube's particle
contact forces f_p (barrier + friction, N) and positions x_p:
  - the torque about the shell centre's z axis, T = sum (d_p x f_p)_z, with
    d_p = x_p - c and c the mean of the shell's nodes (N m);
  - the friction capacity C = mu sum |f_p . n_p| r_p with n_p = d_p/|d_p| (the
    sphere's normal) and r_p = |(d_p)_xy| (N m): T/C -> 1 while the whole patch
    slides, if the law delivers mu times the normal force;
  - the rotation of the top centre (particles with |x|,|y| <= 0.25,
    z >= Z at t = 0, default 0.95: the top face's particles, as the
    peak_rotation band of scripts/validate.py; before 2026-12-07 the box went
    down to 0.85; mean angle about z, rad/pi), the cap's prescribed angle
    (pi/5 rad/s after t = 1 s), and the ratio T/rotation (the cube's torsional
    stiffness seen from the contact while the top sticks, N m/rad).
"""
import argparse

import h5py
import numpy as np

ap = argparse.ArgumentParser()
ap.add_argument("run")
ap.add_argument("mu", type=float)
ap.add_argument("--every", type=int, default=3)
ap.add_argument("--zmin", type=float, default=0.95)
a = ap.parse_args()
# RUN may chain runs as DIR1+DIR2 (a run continued elsewhere, as scripts/h5frames.py):
# the top centre is chosen in DIR1's first frame, and each later run adds its
# frames after the last time before it.
frames = []
for d in a.run.split("+"):
    f = h5py.File(d + "/bfemp.h5", "r")
    last = float(frames[-1].attrs["time"]) if frames else -float("inf")
    frames += [f[k] for k in sorted(k for k in f.keys() if k.startswith("frame_"))
               if float(f[k].attrs["time"]) > last + 1e-9]
x0 = frames[0]["particle_positions"][:]
top = (np.abs(x0[:, 0]) <= 0.25) & (np.abs(x0[:, 1]) <= 0.25) & (x0[:, 2] >= a.zmin)
ang0 = np.arctan2(x0[top, 1], x0[top, 0])
print("t_s  cap_pi  top_pi  torque_Nm  capacity_Nm  T/C  T/rot_Nm_per_rad")
for g in frames[:: a.every]:
    t = float(g.attrs.get("time", 0.0))
    x = g["particle_positions"][:]
    F = g["particle_contact_force"][:]
    c = g["positions"][:].mean(axis=0)
    on = np.linalg.norm(F, axis=1) > 0
    if not on.any():
        continue
    d = x[on] - c
    n = d / np.linalg.norm(d, axis=1)[:, None]
    fn = np.sum(F[on] * n, axis=1)
    T = float(np.sum(d[:, 0] * F[on][:, 1] - d[:, 1] * F[on][:, 0]))
    C = a.mu * float(np.sum(np.abs(fn) * np.hypot(d[:, 0], d[:, 1])))
    ang = np.arctan2(x[top, 1], x[top, 0])
    rot = float(np.mean(np.angle(np.exp(1j * (ang - ang0)))))
    cap = max(0.0, t - 1.0) / 5.0
    k_t = T / rot if abs(rot) > 1e-3 else float("nan")
    tc = T / C if C > 0 else float("nan")
    print(f"{t:4.1f}  {cap:6.3f}  {rot / np.pi:6.3f}  {T:10.4g}  {C:11.4g}  {tc:5.3f}  {k_t:10.4g}")
