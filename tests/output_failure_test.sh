#!/usr/bin/env bash
# A step file that cannot be put in place (here: a folder of that name blocks the rename on rank 0
# only) must stop the run on every rank with a message, never leave the other rank waiting in a
# barrier, and keep the files already written. Usage: output_failure_test.sh SINEW SCENE WORKDIR MPIRUN...
set -uo pipefail
sinew=$1 scene=$2 work=$3; shift 3
rm -rf "$work" && mkdir -p "$work/out/step_000001.h5" && touch "$work/out/step_000001.h5/blocker"
timeout 120 "$@" "$sinew" --quiet --output "$work/out" "$scene" > "$work/stdout" 2> "$work/stderr"
rc=$?
cat "$work/stderr"
[ "$rc" -ne 124 ] || { echo "FAIL: the run hung"; exit 1; }
[ "$rc" -eq 1 ] || { echo "FAIL: exit code $rc, expected 1"; exit 1; }
grep -q "sinew: error: cannot rename .*step_000001.h5.tmp" "$work/stderr" || { echo "FAIL: no message naming the file"; exit 1; }
[ -f "$work/out/step_000000.h5" ] && [ -f "$work/out/mesh.h5" ] || { echo "FAIL: earlier results lost"; exit 1; }
echo "output failure ok"
