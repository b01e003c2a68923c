#!/usr/bin/env bash
# The bfemp executable on 1 and 2 MPI ranks (label mpi): the squash scene
# (FEM only, CG) gives the same frames and diagnostics on both; on 2 ranks a
# direct solver and an explicit scene are refused before the
# first step (exit 2, a message naming the key), as are particles starting outside the grid or
# inside a level set's solid, found in one rank's sampled block or in both (the message 1 rank gives); a 2-rank run restarted on 2 ranks equals the
# uninterrupted one bit for bit. The MPM column (MPM alone: particles in slabs) gives the same
# frames on 1 and 2 ranks (particles written in scene order: each rank its block, MPI-IO), and its 2-rank restart equals
# the uninterrupted run to solver tolerance (the restart re-cuts the slabs), as do a 1-rank
# run restarted on 2 ranks (its serial HDF5 file continued through MPI-IO) and the 2-rank
# checkpoint (each rank wrote its row block, MPI-IO) restarted on 1 and on 3 ranks, and on 2
# with its row blocks removed (the older format, read whole). The colliding
# rings (MPM + FEM, barrier contact) write the same frames on 1 and 2 ranks, the particles'
# contact forces included (in scene order), as do the A6 rings (FEM-FEM contact
# and a slip level set beside MPM-FEM contact) and two FEM blocks in FEM-FEM
# contact (FEM bodies only). The 3D twist (A7, coarsened, shortened)
# with friction on 2 ranks (CG + BLOCK_CHOLMOD) equals 1 rank (Cholmod): the cube is cut at x = 0 under the
# shell, so contact pairs and their lagged friction live on both ranks. Usage: run_np2.sh BFEMP SOURCE_DIR WORK_DIR
set -euo pipefail
exe=$1; src=$2; work=$3
rm -rf "$work"; mkdir -p "$work"
mpi=(mpirun --oversubscribe --allow-run-as-root --bind-to none -x OMP_NUM_THREADS=1 -x OMP_PROC_BIND=false -x OPENBLAS_NUM_THREADS=1)
scene=$src/tests/data/squash_10_steps.yaml
# compare_frames DIR1 DIR2 NFRAMES FIELD,FIELD,... [NONZERO_FIELD]: the two runs
# wrote NFRAMES frames whose FIELDs agree to 1e-8 of their largest value
# (from frame 1 on), and NONZERO_FIELD is not all zero in them.
compare_frames() {
/usr/bin/python3 - "$@" <<'PY'
import sys, h5py, numpy as np
a, b, n, fields = sys.argv[1], sys.argv[2], int(sys.argv[3]), sys.argv[4].split(",")
nonzero = sys.argv[5] if len(sys.argv) > 5 else None
with h5py.File(a + "/bfemp.h5", "r") as fa, h5py.File(b + "/bfemp.h5", "r") as fb:
    fr = sorted(k for k in fa if k.startswith("frame_"))
    assert fr == sorted(k for k in fb if k.startswith("frame_")) and len(fr) == n, fr
    for f in fr[1:]:
        if nonzero:
            assert np.abs(fa[f][nonzero][()]).max() > 0, f"{f}: {nonzero} is zero: the check checks nothing"
        for d in fields:
            va, vb = fa[f][d][()], fb[f][d][()]
            err = np.abs(va - vb).max() / np.abs(va).max()
            assert err < 1e-8, f"{f}/{d}: relative difference {err}"
PY
}
cg=(--set 'Linear Solver/type=CG' --set 'Output/frame every=5')
"${mpi[@]}" -np 1 "$exe" run "$scene" --output "$work/np1" "${cg[@]}" > "$work/np1.log" 2>&1
"${mpi[@]}" -np 2 "$exe" run "$scene" --output "$work/np2" "${cg[@]}" > "$work/np2.log" 2>&1
grep -q "MPI: 2 ranks" "$work/np2.log" || { echo "no MPI line in the 2-rank banner"; cat "$work/np2.log"; exit 1; }
[ "$(grep -c "^summary" "$work/np2.log")" = 1 ] || { echo "the 2-rank summary is not printed once"; cat "$work/np2.log"; exit 1; }
/usr/bin/python3 - "$work/np1" "$work/np2" <<'PY'
import sys, csv, h5py, numpy as np
a, b = sys.argv[1], sys.argv[2]
with h5py.File(a + "/bfemp.h5", "r") as fa, h5py.File(b + "/bfemp.h5", "r") as fb:
    fr_a = sorted(k for k in fa if k.startswith("frame_"))
    fr_b = sorted(k for k in fb if k.startswith("frame_"))
    assert fr_a == fr_b and len(fr_a) == 3, (fr_a, fr_b)
    x0 = fa["frame_000000/positions"][()]
    for f in fr_a:
        for d in fa[f]:
            va, vb = fa[f][d][()], fb[f][d][()]
            assert va.shape == vb.shape, (f, d, va.shape, vb.shape)
            scale = max(np.abs(fa[fr_a[-1]]["positions"][()] - x0).max(), 1e-30) if d == "positions" else max(np.abs(va).max(), 1e-30)
            err = np.abs(va - vb).max() / scale
            # Newton stops at |p|/dt < 1e-9 m/s (dt 0.01): 1e-11 m against 0.1 m.
            assert err < 1e-8, f"{f}/{d}: relative difference {err}"
