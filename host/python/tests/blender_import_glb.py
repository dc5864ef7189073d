"""Run inside Blender (`blender -b --factory-startup --python THIS -- IN.glb OUT.json`), not by
pytest: imports a .glb with Blender's own glTF importer and writes, for each keyframe of the
imported animation, every bone's head in Blender's world (Z up, metres), by bone name."""

import json
import sys

import bpy
import numpy

# Debian 12's Blender 3.4 glTF importer still uses numpy.bool, which Debian 12's numpy 1.24 removed
# (an alias of bool): restored here, in the test, for the importer; nothing of the product needs it.
if not hasattr(numpy, "bool"):
    numpy.bool = bool

glb, out = sys.argv[sys.argv.index("--") + 1:]
bpy.ops.wm.read_factory_settings(use_empty=True)
bpy.context.scene.render.fps = 60  # the export's keyframe rate: one Blender frame per keyframe
bpy.ops.import_scene.gltf(filepath=glb)
armature = next(o for o in bpy.context.scene.objects if o.type == "ARMATURE")
action = armature.animation_data.action
frames = sorted({round(k.co[0], 3) for c in action.fcurves for k in c.keyframe_points})
heads = []
for frame in frames:
    whole = int(frame)
    bpy.context.scene.frame_set(whole, subframe=frame - whole)
    heads.append({b.name: list(armature.matrix_world @ b.head) for b in armature.pose.bones})
with open(out, "w") as f:
    json.dump({"frames": frames, "heads": heads, "blender": bpy.app.version_string}, f)
