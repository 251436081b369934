"""Segments + viseme table + emotions -> ActivationTrack (muscle activations per frame).

ActivationTrack
---------------
A pandas DataFrame, index ``time`` (seconds, frame ``k`` at ``k / fps``),
one column per rig function (the viseme table's numeric columns, in order),
``attrs["fps"]`` the frame rate. ``ceil(T * fps)`` frames cover an utterance
of ``T`` seconds.

Interpolation (``mode=``)
-------------------------
Each segment :math:`s` (start :math:`a_s`, end :math:`b_s`, centre
:math:`c_s`) has the target :math:`T_s`, its phoneme's row of the viseme table.
A segment longer than :math:`2e` (``edge``, 60 ms) *holds* its target over its
middle :math:`[a_s + e, b_s - e]` (exactly in the keyed modes; in coarticulation
up to the neighbours' exponentially decaying dominance); a shorter one has a single key at its centre.
Let :math:`d_s(t)` be the distance from :math:`t` to that held middle (to the
centre for a short segment).

``"linear"`` / ``"cosine"``
    Piecewise interpolation between the keys (linear, or eased with
    :math:`(1 - \\cos \\pi u) / 2`); a segment's influence starts at the
    previous key.
``"coarticulation"`` (default; Cohen & Massaro 1993)
    Every segment has a dominance function
    :math:`D_s(t) = \\alpha_s \\exp(-\\theta_s^{\\pm} d_s(t)^{c_s})`, with
    :math:`\\theta^-` before the centre (anticipation) and :math:`\\theta^+`
    after it (carry-over), from ``data/phonemes/dominance.csv``, and

    .. math:: v(t) = \\frac{\\sum_s D_s(t) T_s}{\\sum_s D_s(t)} .

    Rounded vowels anticipate their rounding over the consonants before them;
    short lingual consonants hardly show.

Lip closure and contact are guaranteed
--------------------------------------
In every mode, for each bilabial (``p b m``) and labiodental (``f v``)
segment the speech track is pulled to the segment's target:
:math:`v \\leftarrow (1 - w_s) v + w_s T_s` with :math:`w_s = 1` within
:math:`h_s = \\max(\\text{held half-width}, \\tfrac{b_s - a_s}{4}, \\tfrac{1}{2\\,\\mathrm{fps}})`
of the centre and a cosine fall to 0 over the next :math:`\\max(\\tfrac{b_s-a_s}{2},
1/\\mathrm{fps})` (between adjacent p b m f v the targets cross-fade around the shared
boundary instead, so a cluster such as /b m/ stays closed). The window :math:`[c_s - h_s, c_s + h_s]`
is at least one frame interval wide, so at least one frame shows the exact target --
the lips close on every /p b m/ however fast the speech.

Emotions
--------
``emotions`` is a mapping ``{name: weight}`` (global, from t = 0), a key track
(DataFrame ``time``, ``emotion``, ``weight``, or a sequence of such triples; see
:mod:`visemeface.speech.g2p`; ``neutral`` sets every emotion to 0), or None; a
key track of an :class:`~visemeface.speech.utterance.Utterance` passed as ``segments`` is applied too. A weight changes by a cosine
ramp of ``emotion_ramp`` seconds centred on its key. Each frame is then
(Edge & Maddock 2001, §2.2.1)

.. math:: a(t) = v(t) + \\sum_e w_e(t)\\, E_e ,

except that on the lip-opening functions (:data:`LIP_OPENING`: jaw, depressor
labii inferioris, levator labii superioris) the emotion term is scaled by
:math:`1 - \\max_s w_s(t)` for the forced p b m f v segments, so a surprised
/b/ still closes; the result is clamped to ``ranges`` (default: each column to
:math:`[\\min(0, \\text{table min}), \\max(1, \\text{table max})]`).
"""

from __future__ import annotations

import csv
import math
from collections.abc import Mapping
from functools import lru_cache

import numpy as np
import pandas as pd

from visemeface.errors import InputError, choose, close_matches
from visemeface.numeric import cosine_step
from visemeface.postures.phonemes import CLOSURE, DECTALK, LABIODENTAL
from visemeface.resources import data_path
from visemeface.track import check_fps, frame_count, frame_times, load_track, make_track, save_track

__all__ = ["MODES", "activation_track", "dominance_table", "emotion_weights", "load_track",
           "save_track", "speech_track"]

