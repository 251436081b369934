"""``visemeface convert``: a take from one tool's format written in another's.

:func:`~visemeface.convert.readers.read_take` reads a file into a :class:`~visemeface.convert.take.Take`;
:func:`write_take` runs it into any sink of :data:`visemeface.export.SINKS` through the one streaming loop
(:func:`visemeface.pipeline.run`), so every output the animating commands write is written the same way.
"""

from __future__ import annotations

import numpy as np

from visemeface.convert.readers import read_take
from visemeface.convert.take import Take

__all__ = ["Take", "read_take", "write_take"]


def _sided_halves(vocab) -> np.ndarray:
    """1 for a whole shape, 0.5 for a sided one (its recipe is the whole function's; its shape half of it)."""
    from visemeface.retarget.recipes import _rows

    if vocab.name == "oculus":
        return np.ones(len(vocab.names))
    side = {r["name"]: (r.get("side") or "").strip() for r in _rows(f"{vocab.name}.csv")[1]}
    return np.array([0.5 if side.get(n) else 1.0 for n in vocab.names])


def _pass_through(sink, vocabulary: str, weights: np.ndarray) -> None:
    """Let a weights sink of the take's own vocabulary take the weights as they are: fitting the played
    shapes again would move weight between near-twins (mouthPressLeft/Right and the whole presser,
    mouthFunnel and mouthPucker), so ARKit in, ARKit (Live Link, Audio2Face, Unity, ...) out keeps them."""
    from visemeface.export.retarget import FitSink, RigFitSink

    if isinstance(sink, RigFitSink):
        if vocabulary != "arkit":
            return
        opened = sink.open

        def open_(run):                 # ARKit in, ARKit out: the take's weights, not the ICT rig's fit
            opened(run)
            sink.values = np.hstack([weights, np.zeros((len(weights), len(sink.names) - weights.shape[1]))])

        def write_rows(frame):
            sink.times.append(frame.time)
            sink.rows.append(frame.index)

        sink.open, sink.write = open_, write_rows
        return
    if not isinstance(sink, FitSink) or sink.vocabulary != vocabulary:
        return

    def write(frame):
        sink.times.append(frame.time)
        sink.weights.append(weights[frame.index])
        sink.residuals.append(0.0)

    sink.write = write


def _weights_run(take: Take, rig, fps: float):
    from visemeface.convert.take import PlayedMotion, phones_of_frames, resample
    from visemeface.retarget import vocabulary
    from visemeface.retarget.played import arkit_activations
    from visemeface.retarget.rigs import arkit_names
    from visemeface.track import make_track

    at, w = resample(take.times, take.weights, fps, take.end)
    # ARKit weights mean what they do on an ARKit rig: played through our muscles fitted on the reference
    # rig's shapes (a glb's ARKit weights were fitted onto our recipe shapes, its targets: played on those)
    if take.vocabulary == "arkit" and take.shapes != "recipes":
        full = _columns(w, take.names, arkit_names())
        played = arkit_activations(rig, arkit_names(), full)
        if played is not None:
            return (*_posed_run(rig, at, played[0], list(rig.names), fps), full)
    vocab = vocabulary(take.vocabulary, rig)
    full = _columns(w, take.names, vocab.names)
    motion = PlayedMotion(rig.face, vocab.shapes, full, fps)
    lo, hi = np.asarray(rig.ranges, np.float64).T
    acts = np.clip(full @ (vocab.activations * _sided_halves(vocab)[:, None]), lo, hi)   # recipes are clamped too
    track = make_track(at, acts, list(rig.names), fps)
    oculus = full if take.vocabulary == "oculus" else None
    rest = motion.rest
    utt = phones_of_frames(rig, (motion.frame(i).vertices - rest for i in range(len(at))) if oculus is None else (),
                           fps, oculus)
    return motion, track, utt, full


def _columns(w: np.ndarray, names, order) -> np.ndarray:
    """Weights (F, len(names)) as (F, len(order)) columns in ``order``, clamped to 0..1 (absent shapes 0)."""
    full = np.zeros((len(w), len(order)))
    full[:, [list(order).index(n) for n in names]] = np.clip(w, 0.0, 1.0)
    return full


def _posed_run(rig, times, values, names, fps: float):
    """``(motion, track, utterance)`` of activations (F, len(names)) at ``times`` posed on ``rig``."""
    from visemeface.convert.take import phones_of_frames
    from visemeface.motion import KinematicMotion
    from visemeface.track import make_track

    track = make_track(times, values, names, fps)
    motion = KinematicMotion(rig, track)
    return motion, track, phones_of_frames(rig, (rig.displacement(a) for a in motion.activations), fps)


def _track_run(take: Take, rig, fps: float):
    from visemeface.convert.take import resample

    src = take.track
    at, v = resample(src.index.to_numpy(np.float64), src.to_numpy(np.float64), fps, take.end)
    return (*_posed_run(rig, at, v, list(src.columns), fps), None)


def write_take(take: Take, sink, rig=None, fps: float | None = None, interp: str | None = None,
               show_progress: bool = False):
    """Write ``take`` into ``sink`` (checked, not yet opened) at ``fps`` (default: the take's, else 30);
    returns the run's :class:`~visemeface.pipeline.RunStats`. ``interp`` is the interpolation between the
    phones of a cue take."""
    from visemeface import pipeline
    from visemeface.animate import animate
    from visemeface.muscles.rig import default_rig
    from visemeface.speech.timeline import MODES

    rig = rig if rig is not None else default_rig()
    fps = float(fps or take.fps or 30.0)
    if take.kind == "phones":
        return animate(take.utterance, [sink], rig=rig, fps=fps, interp=interp, blink=False, source=take.source,
                       show_progress=show_progress)
    motion, track, utt, weights = (_weights_run if take.kind == "weights" else _track_run)(take, rig, fps)
    if weights is not None:
        _pass_through(sink, take.vocabulary, weights)
    return pipeline.run(motion, [sink], info=dict(rig=rig, track=track, end_time=take.end,
                                                  extra={"motion_key": motion.key(), "utterance": utt,
                                                         "interp": MODES[0], "source": take.source}),
                        show_progress=show_progress)
