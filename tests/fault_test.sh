#!/usr/bin/env bash
# An exception inside the solve on one rank only (injected with SINEW_FAULT_RANK) must not leave the
# other rank waiting forever: the job ends within seconds with the message (exit 1). The same exception
# on every rank is an ordinary solver error: the step is cut, the run ends with exit 4 and the message.
# Usage: fault_test.sh SINEW SCENE WORKDIR MPIRUN...
set -uo pipefail
sinew=$1 scene=$2 work=$3; shift 3
rm -rf "$work" && mkdir -p "$work"
start=$SECONDS
SINEW_FAULT_RANK=1 SINEW_MEET_SECONDS=5 timeout 120 "$@" "$sinew" --quiet --output "$work/one" "$scene" > /dev/null 2> "$work/one.err"
rc=$?
cat "$work/one.err"
[ "$rc" -ne 124 ] || { echo "FAIL: the run hung"; exit 1; }
[ "$rc" -ne 0 ] || { echo "FAIL: exit 0 after an error"; exit 1; }
grep -q "error on rank 1 that the other ranks did not meet within 5 s: injected fault" "$work/one.err" ||
  { echo "FAIL: no message naming the rank and the error"; exit 1; }
[ $((SECONDS - start)) -lt 60 ] || { echo "FAIL: took $((SECONDS - start)) s"; exit 1; }
SINEW_FAULT_RANK=all timeout 120 "$@" "$sinew" --quiet --output "$work/all" "$scene" > /dev/null 2> "$work/all.err"
rc=$?
cat "$work/all.err"
[ "$rc" -eq 4 ] || { echo "FAIL: exit $rc, expected 4 (no convergence) when every rank meets the error"; exit 1; }
grep -q "solver exception: injected fault" "$work/all.err" || { echo "FAIL: the reason is not named"; exit 1; }
echo "fault ok"
