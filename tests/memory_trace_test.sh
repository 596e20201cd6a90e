#!/usr/bin/env bash
# SINEW_MEMORY_TRACE=1 prints the resident memory after each phase that allocates a large share of a
# run, in the order they happen, on stderr; without it nothing is printed. And a lattice keeps one
# inverse Jacobian per element: at 12^3 cells its element data is under a tenth of its matrix (dN/dX
# per point would be 0.22 of it).
# Usage: memory_trace_test.sh SINEW SCENE WORKDIR   (SCENE: a hex8 box of {4, 4, 4} cells)
set -uo pipefail
sinew=$1 work=$3
rm -rf "$work" && mkdir -p "$work"
scene=$work/box12.xml
sed 's/{4, 4, 4}/{12, 12, 12}/' "$2" > "$scene"
grep -q "{12, 12, 12}" "$scene" || { echo "FAIL: $2 is not a {4, 4, 4} box"; exit 1; }
# 4 kB pages: with transparent huge pages (sinew's default, README) resident memory grows in 2 MB steps
# and a phase of 1 MB reads as 2.
SINEW_HUGE_PAGES=0 SINEW_MEMORY_TRACE=1 timeout 120 "$sinew" --quiet --output "$work/on" "$scene" > "$work/stdout" 2> "$work/stderr" ||
  { cat "$work/stderr"; echo "FAIL: the traced run failed"; exit 1; }
cat "$work/stderr"
last=0
for phase in "mesh" "element data" "maps and graph" "matrix assembled" "preconditioner set up" "linear solve"; do
  line=$(grep -n -m1 "^\[memory\] $phase: [0-9.]* MB (" "$work/stderr" | cut -d: -f1)
  [ -n "$line" ] || { echo "FAIL: no '[memory] $phase' line"; exit 1; }
  [ "$line" -gt "$last" ] || { echo "FAIL: '$phase' is out of order"; exit 1; }
  last=$line
done
mb() { grep -m1 "^\[memory\] $1:" "$work/stderr" | sed -E 's/.*\(\+?(-?[0-9.]+) MB\)/\1/'; }
ok=$(/usr/bin/python3 -c "print(float('$(mb "element data")') < 0.1 * float('$(mb "matrix assembled")'))")
[ "$ok" = True ] || { echo "FAIL: element data $(mb "element data") MB against the matrix's $(mb "matrix assembled") MB"; exit 1; }
timeout 120 "$sinew" --quiet --output "$work/off" "$scene" > /dev/null 2> "$work/stderr_off" || { echo "FAIL: the plain run failed"; exit 1; }
! grep -q "^\[memory\]" "$work/stderr_off" || { echo "FAIL: memory lines without SINEW_MEMORY_TRACE"; exit 1; }
echo "memory trace ok"
