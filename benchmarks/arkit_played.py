"""ARKit weights played on our face with ARKit's meaning: the round trip's fidelity and the fit's cost.

For each sentence (none used to set anything): our muscles' speech track is written as ARKit weights (fitted
on the ICT Face Model's shapes, the default ``--arkit``) and played back through the reference fit
(:mod:`visemeface.retarget.played`). Prints JSON lines: the lip gap's correlation with the original, the slope
of played over original opening, the largest |gap| where the original lips were shut (mm), and ms a frame::

    PYTHONPATH=src python benchmarks/arkit_played.py
"""

from __future__ import annotations

import json
import time

import numpy as np

SENTENCES = ("bob moves five boats past my pool", "a map of the moon by the blue boom box",
             "we wove two woolly ropes", "papa bought maybe more apples")


def main() -> None:
    import warnings

    from visemeface.muscles.rig import default_rig
    from visemeface.postures.library import load_visemes
    from visemeface.retarget import check
    from visemeface.retarget.played import reference_fit
    from visemeface.retarget.rigs import reference_rig
    from visemeface.speech.g2p import text_to_utterance
    from visemeface.speech.timeline import MODES, activation_track

    warnings.simplefilter("ignore")
    rig, ref, fit = default_rig(), reference_rig(), reference_fit()
    names, to_arkit, _ = ref.arkit_map()
    ranges = {n: tuple(r) for n, r in zip(rig.names, rig.ranges)}

    def gap(A):
        return check.measure(rig.face, np.array([rig.displacement(a) for a in A])).gap

    for text in SENTENCES:
        track = activation_track(text_to_utterance(text), load_visemes(rig=rig), fps=30.0, mode=MODES[0],
                                 ranges=ranges)
        A0 = rig.track_matrix(track)
        W, _ = ref.track_weights(A0, rig.path)
        t0 = time.perf_counter()
        A1, _ = fit.frames(names, W @ to_arkit.T)
        ms = 1000 * (time.perf_counter() - t0) / len(A0)
        g0, g1 = gap(A0), gap(A1)
        print(json.dumps({"sentence": text, "frames": len(A0), "gap_r": round(float(np.corrcoef(g0, g1)[0, 1]), 3),
                          "slope": round(float(np.polyfit(g0, g1, 1)[0]), 3),
                          "shut_max_mm": round(float(np.abs(g1[g0 < 0.5]).max()), 2), "ms_per_frame": round(ms, 1)}))


if __name__ == "__main__":
    main()
