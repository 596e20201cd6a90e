# Renders a run's skin.glb at one step with Blender (background mode, Workbench): the picture of the README's
# skin caches section. Usage: blender -b --factory-startup --python blender_skin.py -- RESULTS OUT.png STEP
import sys, bpy, math
results, out, frame_step = sys.argv[sys.argv.index("--") + 1:]
bpy.ops.wm.read_factory_settings(use_empty=True)
bpy.ops.import_scene.gltf(filepath=results + "/skin.glb", import_shading="SMOOTH")
skin = next(o for o in bpy.context.scene.objects if o.type == "MESH")
keys = skin.data.shape_keys
name = "step_%06d" % int(frame_step)
fc = {f.data_path: f for f in keys.animation_data.action.fcurves}['key_blocks["%s"].value' % name]
fr = next(p.co[0] for p in fc.keyframe_points if p.co[1] > 0.5)
sc = bpy.context.scene
sc.frame_set(int(fr), subframe=fr - int(fr))
mat = bpy.data.materials.new("flesh"); mat.use_nodes = True
mat.node_tree.nodes["Principled BSDF"].inputs["Base Color"].default_value = (0.8, 0.55, 0.45, 1)
skin.data.materials.clear(); skin.data.materials.append(mat)
bpy.ops.object.shade_smooth()
# camera framing the evaluated skin
deps = bpy.context.evaluated_depsgraph_get(); ev = skin.evaluated_get(deps); m = ev.to_mesh()
import mathutils
pts = [skin.matrix_world @ v.co for v in m.vertices]
lo = mathutils.Vector([min(p[i] for p in pts) for i in range(3)]); hi = mathutils.Vector([max(p[i] for p in pts) for i in range(3)])
c = (lo + hi) / 2; size = (hi - lo).length
cam = bpy.data.objects.new("cam", bpy.data.cameras.new("cam")); sc.collection.objects.link(cam); sc.camera = cam
cam.location = c + mathutils.Vector((0.9, -1.6, 0.4)).normalized() * size * 1.6
cam.rotation_euler = (c - cam.location).to_track_quat('-Z', 'Y').to_euler()
light = bpy.data.objects.new("sun", bpy.data.lights.new("sun", "SUN")); sc.collection.objects.link(light)
light.rotation_euler = (0.7, 0.2, 0.8); light.data.energy = 4
sc.world = bpy.data.worlds.new("w"); sc.world.color = (0.9, 0.9, 0.9)
sc.render.engine = "BLENDER_WORKBENCH"
sc.render.resolution_x, sc.render.resolution_y = 480, 480
sc.render.filepath = out
bpy.ops.render.render(write_still=True)
print("rendered", out)
