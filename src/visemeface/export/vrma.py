"""VRM Animation (``.vrma``): the VRM 1.0 expressions as a glTF ``VRMC_vrm_animation`` clip.

A VRMA file is a binary glTF without a mesh: the extension ``VRMC_vrm_animation`` (``specVersion``
"1.0") maps each preset expression to a node (``expressions.preset.<name>.node``), and the expression's
weight is the x of that node's translation, animated by a LINEAR ``translation`` channel (y and z are 0).
The weights are the VRM fit of every frame (:class:`~visemeface.export.retarget.FitSink`, vocabulary
``vrm``: aa ih ou ee oh, blink blinkLeft blinkRight, happy angry sad relaxed surprised). No humanoid
bones: the clip moves the face only. three-vrm's ``VRMAnimationLoaderPlugin`` (and VRM tools that load
VRMA) play it on any VRM 1.0 avatar.
"""

from __future__ import annotations

import numpy as np

from visemeface.export.gltf import _GlbBuffer, glb_bytes
from visemeface.export.retarget import FitSink
from visemeface.export.sinks import register

EXTENSION = "VRMC_vrm_animation"


def vrma_bytes(names, times, weights) -> bytes:
    """The VRMA file of per-frame expression weights (F, K) in 0..1 named by VRM presets ``names``."""
    from visemeface import __version__

    t = np.asarray(times, np.float64)
    w = np.clip(np.asarray(weights, np.float64), 0.0, 1.0).reshape(len(t), len(names))
    buf = _GlbBuffer()
    t_in = buf.add(t.astype("<f4"), "SCALAR")
    samplers, channels = [], []
    for k in range(len(names)):
        xyz = np.zeros((len(t), 3), "<f4")
        xyz[:, 0] = w[:, k]
        samplers.append({"input": t_in, "output": buf.add(xyz, "VEC3"), "interpolation": "LINEAR"})
        channels.append({"sampler": k, "target": {"node": k, "path": "translation"}})
    gltf = {
        "asset": {"version": "2.0", "generator": f"visemeface {__version__}"},
        "extensionsUsed": [EXTENSION],
        "extensions": {EXTENSION: {"specVersion": "1.0", "expressions": {
            "preset": {n: {"node": k} for k, n in enumerate(names)}}}},
        "scene": 0,
        "scenes": [{"nodes": list(range(len(names)))}],
        "nodes": [{"name": f"expression_{n}", "translation": [0.0, 0.0, 0.0]} for n in names],
        "animations": [{"name": "speech", "channels": channels, "samplers": samplers}],
        "buffers": [{"byteLength": buf.offset}],
        "bufferViews": buf.views,
        "accessors": buf.accessors,
    }
    return glb_bytes(gltf, buf.blob())


@register
class VrmaSink(FitSink):
    """The VRM expressions as a VRM Animation clip (module docstring)."""

    name = "vrma"
    vocabulary = "vrm"
    fits_gestures = False      # as --vrm (FitSink.fits_gestures)
    metavar = "FILE.vrma"
    help = "also write a VRM Animation (.vrma): the VRM 1.0 expressions (aa ih ou ee oh, blink, ...) as a glTF clip"
    suffixes = (".vrma",)

    def close(self) -> None:
        self.tmp[0].write_bytes(vrma_bytes(self.vocab.names, self.times, self.weight_matrix()))
