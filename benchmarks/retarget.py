"""Retargeting fit: per-frame residual (RMS over the vertices the rig moves, mm) and fit time (JSON lines).

Fits every frame of "one five zero zero six" repeated (with happiness over it, so the brows and cheeks
move too) onto each vocabulary and prints one line per frame for ARKit (``--per-frame``) and a summary
line per vocabulary (median, 95th percentile and largest residual; milliseconds per frame)::

    PYTHONPATH=src python benchmarks/retarget.py [--seconds 10] [--emotion happiness=0.5] [--per-frame]

The Oculus vocabulary is a partition of one over 15 class-mean visemes, so its residual is the
distance of the frame from the nearest blend of class means (expected to be much larger than ARKit's,
which has a shape per muscle group).
"""

from __future__ import annotations

import argparse
import json
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))


def main() -> None:
    from _runner import write_transcript

    from visemeface.muscles.rig import default_rig
    from visemeface.postures.library import PostureLibrary, parse_weights
    from visemeface.retarget import VOCABULARIES, ShapeFit, moving_vertices, vocabulary
    from visemeface.speech.timeline import activation_track
    from visemeface.speech.transcripts import read_utterance

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seconds", type=float, default=10.0)
    ap.add_argument("--emotion", default="happiness=0.5", help="emotion over the utterance ('' for none)")
    ap.add_argument("--per-frame", action="store_true", help="also print the ARKit residual of every frame")
    args = ap.parse_args()
    rig = default_rig()
    lib = PostureLibrary(rig)
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "b.txt"
        write_transcript(path, args.seconds)
        utt = read_utterance(path)
    ranges = {n: tuple(r) for n, r in zip(rig.names, rig.ranges)}
    track = activation_track(utt, lib.visemes, fps=30, emotions=parse_weights(args.emotion) if args.emotion else None,
                             ranges=ranges)
    poses = rig.poses(track).astype(np.float64) - rig.face.vertices
    for name in VOCABULARIES:
        t0 = time.perf_counter()
        fit = ShapeFit(vocabulary(name, rig, lib), moving_vertices(rig))
        build = time.perf_counter() - t0
        t0 = time.perf_counter()
        weights, res = fit.frames(poses)
        per_frame = (time.perf_counter() - t0) / len(poses)
        mm = res * 1000
        if name == "arkit" and args.per_frame:
            for i, (t, r) in enumerate(zip(track.index, mm)):
                print(json.dumps({"benchmark": "retarget_frame", "vocabulary": name, "frame": i,
                                  "time": round(float(t), 4), "residual_mm": round(float(r), 5)}))
        motion = np.sqrt((poses[:, fit.mask] ** 2).sum(axis=2).mean(axis=1)) * 1000
        print(json.dumps({"benchmark": "retarget", "vocabulary": name, "frames": len(poses),
                          "shapes_fitted": int(len(fit.made)), "residual_mm_median": round(float(np.median(mm)), 4),
                          "residual_mm_p95": round(float(np.percentile(mm, 95)), 4),
                          "residual_mm_max": round(float(mm.max()), 4),
                          "motion_rms_mm_median": round(float(np.median(motion)), 3),
                          "weight_sum_median": round(float(np.median(weights.sum(axis=1))), 4),
                          "ms_per_frame": round(per_frame * 1000, 3), "build_s": round(build, 3)}))


if __name__ == "__main__":
    main()
