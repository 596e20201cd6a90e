#!/usr/bin/env bash
# A run on 2 ranks stopped after step 2, then continued on 1 rank in the same folder and in a new one:
# the step files of each layout (row order) must be paired with the mesh file of that layout, so that
# ParaView shows the same body a 1-rank run shows at every step (tests/read_layout.py).
# Usage: restart_layout_test.sh SINEW SCENE WORKDIR MPI-LAUNCHER-WORDS...
set -euo pipefail
sinew=$1 scene=$2 work=$3
shift 3
here=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
rm -rf "$work" && mkdir -p "$work"
export OMP_NUM_THREADS=1
"$sinew" --quiet --output "$work/reference" "$scene"
set +e
SINEW_STOP_AFTER_STEP=2 "$@" "$sinew" --quiet --output "$work/same" "$scene" 2> "$work/stop.err"
rc=$?
set -e
grep -q "stopped by signal 15 after step 2" "$work/stop.err" || { echo "FAIL: not stopped after step 2 (exit $rc)"; cat "$work/stop.err"; exit 1; }
cp "$work/same/checkpoint.h5" "$work/checkpoint_step2.h5"
"$sinew" --quiet --output "$work/same" --restart "$work/same/checkpoint.h5" "$scene"
"$sinew" --quiet --output "$work/new" --restart "$work/checkpoint_step2.h5" "$scene"
# Restarted twice more in the same folder on 1 rank: no further mesh file (the layout is on disk).
"$sinew" --quiet --output "$work/same" --restart "$work/checkpoint_step2.h5" "$scene"
/usr/bin/python3 "$here/read_layout.py" "$work"
