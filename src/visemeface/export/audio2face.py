"""NVIDIA Audio2Face blendshape weights (``.json``), the layout of its *Export > Blendshape weights*.

``{"exportFps", "trackPath", "numPoses", "numFrames", "facsNames": [52 ARKit names],
"weightMat": [[52 weights] a frame]}``: the file Audio2Face's blendshape solver writes and the tools
that replay it read (Omniverse's importers, the Unreal and Blender add-ons that load A2F's JSON). The
weights are the ARKit weights (:class:`~visemeface.export.retarget.RigFitSink`: fitted on a real ARKit rig), 0..1 with 6 decimals;
``trackPath`` is the run's sound, or "" without one.
"""

from __future__ import annotations

import json

import numpy as np

from visemeface.export.retarget import RigFitSink
from visemeface.export.sinks import register


def a2f_document(names, weights, fps: float, track_path: str = "") -> dict:
    """Audio2Face's export document of per-frame weights (F, K) in 0..1."""
    w = np.round(np.clip(np.asarray(weights, np.float64), 0.0, 1.0), 6)
    return {"exportFps": float(fps), "trackPath": track_path, "numPoses": len(names), "numFrames": len(w),
            "facsNames": list(names), "weightMat": w.tolist()}


@register
class Audio2FaceSink(RigFitSink):
    """ARKit weights in Audio2Face's blendshape-weights JSON (module docstring)."""

    name = "audio2face"
    metavar = "FILE.json"
    help = "also write NVIDIA Audio2Face blendshape weights (JSON: exportFps, facsNames, weightMat)"
    suffixes = (".json",)

    def close(self) -> None:
        audio = self.run.audio
        doc = a2f_document(self.names, self.weight_matrix(), self.run.fps, str(audio) if audio else "")
        self.tmp[0].write_text(json.dumps(doc, separators=(",", ":")) + "\n", encoding="utf-8")
