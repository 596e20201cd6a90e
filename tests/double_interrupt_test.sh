#!/usr/bin/env bash
# A first SIGINT asks the run to stop at its next safe point; a second one, sent while it is still busy
# (a long linear solve), makes it exit at once with 128 + the signal and a message, leaving the last
# checkpoint in place. Usage: double_interrupt_test.sh SINEW SCENE WORKDIR
set -uo pipefail
sinew=$1 scene=$2 work=$3
rm -rf "$work" && mkdir -p "$work"
"$sinew" --output "$work/out" "$scene" > "$work/stdout" 2> "$work/stderr" &
pid=$!
# Wait for the first Newton iteration of the second step (a checkpoint of step 1 exists by then).
for _ in $(seq 1 600); do
  grep -q "^step 2/" "$work/stdout" 2>/dev/null && break
  sleep 0.05
done
kill -INT "$pid"; sleep 0.1; kill -INT "$pid"
wait "$pid"; rc=$?
cat "$work/stderr"
[ "$rc" -eq 130 ] || { echo "FAIL: exit code $rc, expected 130"; exit 1; }
grep -q "second interrupt: exiting now" "$work/stderr" || { echo "FAIL: no message"; exit 1; }
# The first interrupt alone would have stopped at the end of the Newton iteration; it must not have
# had the time to (each iteration of this scene takes about a second).
! grep -q "stopped by signal" "$work/stderr" || { echo "FAIL: the run stopped gracefully before the second signal"; exit 1; }
[ -f "$work/out/checkpoint.h5" ] || { echo "FAIL: the checkpoint of step 1 is gone"; exit 1; }
echo "double interrupt ok"
