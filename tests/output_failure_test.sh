#!/usr/bin/env bash
# A step file that cannot be put in place (here: a folder of that name blocks the rename on rank 0
# only) must stop the run on every rank with a message, never leave the other rank waiting in a
# barrier, and keep the files already written; the step's converged state is in the checkpoint (it is
# written before the step file), and a .tmp file of the user's in the folder is left alone.
# Usage: output_failure_test.sh SINEW SCENE WORKDIR MPIRUN...
set -uo pipefail
sinew=$1 scene=$2 work=$3; shift 3
rm -rf "$work" && mkdir -p "$work/out/step_000001.h5" && touch "$work/out/step_000001.h5/blocker"
echo "the user's notes" > "$work/out/notes.tmp" && echo "half" > "$work/out/step_000007.h5.tmp"
timeout 120 "$@" "$sinew" --quiet --output "$work/out" "$scene" > "$work/stdout" 2> "$work/stderr"
rc=$?
cat "$work/stderr"
[ "$rc" -ne 124 ] || { echo "FAIL: the run hung"; exit 1; }
[ "$rc" -eq 1 ] || { echo "FAIL: exit code $rc, expected 1"; exit 1; }
grep -q "sinew: error: cannot rename .*step_000001.h5.tmp" "$work/stderr" || { echo "FAIL: no message naming the file"; exit 1; }
[ -f "$work/out/step_000000.h5" ] && [ -f "$work/out/mesh.h5" ] || { echo "FAIL: earlier results lost"; exit 1; }
[ -f "$work/out/notes.tmp" ] || { echo "FAIL: a .tmp file Sinew did not write was deleted"; exit 1; }
[ ! -f "$work/out/step_000007.h5.tmp" ] || { echo "FAIL: a half-written file of Sinew's was kept"; exit 1; }
step=$(/usr/bin/python3 -c "import h5py; print(int(h5py.File('$work/out/checkpoint.h5')['/'].attrs['step']))")
[ "$step" = 1 ] || { echo "FAIL: the checkpoint holds step '$step', not the converged step 1"; exit 1; }
echo "output failure ok"