ra = list(csv.DictReader(open(a + "/diagnostics.csv")))
rb = list(csv.DictReader(open(b + "/diagnostics.csv")))
assert len(ra) == len(rb) == 10, (len(ra), len(rb))
for x, y in zip(ra, rb):
    for k in ("kinetic", "elastic", "potential"):
        u, v = float(x[k]), float(y[k])
        assert abs(u - v) <= 1e-8 * max(abs(u), 1e-12), (x["step"], k, u, v)
    # (Newton iteration counts may differ: CG's inexact-Newton directions
    # depend on the rank count through the preconditioner; the minimiser
    # does not.)
print("1 and 2 ranks agree: 3 frames, 10 diagnostics rows")
PY
# Restart on 2 ranks: 5 steps, then `bfemp restart` to step 10, equals the
# uninterrupted 2-rank run (same partition, same operations) bit for bit.
"${mpi[@]}" -np 2 "$exe" run "$scene" --output "$work/np2_half" "${cg[@]}" --set 'Time/end time=0.0475' > "$work/np2_half.log" 2>&1
"${mpi[@]}" -np 2 "$exe" restart "$work/np2_half" --set 'Time/end time=0.1' > "$work/np2_restart.log" 2>&1 \
  || { echo "restart on 2 ranks failed"; cat "$work/np2_restart.log"; exit 1; }
/usr/bin/python3 - "$work/np2" "$work/np2_half" <<'PY'
import sys, csv, h5py
a, b = sys.argv[1], sys.argv[2]
with h5py.File(a + "/checkpoint.h5", "r") as fa, h5py.File(b + "/checkpoint.h5", "r") as fb:
    assert int(fa["checkpoint"].attrs["step"]) == int(fb["checkpoint"].attrs["step"]) == 10
    for k in ("fem_x", "fem_v"):
        va, vb = fa["checkpoint"][k][()], fb["checkpoint"][k][()]
        assert (va == vb).all(), f"checkpoint {k}: the restarted 2-rank run differs from the uninterrupted one"
ra = list(csv.DictReader(open(a + "/diagnostics.csv")))
rb = list(csv.DictReader(open(b + "/diagnostics.csv")))
assert len(ra) == len(rb) == 10, (len(ra), len(rb))
for x, y in zip(ra, rb):
    for k in ("kinetic", "elastic", "newton_iters"):
        assert x[k] == y[k], (x["step"], k, x[k], y[k])
