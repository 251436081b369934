"""Per-frame weights in other tools' vocabularies: ARKit (plain and Live Link Face CSV), VRM, Oculus visemes.

Each sink fits every frame's displacement (the posed or simulated vertices minus rest) onto its
vocabulary (:class:`visemeface.retarget.ShapeFit`) as the frames stream by (the Oculus visemes of a run
with phones are the phones' classes instead, :class:`OculusSink`), and writes the weights when the run
closes: ``.csv`` (``frame,time,<names>``) or ``.json``
(``{"vocabulary", "fps", "names", "time", "weights": [[...], ...]}``), weights in 0–1 with 6 decimals.
"""

from __future__ import annotations

import csv
import json

import numpy as np

from visemeface.errors import InputError
from visemeface.export.sinks import Sink, register
from visemeface.outputs import atomic_output

#: Live Link Face's columns after the 52 blendshapes: head and eye rotations (written as 0).
LIVE_LINK_ROTATIONS = ("HeadYaw", "HeadPitch", "HeadRoll", "LeftEyeYaw", "LeftEyePitch", "LeftEyeRoll",
                       "RightEyeYaw", "RightEyePitch", "RightEyeRoll")


def live_link_timecode(t: float, fps: float) -> str:
    """``HH:MM:SS:FF.fff`` of time ``t`` (s) at ``fps``: frame ``FF`` within the second and its fraction."""
    whole = int(np.floor(t + 1e-9))
    f = round((t - whole) * fps, 3)
    ff = int(np.floor(f))
    m, s = divmod(whole, 60)
    h, m = divmod(m, 60)
    return f"{h:02d}:{m:02d}:{s:02d}:{ff:02d}.{int(round((f - ff) * 1000)):03d}"


def write_weights(path, vocabulary: str, names, times, weights, fps: float, force: bool = False) -> None:
    """Per-frame weights as CSV (``frame,time,<names>``) or JSON, chosen by ``path``'s suffix."""
    w = np.clip(np.asarray(weights, dtype=np.float64), 0.0, 1.0)
    t = np.asarray(times, dtype=np.float64)
    with atomic_output(path, force) as tmp:
        if str(path).lower().endswith(".json"):
            doc = {"format": "visemeface-weights", "vocabulary": vocabulary, "fps": fps, "names": list(names),
                   "time": [round(float(x), 6) for x in t], "weights": np.round(w, 6).tolist()}
            tmp.write_text(json.dumps(doc, separators=(",", ":")) + "\n", encoding="utf-8")
            return
        with open(tmp, "w", newline="", encoding="utf-8") as fh:
            out = csv.writer(fh, lineterminator="\n")
            out.writerow(["frame", "time", *names])
            for i, (ti, row) in enumerate(zip(t, w)):
                out.writerow([i, f"{ti:.6f}", *(f"{x:.6f}" for x in row)])


def write_live_link(path, names, times, weights, fps: float, force: bool = False) -> None:
    """ARKit weights as a Live Link Face CSV: ``Timecode,BlendShapeCount,EyeBlinkLeft,…,RightEyeRoll``.

    ``names`` are the 52 camelCase ARKit names in Live Link's column order; blendshape columns are
    PascalCase; head and eye rotations are 0; ``BlendShapeCount`` is the number of value columns (61).
    """
    from visemeface.retarget import live_link_name

    w = np.clip(np.asarray(weights, dtype=np.float64), 0.0, 1.0)
    cols = [live_link_name(n) for n in names] + list(LIVE_LINK_ROTATIONS)
    zeros = ["0"] * len(LIVE_LINK_ROTATIONS)
    with atomic_output(path, force) as tmp, open(tmp, "w", newline="", encoding="utf-8") as fh:
        out = csv.writer(fh, lineterminator="\n")
        out.writerow(["Timecode", "BlendShapeCount", *cols])
        for ti, row in zip(times, w):
            out.writerow([live_link_timecode(float(ti), fps), len(cols), *(f"{x:.6f}" for x in row), *zeros])


