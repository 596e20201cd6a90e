# Read Sinew's skin caches back with Blender, as an artist would (issue 43): the glTF binary through
# Blender's own glTF importer (shape keys animated by the file's STEP weights), and the PC2 point cache
# through the Mesh Cache modifier on the rest skin imported from skin_rest.obj. At the given steps the
# evaluated vertices must equal the matching skin_NNNNNN.obj to TOL.
#
# Usage: blender -b --factory-startup --python-exit-code 1 --python blender_readback.py -- RESULTS STEP [STEP ...]
import json
import os
import struct
import sys

import bpy
from mathutils import kdtree

TOL = 1e-5

argv = sys.argv[sys.argv.index("--") + 1:]
results, steps = argv[0], [int(s) for s in argv[1:]]
failures = []


def read_obj(path):
    v = []
    with open(path) as f:
        for line in f:
            if line.startswith("v "):
                v.append(tuple(float(t) for t in line.split()[1:4]))
    return v


def evaluated(obj):
    deps = bpy.context.evaluated_depsgraph_get()
    ev = obj.evaluated_get(deps)
    mesh = ev.to_mesh()
    out = [tuple(ev.matrix_world @ v.co) for v in mesh.vertices]
    ev.to_mesh_clear()
    return out


def compare(what, got, want, order=None):
    if len(got) != len(want):
        failures.append(f"{what}: {len(got)} vertices in Blender, {len(want)} in the OBJ")
        return
    worst = 0.0
    for i, g in enumerate(got):
        w = want[order[i] if order else i]
        worst = max(worst, max(abs(g[k] - w[k]) for k in range(3)))
    print(f"{what}: {len(got)} vertices, largest difference {worst:.3g}")
    if not worst <= TOL:
        failures.append(f"{what}: largest difference {worst:.3g} > {TOL}")


def clear():
    bpy.ops.wm.read_factory_settings(use_empty=True)


# Frame k of the caches is the k-th written skin frame; the steps written are in the glTF file's extras.
with open(os.path.join(results, "skin.glb"), "rb") as f:
    f.read(12)
    length, _ = struct.unpack("<II", f.read(8))
    doc = json.loads(f.read(length))
written = doc["meshes"][0]["extras"]["sinew_steps"]
rest = read_obj(os.path.join(results, "skin_rest.obj"))

# 1. glTF: Blender turns glTF's Y-up into its Z-up, (x, y, z) -> (x, -z, y).
clear()
# Shading "Smooth", as the import dialog offers it: Debian 12's Blender 3.4 fails with its default,
# "Normals", on any mesh with normals (its importer calls numpy.bool, which Debian's numpy 1.24 lacks).
bpy.ops.import_scene.gltf(filepath=os.path.join(results, "skin.glb"), merge_vertices=False, import_shading="SMOOTH")
skin = next(o for o in bpy.context.scene.objects if o.type == "MESH")
keys = skin.data.shape_keys
if keys is None or len(keys.key_blocks) != len(written) + 1:
    failures.append(f"glTF: {0 if keys is None else len(keys.key_blocks) - 1} shape keys, {len(written)} frames written")
else:
    # The importer may reorder vertices: match them to the OBJ's by their rest position.
    tree = kdtree.KDTree(len(rest))
    for i, p in enumerate(rest):
        tree.insert((p[0], -p[2], p[1]), i)
    tree.balance()
    order = [tree.find(v.co)[1] for v in keys.key_blocks[0].data]
    fcurves = {fc.data_path: fc for fc in keys.animation_data.action.fcurves}
    for step in steps:
        k = written.index(step)
        name = keys.key_blocks[k + 1].name
        fc = fcurves[f'key_blocks["{name}"].value']
        frame = next(p.co[0] for p in fc.keyframe_points if p.co[1] > 0.5)
        bpy.context.scene.frame_set(int(frame), subframe=frame - int(frame))
        want = [(x, -z, y) for (x, y, z) in read_obj(os.path.join(results, f"skin_{step:06d}.obj"))]
        compare(f"glTF step {step} (shape key {name}, frame {frame:g})", evaluated(skin), want, order)

# 2. PC2 on the rest skin: the OBJ imported without turning its axes, the cache's frame k at scene frame k.
clear()
bpy.ops.wm.obj_import(filepath=os.path.join(results, "skin_rest.obj"), forward_axis="Y", up_axis="Z")
body = next(o for o in bpy.context.scene.objects if o.type == "MESH")
compare("rest OBJ", evaluated(body), rest)
cache = body.modifiers.new("sinew", "MESH_CACHE")
cache.cache_format = "PC2"
cache.filepath = os.path.join(results, "skin.pc2")
cache.frame_start = 0.0
for step in steps:
    k = written.index(step)
    bpy.context.scene.frame_set(k)
    compare(f"PC2 step {step} (frame {k})", evaluated(body), read_obj(os.path.join(results, f"skin_{step:06d}.obj")))

# The comparison means something only where the skin moved.
moved = max(max(abs(a - b) for a, b in zip(p, q))
            for step in steps for p, q in zip(read_obj(os.path.join(results, f"skin_{step:06d}.obj")), rest))
print(f"the skin moved up to {moved:.3g} from its rest at these steps")
if not moved > 100 * TOL:
    failures.append(f"the skin moved only {moved:.3g} at steps {steps}: nothing to compare")

if failures:
    print("FAIL: " + "; ".join(failures))
    sys.exit(1)
print("Blender read the glTF and PC2 caches back")