print("restart on 2 ranks: 5 + 5 steps equal 10 bit for bit")
PY
set +e
"${mpi[@]}" -np 2 "$exe" run "$scene" --output "$work/direct" > "$work/direct.log" 2>&1; rc=$?
set -e
[ $rc = 2 ] && grep -q "Linear Solver/type" "$work/direct.log" || { echo "direct solver on 2 ranks: exit $rc"; cat "$work/direct.log"; exit 1; }
[ ! -e "$work/direct/bfemp.h5" ] || { echo "the refused run wrote output"; exit 1; }
# FEM-FEM contact in a scene of FEM bodies only: a block dropped on a held
# one under gravity (every rank holds the whole mesh and evaluates the pairs of
# the boundary nodes it owns). 1 and 2 ranks write the same frames.
cat > "$work/fem_fem.yaml" <<'YAML'
bfemp:
  dimension: 2
  gravity: [0.0, -10.0]
  Time: {dt: 1.0e-2, end time: 0.2, integrator: backward-euler}
  Newton: {eps_d: 1.0e-9}
  Output: {frame every: 10}
  Materials:
    soft: {E: 1.0e5, nu: 0.3, density: 1000.0}
  FEM Bodies:
    lower:
      material: soft
      Mesh: {shape: rectangle, center: [0.0, 0.0], size: [1.0, 0.2], element size: 0.1}
      Boundary Conditions:
        base: {box min: [-1.0, -0.2], box max: [1.0, -0.09]}
    upper:
      material: soft
      Mesh: {shape: rectangle, center: [0.05, 0.152], size: [0.4, 0.1], element size: 0.1}
  Contact: {dhat: 1.0e-3, kappa: 1.0e5, FEM-FEM: true, friction: 0.3, force body: lower}
  Linear Solver: {type: CG, CG: {tolerance: 1.0e-13}}
YAML
"${mpi[@]}" -np 1 "$exe" run "$work/fem_fem.yaml" --output "$work/fem_fem1" > "$work/fem_fem1.log" 2>&1
"${mpi[@]}" -np 2 "$exe" run "$work/fem_fem.yaml" --output "$work/fem_fem2" > "$work/fem_fem2.log" 2>&1 \
  || { echo "FEM-FEM contact (FEM bodies only) on 2 ranks failed"; cat "$work/fem_fem2.log"; exit 1; }
compare_frames "$work/fem_fem1" "$work/fem_fem2" 3 positions,velocities
/usr/bin/python3 - "$work/fem_fem1" "$work/fem_fem2" <<'PY'
import sys, csv
a, b = sys.argv[1:3]
ra = list(csv.DictReader(open(a + "/diagnostics.csv")))
rb = list(csv.DictReader(open(b + "/diagnostics.csv")))
touching = sum(int(r["contact_pairs"]) > 0 for r in ra)
assert touching >= 5, f"the upper block touched the lower one in {touching} steps: the check checks no contact"
for x, y in zip(ra, rb):
    assert x["contact_pairs"] == y["contact_pairs"], (x["step"], x["contact_pairs"], y["contact_pairs"])
    u, v = float(x["contact_force_y"]), float(y["contact_force_y"])  # on the lower block
    assert abs(u - v) <= 1e-6 * max(abs(u), 1.0), (x["step"], u, v)
assert abs(float(ra[-1]["contact_force_y"])) > 100, "no contact force on the lower block"  # (the upper's weight: 400 N/m)
print(f"FEM-FEM contact, FEM bodies only: 1 and 2 ranks write the same frames ({touching} steps in contact)")
PY
set +e
"${mpi[@]}" -np 2 "$exe" run "$src/inputs/b1_contact.yaml" --output "$work/explicit" > "$work/explicit.log" 2>&1; rc=$?
set -e
[ $rc = 2 ] && grep -q "'Solver' = 'explicit'" "$work/explicit.log" || { echo "explicit scene on 2 ranks: exit $rc"; cat "$work/explicit.log"; exit 1; }
[ ! -e "$work/explicit/bfemp.h5" ] || { echo "the refused explicit run wrote output"; exit 1; }
set +e
"${mpi[@]}" -np 2 "$exe" run "$src/inputs/mpm_column.yaml" --output "$work/boxes" --set 'Linear Solver/type=CG' \
  --set 'MPM/boxes per axis=[1, 1]' > "$work/boxes.log" 2>&1; rc=$?
