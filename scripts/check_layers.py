#!/usr/bin/env python3
"""Checks that every #include "dir/..." in the library goes to the same layer
or a lower one (ctest `layering`; the CMake libraries of src/CMakeLists.txt
follow the same layers, so a call upwards also fails to link).

Layers, bottom to top (a directory's files may include its own layer and the
ones below):
  0 base    core/, materials/, kernels/  (types, materials, the kernels and
                                          the plain data they work on)
  1 solver  solver/, time/               (DOF space, Newton, linear solvers)
  2 bodies  fem/, mpm/, contact/, explicit/  (energy terms, bodies, contact,
                                              the explicit stepper)
  3 sim     sim/                         (the implicit Simulation)
  4 io      io/                          (scene input, output, checkpoints)
  5 app     app/, probes/, sweep/        (run, restart, probe, sweep)
Within the bodies layer contact/ sits above fem/ and mpm/, and explicit/
above mpm/ (it uses the MPM grid): peers may not include each other
otherwise.

Usage: check_layers.py [REPO]   (exit 1 and one line per violation)
"""
import os
import re
import sys

LAYER = {"core": 0, "materials": 0, "kernels": 0, "solver": 1, "time": 1, "fem": 2, "mpm": 2, "contact": 2,
         "explicit": 2, "sim": 3, "io": 4, "app": 5, "probes": 5, "sweep": 5}
# Allowed includes between two directories of one layer.
PEERS = {("contact", "fem"), ("contact", "mpm"), ("explicit", "mpm"), ("probes", "app"), ("sweep", "app"),
         ("sweep", "probes"), ("app", "probes"), ("kernels", "core"), ("kernels", "materials"),
         ("materials", "core"), ("time", "solver"), ("solver", "time")}


def directory_of(path, repo):
    rel = os.path.relpath(path, repo).split(os.sep)
    if rel[0] == "kernels":
        return "kernels"
    if rel[0] == "src" and len(rel) > 2:
        return rel[1]
    return None


def main():
    repo = sys.argv[1] if len(sys.argv) > 1 else os.path.join(os.path.dirname(os.path.abspath(__file__)), "..")
    bad = []
    checked = 0
    for top in ("src", "kernels"):
        for dirpath, _, files in os.walk(os.path.join(repo, top)):
            for f in sorted(files):
                if not f.endswith((".hpp", ".cpp")):
                    continue
                path = os.path.join(dirpath, f)
                mine = directory_of(path, repo)
                if mine not in LAYER:
                    bad.append(f"{os.path.relpath(path, repo)}: directory '{mine}' has no layer in check_layers.py")
                    continue
                for n, line in enumerate(open(path, encoding="utf-8"), 1):
                    m = re.match(r'\s*#include "([a-z_]+)/', line)
                    if not m:
                        continue
                    checked += 1
                    other = m.group(1)
                    if other not in LAYER:
                        bad.append(f"{os.path.relpath(path, repo)}:{n}: includes '{other}/', which has no layer")
                    elif other == mine or (mine, other) in PEERS:
                        continue
                    elif LAYER[other] > LAYER[mine]:
                        bad.append(f"{os.path.relpath(path, repo)}:{n}: {mine}/ (layer {LAYER[mine]}) includes "
                                   f"{line.strip()[9:]} (layer {LAYER[other]}): an include upwards")
                    elif LAYER[other] == LAYER[mine]:
                        bad.append(f"{os.path.relpath(path, repo)}:{n}: {mine}/ includes its peer {other}/ "
                                   f"(not in check_layers.py's PEERS)")
    for b in bad:
        print(b)
    print(f"check_layers.py: {checked} includes checked, {len(bad)} violation(s)")
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
