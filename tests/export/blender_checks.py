"""Run inside Blender: ``blender -b --factory-startup --python blender_checks.py -- GLB OBJ_DIR PC2 HEAD_GLB OUT.json``.

Checks what the README tells Blender users to do, and writes what it found as JSON (read by
test_clients.py):

- glb: set the scene's frame rate to the glb's ``asset.extras.fps`` first, import (File > Import >
  glTF 2.0): the shape-key names and the frames of the shape-key action's keys;
- PC2: import ``frame_000000.obj`` (File > Import > Wavefront OBJ, default axes), add a Mesh Cache
  modifier (PC2, axes left at their defaults) and compare the evaluated mesh at several frames with
  the OBJ of that frame imported the same way (world coordinates): the largest distance (mm);
- a glb spoken from a recording (head gestures on): the object the face mesh hangs from and its world
  rotation (w, x, y, z, Blender's axes) at every frame, as the importer animates it.
"""

import json
import struct
import sys
from pathlib import Path

import bpy

try:  # Blender 3.4's glTF importer uses np.bool, gone since numpy 1.24 (Debian 12 pairs the two)
    import numpy

    if "bool" not in numpy.__dict__:
        numpy.bool = bool
except ImportError:
    pass

glb, obj_dir, pc2, head_glb, out = (Path(a) for a in sys.argv[sys.argv.index("--") + 1:])
result = {"blender": bpy.app.version_string}


def clear():
    for o in list(bpy.data.objects):
        bpy.data.objects.remove(o, do_unlink=True)


def world_vertices(ob, evaluated=True):
    dg = bpy.context.evaluated_depsgraph_get()
    e = ob.evaluated_get(dg) if evaluated else ob
    me = e.to_mesh()
    m = ob.matrix_world.copy()
    co = [tuple(m @ v.co) for v in me.vertices]
    e.to_mesh_clear()
    return co


def import_obj(path):
    before = set(bpy.data.objects)
    if hasattr(bpy.ops.wm, "obj_import"):
        bpy.ops.wm.obj_import(filepath=str(path))
    else:
        bpy.ops.import_scene.obj(filepath=str(path), split_mode="OFF", use_split_objects=False,
                                 use_split_groups=False)
    return next(iter(set(bpy.data.objects) - before))


def import_glb(path):
    """Import as the README says: the scene's frame rate set to the glb's first; its ``asset.extras``."""
    clear()
    data = path.read_bytes()
    n = struct.unpack_from("<I", data, 12)[0]
    extras = json.loads(data[20:20 + n])["asset"]["extras"]
    fps = extras["fps"]
    bpy.context.scene.render.fps = int(round(fps))
    bpy.context.scene.render.fps_base = round(fps) / fps
    bpy.ops.import_scene.gltf(filepath=str(path))
    return extras


head_extras = import_glb(head_glb)
face = next(o for o in bpy.data.objects if o.type == "MESH")
result["face_parent"] = face.parent.name if face.parent else None
rotations = []
for k in range(head_extras["frames"]):
    bpy.context.scene.frame_set(k)
    q = face.parent.matrix_world.to_quaternion() if face.parent else None
    rotations.append(None if q is None else [q.w, q.x, q.y, q.z])
result["head_rotations"] = rotations

import_glb(glb)
mesh = next(o for o in bpy.data.objects if o.type == "MESH")
keys = mesh.data.shape_keys
result["shape_keys"] = [k.name for k in keys.key_blocks]
action = keys.animation_data.action if keys.animation_data else None
frames = sorted({kp.co[0] for fc in action.fcurves for kp in fc.keyframe_points}) if action else []
result["key_frames"] = frames
result["scene_fps"] = bpy.context.scene.render.fps / bpy.context.scene.render.fps_base

clear()
base = import_obj(obj_dir / "frame_000000.obj")
mod = base.modifiers.new("cache", "MESH_CACHE")
mod.cache_format = "PC2"
mod.filepath = str(pc2)
count = len(list(obj_dir.glob("frame_*.obj")))
errors = {}
for k in sorted({0, 1, count // 2, count - 1}):
    bpy.context.scene.frame_set(k)
    got = world_vertices(base)
    ref_ob = import_obj(obj_dir / f"frame_{k:06d}.obj")
    ref = world_vertices(ref_ob, evaluated=False)
    bpy.data.objects.remove(ref_ob, do_unlink=True)
    same = len(got) == len(ref)
    errors[k] = max(abs(a - b) for p, q in zip(got, ref) for a, b in zip(p, q)) * 1000 if same else None
result["pc2_error_mm"] = errors
result["obj_materials"] = sorted(m.name for m in bpy.data.materials)
out.write_text(json.dumps(result))
