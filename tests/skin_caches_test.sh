#!/usr/bin/env bash
# The skin where artists work (issue 43), checked with the programs they use: a rig scene's skin.glb
# passes the Khronos glTF-Validator, Blender 3.4 (Debian's, background mode) imports skin.glb and the
# PC2 cache on skin_rest.obj and finds the vertices of skin_NNNNNN.obj at two frames (1e-5), the
# browser viewer (sinew-view) draws two frames in headless Chromium (non-blank, different), and a run
# stopped and restarted (appending, then again from an earlier checkpoint over the frames written
# since) ends with the same frames as a run straight through.
# Usage: skin_caches_test.sh SINEW SCENE OUTDIR
# Exits 77 (CTest: skipped) only when Blender, Chromium or the npm packages are not installed.
set -euo pipefail
sinew=$1 scene=$2 out=$3
here=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
repo=$(cd "$here/.." && pwd)
modules=${SINEW_VIEWER_MODULES:-$repo/.deps/viewer/node_modules}
for need in blender chromium node; do
  command -v "$need" > /dev/null || { echo "SKIP: $need is not installed (scripts/deps.sh installs it)"; exit 77; }
done
[ -d "$modules/three" ] && [ -d "$modules/gltf-validator" ] ||
  { echo "SKIP: three and gltf-validator are not installed in $modules (scripts/deps.sh runs npm)"; exit 77; }
rm -rf "$out"
mkdir -p "$out"
export OMP_NUM_THREADS=1

# A run straight through, and one stopped after step 4 and restarted in its folder.
"$sinew" --quiet --output "$out/straight" "$scene"
set +e
SINEW_STOP_AFTER_STEP=4 "$sinew" --quiet --output "$out/run" "$scene" 2> "$out/stop.err"
set -e
grep -q "stopped by signal 15 after step 4" "$out/stop.err" || { echo "FAIL: not stopped after step 4"; cat "$out/stop.err"; exit 1; }
cp "$out/run/checkpoint.h5" "$out/step4.h5"
# The caches of the stopped run are complete up to its last frame.
/usr/bin/python3 "$here/read_skin_frames.py" "$out/run" --steps 0,1,2,3,4
"$sinew" --quiet --output "$out/run" --restart "$out/run/checkpoint.h5" "$scene"
/usr/bin/python3 "$here/read_skin_frames.py" "$out/run" --steps 0,1,2,3,4,5,6,7,8 --same-as "$out/straight"
# Again from step 4, over the frames of steps 5-8 already on disk: they are cut off and made anew.
"$sinew" --quiet --output "$out/run" --restart "$out/step4.h5" "$scene"
/usr/bin/python3 "$here/read_skin_frames.py" "$out/run" --steps 0,1,2,3,4,5,6,7,8 --same-as "$out/straight"

node "$here/validate_gltf.js" "$modules" "$out/straight/skin.glb" "$out/run/skin.glb"
blender -b --factory-startup --python-exit-code 1 --python "$here/blender_readback.py" -- "$out/run" 1 8 > "$out/blender.log" 2>&1 ||
  { cat "$out/blender.log"; echo "FAIL: Blender did not read the caches back"; exit 1; }
grep -E "step|moved|read" "$out/blender.log"

# The viewer, in a real browser: two frames drawn, not blank, not the same.
SINEW_VIEWER_MODULES=$modules "$repo/scripts/sinew-view" "$out/run"
for k in 0 8; do
  timeout 120 chromium --headless=new --no-sandbox --disable-gpu-sandbox --use-angle=swiftshader --enable-unsafe-swiftshader \
    --user-data-dir="$out/chromium" --window-size=800,600 --virtual-time-budget=20000 --screenshot="$out/frame$k.png" \
    "file://$out/run/view.html#frame=$k&color=lbs_distance" > "$out/chromium$k.log" 2>&1 ||
    { cat "$out/chromium$k.log"; echo "FAIL: Chromium did not take the screenshot of frame $k"; exit 1; }
done
/usr/bin/python3 - "$out/frame0.png" "$out/frame8.png" <<'PY'
import sys
import numpy as np
from PIL import Image
a, b = (np.asarray(Image.open(p).convert("RGB")).astype(int) for p in sys.argv[1:3])
tinted = {}
for name, img in zip(("frame 0", "frame 8"), (a, b)):
    background = img[5, 5]
    drawn = np.abs(img - background).sum(axis=2) > 30
    # The colour map runs from white (0) to red (its span): red above blue by 30 of 255 is about an
    # eighth of the span, lit from the front.
    tinted[name] = (drawn & (img[..., 0] - img[..., 2] > 30)).sum() / max(drawn.sum(), 1)
    print(f"{name}: {100 * drawn.mean():.1f}% of the pixels drawn, {100 * tinted[name]:.2f}% of them tinted red")
    if drawn.mean() < 0.03:
        sys.exit(f"FAIL: {name} is blank ({100 * drawn.mean():.2f}% drawn)")
changed = (np.abs(a - b).sum(axis=2) > 30).mean()
print(f"{100 * changed:.1f}% of the pixels differ between the frames")
if changed < 0.01:
    sys.exit("FAIL: the two frames look the same")
# Frame 8 is coloured by the distance to the rig's own skinning, which is 0 at frame 0. (Counted as a
# share of the drawn skin, not of the picture: strongly red pixels over 0.1% of the picture failed
# when thinner bones ('Bone thickness' 0.4) left 0.07% of it, with 10% of the skin tinted.)
if not (tinted["frame 8"] > 0.01 and tinted["frame 0"] < 0.001):
    sys.exit("FAIL: frame 8 has no colour for the distance to the rig's skinning, or frame 0 has")
PY
echo "PASS"