MODES = ("coarticulation", "linear", "cosine")
#: Phonemes whose target is forced at their centre (lip closure / lip-teeth contact).
FORCED = frozenset(CLOSURE) | frozenset(LABIODENTAL)
#: Rig functions that open the lips (Edge & Maddock 2001, Table 1: jaw rotation, depressor labii lowers the
#: bottom lip, levator labii superioris raises the upper one): an emotion does not move them
#: while a p b m f v target is forced, so closure and contact survive e.g. surprise's jaw drop.
LIP_OPENING = ("jaw", "depressor_labii_inferioris", "levator_labii_superioris")
_LIP_OPENING_COLUMNS = frozenset(["jaw"] + [f"{m}_{s}" for m in LIP_OPENING[1:] for s in ("left", "right")])


@lru_cache(maxsize=1)
def dominance_table() -> pd.DataFrame:
    """Dominance parameters: index DECtalk symbol, columns alpha, theta_before, theta_after, c."""
    path = data_path("phonemes", "dominance.csv")
    with open(path, encoding="utf-8", newline="") as f:
        rows = list(csv.DictReader(line for line in f if not line.lstrip().startswith("#")))
    table = pd.DataFrame({k: [float(r[k]) for r in rows] for k in ("alpha", "theta_before", "theta_after", "c")},
                         index=pd.Index([r["symbol"] for r in rows], name="symbol"))
    assert set(DECTALK) <= set(table.index), f"{path} lacks {sorted(set(DECTALK) - set(table.index))}"
    assert (table.to_numpy() > 0).all(), f"{path}: parameters must be positive"
    return table


@lru_cache(maxsize=1)
def _dominance_rows() -> dict[str, np.ndarray]:
    """Symbol -> (alpha, theta_before, theta_after, c): the table as plain rows (four pandas look-ups per
    call cost more than the whole coarticulation of a short window, which ``live`` makes 30 times a second)."""
    dom = dominance_table()
    return dict(zip(dom.index, dom[["alpha", "theta_before", "theta_after", "c"]].to_numpy(dtype=float)))


# ----------------------------------------------------------------------------- checks

def check_segments(segments: pd.DataFrame, what: str = "animate") -> tuple[np.ndarray, np.ndarray, list[str]]:
    """(start, end, phones) of timed segments, refused (InputError) unless they have the columns, at least one
    row (there is nothing to ``what`` otherwise), and finite, non-negative, sorted, non-overlapping times."""
    for col in ("start", "end", "phoneme"):
        if col not in segments.columns:
            raise InputError(f"segments lack the column {col!r}")
    start = segments["start"].to_numpy(dtype=float)
    end = segments["end"].to_numpy(dtype=float)
    phones = [str(p) for p in segments["phoneme"]]
    if len(phones) == 0:
        raise InputError(f"no segments to {what}")
    if not (np.isfinite(start).all() and np.isfinite(end).all()):
        raise InputError("segment times must be finite")
    if (start < 0).any() or (end <= start).any() or (start[1:] < end[:-1] - 1e-9).any():
        raise InputError("segments must be non-negative, of positive length, sorted and non-overlapping")
    return start, end, phones


def _viseme_matrix(visemes: pd.DataFrame, phones: list[str]) -> tuple[np.ndarray, list[str]]:
    table = visemes.select_dtypes(include="number")
    if table.shape[1] == 0:
        raise InputError("the viseme table has no numeric columns")
    index = [str(i) for i in table.index]
    missing = sorted(set(phones) - set(index))
    if missing:
        raise InputError(f"the viseme table has no row for phoneme(s) {', '.join(missing)}"
                         f"{close_matches(missing[0], index)}")
    rows = table.to_numpy(dtype=float)
    if not np.isfinite(rows).all():
        raise InputError("the viseme table holds a non-finite value")
    pos = {s: i for i, s in enumerate(index)}
    return rows[[pos[p] for p in phones]], [str(c) for c in table.columns]


# ----------------------------------------------------------------------------- speech

def _held_half_width(start, end, edge):
    return np.maximum(0.0, (end - start) / 2 - edge)


