#!/usr/bin/env bash
# Kill a run (SIGKILL, or SIGTERM with MODE=term) once a checkpoint exists, continue it with --restart,
# and check that it ends in the same state as an uninterrupted run (1e-10 relative unless TOL is given),
# with a complete log.
# Usage: restart_test.sh SINEW SCENE WORKDIR [kill|term] [TOL]
set -euo pipefail
sinew=$1 scene=$2 work=$3 mode=${4:-kill} tol=${5:-1e-10}
rm -rf "$work" && mkdir -p "$work"
export OMP_NUM_THREADS=${OMP_NUM_THREADS:-1}
# Debian's python3 has python3-h5py (scripts/deps.sh); a python3 earlier in PATH may not.
py=/usr/bin/python3
[ -x "$py" ] || py=python3
ckpt_step() { "$py" -c "import h5py,sys; print(int(h5py.File(sys.argv[1],'r').attrs['step']))" "$1" 2>/dev/null || echo -1; }

"$sinew" --quiet --output "$work/full" "$scene"
steps=$("$py" -c "import h5py,sys; print(int(h5py.File(sys.argv[1],'r').attrs['steps']))" "$work/full/checkpoint.h5")

# The interrupted run: killed once its log has three steps (the log row of step k is written before
# its checkpoint, so a checkpoint of step 2 or later exists). Polled from bash every 10 ms: a python
# poll (0.2 s to import h5py) let this 8-step scene (0.07 s a step) finish before the kill on a loaded
# machine. A run that still finished first is tried again, twice at most.
logged() { local n; n=$(wc -l < "$work/cut/log.csv" 2> /dev/null) || n=1; echo $((n - 1)); }
for attempt in 1 2 3; do
  rm -rf "$work/cut"
  "$sinew" --quiet --output "$work/cut" "$scene" &
  pid=$!
  for _ in $(seq 1 12000); do
    [ "$(logged)" -ge 3 ] && break
    kill -0 "$pid" 2> /dev/null || break
    sleep 0.01
  done
  if [ "$mode" = term ]; then
    kill -TERM "$pid" 2> /dev/null || true
    set +e; wait "$pid"; rc=$?; set -e
  else
    kill -KILL "$pid" 2> /dev/null || true
    wait "$pid" || true
  fi
  at=$(ckpt_step "$work/cut/checkpoint.h5")
  echo "attempt $attempt: interrupted ($mode) with a checkpoint of step $at of $steps"
  [ "$at" -lt "$steps" ] && break
done
[ "$mode" != term ] || [ "$rc" -eq 143 ] || { echo "FAIL: SIGTERM run exited with $rc, expected 143"; exit 1; }
[ "$at" -ge 1 ] && [ "$at" -lt "$steps" ] || { echo "FAIL: the run was not interrupted mid-way (checkpoint step $at)"; exit 1; }

"$sinew" --quiet --output "$work/cut" --restart "$work/cut/checkpoint.h5" "$scene"

"$py" - "$work" "$steps" "$tol" <<'PY'
import csv, glob, sys
import h5py, numpy as np
work, steps, tol = sys.argv[1], int(sys.argv[2]), float(sys.argv[3])
last = "step_%06d.h5" % steps
a = h5py.File(f"{work}/full/{last}", "r")["displacement"][:]
b = h5py.File(f"{work}/cut/{last}", "r")["displacement"][:]
rel = np.abs(a - b).max() / np.abs(a).max()
print(f"max |u_full - u_restarted| / max |u_full| = {rel:.3e}")
rows = list(csv.DictReader(open(f"{work}/cut/log.csv")))
assert [int(r["step"]) for r in rows] == list(range(1, steps + 1)), f"log steps {[r['step'] for r in rows]}"
# A kill may leave a half-written file aside; the restarted run removes it.
assert not glob.glob(f"{work}/cut/*.tmp"), glob.glob(f"{work}/cut/*.tmp")
assert rel <= tol, (rel, tol)
print("restart ok")
PY
