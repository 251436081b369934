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
from pathlib import Path
from typing import ClassVar

import numpy as np

from visemeface.errors import InputError
from visemeface.export.sinks import Sink, register
from visemeface.outputs import atomic_output

#: Live Link Face's columns after the 52 blendshapes: head and eye rotations (the head's from the run's
#: gestures, the eyes' 0).
LIVE_LINK_ROTATIONS = ("HeadYaw", "HeadPitch", "HeadRoll", "LeftEyeYaw", "LeftEyePitch", "LeftEyeRoll",
                       "RightEyeYaw", "RightEyePitch", "RightEyeRoll")
#: Degrees of head rotation per unit of Live Link Face's HeadYaw/HeadPitch/HeadRoll (the app writes them
#: normalised, 1 = a quarter turn).
LIVE_LINK_HEAD_DEG = 90.0


def live_link_head(head, n: int) -> np.ndarray:
    """(n, 3) HeadYaw, HeadPitch, HeadRoll values of per-frame (yaw, pitch, roll) degrees (zeros for None)."""
    if head is None:
        return np.zeros((n, 3))
    h = np.asarray(head, dtype=np.float64).reshape(-1, 3)[:n] / LIVE_LINK_HEAD_DEG
    return np.vstack([h, np.repeat(h[-1:] if len(h) else np.zeros((1, 3)), n - len(h), axis=0)])


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


def write_live_link(path, names, times, weights, fps: float, force: bool = False, head=None) -> None:
    """ARKit weights as a Live Link Face CSV: ``Timecode,BlendShapeCount,EyeBlinkLeft,…,RightEyeRoll``.

    ``names`` are the 52 camelCase ARKit names in Live Link's column order; blendshape columns are
    PascalCase; the head's rotation is ``head`` ((F, 3) yaw, pitch, roll degrees, :func:`live_link_head`), 0
    without it, and the eyes' 0; ``BlendShapeCount`` is the number of value columns (61).
    """
    from visemeface.retarget import live_link_name

    w = np.clip(np.asarray(weights, dtype=np.float64), 0.0, 1.0)
    cols = [live_link_name(n) for n in names] + list(LIVE_LINK_ROTATIONS)
    zeros = ["0"] * (len(LIVE_LINK_ROTATIONS) - 3)
    rot = live_link_head(head, len(w))
    with atomic_output(path, force) as tmp, open(tmp, "w", newline="", encoding="utf-8") as fh:
        out = csv.writer(fh, lineterminator="\n")
        out.writerow(["Timecode", "BlendShapeCount", *cols])
        for ti, row, hr in zip(times, w, rot):
            head_cols = [f"{x:.6f}" if x else "0" for x in hr]
            out.writerow([live_link_timecode(float(ti), fps), len(cols), *(f"{x:.6f}" for x in row), *head_cols,
                          *zeros])


class FitSink(Sink):
    """Base of the weight sinks: fits each frame onto ``vocabulary`` and keeps the (F, K) weights."""

    vocabulary = ""
    suffixes = (".csv", ".json")
    #: Whether the speech's prosodic gestures (brow raises, gaze) are fitted with the rest of the pose. A
    #: vocabulary with no brow raise of its own (VRM's presets) sets False: fitted, the raises read as
    #: 'surprised' (0.4 on "set white with p two soon") and its open jaw took 'aa' from 0.25 to 0.04, so its
    #: expressions are fitted to the pose without them (the emotions and blinks stay).
    fits_gestures: ClassVar[bool] = True

    def open(self, run) -> None:
        from visemeface.retarget import ShapeFit, moving_vertices, vocabulary

        super().open(run)
        if run.rig is None:
            raise InputError(f"--{self.name} needs a rig (speak, say or simulate)", self.path)
        self.vocab = vocabulary(self.vocabulary, run.rig)
        self.fit = ShapeFit(self.vocab, moving_vertices(run.rig))
        self.rest = np.asarray(run.face.vertices, dtype=np.float64)
        self.times, self.weights, self.residuals = [], [], []
        plain = None if self.fits_gestures else run.extra.get("track_without_gestures")
        self.plain = None if plain is None else run.rig.clamp(run.rig.track_matrix(plain))

    def write(self, frame) -> None:
        if self.plain is not None:      # the pose without the prosodic gestures (see fits_gestures)
            d = self.run.rig.displacement(self.plain[min(frame.index, len(self.plain) - 1)])
        else:
            d = np.asarray(frame.vertices, dtype=np.float64) - self.rest
        w, r = self.fit.frame(d)
        self.times.append(frame.time)
        self.weights.append(w)
        self.residuals.append(r)

    def weight_matrix(self) -> np.ndarray:
        return np.array(self.weights).reshape(len(self.weights), len(self.vocab.names))

    def close(self) -> None:
        write_weights(self.tmp[0], self.vocabulary, self.vocab.names, self.times, self.weight_matrix(),
                      self.run.fps, force=True)


