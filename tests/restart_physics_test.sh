#!/usr/bin/env bash
# A checkpoint continues the physics it was written for: a restart with another material or load is
# refused naming the section (exit 3), --restart-anyway accepts it, and what does not change the
# physics (solver settings, a default spelled out, entries reordered) is accepted.
# Usage: restart_physics_test.sh SINEW SCENE WORKDIR
set -euo pipefail
sinew=$1 scene=$2 work=$3
rm -rf "$work" && mkdir -p "$work"
export OMP_NUM_THREADS=1
dir=$(cd "$(dirname "$scene")" && pwd)
set +e
SINEW_STOP_AFTER_STEP=1 "$sinew" --quiet --output "$work/run" "$scene" 2> /dev/null
set -e
cp "$work/run/checkpoint.h5" "$work/step1.h5"
# Variants of the scene, next to it so that its relative mesh path still holds.
variant() {  # NAME SED-EXPRESSION
  sed "$2" "$scene" > "$dir/.restart_physics_$1.xml"
  echo "$dir/.restart_physics_$1.xml"
}
trap 'rm -f "$dir"/.restart_physics_*.xml' EXIT
expect() {  # CODE REGEX ARGS...
  local want=$1 re=$2
  shift 2
  cp "$work/step1.h5" "$work/ckpt.h5"
  set +e
  "$sinew" --quiet --output "$work/out" "$@" 2> "$work/err"
  local rc=$?
  set -e
  [ "$rc" -eq "$want" ] || { echo "FAIL: $* exited $rc, expected $want"; cat "$work/err"; exit 1; }
  [ -z "$re" ] || grep -Eq "$re" "$work/err" || { echo "FAIL: $*: stderr does not match '$re'"; cat "$work/err"; exit 1; }
  echo "ok: exit $rc: $(head -c 300 "$work/err")"
}
stiffer=$(variant stiffer 's/"Young modulus" type="double" value="1.0e4"/"Young modulus" type="double" value="2.0e4"/')
grep -q 'value="2.0e4"' "$stiffer"
expect 3 "restart file '.*ckpt.h5': was written by a run whose 'Material' section differs from this scene's" --restart "$work/ckpt.h5" "$stiffer"
both=$(variant both 's/value="1.0e4"/value="2.0e4"/; s/"Angle" type="double" value="1.0"/"Angle" type="double" value="1.5"/')
expect 3 "whose 'Material' or 'Loading' sections differ" --restart "$work/ckpt.h5" "$both"
expect 0 "" --restart-anyway "$work/ckpt.h5" "$stiffer"
# Not physics: the solver's tolerance; a default written out; the two materials entries swapped.
solver=$(variant solver 's/"Absolute tolerance" type="double" value="1.0e-6"/"Absolute tolerance" type="double" value="1.0e-7"/')
expect 0 "" --restart "$work/ckpt.h5" "$solver"
spelled=$(variant spelled 's|<Parameter name="Poisson ratio" type="double" value="0.45"/>|<Parameter name="Projection" type="string" value="clamp"/><Parameter name="Poisson ratio" type="double" value="0.45"/>|')
grep -q Projection "$spelled"
expect 0 "" --restart "$work/ckpt.h5" "$spelled"
echo "restart physics checks ok"