def _coarticulation(times, start, end, phones, targets, edge, chunk=2048):
    rows = _dominance_rows()
    alpha, th_b, th_a, cexp = np.array([rows[p] for p in phones], dtype=float).reshape(-1, 4).T
    centre = (start + end) / 2
    half = _held_half_width(start, end, edge)
    # Segments farther than `reach` contribute < 1e-7 of the nearest: skip them.
    reach = float(np.max((16.0 / np.minimum(th_b, th_a)) ** (1.0 / cexp)) + np.max(half))
    out = np.empty((times.size, targets.shape[1]))
    for lo in range(0, times.size, chunk):
        t = times[lo:lo + chunk]
        i0 = int(np.searchsorted(end, t[0] - reach))
        i1 = int(np.searchsorted(start, t[-1] + reach, side="right"))
        i1 = max(i1, i0 + 1)
        rel = t[:, None] - centre[None, i0:i1]                       # (F, S)
        dist = np.maximum(np.abs(rel) - half[None, i0:i1], 0.0)
        theta = np.where(rel < 0, th_b[None, i0:i1], th_a[None, i0:i1])
        # Work in logs relative to the row maximum so far-away segments cannot underflow all to 0.
        logd = np.log(alpha[None, i0:i1]) - theta * dist ** cexp[None, i0:i1]
        logd -= logd.max(axis=1, keepdims=True)
        d = np.exp(logd)
        out[lo:lo + chunk] = (d @ targets[i0:i1]) / d.sum(axis=1, keepdims=True)
    return out


def _keyed(times, start, end, targets, edge, ease):
    centre = (start + end) / 2
    half = _held_half_width(start, end, edge)
    key_t = np.ravel(np.column_stack([centre - half, centre + half]))
    key_v = np.repeat(targets, 2, axis=0)
    out = np.empty((times.size, targets.shape[1]))
    j = np.clip(np.searchsorted(key_t, times, side="right") - 1, 0, key_t.size - 2)
    t0, t1 = key_t[j], key_t[j + 1]
    span = np.where(t1 > t0, t1 - t0, 1.0)
    u = np.clip((times - t0) / span, 0.0, 1.0)
    u = np.where(t1 > t0, u, 1.0)
    if ease:
        u = cosine_step(u)
    out[:] = key_v[j] * (1 - u)[:, None] + key_v[j + 1] * u[:, None]
    return out


def _force_contacts(values, times, start, end, phones, targets, fps, edge):
    """Pull the track to the target of every p b m f v segment around its centre (see module doc).

    Returns the new values and, per frame, the largest forcing weight (1 where a
    segment's exact target is shown).

    Between adjacent forced segments (``b m``, ``v b``) the first holds its target up to
    the boundary + r and the second fades in over [boundary - r, boundary + r], so the
    lips stay in contact through the cluster while moving smoothly from one target to
    the next; r is small enough that each segment keeps frames at its exact target.
    """
    frame = 1.0 / fps
    n = len(phones)
    forced = [p in FORCED for p in phones]
    strength = np.zeros(times.size)
    held_by = np.full(times.size, -1)          # the segment whose exact target a frame shows (-1: none)
    dur = end - start
    hold = np.maximum.reduce([_held_half_width(start, end, edge), dur / 4,
                              np.full(n, 0.5 * frame * (1 + 1e-9))])
    # Cross-fade half-width r[s] at the boundary between s and s+1 when both are forced.
    r = np.zeros(n)
    for s in range(n - 1):
        if forced[s] and forced[s + 1] and abs(end[s] - start[s + 1]) < 1e-9:
            r[s] = max(0.0, min(min(dur[s], dur[s + 1]) / 4, dur[s] / 2 + hold[s] - frame * (1 + 1e-9),
                                dur[s + 1] / 2 + hold[s + 1] - frame * (1 + 1e-9)))
    for s in range(n):
        if not forced[s]:
            continue
        c = (start[s] + end[s]) / 2
        ramp = max(dur[s] / 2, frame)
        prev_forced = s > 0 and forced[s - 1] and abs(end[s - 1] - start[s]) < 1e-9
        next_forced = s + 1 < n and forced[s + 1] and abs(start[s + 1] - end[s]) < 1e-9
        hold_b, ramp_b = (max(hold[s], c - start[s] - r[s - 1]), 2 * r[s - 1]) if prev_forced else (hold[s], ramp)
        hold_a, ramp_a = (end[s] - c + r[s], 0.0) if next_forced else (hold[s], ramp)
        lo = int(np.searchsorted(times, c - hold_b - ramp_b))
        hi = int(np.searchsorted(times, c + hold_a + ramp_a, side="right"))
        if hi <= lo:
            continue
        rel = times[lo:hi] - c
        before = rel < 0
        hold_t = np.where(before, hold_b, hold_a)
        ramp_t = np.where(before, ramp_b, ramp_a)
        d = np.abs(rel)
        u = np.clip((d - hold_t) / np.where(ramp_t > 0, ramp_t, 1.0), 0.0, 1.0)
        w = np.where(d <= hold_t, 1.0, np.where(ramp_t > 0, 1.0 - cosine_step(u), 0.0))
        # a frame showing another segment's exact target keeps it (a long /f/'s ramp does not reopen the
        # /p/ before it), unless that segment is the one just before, which this one cross-fades from
        held = held_by[lo:hi]
        w = np.where((held >= 0) & ~((held == s - 1) & prev_forced), 0.0, w)
        values[lo:hi] = values[lo:hi] * (1 - w)[:, None] + targets[s][None, :] * w[:, None]
        strength[lo:hi] = np.maximum(strength[lo:hi], w)
        held_by[lo:hi] = np.where(w == 1.0, s, held)
    return values, strength