class RigFitSink(FitSink):
    """Base of the ARKit sinks: the weights of a blendshape rig made to ARKit's definitions
    (:mod:`visemeface.retarget.rigs`).

    Our muscles pose the rig's neutral with the run's activations (the drive track of a simulation, so the
    lips' sticking is not in the weights) and each frame is fitted onto the rig's own shapes, ``mouthClose``
    never above ``jawOpen``. Without ``--arkit-rig``/``--livelink-rig`` the rig is the ICT Face Model's 53
    artist-made shapes, so the weights mean on any ARKit character what they mean in ARKit; with a rig of the
    user's, its shapes are fitted and written under ARKit's names (its own names for shapes ARKit lacks).
    """

    vocabulary = "arkit"
    rig_setting = ""

    def open(self, run) -> None:
        import warnings

        from visemeface.retarget.rigs import load_client_rig, reference_rig

        Sink.open(self, run)
        if run.rig is None or run.track is None:
            raise InputError(f"--{self.name} needs a run with an activation track (speak, say, batch or simulate)",
                             self.path)
        given = self.settings.get(self.rig_setting)
        client = load_client_rig(given) if given else reference_rig()
        names, M, missing = client.arkit_map()
        if given and missing:
            warnings.warn(f"{given}: the rig has no shape for {len(missing)} of ARKit's 52 "
                          f"({', '.join(missing[:8])}{' ...' if len(missing) > 8 else ''}); written as 0",
                          stacklevel=2)
        W, self.residuals = client.track_weights(run.rig.track_matrix(run.track), run.rig.path)
        extra = client.extra_shapes() if given else []
        self.names = list(names) + [client.shapes.names[j] for j in extra]
        self.values = np.hstack([W @ M.T, W[:, extra]])
        self.client = client
        self.times, self.rows = [], []

    def write(self, frame) -> None:
        self.times.append(frame.time)
        self.rows.append(min(frame.index, len(self.values) - 1))

    def weight_matrix(self) -> np.ndarray:
        return self.values[self.rows].reshape(len(self.rows), len(self.names))

    def close(self) -> None:
        write_weights(self.tmp[0], self.vocabulary, self.names, self.times, self.weight_matrix(), self.run.fps,
                      force=True)


_RIG_HELP = ("the character's blendshape rig the ARKit weights are fitted onto: a .glb/.gltf with morph targets "
             "or a folder of OBJ shapes with a *neutral*.obj, with a <name>.landmarks.json beside it (a mesh in "
             "the ICT Face Model's topology needs none); default: the ICT Face Model's 53 shapes")


@register
class ArkitSink(RigFitSink):
    """ARKit's 52 blendshape weights per frame (camelCase names), with ARKit's meaning (:class:`RigFitSink`)."""

    name = "arkit"
    metavar = "FILE.csv|.json"
    help = ("also write ARKit's 52 blendshape weights per frame (CSV or JSON by the suffix), fitted on an ARKit "
            "rig (--arkit-rig)")
    rig_setting = "arkit_rig"
    arguments = ((("--arkit-rig",), dict(dest="arkit_rig", metavar="RIG", type=Path, help=_RIG_HELP)),)


@register
class LiveLinkSink(RigFitSink):
    """ARKit weights in Live Link Face's CSV layout (Unreal's Live Link Face app, MetaHumans)."""

    name = "livelink"
    metavar = "FILE.csv"
    help = ("also write ARKit weights as a Live Link Face CSV (Timecode, BlendShapeCount, EyeBlinkLeft, ...), "
            "fitted on an ARKit rig (--livelink-rig)")
    suffixes = (".csv",)
    rig_setting = "livelink_rig"
    arguments = ((("--livelink-rig",), dict(dest="livelink_rig", metavar="RIG", type=Path, help=_RIG_HELP)),)

    def close(self) -> None:
        from visemeface.retarget.rigs import arkit_names

        names = arkit_names()
        write_live_link(self.tmp[0], names, self.times, self.weight_matrix()[:, : len(names)], self.run.fps,
                        force=True, head=self.run.extra.get("head"))


@register
class VrmSink(FitSink):
    """VRM 1.0 preset expressions per frame (aa ih ou ee oh, blink, happy angry sad relaxed surprised)."""

    name = "vrm"
    vocabulary = "vrm"
    metavar = "FILE.csv|.json"
    help = "also write VRM expression weights per frame (aa ih ou ee oh, blink, happy, ...; CSV or JSON)"

    fits_gestures = False


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