set -e
[ $rc = 2 ] && grep -q "'MPM/boxes per axis' = \[1, 1\]" "$work/boxes.log" && grep -q "number of ranks, 2" "$work/boxes.log" \
  || { echo "boxes for 1 rank on 2 ranks: exit $rc"; cat "$work/boxes.log"; exit 1; }
[ ! -e "$work/boxes/bfemp.h5" ] || { echo "the refused boxes run wrote output"; exit 1; }
echo "refusals on 2 ranks: direct solver, explicit scene, boxes for another rank count (exit 2)"
# Each rank samples its id block of the particles and checks only those: a
# bad start found on one rank (the column's top, rank 1's block, above the
# grid) or on both (the ground raised into the column) stops both ranks with
# exit 2 and the message 1 rank gives (the first particle in id order).
# Both at once (the top above the grid: rank 1; the bottom in the ground:
# rank 0): the grid's message, the check 1 rank makes first.
for bad in "MPM/domain max=[0.5, 0.8]" "Level Sets/ground/point=[0.0, 0.6]" "MPM/domain max=[0.5, 0.8]|Level Sets/ground/point=[0.0, 0.3]"; do
  sets=(); IFS='|' read -ra keys <<< "$bad"; for k in "${keys[@]}"; do sets+=(--set "$k"); done
  for np in 1 2; do
    set +e
    "${mpi[@]}" -np $np "$exe" run "$src/inputs/mpm_column.yaml" --output "$work/bad_start$np" \
      --set 'Linear Solver/type=CG' "${sets[@]}" > "$work/bad_start$np.log" 2>&1; rc=$?
    set -e
    [ $rc = 2 ] || { echo "bad start ($bad) on $np rank(s): exit $rc"; cat "$work/bad_start$np.log"; exit 1; }
    [ ! -e "$work/bad_start$np/bfemp.h5" ] || { echo "the refused run ($bad) wrote output"; exit 1; }
  done
  m1=$(grep "bad input" "$work/bad_start1.log"); m2=$(grep "bad input" "$work/bad_start2.log")
  [ -n "$m1" ] && [ "$m1" = "$m2" ] || { echo "bad start ($bad): 1 rank '$m1', 2 ranks '$m2'"; cat "$work/bad_start2.log"; exit 1; }
  case "$bad" in MPM/domain*) echo "$m1" | grep -q "outside the MPM grid domain" || { echo "bad start ($bad): '$m1'"; exit 1; } ;; esac
done
echo "bad starts found by one rank's particle block or by both: exit 2 on 2 ranks, the 1-rank message"
# MPM bodies alone on 2 ranks.
mcg=(--set 'Linear Solver/type=CG' --set 'Time/end time=0.2')
"${mpi[@]}" -np 1 "$exe" run "$src/inputs/mpm_column.yaml" --output "$work/mpm1" "${mcg[@]}" > "$work/mpm1.log" 2>&1
"${mpi[@]}" -np 2 "$exe" run "$src/inputs/mpm_column.yaml" --output "$work/mpm2" "${mcg[@]}" > "$work/mpm2.log" 2>&1
grep -q "MPM particles in slabs" "$work/mpm2.log" || { echo "no MPM slab line in the 2-rank banner"; cat "$work/mpm2.log"; exit 1; }
"${mpi[@]}" -np 2 "$exe" run "$src/inputs/mpm_column.yaml" --output "$work/mpm2_half" --set 'Linear Solver/type=CG' --set 'Time/end time=0.1' > "$work/mpm2_half.log" 2>&1
cp -r "$work/mpm2_half" "$work/mpm2_half_on1"; cp -r "$work/mpm2_half" "$work/mpm2_half_on3"
cp -r "$work/mpm2_half" "$work/mpm2_half_old"
# An older checkpoint (every array whole, no row blocks: the "blocked" attributes removed).
/usr/bin/python3 - "$work/mpm2_half_old/checkpoint.h5" <<'PY'
import sys, h5py
with h5py.File(sys.argv[1], "r+") as f:
    g = f["checkpoint"]
    names = [k for k in g if k != "text" and "blocked" in g[k].attrs]
    assert len(names) == 8, names
    for k in names:
        del g[k].attrs["blocked"]
