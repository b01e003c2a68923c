#!/usr/bin/env bash
# ParaView check of bfemp's XDMF output (ctest -L paraview).
#   tests/paraview/run_check.sh BFEMP_EXECUTABLE SOURCE_DIR WORK_DIR [implicit|explicit]
# implicit (default; test paraview_xdmf): a short contact run
#   (inputs/default_contact.yaml: FEM disk on an MPM floor, barrier contact
#   with friction; 10 steps, 6 frames) into WORK_DIR/run, checked with
#   check_xdmf.py --grids fem,particles; screenshot WORK_DIR/paraview_check.png.
# explicit (test paraview_xdmf_explicit): a short explicit run
#   (inputs/b1_contact.yaml, Solver: explicit: two MPM blocks; about 24 steps,
#   6 frames) into WORK_DIR/run_explicit, checked with check_xdmf.py
#   --grids particles (one Uniform particle grid per frame, stress tensor,
#   material_class); screenshot WORK_DIR/paraview_check_explicit.png.
# check_xdmf.py runs in pvpython: time steps against the /frame_* groups of
# bfemp.h5, the grids, every array's tuples, components and values against
# the HDF5 datasets, and a PNG screenshot under xvfb-run. The two modes write
# distinct files in WORK_DIR, so the two tests can run at once.
# Exit: 0 pass; 1 a check failed; 77 skipped (ctest SKIP_RETURN_CODE):
#   - no pvpython (PVPYTHON or on PATH): nothing is checked;
#   - no xvfb-run and no DISPLAY: the arrays are checked (a wrong one fails)
#     but no screenshot can be rendered, so the test reports skipped.
# Always strict: the particle grid must have one cell per particle.
set -uo pipefail
if [ $# -lt 3 ] || [ $# -gt 4 ]; then
  sed -n 2,3p "$0" >&2
  exit 2
fi
bfemp=$1
src=$2
work=$3
mode=${4:-implicit}
case $mode in
  implicit)
    run=$work/run; suffix=""
    scene=$src/inputs/default_contact.yaml
    settings=(--set 'Time/end time=0.02' --set 'Output/frame every=2')
    grids=fem,particles
    what="short contact run" ;;
  explicit)
    run=$work/run_explicit; suffix=_explicit
    scene=$src/inputs/b1_contact.yaml
    settings=(--set 'Time/end time=3e-5' --set 'Output/frame every=5')
    grids=particles
    what="short explicit run (Solver: explicit)" ;;
  *)
    echo "run_check.sh: mode '$mode', expected implicit or explicit" >&2
    exit 2 ;;
esac

# PVPYTHON / XVFB_RUN name the programs; set to "" they count as absent.
pvpython=${PVPYTHON-$(command -v pvpython || true)}
xvfb_run=${XVFB_RUN-$(command -v xvfb-run || true)}
if [ -z "$pvpython" ] || [ ! -x "$pvpython" ]; then
  echo "SKIPPED: pvpython not found (ParaView with Python). Install it with"
  echo "  scripts/setup.sh --with-paraview   (or: apt-get install paraview python3-paraview xvfb xauth)"
  exit 77
fi
if [ ! -x "$bfemp" ]; then
  echo "run_check.sh: bfemp executable '$bfemp' not found" >&2
  exit 2
fi

png=$work/paraview_check$suffix.png
runlog=$work/bfemp_run$suffix.log
pvlog=$work/pvpython$suffix.log
rm -rf "$run" "$png"
mkdir -p "$work"
echo "== bfemp: $what into $run"
OMP_NUM_THREADS=${OMP_NUM_THREADS:-1} OMP_PROC_BIND=${OMP_PROC_BIND:-false} \
OMP_WAIT_POLICY=${OMP_WAIT_POLICY:-PASSIVE} OPENBLAS_NUM_THREADS=1 \
  "$bfemp" run "$scene" --output "$run" \
    "${settings[@]}" --set 'Output/progress every=0' \
    > "$runlog" 2>&1
rc=$?
if [ $rc -ne 0 ]; then
  cat "$runlog"
  echo "run_check.sh: bfemp exited with $rc" >&2
  exit 1
fi
tail -n 3 "$runlog"

check=$src/tests/paraview/check_xdmf.py
# --strict: the particle grid's cells (fixed in the writer) are checked too;
# --grids: the layout this mode's run must have written.
strict=(--strict --grids "$grids")
if [ -n "$xvfb_run" ]; then
  echo "== pvpython under xvfb-run: $check"
  "$xvfb_run" -a -s "-screen 0 1280x1024x24" "$pvpython" "$check" "$run" --screenshot "$png" "${strict[@]}" \
    2>&1 | tee "$pvlog"
  rc=${PIPESTATUS[0]}
  # xvfb-run -a picks :99 upward by lock files; two test runs starting at once
  # can both take the same number and one gets "bad X server connection".
  # That is the harness, not the output: retry once on a random server number.
  if [ "$rc" -ne 0 ] && grep -q "bad X server connection" "$pvlog"; then
    server=$((200 + RANDOM % 600))
    echo "== X server collision; retrying on :$server"
    "$xvfb_run" -n "$server" -s "-screen 0 1280x1024x24" "$pvpython" "$check" "$run" --screenshot "$png" "${strict[@]}"
    rc=$?
  fi
elif [ -n "${DISPLAY:-}" ]; then
  echo "== pvpython on DISPLAY=$DISPLAY (no xvfb-run): $check"
  "$pvpython" "$check" "$run" --screenshot "$png" "${strict[@]}"
  rc=$?
else
  echo "== pvpython without a display (no xvfb-run, no DISPLAY): arrays only"
  "$pvpython" "$check" "$run" "${strict[@]}"
  rc=$?
  if [ $rc -eq 0 ]; then
    echo "SKIPPED: frames and arrays checked and correct, but no screenshot: xvfb-run not found"
    echo "  and no DISPLAY (install it with: apt-get install xvfb xauth)"
    exit 77
  fi
fi
[ $rc -eq 0 ] && [ -f "$png" ] && echo "screenshot: $png"
exit $rc
