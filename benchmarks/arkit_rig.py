"""ARKit weights on a real ARKit rig: the fit's residual (mm) and speed, reference ICT and a glb round trip.

For each sentence: our muscles pose the ICT Face Model's neutral along the speech track and each frame is
fitted onto ICT's 53 shapes (the default ``--arkit``); then the same with ICT's shapes written as a ``.glb``
(centimetres, as ICT ships) and read back as a client rig (``--arkit-rig``). Prints JSON lines: frames/s of
the fit, residual median / 95th percentile / largest (RMS over the fitted vertices, mm)::

    PYTHONPATH=src python benchmarks/arkit_rig.py
"""

from __future__ import annotations

import json
import tempfile
import time
from pathlib import Path

import numpy as np

SENTENCES = ("bob moves five boats past my pool", "a map of the moon by the blue boom box",
             "we wove two woolly ropes", "papa bought maybe more apples")


def main() -> None:
    import warnings

    from visemeface.export.gltf import write_morph_animation_glb
    from visemeface.muscles.rig import default_rig
    from visemeface.postures.library import load_visemes
    from visemeface.retarget.rigs import load_client_rig, reference_rig
    from visemeface.speech.g2p import text_to_utterance
    from visemeface.speech.timeline import MODES, activation_track

    warnings.simplefilter("ignore")
    rig = default_rig()
    ranges = {n: tuple(r) for n, r in zip(rig.names, rig.ranges)}
    ict = reference_rig()
    with tempfile.TemporaryDirectory() as tmp:
        glb = Path(tmp) / "ict.glb"
        write_morph_animation_glb(glb, ict.face.vertices * 100, ict.face.triangles, ict.shapes.deltas * 100,
                                  ict.shapes.names, np.array([0.0, 1.0]), np.zeros((2, len(ict.shapes.names))))
        t0 = time.perf_counter()
        client = load_client_rig(glb)
        load_s = time.perf_counter() - t0
    for label, target in (("ict", ict), ("ict_glb", client)):
        target.track_weights(np.zeros((1, len(rig.names))), rig.path)          # factor once
        for text in SENTENCES:
            u = text_to_utterance(text)
            A = rig.track_matrix(activation_track(u, load_visemes(rig=rig), fps=30.0, mode=MODES[0],
                                                  ranges=ranges))
            t = time.perf_counter()
            W, R = target.track_weights(A, rig.path)
            dt = time.perf_counter() - t
            r = R * 1000
            print(json.dumps({"benchmark": "arkit_rig", "rig": label, "text": text, "frames": len(A),
                              "fps": round(len(A) / dt, 1), "residual_median_mm": round(float(np.median(r)), 3),
                              "residual_p95_mm": round(float(np.percentile(r, 95)), 3),
                              "residual_max_mm": round(float(r.max()), 3),
                              **({"glb_load_s": round(load_s, 2)} if label == "ict_glb" else {})}))


if __name__ == "__main__":
    main()