def _blend(segments, fps, mode, edge, targets_of):
    """The frames' times and the per-segment targets (``targets_of(phones)`` -> (targets, columns)) blended
    along the timeline, the contacts forced: (times, values, columns, forcing strength per frame)."""
    mode = choose(mode, MODES, "interpolation mode")
    fps = check_fps(fps)
    start, end, phones = check_segments(segments)
    targets, columns = targets_of(phones)
    times = frame_times(frame_count(float(end[-1]), fps), fps)
    if mode == "coarticulation":
        values = _coarticulation(times, start, end, phones, targets, edge)
    else:
        values = _keyed(times, start, end, targets, edge, ease=(mode == "cosine"))
    values, strength = _force_contacts(values, times, start, end, phones, targets, float(fps), edge)
    return times, values, columns, strength


def _speech(segments, visemes, fps, mode, edge, jali=None):
    def targets_of(phones):
        targets, columns = _viseme_matrix(visemes, phones)
        if jali is not None:
            from visemeface.speech.articulation import articulate

            targets = articulate(targets, columns, phones, *jali)
        return targets, columns
    return _blend(segments, fps, mode, edge, targets_of)


def speech_track(segments: pd.DataFrame, visemes: pd.DataFrame, fps: float = 30.0,
                 mode: str = "coarticulation", edge: float = 0.06, jali=None) -> pd.DataFrame:
    """The viseme part of the track (no emotion, no clamping); see the module doc (``jali`` as
    :func:`activation_track`'s)."""
    times, values, columns, _ = _speech(segments, visemes, fps, mode, edge, jali)
    return make_track(times, values, columns, fps)


def class_track(segments: pd.DataFrame, classes: Mapping[str, str], names, fps: float = 30.0,
                mode: str = "coarticulation", edge: float = 0.06) -> pd.DataFrame:
    """Per-frame weights over the phone classes ``names`` (phone p's class is ``classes[p]``), blended along
    the timeline as the visemes are (the same coarticulation or keyed interpolation, and /p b m f v/ held at
    their class around their centres, as their lip contacts are): each row adds up to 1. For clients whose
    vocabulary is classes of phones (Oculus visemes)."""
    names = [str(n) for n in names]

    def onehot(phones):
        col = {n: j for j, n in enumerate(names)}
        bad = sorted({p for p in phones if classes.get(p) not in col})
        if bad:
            raise InputError(f"no class among {', '.join(names)} for phoneme(s) {', '.join(bad)}")
        out = np.zeros((len(phones), len(names)))
        out[np.arange(len(phones)), [col[classes[p]] for p in phones]] = 1.0
        return out, names
    times, values, columns, _ = _blend(segments, fps, mode, edge, onehot)
    return make_track(times, values, columns, fps)


# ----------------------------------------------------------------------------- emotions

