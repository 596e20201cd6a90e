#!/usr/bin/env bash
# A checkpoint continues the physics it was written for: a restart with another material or load is
# refused naming the section and the entries that differ (exit 3), --restart-anyway accepts it, and
# what does not change the physics (solver settings, a default spelled out, entries reordered) is
# accepted. A checkpoint of a run that lacked a parameter added since (made here by taking an entry
# out of the checkpoint's record) is accepted while the scene leaves it at its default, with a note,
# and refused naming it otherwise; one that recorded digests only is refused naming the section.
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
from=step1.h5  # the checkpoint expect() restarts from (as ckpt.h5)
expect() {  # CODE REGEX ARGS...
  local want=$1 re=$2
  shift 2
  cp "$work/$from" "$work/ckpt.h5"
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
expect 3 "restart file '.*ckpt.h5': was written by a run whose 'Material' section differs from this scene's \('Material/Young modulus' 10000 there, 20000 here\)" --restart "$work/ckpt.h5" "$stiffer"
both=$(variant both 's/value="1.0e4"/value="2.0e4"/; s/"Angle" type="double" value="1.0"/"Angle" type="double" value="1.5"/')
expect 3 "whose 'Material' or 'Loading' sections differ from this scene's \('Material/Young modulus' 10000 there, 20000 here; 'Loading/Boundary conditions/top/Angle' 1 there, 1.5 here\)" --restart "$work/ckpt.h5" "$both"
expect 0 "" --restart-anyway "$work/ckpt.h5" "$stiffer"
# Not physics: the solver's tolerance; a default written out; the two materials entries swapped.
solver=$(variant solver 's/"Absolute tolerance" type="double" value="1.0e-6"/"Absolute tolerance" type="double" value="1.0e-7"/')
expect 0 "" --restart "$work/ckpt.h5" "$solver"
spelled=$(variant spelled 's|<Parameter name="Poisson ratio" type="double" value="0.45"/>|<Parameter name="Projection" type="string" value="clamp"/><Parameter name="Poisson ratio" type="double" value="0.45"/>|')
grep -q Projection "$spelled"
expect 0 "" --restart "$work/ckpt.h5" "$spelled"

# A checkpoint of an older version: its Material record lacks 'Projection', and its digest differs.
py=/usr/bin/python3
[ -x "$py" ] || py=python3
older() {  # SRC DST [drop the record too]
  "$py" - "$1" "$2" "${3:-}" <<'PY'
import shutil, sys
import h5py, numpy as np
src, dst, drop = sys.argv[1:]
shutil.copy(src, dst)
with h5py.File(dst, "r+") as f:
    f.attrs["physics Material"] = np.bytes_("0123456789abcdef")
    text = f["physics Material"][()].tobytes().decode()
    assert '\nProjection="clamp"\n' in text, text
    del f["physics Material"]
    if not drop:
        kept = "\n".join(l for l in text.split("\n") if not l.startswith("Projection=")).encode()
        f.create_dataset("physics Material", data=np.frombuffer(kept, dtype=np.int8))
PY
}
older "$work/step1.h5" "$work/older.h5"
cp "$work/older.h5" "$work/ckpt.h5"
OMP_NUM_THREADS=1 "$sinew" --output "$work/out_older" --restart "$work/ckpt.h5" "$scene" > "$work/older.out" 2>&1 ||
  { echo "FAIL: restart from a checkpoint without 'Projection'"; cat "$work/older.out"; exit 1; }
grep -q "restart note: 'Material/Projection' (\"clamp\") is new since the checkpoint was written; taken at its default" "$work/older.out" ||
  { echo "FAIL: no note on the new entry"; cat "$work/older.out"; exit 1; }
echo "ok: a parameter new since the checkpoint, at its default: accepted with a note"
abs=$(variant abs 's|<Parameter name="Poisson ratio" type="double" value="0.45"/>|<Parameter name="Projection" type="string" value="abs"/><Parameter name="Poisson ratio" type="double" value="0.45"/>|')
from=older.h5
expect 3 "'Material' section differs from this scene's \('Material/Projection' \"abs\" here, which that run did not have\)" --restart "$work/ckpt.h5" "$abs"
# Digests only (checkpoints written before the records were kept): the section alone is named.
older "$work/step1.h5" "$work/digests_only.h5" drop
from=digests_only.h5
expect 3 "'Material' section differs from this scene's; a restart continues" --restart "$work/ckpt.h5" "$scene"
echo "restart physics checks ok"
