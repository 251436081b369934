r"""Blinks: a natural, irregular, deterministic blink schedule added to an activation track.

People blink about 15–20 times a minute while speaking (Bentivoglio et al. 1997:
26/min in conversation, 17/min at rest; 15–20/min is the usual figure), each blink
lasting 100–300 ms with a quick closing and a slower opening, and they blink
preferably at word and phrase boundaries rather than mid-word.

Schedule
--------
Inter-blink intervals are drawn from a gamma distribution (shape 4, mean
:data:`MEAN_INTERVAL` = 3.5 s, about 17 a minute), never shorter than
:data:`MIN_GAP` between one blink's end and the next one's start; each blink
lasts :math:`U(0.15, 0.28)` s. With word timings, a blink that would start
mid-word moves to the nearest word boundary within :data:`SNAP` s. The same
``seed`` gives the same blinks.

Shape
-----
With :math:`s = (t - t_0)/L`, the closing takes the first 35% of the blink
(cosine ease to 1), the lid stays shut for 10%, and opens over the remaining 55%:
``upper_lid_close`` follows it, ``lower_lid_raise`` rises to 0.4 of it (the lids
meet a little below the pupil, as in ``data/rig/default.toml``), and an upper-lid
raise (AU5, surprise) gives way while the eye is shut.
"""

from __future__ import annotations

import numpy as np
import pandas as pd

from visemeface.numeric import cosine_step

MEAN_INTERVAL = 3.5
MIN_GAP = 1.0
SNAP = 0.4
DURATION = (0.15, 0.28)
SIDES = ("left", "right")


def blink_schedule(duration: float, seed: int = 0, words=None) -> list[tuple[float, float]]:
    """(start, length) of every blink in ``[0, duration]`` s, sorted, deterministic for ``seed``.

    ``words``: optional (start, end) times of the words; blinks starting mid-word move to the
    nearest word boundary within :data:`SNAP` s when the gaps allow.
    """
    rng = np.random.default_rng(seed)
    bounds = None
    if words is not None and len(words):
        w = np.asarray(words, dtype=float).reshape(-1, 2)
        bounds = np.unique(w.ravel())
        inside = w
    out: list[tuple[float, float]] = []
    t = float(rng.uniform(0.3, 2.0))
    while True:
        length = float(rng.uniform(*DURATION))
        start = t
        if bounds is not None and ((inside[:, 0] < start) & (start < inside[:, 1])).any():
            near = bounds[np.argmin(np.abs(bounds - start))]
            if abs(near - start) <= SNAP:
                start = float(near)
        if out and start < out[-1][0] + out[-1][1] + MIN_GAP:
            start = out[-1][0] + out[-1][1] + MIN_GAP
        if start + length > duration:
            break
        out.append((start, length))
        t = start + length + max(MIN_GAP, float(rng.gamma(4.0, MEAN_INTERVAL / 4.0)) - length)
    return out


def blink_curve(times: np.ndarray, schedule) -> np.ndarray:
    """Lid closure 0..1 at ``times`` for a :func:`blink_schedule`."""
    times = np.asarray(times, dtype=float)
    out = np.zeros(len(times))
    for start, length in schedule:
        s = (times - start) / length
        on = (s >= 0) & (s <= 1)
        if not on.any():
            continue
        x = s[on]
        closing = cosine_step(x / 0.35)
        opening = 1.0 - cosine_step((x - 0.45) / 0.55)
        out[on] = np.maximum(out[on], np.where(x < 0.45, closing, opening))
    return out


def add_blinks(track: pd.DataFrame, names, schedule) -> pd.DataFrame:
    """A copy of ``track`` with blinks on the lid functions ``names`` has (others left alone).

    The closure :math:`b` adds as :math:`a + b(1 - a)` to ``upper_lid_close`` (reaching 1
    from any emotion's lid posture), as :math:`0.4 b` likewise to ``lower_lid_raise``, and
    scales ``upper_lid_raise`` by :math:`1 - b`. The sample at frame ``k`` is taken at the
    frame's middle, :math:`(k + \\tfrac12)/\\mathrm{fps}`, so a 100 ms blink shows at 30 fps.
    """
    out = track.copy()
    fps = float(track.attrs.get("fps", 30.0))
    b = blink_curve(np.asarray(track.index, dtype=float) + 0.5 / fps, schedule)
    for side in SIDES:
        for name, gain in ((f"upper_lid_close_{side}", 1.0), (f"lower_lid_raise_{side}", 0.4)):
            if name in names:
                a = out[name].to_numpy(dtype=float) if name in out else np.zeros(len(out))
                out[name] = a + gain * b * (1.0 - a)
        raise_ = f"upper_lid_raise_{side}"
        if raise_ in out:
            out[raise_] = out[raise_].to_numpy(dtype=float) * (1.0 - b)
    out.attrs = dict(track.attrs)
    return out


def blink_utterance(track: pd.DataFrame, rig, utterance=None, seed: int = 0) -> pd.DataFrame:
    """:func:`add_blinks` over the track's span, snapping to ``utterance``'s words when it has them."""
    fps = float(track.attrs.get("fps", 30.0))
    duration = len(track) / fps
    words = None
    if utterance is not None and getattr(utterance, "words", None) is not None and len(utterance.words):
        words = utterance.words[["start", "end"]].to_numpy(dtype=float)
    return add_blinks(track, rig.names, blink_schedule(duration, seed=seed, words=words))
