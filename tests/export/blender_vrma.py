"""Run inside Blender: ``blender -b --factory-startup --python blender_vrma.py -- FILE.vrma OUT.json``.

Imports a VRM animation (File > Import > glTF 2.0: a VRMA is a glTF whose expression nodes move) and writes,
for each node, the keys of its X location (seconds, value), read by test_engines.py.
"""

import json
import sys

import bpy

try:  # Blender 3.4's glTF importer uses np.bool, gone since numpy 1.24 (Debian 12 pairs the two)
    import numpy

    if "bool" not in numpy.__dict__:
        numpy.bool = bool
except ImportError:
    pass

vrma, out = sys.argv[sys.argv.index("--") + 1:]
for o in list(bpy.data.objects):
    bpy.data.objects.remove(o, do_unlink=True)
bpy.ops.import_scene.gltf(filepath=vrma)
fps = bpy.context.scene.render.fps / bpy.context.scene.render.fps_base
nodes = {}
for o in bpy.data.objects:
    action = o.animation_data.action if o.animation_data else None
    for fc in (action.fcurves if action else ()):
        if fc.data_path == "location" and fc.array_index == 0:
            nodes[o.name] = [(k.co[0] / fps, k.co[1]) for k in fc.keyframe_points]
json.dump({"blender": bpy.app.version_string, "x_keys": nodes}, open(out, "w"))