class FitSink(Sink):
    """Base of the weight sinks: fits each frame onto ``vocabulary`` and keeps the (F, K) weights."""

    vocabulary = ""
    suffixes = (".csv", ".json")

    def open(self, run) -> None:
        from visemeface.retarget import ShapeFit, moving_vertices, vocabulary

        super().open(run)
        if run.rig is None:
            raise InputError(f"--{self.name} needs a rig (speak, say or simulate)", self.path)
        self.vocab = vocabulary(self.vocabulary, run.rig)
        self.fit = ShapeFit(self.vocab, moving_vertices(run.rig))
        self.rest = np.asarray(run.face.vertices, dtype=np.float64)
        self.times, self.weights, self.residuals = [], [], []

    def write(self, frame) -> None:
        w, r = self.fit.frame(np.asarray(frame.vertices, dtype=np.float64) - self.rest)
        self.times.append(frame.time)
        self.weights.append(w)
        self.residuals.append(r)

    def weight_matrix(self) -> np.ndarray:
        return np.array(self.weights).reshape(len(self.weights), len(self.vocab.names))

    def close(self) -> None:
        write_weights(self.tmp[0], self.vocabulary, self.vocab.names, self.times, self.weight_matrix(),
                      self.run.fps, force=True)


@register
class ArkitSink(FitSink):
    """ARKit's 52 blendshape weights per frame (camelCase names)."""

    name = "arkit"
    vocabulary = "arkit"
    metavar = "FILE.csv|.json"
    help = "also write ARKit's 52 blendshape weights per frame (CSV or JSON by the suffix)"


@register
class LiveLinkSink(FitSink):
    """ARKit weights in Live Link Face's CSV layout (Unreal's Live Link Face app, MetaHumans)."""

    name = "livelink"
    vocabulary = "arkit"
    metavar = "FILE.csv"
    help = "also write ARKit weights as a Live Link Face CSV (Timecode, BlendShapeCount, EyeBlinkLeft, ...)"
    suffixes = (".csv",)

    def close(self) -> None:
        write_live_link(self.tmp[0], self.vocab.names, self.times, self.weight_matrix(), self.run.fps, force=True)


@register
class VrmSink(FitSink):
    """VRM 1.0 preset expressions per frame (aa ih ou ee oh, blink, happy angry sad relaxed surprised)."""

    name = "vrm"
    vocabulary = "vrm"
    metavar = "FILE.csv|.json"
    help = "also write VRM expression weights per frame (aa ih ou ee oh, blink, happy, ...; CSV or JSON)"


@register
class OculusSink(FitSink):
    """Oculus/Meta's 15 viseme weights per frame (sil PP FF TH DD kk CH SS nn RR aa E ih oh ou), adding up to 1.

    They say what is spoken, as Meta's lip sync reports it from audio, and a character's expressions are
    driven beside them. So from ``speak``, ``say`` and ``batch`` (a run with an utterance) they are the
    phones' classes (``phoneme_classes.csv``) blended along the timeline as the visemes are
    (:func:`~visemeface.speech.timeline.class_track`): a held /p/ is PP at 1. Fitted to the face they were
    not: a smile at rest read as FF 0.81, and 24 of the 56 visemes posed alone came out as another class.
    A run without speech (``simulate``) fits its frames.
    """

    name = "oculus"
    vocabulary = "oculus"
    metavar = "FILE.csv|.json"
    help = ("also write Oculus/Meta's 15 viseme weights per frame (sil PP FF ... ou; CSV or JSON): the phones' "
            "classes where there are phones, else fitted to the frames")

    def open(self, run) -> None:
        super().open(run)
        self.classes = None
        utterance = run.extra.get("utterance")
        if utterance is not None:
            from visemeface.retarget.recipes import OCULUS, phoneme_classes
            from visemeface.speech.timeline import MODES, class_track

            classes = {s: c[0] for s, c in phoneme_classes().items()}
            self.classes = class_track(utterance.segments, classes, OCULUS, fps=run.fps,
                                       mode=run.extra.get("interp", MODES[0])).to_numpy()

    def write(self, frame) -> None:
        if self.classes is None:
            return super().write(frame)
        self.times.append(frame.time)
        self.weights.append(self.classes[min(frame.index, len(self.classes) - 1)])
        self.residuals.append(float("nan"))
