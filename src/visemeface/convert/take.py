"""A take read from another tool, and the run that writes it again in any output.

A :class:`Take` is one of

- ``phones``: mouth cues read as timed DECtalk phones (an :class:`~visemeface.speech.utterance.Utterance`,
  with words where the file had them). Each Rhubarb shape stands for the first DECtalk phone of
  ``data/retarget/phoneme_classes.csv`` with that shape (A /m/, B /iy/, C /ey/, D /aa/, E /ao/, F /ow/,
  G /f/, H /l/, X silence), so the run is the ordinary animation of those phones (:func:`visemeface.animate.animate`)
  and a cue output gives back the same shapes at the same times;
- ``weights``: per-frame weights in a vocabulary (ARKit, VRM, Oculus), re-sampled linearly at the output's
  frame rate. VRM and Oculus weights (and a glb's ARKit weights, fitted onto our recipe shapes) are played
  on the rig as a blend-shape client plays them (:math:`\\sum_k w_k S_k`, the shapes of
  ``data/retarget/*.csv``), the activations for a track output being the recipes' sums; ARKit weights keep
  ARKit's meaning: each frame's muscles are fitted on the reference ARKit rig
  (:func:`visemeface.retarget.played.arkit_activations`) and posed;
- ``track``: the rig's activations (a track CSV, a muscle glb), re-sampled and posed.

A weights or track take has no phones: the cue outputs (Rhubarb, Oculus classes) get them from its frames,
each fitted onto the Oculus visemes (:class:`~visemeface.retarget.ShapeFit`) and read as the first phone
of its strongest class, PP (/p b m/) only where the lips touch (a mixture of shapes fitted to a face moved
otherwise, as an ARKit take played with ARKit's meaning, can weigh the lips' press more than the jaw's
opening); runs of one phone are one segment, so cue times lie on the frames.
"""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass, field

import numpy as np
import pandas as pd

from visemeface.errors import InputError
from visemeface.motion import Frame, Motion, digest


@dataclass
class Take:
    """A take (module docstring): ``kind`` phones, weights or track; ``end`` (s); ``source`` its path."""

    kind: str
    end: float
    source: str
    format: str
    fps: float | None = None
    utterance: object = None
    vocabulary: str = ""
    names: list = field(default_factory=list)
    times: np.ndarray | None = None
    weights: np.ndarray | None = None
    track: pd.DataFrame | None = None
    #: ``"recipes"``: the weights were fitted onto our face's recipe shapes (a glb that carries them), not
    #: made to the vocabulary's own definition (an ARKit take means what it does on an ARKit rig)
    shapes: str = ""


def shape_phones() -> dict[str, str]:
    """Rhubarb shape -> the first DECtalk phone of ``phoneme_classes.csv`` with it."""
    from visemeface.retarget.recipes import phoneme_classes

    out: dict[str, str] = {}
    for phone, (_, shape) in phoneme_classes().items():
        out.setdefault(shape, phone)
    return out


def cue_take(cues, end: float, path, fmt: str, words=(), fps: float | None = None) -> Take:
    """A phones take of ``(start, end, shape)`` cues: contiguous from 0 (gaps silent), checked in order."""
    from visemeface.postures.phonemes import SILENCE
    from visemeface.speech.utterance import Utterance, no_words

    phones = shape_phones()
    rows, t = [], 0.0
    for a, b, s in sorted(cues, key=lambda c: c[0]):
        if a < t - 1e-9:
            raise InputError(f"mouth cues overlap at {a:g} s", path)
        if b <= a:
            continue
        if a > t + 1e-9:
            rows.append((t, a, SILENCE))
        rows.append((a, b, phones[s]))
        t = b
    end = max(float(end), t)
    if not rows or end <= 0:
        raise InputError("the take holds no mouth cue", path)
    if end > t + 1e-9:
        rows.append((t, end, SILENCE))
    seg = pd.DataFrame(rows, columns=["start", "end", "phoneme"])
    seg = seg[seg["end"] > seg["start"]].reset_index(drop=True)
    w = pd.DataFrame(list(words), columns=["start", "end", "word"]) if len(words) else no_words()
    return Take("phones", end, str(path), fmt, fps=fps, utterance=Utterance(seg, words=w, source_format=fmt))