def _keys_frame(keys) -> pd.DataFrame:
    """An emotion key track as a DataFrame (from a DataFrame or ``(time, emotion, weight)`` tuples)."""
    if keys is None:
        return pd.DataFrame({"time": [], "emotion": [], "weight": []})
    if isinstance(keys, pd.DataFrame):
        missing = [c for c in ("time", "emotion", "weight") if c not in keys.columns]
        if missing:
            raise InputError(f"emotion key track lacks column(s) {', '.join(missing)}")
        out = keys[["time", "emotion", "weight"]]
    elif isinstance(keys, (list, tuple)):
        if not all(isinstance(k, (list, tuple)) and len(k) == 3 for k in keys):
            raise InputError("emotion keys must be (time, emotion, weight) triples")
        out = pd.DataFrame({"time": [k[0] for k in keys], "emotion": [str(k[1]) for k in keys],
                            "weight": [k[2] for k in keys]})
    else:
        raise InputError(f"emotions must be a mapping name->weight or a key track, got {type(keys).__name__}")
    t = pd.to_numeric(out["time"], errors="coerce").to_numpy(dtype=float)
    bad = ~(np.isfinite(t) & (t >= 0))
    if bad.any():
        raise InputError(f"emotion key times must be finite seconds >= 0, got {out['time'].iloc[int(np.argmax(bad))]}")
    return out


def emotion_weights(times: np.ndarray, names: list[str], base: Mapping[str, float] | None = None,
                    keys: pd.DataFrame | None = None, ramp: float = 0.3) -> np.ndarray:
    """Weight of each emotion at each time: (len(times), len(names)).

    ``base`` weights hold from the start; each key ``(time, emotion, weight)``
    moves that emotion's weight to ``weight`` (``neutral``: all to 0) by a
    cosine step of width ``ramp`` centred on ``time``:

    .. math:: w_e(t) = w_e^0 + \\sum_k \\Delta_k\\, S\\!\\left(\\frac{t - \\tau_k}{r} + \\tfrac12\\right),
              \\quad S(u) = \\tfrac{1 - \\cos(\\pi\\,\\mathrm{clip}(u, 0, 1))}{2}.
    """
    col = {n: i for i, n in enumerate(names)}
    level = np.zeros(len(names))
    for name, w in (base or {}).items():
        level[col[name]] = w
    out = np.repeat(level[None, :], times.size, axis=0)
    if keys is not None and len(keys):
        order = np.argsort(keys["time"].to_numpy(dtype=float), kind="stable")
        for k in order:
            tau = float(keys["time"].iloc[k])
            name = str(keys["emotion"].iloc[k])
            w = float(keys["weight"].iloc[k])
            idx = list(range(len(names))) if name == "neutral" else [col[name]]
            target = np.zeros(len(idx)) if name == "neutral" else np.array([w])
            delta = target - level[idx]
            level[idx] = target
            if ramp > 0:
                step = cosine_step((times - tau) / ramp + 0.5)
            else:
                step = (times >= tau).astype(float)
            out[:, idx] += step[:, None] * delta[None, :]
    return out


def _check_weight(name, w):
    try:
        w = float(w)
    except (TypeError, ValueError):
        raise InputError(f"emotion weight for {name!r} is not a number: {w!r}") from None
    if not math.isfinite(w) or w < 0:
        raise InputError(f"emotion weight for {name!r} must be finite and >= 0, got {w!r}")
    return w


def _add_emotions(times, values, columns, contact_strength, base, key_track, expressions, ramp,
                  table_lo, table_hi):
    """Add the weighted emotions to the speech values (module doc); widens the clamp ranges."""
    names = sorted(set(base) | (set(key_track["emotion"].astype(str)) - {"neutral"} if key_track is not None
                                else set()))
    if not names:
        return values, columns
    if expressions is None:
        from visemeface.postures.library import load_expressions
        expressions = load_expressions()
    expr = expressions.select_dtypes(include="number")
    known = [str(i) for i in expr.index]
    for n in names:
        if n not in known:
            raise InputError(f"unknown emotion {n!r}{close_matches(n, known) or '; known: ' + ', '.join(known)}")
    if key_track is not None:
        for _, row in key_track.iterrows():
            if str(row["emotion"]) != "neutral":
                _check_weight(row["emotion"], row["weight"])
    extra = [c for c in expr.columns if c not in columns]
    if extra:
        columns = columns + [str(c) for c in extra]
        values = np.hstack([values, np.zeros((values.shape[0], len(extra)))])
    E = expr.reindex(columns=columns, fill_value=0.0).loc[names].to_numpy(dtype=float)
    added = emotion_weights(times, names, base, key_track, ramp) @ E
    # Keep lip closure / contact: the emotion does not move the lip-opening functions
    # while a p b m f v target is forced.
    mouth = [j for j, c in enumerate(columns) if c in _LIP_OPENING_COLUMNS]
    added[:, mouth] *= (1.0 - contact_strength)[:, None]
    for c in expr.columns:
        table_lo[c] = min(table_lo.get(c, 0.0), float(expr[c].min()))
        table_hi[c] = max(table_hi.get(c, 1.0), float(expr[c].max()))
    return values + added, columns