PY
"${mpi[@]}" -np 2 "$exe" restart "$work/mpm2_half" --set 'Time/end time=0.2' > "$work/mpm2_restart.log" 2>&1 \
  || { echo "MPM restart on 2 ranks failed"; cat "$work/mpm2_restart.log"; exit 1; }
# The 2-rank checkpoint (row blocks written by each rank) continued on 1 and on 3 ranks,
# and read whole (the older format) on 2.
for n in 1 3; do
  "${mpi[@]}" -np $n "$exe" restart "$work/mpm2_half_on$n" --set 'Time/end time=0.2' > "$work/mpm2_restart_on$n.log" 2>&1 \
    || { echo "the 2-rank MPM checkpoint restarted on $n rank(s) failed"; cat "$work/mpm2_restart_on$n.log"; exit 1; }
done
"${mpi[@]}" -np 2 "$exe" restart "$work/mpm2_half_old" --set 'Time/end time=0.2' > "$work/mpm2_restart_old.log" 2>&1 \
  || { echo "a checkpoint without row blocks restarted on 2 ranks failed"; cat "$work/mpm2_restart_old.log"; exit 1; }
# A 1-rank run (serial HDF5 file) continued on 2 ranks (the file reopened with MPI-IO).
"${mpi[@]}" -np 1 "$exe" run "$src/inputs/mpm_column.yaml" --output "$work/mpm1_half" --set 'Linear Solver/type=CG' --set 'Time/end time=0.1' > "$work/mpm1_half.log" 2>&1
# (with the boxes chosen by hand: slabs along x instead of the column's y)
"${mpi[@]}" -np 2 "$exe" restart "$work/mpm1_half" --set 'Time/end time=0.2' --set 'MPM/boxes per axis=[2, 1]' \
  > "$work/mpm1_restart.log" 2>&1 \
  || { echo "a 1-rank MPM run restarted on 2 ranks failed"; cat "$work/mpm1_restart.log"; exit 1; }
grep -q "MPM particles in slabs along axis 0" "$work/mpm1_restart.log" \
  || { echo "the restart's boxes are not the ones asked for"; cat "$work/mpm1_restart.log"; exit 1; }
/usr/bin/python3 - "$work/mpm1" "$work/mpm2" "$work/mpm2_half" "$work/mpm1_half" "$work/mpm2_half_on1" \
    "$work/mpm2_half_on3" "$work/mpm2_half_old" <<'PY'
import sys, csv, h5py, numpy as np
a, b, c, d1, e1, e3, o2 = sys.argv[1:8]
with h5py.File(a + "/bfemp.h5", "r") as fa, h5py.File(b + "/bfemp.h5", "r") as fb, h5py.File(c + "/bfemp.h5", "r") as fc, \
        h5py.File(d1 + "/bfemp.h5", "r") as fd, h5py.File(e1 + "/bfemp.h5", "r") as fe1, \
        h5py.File(e3 + "/bfemp.h5", "r") as fe3, h5py.File(o2 + "/bfemp.h5", "r") as fo2:
    others = ((fb, "2 ranks"), (fc, "2 ranks restarted"), (fd, "1 rank restarted on 2"),
              (fe1, "2 ranks restarted on 1"), (fe3, "2 ranks restarted on 3"),
              (fo2, "2 ranks restarted from a checkpoint without row blocks"))
    fr = sorted(k for k in fa if k.startswith("frame_"))
    for other, _ in others:
        assert fr == sorted(k for k in other if k.startswith("frame_")), (fr, sorted(other))
    assert len(fr) == 3, fr
    for f in fr:
        for d in fa[f]:
            va = fa[f][d][()]
            for other, name in others:
                vb = other[f][d][()]
                assert va.shape == vb.shape, (name, f, d, va.shape, vb.shape)
                # Newton stops at |p|/dt < 1e-10 m/s (dt 0.02): 2e-12 m per step.
                tol = 1e-9 if d in ("particle_positions", "particle_body") else 1e-6 * max(np.abs(va).max(), 1e-12)
                err = np.abs(va - vb).max()
                assert err <= tol, f"{name}: {f}/{d} differs by {err}"