def vocabulary_of(names) -> str:
    """The vocabulary whose shapes ``names`` are (ARKit, VRM, Oculus), or :class:`InputError`."""
    from visemeface.retarget.recipes import OCULUS, _rows

    names = list(names)
    tables = {"oculus": list(OCULUS)}
    for v in ("arkit", "vrm"):
        tables[v] = [r["name"] for r in _rows(f"{v}.csv")[1]]
    for v, known in tables.items():
        if names and set(names) <= set(known):
            return v
    unknown = next((n for n in names if not any(n in k for k in tables.values())), names[:1])
    raise InputError(f"the weights are not ARKit, VRM or Oculus shapes ({unknown!r} is none of them)")


def weights_take(path, names, times, values, fmt: str, fps: float | None = None, end: float | None = None) -> Take:
    from visemeface.track import even_step

    t = np.asarray(times, dtype=np.float64)
    w = np.asarray(values, dtype=np.float64)
    if len(t) == 0 or w.shape != (len(t), len(names)):
        raise InputError("the weights need one row of every shape a frame", path)
    if np.any(np.diff(t) <= 0):
        raise InputError("times must increase", path)
    if not np.all(np.isfinite(w)):
        raise InputError("a weight is not a finite number", path)
    try:
        vocab = vocabulary_of(names)
    except InputError as exc:
        raise InputError(exc.reason, path) from None
    step = even_step(t)
    fps = fps or (round(1.0 / step, 3) if step > 0 else None)     # times written to 6 decimals: 30.00003 is 30
    if not fps:
        raise InputError("the frames are not evenly timed: no frame rate", path)
    if end is None:
        end = float(t[-1]) + 1.0 / fps
        if abs(end * fps - round(end * fps)) < 1e-3:            # times rounded in the file: on the frame clock
            end = round(end * fps) / fps
    end = max(float(end), float(t[-1]))
    return Take("weights", end, str(path), fmt, fps=float(fps), vocabulary=vocab,
                names=list(names), times=t, weights=np.clip(w, 0.0, 1.0))


class PlayedMotion(Motion):
    """Displacements ``frame_weights @ shapes`` on the rig's face, one frame at a time."""

    label = "converting"

    def __init__(self, face, shapes: np.ndarray, weights: np.ndarray, fps: float):
        self.face, self.shapes, self.weights, self.fps = face, shapes, weights, float(fps)
        self.n_frames = len(weights)
        self.rest = np.asarray(face.vertices, dtype=np.float64)

    def frame(self, index: int) -> Frame:
        d = np.tensordot(self.weights[index], self.shapes, axes=1)
        return Frame(index, index / self.fps, (self.rest + d).astype(np.float32))

    def frames(self, start: int = 0, state: dict | None = None) -> Iterator[Frame]:
        for i in range(start, self.n_frames):
            yield self.frame(i)

    def key(self) -> str:
        return digest(np.asarray(self.weights), self.fps, self.n_frames)


def resample(times, values: np.ndarray, fps: float, end: float) -> tuple[np.ndarray, np.ndarray]:
    """Frame times of ``[0, end)`` at ``fps`` and ``values`` (F, K) interpolated linearly there."""
    from visemeface.track import frame_count, frame_times

    at = frame_times(frame_count(end, fps), fps)
    v = np.asarray(values, np.float64)
    return at, np.column_stack([np.interp(at, times, v[:, k]) for k in range(v.shape[1])])


def phones_of_frames(rig, displacements, fps: float, oculus_weights=None):
    """An utterance of the frames' Oculus classes (module docstring)."""
    from visemeface.retarget import OCULUS, ShapeFit, moving_vertices, vocabulary
    from visemeface.retarget.recipes import phoneme_classes
    from visemeface.speech.utterance import Utterance

    if oculus_weights is None:
        from visemeface.muscles.measure import inner_opening

        fit = ShapeFit(vocabulary("oculus", rig), moving_vertices(rig))
        rest = rig.face.vertices
        rows = []
        for d in displacements:
            w = fit.frame(d)[0]
            if inner_opening(rig.face, rest + d)["height"] > 0:
                w[OCULUS.index("PP")] = 0.0         # a bilabial shuts the lips: an open frame is not one
            rows.append(w)
        oculus_weights = np.array(rows)
    first: dict[str, str] = {}
    for phone, (cls, _) in phoneme_classes().items():
        first.setdefault(cls, phone)
    phones = [first[OCULUS[int(k)]] for k in np.argmax(oculus_weights, axis=1)]
    rows = []
    for i, p in enumerate(phones):
        if rows and rows[-1][2] == p:
            rows[-1][1] = (i + 1) / fps
        else:
            rows.append([i / fps, (i + 1) / fps, p])
    return Utterance(pd.DataFrame(rows, columns=["start", "end", "phoneme"]), source_format="frames")
