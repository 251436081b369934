"""Phones so far -> the mouth's frames, each as soon as its look-ahead has been heard.

Frame ``k`` (time :math:`t_k = k / \\mathrm{fps}`) is made once the stream has reached
:math:`t_k + L`, with :math:`L` the ``latency``: the phones decoded by then (the decoder's frontier
trails the audio by about 50 ms, :mod:`visemeface.live.phones`) are turned into the activation
track exactly as offline (:func:`visemeface.speech.timeline.activation_track`: the same dominance
coarticulation and closures of /p b m f v/, the same /n/ -> /m/ assimilation before a bilabial), over
a window from :data:`WINDOW_S` before the frame to the frontier, the newest phone held to the frame if
the frontier has not reached it. The posed face is then retargeted as offline
(:class:`visemeface.retarget.ShapeFit` onto the vocabulary; ARKit's on the reference ARKit rig as ``--arkit``
does, :class:`visemeface.retarget.rigs.ClientRig`), so a frame differs from the offline run's
only where the phones decoded by then differ from the finished decode's, or where the phones after
:math:`t_k + L` would have been anticipated.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from visemeface.speech.timeline import MODES, activation_track
from visemeface.track import check_fps, frame_count, frame_of

#: Seconds of phones before a frame that its window holds. The dominance of a segment 0.5 s away is
#: below 1e-3 of the nearest's (dominance.csv's slowest decay); the window's first segment is cut at its
#: start, which moves its centre, so it starts well before that.
WINDOW_S = 1.0


@dataclass
class LiveFrame:
    """One frame of the live mouth: ``index``, ``time`` (s from the stream's start), ``weights`` (vocabulary
    name -> its weights, in its order; None for a frame skipped to catch up), ``activations`` (the rig's, in its names' order), ``phone`` (the DECtalk
    phone under the frame), ``level`` (dB re full scale of the audio block it was made after)."""

    index: int
    time: float
    weights: dict | None
    activations: np.ndarray
    phone: str
    level: float = -120.0


class LiveMouth:
    """Frames from a growing list of phones (see the module docstring).

    Parameters
    ----------
    rig : MuscleRig
    vocabularies : sequence of str
        Those fitted each frame: ``"arkit"``, ``"vrm"`` (:func:`visemeface.retarget.vocabulary`).
    fps : float
    latency : float
        :math:`L` (s), from a frame's time to when it is made.
    interp : str
        The timeline's interpolation (default: coarticulation).
    emotions : mapping, optional
        ``{name: weight}`` blended over the whole stream, as ``--emotion`` offline.
    """

    def __init__(self, rig, vocabularies=("arkit",), fps: float = 30.0, latency: float = 0.1,
                 interp: str = MODES[0], emotions=None):
        from visemeface.postures.library import load_visemes
        from visemeface.retarget import ShapeFit, moving_vertices
        from visemeface.retarget import vocabulary as make_vocabulary

        self.rig = rig
        self.fps = check_fps(fps)
        self.latency = float(latency)
        self.interp = interp
        self.emotions = emotions or None
        self.visemes = load_visemes(rig=rig)
        self.ranges = {n: tuple(r) for n, r in zip(rig.names, rig.ranges)}
        mask = moving_vertices(rig)
        self.vocabs = {name: make_vocabulary(name, rig) for name in dict.fromkeys(vocabularies)}
        self.fits = {name: ShapeFit(v, mask) for name, v in self.vocabs.items() if name != "arkit"}
        if "arkit" in self.vocabs:      # ARKit's meaning: the offline --arkit's fit on the reference ARKit rig
            from visemeface.retarget.rigs import reference_rig

            self.arkit_rig = reference_rig()
            self.arkit_map = self.arkit_rig.arkit_map()[1]
            self.arkit_rig.track_weights(np.zeros((1, len(rig.names))), rig.path)      # factor it now
        self.rest = np.asarray(rig.face.vertices, dtype=np.float64)
        self.next = 0

    def driven(self, vocabulary: str = "arkit") -> np.ndarray:
        """(K,) bool: the shapes of the vocabulary this mouth can move, those the rig makes whose recipe shares a
        rig function with the viseme table or the emotions given (the others, eyelids without blinks,
        are always 0: a client is not sent them, so they never override its own tracking)."""
        from visemeface.postures.library import load_expressions

        used = self.visemes.select_dtypes(include="number").abs().sum() > 0
        columns = set(used.index[used])
        if self.emotions:
            expr = load_expressions(rig=self.rig).select_dtypes(include="number").loc[list(self.emotions)]
            columns |= set(expr.columns[(expr.abs() > 0).any()])
        touched = np.array([n in columns for n in self.rig.names])
        vocab = self.vocabs[vocabulary]
        acts = np.asarray(vocab.activations)
        out = np.asarray(vocab.made, bool) & (np.abs(acts[:, touched]) > 0).any(axis=1)
        if vocabulary == "arkit" and "jawOpen" in vocab.names:     # the corrective goes with the jaw it closes
            out[vocab.names.index("mouthClose")] = out[vocab.names.index("jawOpen")]
        return out

    def names(self, vocabulary: str = "arkit") -> list[str]:
        return list(self.vocabs[vocabulary].names)

    def last_due(self, audio_s: float, final: bool = False) -> int:
        """The newest frame due once the stream has reached ``audio_s`` (every frame it covers if ``final``)."""
        if final:                                        # the offline run's frames: ceil(T · fps)
            return frame_count(audio_s, self.fps) - 1
        return frame_of(audio_s - self.latency, self.fps)

    def due(self, audio_s: float) -> bool:
        """Whether a frame is due once the stream has reached ``audio_s``."""
        return self.last_due(audio_s) >= self.next

    def advance(self, phones, frontier: float, audio_s: float, final: bool = False, level: float = -120.0,
                newest_only: bool = False):
        """The frames due at ``audio_s`` not made yet.

        ``phones``: ``(ARPAbet or silence label, start, end)`` from the stream's start, at least those
        ending after :data:`WINDOW_S` before the next frame; ``frontier``: where they end (s).
        ``newest_only``: retarget only the newest frame (catching up: the others keep their activations
        and phone, their ``weights`` are None).
        """
        from visemeface.speech.align import _segments

        last = self.last_due(audio_s, final)
        if last < self.next:
            return []
        ks = np.arange(self.next, last + 1)
        k0 = max(0, int(ks[0]) - int(np.ceil(WINDOW_S * self.fps)))
        w0 = k0 / self.fps
        end = max(float(frontier), (ks[-1] + 1) / self.fps) - w0
        timed = [(lab, max(s - w0, 0.0), e - w0) for lab, s, e in phones if e > w0 + 1e-9 and s - w0 < end]
        if not timed:
            timed = [("SIL", 0.0, end)]
        lab, s, _ = timed[-1]
        timed[-1] = (lab, s, end)                        # the newest phone held to the frames due
        if timed[0][1] > 0:
            timed.insert(0, ("SIL", 0.0, timed[0][1]))
        seg = _segments(timed, end, "the live stream")
        track = activation_track(seg, self.visemes, fps=self.fps, mode=self.interp, emotions=self.emotions,
                                 ranges=self.ranges)
        A = self.rig.track_matrix(track)
        starts = seg["start"].to_numpy(float)
        symbols = seg["phoneme"].tolist()
        out = []
        for k in ks:
            j = min(int(k) - k0, len(A) - 1)
            a = A[j]
            w = None
            if not newest_only or k == ks[-1]:
                d = np.asarray(self.rig.pose(a), dtype=np.float64) - self.rest
                w = {name: fit.frame(d)[0] for name, fit in self.fits.items()}
                if "arkit" in self.vocabs:
                    W, _ = self.arkit_rig.track_weights(a[None], self.rig.path)
                    w["arkit"] = (W @ self.arkit_map.T)[0]
            phone = symbols[max(0, int(np.searchsorted(starts, j / self.fps + 1e-9, side="right")) - 1)]
            out.append(LiveFrame(int(k), k / self.fps, w, a, phone, level))
        self.next = last + 1
        return out