for other in (b, c, d1, e1, e3, o2):
    ra = list(csv.DictReader(open(a + "/diagnostics.csv")))
    rb = list(csv.DictReader(open(other + "/diagnostics.csv")))
    assert len(ra) == len(rb) == 10, (len(ra), len(rb))
    for x, y in zip(ra, rb):
        for k in ("kinetic", "elastic", "potential"):
            u, v = float(x[k]), float(y[k])
            assert abs(u - v) <= 1e-7 * max(abs(u), 1e-9), (other, x["step"], k, u, v)
        assert x["active_grid_nodes"] == y["active_grid_nodes"], (other, x["step"])
print("MPM column: 1 rank, 2 ranks, a 2-rank restart, a 1-rank run restarted on 2 and a 2-rank run restarted on 1 and 3 "
      "agree (3 frames, 10 diagnostics rows)")
PY
# MPM and FEM bodies in contact on 2 ranks.
rcg=(--set 'Linear Solver/type=CG' --set 'Linear Solver/CG/tolerance=1e-13' --set 'Newton/eps_d=1e-9' --set 'Time/end time=0.03')
"${mpi[@]}" -np 1 "$exe" run "$src/inputs/contact_rings.yaml" --output "$work/rings1" "${rcg[@]}" > "$work/rings1.log" 2>&1
"${mpi[@]}" -np 2 "$exe" run "$src/inputs/contact_rings.yaml" --output "$work/rings2" "${rcg[@]}" > "$work/rings2.log" 2>&1
/usr/bin/python3 - "$work/rings1" "$work/rings2" <<'PY'
import sys, h5py, numpy as np
a, b = sys.argv[1:3]
with h5py.File(a + "/bfemp.h5", "r") as fa, h5py.File(b + "/bfemp.h5", "r") as fb:
    fr = sorted(k for k in fa if k.startswith("frame_"))
    assert fr == sorted(k for k in fb if k.startswith("frame_")) and len(fr) == 4, fr
    f = fr[-1]
    force = fa[f]["particle_contact_force"][()]
    assert np.abs(force).max() > 0, "no contact force in the last frame: the check checks nothing"
    for d in ("positions", "particle_positions", "particle_contact_force", "particle_velocities"):
        va, vb = fa[f][d][()], fb[f][d][()]
        err = np.abs(va - vb).max() / np.abs(va).max()
        assert err < 1e-8, f"{f}/{d}: relative difference {err}"
print("rings (MPM + FEM contact): 1 and 2 ranks write the same frames, contact forces included")
PY
# The A6 rings (MPM inner ring, FEM outer ring and plate: FEM-FEM contact
# beside MPM-FEM contact, and a slip level set under the middle), 30 steps:
# 1 and 2 ranks write the same frames, the particles' contact forces included.
a6=(--set 'Time/end time=0.3' --set 'Linear Solver/type=CG' --set 'Linear Solver/CG/tolerance=1e-13'
    --set 'Newton/eps_d=1e-9' --set 'Output/frame every=10')
"${mpi[@]}" -np 1 "$exe" run "$src/inputs/a6_semiring_buckling.yaml" --output "$work/a6_1" "${a6[@]}" > "$work/a6_1.log" 2>&1
"${mpi[@]}" -np 2 "$exe" run "$src/inputs/a6_semiring_buckling.yaml" --output "$work/a6_2" "${a6[@]}" > "$work/a6_2.log" 2>&1 \
  || { echo "A6 (FEM-FEM + slip level set) on 2 ranks failed"; cat "$work/a6_2.log"; exit 1; }
