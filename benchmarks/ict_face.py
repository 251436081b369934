"""Kinematic speech on the ICT head beside the default face, in one run: frames per second (JSON lines).

Each frame is a rig pose (one matrix product) and a 512x512 render without multisampling, as ``speak --msaa 0``
makes them (encoding left out): the renderer is given the vertices the run's track leaves at rest, as the
pipeline gives it (``--no-culling``: draw every triangle). ``triangles_drawn`` is what it draws then;
``renderer_setup_s`` includes finding them. Target: >= 100 frames/s on the ICT head (24,591 vertices, about
49,000 triangles) on the 2-core machine::

    PYTHONPATH=src python benchmarks/ict_face.py [--frames 150] [--size 512] [--no-culling] [--gestures]
"""

from __future__ import annotations

import argparse
import json
import os
import time
import warnings

import numpy as np


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--frames", type=int, default=150)
    ap.add_argument("--size", type=int, default=512)
    ap.add_argument("--no-culling", action="store_true", help="draw every triangle (the renderer without `still`)")
    ap.add_argument("--gestures", action="store_true",
                    help="add the blinks and the prosodic gestures (gaze, brows) `speak` adds: the eyes and lids move")
    args = ap.parse_args(argv)
    warnings.simplefilter("ignore")

    from visemeface.face.ict import ict_face
    from visemeface.face.procedural import default_face
    from visemeface.muscles.rig import MuscleRig
    from visemeface.postures.library import load_visemes
    from visemeface.render.renderer import Renderer
    from visemeface.speech.blinks import blink_utterance
    from visemeface.speech.g2p import text_to_utterance
    from visemeface.speech.gestures import add_face_gestures, speech_gestures
    from visemeface.speech.timeline import MODES, activation_track

    for name, face in (("procedural", default_face()), ("ict", ict_face())):
        rig = MuscleRig.from_file(face)
        ranges = {n: tuple(r) for n, r in zip(rig.names, rig.ranges)}
        u = text_to_utterance("bob moves five boats past my pool " * 3)
        track = activation_track(u, load_visemes(rig=rig), fps=30.0, mode=MODES[0], ranges=ranges)
        if args.gestures:
            track = blink_utterance(track, rig, u)
            track = add_face_gestures(track, rig.names, speech_gestures(u, len(track), 30.0, None, seed=0))
        A = rig.clamp(rig.track_matrix(track))[: args.frames]
        setup = time.perf_counter()
        with Renderer(face, size=args.size, samples=0, still=None if args.no_culling else rig.still_vertices(A)) as r:
            setup = time.perf_counter() - setup
            r.render(rig.pose(A[0]))
            t, c = time.perf_counter(), time.process_time()
            for a in A:
                r.render(np.asarray(rig.pose(a), dtype=np.float32))   # as KinematicMotion's frames
            wall, cpu = time.perf_counter() - t, time.process_time() - c
            drawn = r.n_shown
        print(json.dumps({"benchmark": "speak_kinematic_frames", "face": name, "vertices": face.n_vertices,
                          "triangles": len(face.triangles), "triangles_drawn": drawn,
                          "renderer_setup_s": round(setup, 3), "size": args.size, "msaa_samples": 0,
                          "gestures": args.gestures,
                          "frames": len(A), "fps": round(len(A) / wall, 1),
                          "cpu_ms_per_frame": round(1000 * cpu / len(A), 2), "target_fps": 100,
                          "load_avg_1min": round(os.getloadavg()[0], 2)}), flush=True)


if __name__ == "__main__":
    main()