def activation_track(segments: pd.DataFrame, visemes: pd.DataFrame, fps: float = 30.0,
                     mode: str = "coarticulation", emotions=None, expressions: pd.DataFrame | None = None,
                     ranges: Mapping[str, tuple[float, float]] | None = None, edge: float = 0.06,
                     emotion_ramp: float = 0.3, jali=None) -> pd.DataFrame:
    """Muscle activations per frame for timed phonemes (see the module doc).

    Parameters
    ----------
    segments : Segments or Utterance
        DataFrame ``start``, ``end``, ``phoneme`` (DECtalk), or an Utterance
        whose emotion key track is applied too.
    visemes : DataFrame
        Index DECtalk symbol, numeric columns = rig function names
        (non-numeric columns such as notes are ignored).
    fps : float
        Frame rate.
    mode : {"coarticulation", "linear", "cosine"}
    emotions : mapping or DataFrame, optional
        Global weights ``{name: weight}`` or an emotion key track.
    expressions : DataFrame, optional
        Emotion table (index emotion name, columns rig functions); default
        :func:`visemeface.postures.library.load_expressions` when needed.
    ranges : mapping name -> (low, high), optional
        Clamp of each column (default: see module doc).
    edge : float
        Ramp (s) at each end of a held segment.
    emotion_ramp : float
        Duration (s) of an emotion change.
    jali : (ja, li) arrays, optional
        Per-segment jaw and lip factors (:mod:`visemeface.speech.articulation`) applied to each
        segment's target before the blend; None: the tabled targets.

    Returns
    -------
    ActivationTrack

    Raises
    ------
    InputError
        Unknown mode, phoneme missing from the table, unknown emotion, bad weight.

    Examples
    --------
    >>> seg = pd.DataFrame({"start": [0.0, 0.2, 0.3], "end": [0.2, 0.3, 0.5], "phoneme": ["_", "m", "_"]})
    >>> vis = pd.DataFrame({"jaw": [0.3, 0.0], "orbicularis_oris": [0.0, 0.8]}, index=["_", "m"])
    >>> track = activation_track(seg, vis, fps=20)
    >>> track.loc[0.25].tolist()        # the frame at the centre of /m/
    [0.0, 0.8]
    """
    from visemeface.speech.utterance import Utterance

    if not isinstance(visemes, pd.DataFrame):
        raise InputError(f"visemes must be a DataFrame indexed by DECtalk symbol (load_visemes()), "
                         f"got {type(visemes).__name__}")
    keys = []
    if isinstance(segments, Utterance):
        keys.append(_keys_frame(segments.emotion_keys))
        segments = segments.segments
    times, values, columns, contact_strength = _speech(segments, visemes, fps, mode, edge, jali)
    base: dict[str, float] = {}
    if isinstance(emotions, Mapping):
        base = {str(k): _check_weight(k, v) for k, v in emotions.items()}
    elif emotions is not None:
        keys.append(_keys_frame(emotions))
    keys = [k for k in keys if len(k)]
    key_track = pd.concat(keys, ignore_index=True) if keys else None
    table_lo = visemes.select_dtypes(include="number").min().to_dict()
    table_hi = visemes.select_dtypes(include="number").max().to_dict()
    if base or key_track is not None:
        values, columns = _add_emotions(times, values, columns, contact_strength, base, key_track,
                                        expressions, emotion_ramp, table_lo, table_hi)
    lo = np.array([min(0.0, table_lo.get(c, 0.0)) for c in columns])
    hi = np.array([max(1.0, table_hi.get(c, 1.0)) for c in columns])
    if ranges is not None:
        for j, c in enumerate(columns):
            if c in ranges:
                lo[j], hi[j] = ranges[c]
    values = np.clip(values, lo, hi)
    return make_track(times, values, columns, fps)
