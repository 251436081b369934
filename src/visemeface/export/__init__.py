"""Outputs of an animation, one module per format, each a writer and a sink in :data:`SINKS`.

:mod:`.video` (MP4 + audio + mouth-box sidecar), :mod:`.images` (PNG frames,
resumable), :mod:`.obj` (OBJ sequence), :mod:`.pc2` (point cache),
:mod:`.gltf` (morph-target animation), :mod:`.tables` (activation track and
per-frame measures), :mod:`.retarget` (ARKit/Live Link, VRM, Oculus weights),
:mod:`.rhubarb` (Rhubarb Lip Sync cues), :mod:`.preview` (a self-contained three.js
page), the engines' formats from the ARKit or VRM weights (:mod:`.unity` .anim, :mod:`.godot` .tres,
:mod:`.live2d` motion3.json, :mod:`.mmd` .vmd, :mod:`.audio2face` JSON, :mod:`.vrma` VRM Animation)
and the words' (:mod:`.captions` SRT/WebVTT, :mod:`.papagayo` .pgo). Writers are pure over numpy arrays and stream (one frame in, one frame
written); every file appears under its final name only when complete
(:mod:`visemeface.outputs`).
"""

# Registration order is the order of the command-line options.
from visemeface.export import video, images, obj, pc2, gltf, tables  # noqa: F401,I001  # isort: skip
from visemeface.export import retarget, rhubarb, preview  # noqa: F401,I001  # isort: skip
from visemeface.export import unity, godot, live2d, mmd, audio2face, vrma  # noqa: F401,I001  # isort: skip
from visemeface.export import captions, papagayo  # noqa: F401,I001  # isort: skip
from visemeface.export.sinks import SINKS, RunInfo, Sink, register

__all__ = ["SINKS", "RunInfo", "Sink", "register"]