compare_frames "$work/a6_1" "$work/a6_2" 4 \
  positions,velocities,particle_positions,particle_velocities,particle_contact_force particle_contact_force
echo "A6 rings (FEM-FEM + MPM-FEM contact, slip level set): 1 and 2 ranks write the same frames"
# The 3D twist (A7) with friction mu 0.5, coarsened (dx 0.25: 512 particles; shell element
# size 0.2), the shell lowered to 1.25 cm above the particles and the schedule shortened
# (down at 0.5 m/s for 0.1 s, then 2 rad/s about z, to 0.14 s): the shell presses on the
# cube's top from step 4 and drags it for 4 steps. 1 rank with Cholmod and 2 ranks with CG +
# BLOCK_CHOLMOD (slabs cut at x = 0 through the contact patch: a pair on each rank) give the
# same frames;
# the friction torque on the cube is a sizeable share of mu x the normal force's moment
# (0.41 measured; the comparison compares friction, not its absence).
mo='FEM Bodies/shell/Boundary Conditions/cap'
tw=(--set 'MPM/grid spacing=0.25' --set 'FEM Bodies/shell/Mesh/element size=0.2'
    --set 'FEM Bodies/shell/Mesh/center=[0,0,1.45]' --set "$mo/box min=[-1,-1,1.74]"
    --set "$mo/Motion/a down/duration=0.1" --set "$mo/Motion/b twist/angular velocity=2"
    --set 'Time/end time=0.14' --set 'Output/frame every=7' --set 'Newton/eps_d=1e-5')
"${mpi[@]}" -np 1 "$exe" run "$src/inputs/a7_twist.yaml" --output "$work/twist1" "${tw[@]}" > "$work/twist1.log" 2>&1
"${mpi[@]}" -np 2 "$exe" run "$src/inputs/a7_twist.yaml" --output "$work/twist2" "${tw[@]}" \
  --set 'Linear Solver/type=CG' --set 'Linear Solver/CG/tolerance=1e-13' \
  --set 'Linear Solver/CG/preconditioner=BLOCK_CHOLMOD' > "$work/twist2.log" 2>&1 \
  || { echo "the twist on 2 ranks failed"; cat "$work/twist2.log"; exit 1; }
grep -q "cuts at 0 m" "$work/twist2.log" || { echo "the twist's slabs are not cut at x = 0"; cat "$work/twist2.log"; exit 1; }
/usr/bin/python3 - "$work/twist1" "$work/twist2" <<'PY'
import sys, h5py, numpy as np
a, b = sys.argv[1:3]
mu = 0.5
with h5py.File(a + "/bfemp.h5", "r") as fa, h5py.File(b + "/bfemp.h5", "r") as fb:
    fr = sorted(k for k in fa if k.startswith("frame_"))
    assert fr == sorted(k for k in fb if k.startswith("frame_")) and len(fr) == 3, fr
    f = fr[-1]
    p, F = fa[f]["particle_positions"][()], fa[f]["particle_contact_force"][()]
    pressed = np.abs(F[:, 2]) > 0
    assert (p[pressed, 0] < 0).any() and (p[pressed, 0] >= 0).any(), "the contact patch is not cut by the slabs"
    torque = (p[:, 0] * F[:, 1] - p[:, 1] * F[:, 0]).sum()
    bound = mu * (np.abs(F[:, 2]) * np.hypot(p[:, 0], p[:, 1])).sum()
    assert torque > 0.25 * bound, f"friction torque {torque} N m against mu |Fz| r {bound}"
    for d in ("positions", "velocities", "particle_positions", "particle_velocities", "particle_contact_force"):
        va, vb = fa[f][d][()], fb[f][d][()]
        # Newton stops at |p|/dt < 1e-5 m/s; measured: 1.2e-8 of the largest value.
        err = np.abs(va - vb).max() / np.abs(va).max()
        assert err < 1e-7, f"{f}/{d}: relative difference {err}"
print(f"twist (friction across ranks): 1 and 2 ranks agree; friction torque {torque:.0f} N m, {torque / bound:.2f} of mu |Fz| r")
PY
