"""The writers of :mod:`visemeface.export` under their earlier home (docs/conventions.md).

Kept so that ``visemeface.render.export.VideoWriter`` and friends still import;
new code imports from :mod:`visemeface.export` (one module per format).
"""

from visemeface.export.gltf import glb_bytes, unit_normals, write_morph_animation_glb, write_rig_animation  # noqa: F401
from visemeface.export.images import (FRAME_DIGITS, PngSequenceWriter, encode_png, frame_name,  # noqa: F401
                                      read_png, write_png)
from visemeface.export.obj import ObjSequenceWriter, obj_faces_text, obj_text  # noqa: F401
from visemeface.export.pc2 import PC2_MAGIC, Pc2Writer, read_pc2, write_pc2  # noqa: F401
from visemeface.export.video import VideoWriter, read_video_audio, read_video_info  # noqa: F401
from visemeface.muscles.morphs import jaw_sample_weights  # noqa: F401
