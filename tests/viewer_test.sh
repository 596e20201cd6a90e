#!/usr/bin/env bash
# Results as users see them: run a small scene on a Gmsh mesh, open its output with meshio and
# ParaView (tests/read_results.py), render it with sinew-render (one step and a strip) and plot it with
# sinew-plot, render a voxelized ball's carried skin, and check the pictures: the asked size, and not
# blank.
# Usage: viewer_test.sh SINEW SCENE OUTDIR [launcher words...]
set -euo pipefail
sinew=$1 scene=$2 out=$3
shift 3
here=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
scripts=$here/../scripts
rm -rf "$out"
"$@" "$sinew" --output "$out" "$scene" > /dev/null
/usr/bin/python3 "$here/read_results.py" "$out" 2 "$here/meshes/box_v41.msh"
t0=$(date +%s%N)
"$scripts/sinew-render" "$out" --size 640x480 --rest -o "$out/one.png"
t1=$(date +%s%N)
"$scripts/sinew-render" "$out" --steps strip:3 --size 900x400 -o "$out/strip.png"
# Renders started together each get a display of their own (xvfb-run -a raced: 1 in 4 crashed).
pids=()
for k in 1 2 3 4; do
  "$scripts/sinew-render" "$out" --size 320x240 -o "$out/together_$k.png" &
  pids+=($!)
done
for p in "${pids[@]}"; do wait "$p" || { echo "FAIL: one of 4 renders started together failed"; exit 1; }; done
"$scripts/sinew-plot" "$out" -o "$out/convergence.png"
# A voxelized body: its carried skin rendered with --skin.
"$@" "$sinew" --output "$out/ball" "$here/scenes/voxel_ball.xml" > /dev/null
"$scripts/sinew-render" "$out/ball" --skin --steps strip:3 --size 800x300 -o "$out/skin.png"
/usr/bin/python3 - "$out" <<'PY'
import sys
from PIL import Image
out = sys.argv[1]
for name, size in (("together_1.png", (320, 240)), ("together_4.png", (320, 240)), ("one.png", (640, 480)), ("strip.png", (900, 400)), ("convergence.png", None), ("skin.png", (800, 300))):
    im = Image.open(f"{out}/{name}").convert("RGB")
    assert size is None or im.size == size, f"{name}: size {im.size}, expected {size}"
    colours = len(set(im.getdata()))
    assert colours > 50, f"{name}: only {colours} colours: blank?"
    # Not all background: a good share of the pixels is not white.
    drawn = sum(1 for p in im.getdata() if p != (255, 255, 255)) / (im.size[0] * im.size[1])
    assert drawn > 0.03, f"{name}: only {drawn:.1%} of the pixels drawn"
    print(f"{name}: {im.size[0]}x{im.size[1]}, {colours} colours, {drawn:.0%} drawn")
PY
echo "render of one step: $(( (t1 - t0) / 1000000 )) ms"
