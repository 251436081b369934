"""Head, brows and gaze that move with the speech: nods on pitch accents, a pose per phrase, saccades.

Talking heads move: the head nods on stressed syllables and settles into a new pose at a phrase
start, its pitch follows the voice's F0 a little (Yehia, Kuratate & Vatikiotis-Bateson 2002), the brows
rise on some pitch accents (Cavé et al. 1996), and the eyes look away as a phrase starts and come back,
with small saccades between (Kendon 1967). :func:`speech_gestures` makes all of it from an utterance
and, when there is one, its recording's :class:`~visemeface.speech.acoustics.Acoustics`; the sizes and
timing are ``data/phonemes/gestures.csv``'s. The same ``seed`` gives the same motion.

Accents
-------
Each vowel gets a prominence: with a recording, the sum of its F0 peak (semitones above the
utterance's median), its level (dB above the median vowel's, halved) and its length (relative to the
median vowel's), each as a z-score, mapped onto 0..1 within the utterance; without one, its lexical
stress (emphasised 1, primary 0.6, secondary 0.3, unstressed 0) and, lacking that, its length. The
accents are the most prominent vowels above ``accent_threshold``, at least ``accent_min_gap_s``
apart; an accent's time is its F0 peak (the vowel's centre without a recording).

Head (degrees; yaw + toward the subject's left, pitch + chin down, roll + top of the head toward the
subject's right)
    pitch: a raised-cosine nod of ``nod_deg`` x prominence peaking ``nod_lead_s`` before each accent,
    minus ``pitch_per_semitone_deg`` per semitone of the smoothed F0 (the head rises with the voice);
    yaw and roll: each phrase (speech between pauses of 150 ms or more) eases to its own pose, drawn
    from normal laws (``phrase_yaw_sd_deg``, ``phrase_roll_sd_deg``), and back to 0 after the last;
    all three: a slow sway of three sines, and a soft limit :math:`L \\tanh(x / L)`.
Brows
    a raise of ``brow_raise`` x prominence on the accents of prominence ``brow_min_prominence`` or more.
Gaze (eye-turn units: 1 = 20 degrees horizontally, 15 vertically)
    a look-away of ``gaze_away`` at each phrase start for ``gaze_away_s``, to a side drawn at random;
    between, small saccades every ``saccade_interval_s`` on average (gamma intervals).
"""

from __future__ import annotations

import csv
from dataclasses import dataclass
from functools import lru_cache

import numpy as np

from visemeface.numeric import cosine_step
from visemeface.postures.phonemes import SILENCE, is_vowel
from visemeface.resources import data_path

__all__ = ["AXES", "BROW_COLUMNS", "Gestures", "accents", "add_face_gestures", "gesture_settings",
           "speech_gestures"]

#: The head's rotation axes, in the order of :attr:`Gestures.head`'s columns.
AXES = ("yaw", "pitch", "roll")
BROW_COLUMNS = ("frontalis_medialis_left", "frontalis_medialis_right", "frontalis_lateralis_left",
                "frontalis_lateralis_right")
GAZE_COLUMNS = (("eye_turn_horizontal_left", "eye_turn_horizontal_right"),
                ("eye_turn_vertical_left", "eye_turn_vertical_right"))
#: A silence at least this long ends a phrase (s).
PHRASE_PAUSE_S = 0.15


@lru_cache(maxsize=1)
def gesture_settings() -> dict[str, float]:
    """``data/phonemes/gestures.csv``: name -> value."""
    with open(data_path("phonemes", "gestures.csv"), encoding="utf-8", newline="") as f:
        rows = list(csv.DictReader(line for line in f if not line.lstrip().startswith("#")))
    return {r["name"]: float(r["value"]) for r in rows}


@dataclass(frozen=True)
class Gestures:
    """Per-frame gestures (frame ``k`` at ``times[k] = k / fps``) and the accents they follow.

    Attributes
    ----------
    times : (F,) float
    head : (F, 3) float
        Yaw, pitch, roll in degrees (module doc for the signs).
    brow : (F,) float
        Brow raise, 0..1 of the frontalis.
    gaze : (F, 2) float
        Horizontal and vertical eye turn (rig units, -1..1).
    accent_times, prominence, f0_peak_times : (A,) float
        The accents: when the nods fall, how prominent, and the F0 peak each was found at (NaN
        without a recording).
    """

    times: np.ndarray
    head: np.ndarray
    brow: np.ndarray
    gaze: np.ndarray
    accent_times: np.ndarray
    prominence: np.ndarray
    f0_peak_times: np.ndarray

    def nod_times(self) -> np.ndarray:
        """Times of the head pitch's local maxima above half a degree (the nods as drawn)."""
        p = self.head[:, 1]
        if p.size < 3:
            return np.zeros(0)
        k = np.flatnonzero((p[1:-1] > p[:-2]) & (p[1:-1] >= p[2:]) & (p[1:-1] > 0.5)) + 1
        return self.times[k]


def _z(x):
    x = np.asarray(x, float)
    ok = np.isfinite(x)
    if ok.sum() < 2 or np.nanstd(x) == 0:
        return np.where(ok, 0.0, np.nan)
    return (x - np.nanmean(x)) / np.nanstd(x)


def _vowels(segments):
    start = segments["start"].to_numpy(float)
    end = segments["end"].to_numpy(float)
    phones = [str(p) for p in segments["phoneme"]]
    v = np.array([is_vowel(p) for p in phones], dtype=bool)
    return start, end, phones, v


def accents(utterance, acoustics=None):
    """(accent times, prominence 0..1, F0 peak times or NaN) of an utterance (module doc)."""
    g = gesture_settings()
    seg = utterance.segments
    start, end, phones, v = _vowels(seg)
    idx = np.flatnonzero(v)
    if idx.size == 0:
        return np.zeros(0), np.zeros(0), np.zeros(0)
    a, b = start[idx], end[idx]
    dur = b - a
    peak_t = np.full(idx.size, np.nan)
    if acoustics is not None and np.isfinite(acoustics.f0).any():
        f0 = acoustics.f0
        st = 12 * np.log2(f0 / np.nanmedian(f0))
        peak = np.full(idx.size, np.nan)
        for j in range(idx.size):
            k = np.flatnonzero((acoustics.times >= a[j]) & (acoustics.times < b[j]) & np.isfinite(st))
            if k.size:
                m = k[np.argmax(st[k])]
                peak[j], peak_t[j] = st[m], acoustics.times[m]
        from visemeface.speech.acoustics import span_mean

        level = span_mean(acoustics.level, acoustics.times, a, b)
        score = np.nan_to_num(_z(peak)) + 0.5 * np.nan_to_num(_z(level)) + 0.5 * np.nan_to_num(_z(np.log(dur)))
    elif utterance.phone_stress() is not None:
        stress, emph = (x[idx] for x in utterance.phone_stress())
        score = np.select([emph, stress == 1, stress == 2], [1.0, 0.6, 0.3], 0.0) + 0.05 * _z(np.log(dur))
    else:
        score = _z(np.log(dur))
    score = np.nan_to_num(score)
    lo, hi = score.min(), score.max()
    prom = (score - lo) / (hi - lo) if hi > lo else np.full(score.size, 0.5)
    when = np.where(np.isfinite(peak_t), peak_t, (a + b) / 2)
    chosen: list[int] = []
    for j in np.argsort(-prom, kind="stable"):
        if prom[j] < g["accent_threshold"]:
            break
        if all(abs(when[j] - when[c]) >= g["accent_min_gap_s"] for c in chosen):
            chosen.append(int(j))
    chosen.sort(key=lambda j: when[j])
    c = np.array(chosen, dtype=int)
    return when[c], prom[c], peak_t[c]


def _pulse(times, centre, width):
    u = (times - centre) / width
    return np.where(np.abs(u) < 0.5, 0.5 * (1 + np.cos(2 * np.pi * u)), 0.0)


def _phrases(segments) -> list[tuple[float, float]]:
    """(start, end) of the stretches of speech between silences of :data:`PHRASE_PAUSE_S` or more."""
    out, cur = [], None
    for s, e, p in zip(segments["start"], segments["end"], segments["phoneme"]):
        if str(p) == SILENCE and (e - s >= PHRASE_PAUSE_S or cur is None):
            if cur is not None:
                out.append(cur)
                cur = None
            continue
        cur = (cur[0], float(e)) if cur is not None else (float(s), float(e))
    if cur is not None:
        out.append(cur)
    return out


def _steps(times, keys, values, ramp):
    """Piecewise-constant values changing at ``keys`` by cosine steps of ``ramp`` s (value 0 before the first)."""
    out = np.zeros(times.size)
    level = 0.0
    for t, v in zip(keys, values):
        out += (v - level) * cosine_step((times - t) / ramp)
        level = v
    return out


def _soft_limit(x, limit):
    return limit * np.tanh(x / limit)


def speech_gestures(utterance, n_frames: int, fps: float, acoustics=None, seed: int = 0) -> Gestures:
    """The head, brow and gaze motion of an utterance over ``n_frames`` frames (module doc)."""
    g = gesture_settings()
    times = np.arange(int(n_frames)) / float(fps)
    rng = np.random.default_rng([int(seed), 38])
    when, prom, peak_t = accents(utterance, acoustics)
    phrases = _phrases(utterance.segments)

    pitch = np.zeros(times.size)
    for t, p in zip(when, prom):
        pitch += g["nod_deg"] * p * _pulse(times, t - g["nod_lead_s"], g["nod_width_s"])
    if acoustics is not None and np.isfinite(acoustics.f0).any():
        st = 12 * np.log2(acoustics.f0 / np.nanmedian(acoustics.f0))
        ok = np.isfinite(st)
        contour = np.interp(times, acoustics.times[ok], st[ok]) if ok.sum() >= 2 else np.zeros(times.size)
        inside = np.zeros(times.size, bool)
        for a, b in phrases:
            inside |= (times >= a) & (times <= b)
        k = max(1, int(round(0.25 * fps)))
        contour = np.convolve(np.where(inside, contour, 0.0), np.ones(k) / k, mode="same")
        pitch -= g["pitch_per_semitone_deg"] * np.clip(contour, -12, 12)

    keys = [a - 0.2 for a, _ in phrases] + ([phrases[-1][1]] if phrases else [])
    yaw_t = list(rng.normal(0.0, g["phrase_yaw_sd_deg"], len(phrases))) + [0.0] * bool(phrases)
    roll_t = list(rng.normal(0.0, g["phrase_roll_sd_deg"], len(phrases))) + [0.0] * bool(phrases)
    yaw = _steps(times, keys, yaw_t, g["phrase_turn_s"])
    roll = _steps(times, keys, roll_t, g["phrase_turn_s"])
    head = np.column_stack([yaw, pitch, roll])
    freq = rng.uniform(0.08, 0.35, (3, 3))
    phase = rng.uniform(0, 2 * np.pi, (3, 3))
    for axis in range(3):
        head[:, axis] += g["sway_deg"] / 3 * np.sin(2 * np.pi * freq[axis][None, :] * times[:, None]
                                                    + phase[axis][None, :]).sum(axis=1)
    limits = np.array([g["yaw_limit_deg"], g["pitch_limit_deg"], g["roll_limit_deg"]])
    head = _soft_limit(head, limits[None, :])

    brow = np.zeros(times.size)
    for t, p in zip(when, prom):
        if p >= g["brow_min_prominence"]:
            brow = np.maximum(brow, g["brow_raise"] * p * _pulse(times, t, g["brow_width_s"]))

    gaze = np.zeros((times.size, 2))
    g_keys, g_h, g_v = [], [], []
    for a, _ in phrases:
        side = rng.choice([-1.0, 1.0])
        g_keys += [a, a + g["gaze_away_s"]]
        g_h += [side * g["gaze_away"], 0.0]
        g_v += [rng.uniform(-0.4, 0.1) * g["gaze_away"], 0.0]
    t = float(rng.uniform(0.2, g["saccade_interval_s"]))
    end = times[-1] if times.size else 0.0
    while t < end:
        if not any(a <= t < a + g["gaze_away_s"] for a, _ in phrases):
            g_keys.append(t)
            g_h.append(float(rng.normal(0.0, g["saccade_size"])))
            g_v.append(float(rng.normal(0.0, g["saccade_size"] * 0.6)))
        t += float(rng.gamma(4.0, g["saccade_interval_s"] / 4.0))
    order = np.argsort(g_keys, kind="stable")
    keys_sorted = np.asarray(g_keys, float)[order]
    gaze[:, 0] = _steps(times, keys_sorted, np.asarray(g_h, float)[order], g["saccade_s"])
    gaze[:, 1] = _steps(times, keys_sorted, np.asarray(g_v, float)[order], g["saccade_s"])
    return Gestures(times, head, np.clip(brow, 0.0, 1.0), np.clip(gaze, -1.0, 1.0), when, prom, peak_t)


def add_face_gestures(track, names, gestures: Gestures):
    """A copy of the activation ``track`` with the brow raise (``a + b (1 - a)`` on the frontalis) and the
    gaze (added to the eye turns, clipped to -1..1) on the functions ``names`` has."""
    out = track.copy()
    n = len(out)
    brow = np.resize(gestures.brow, n) if gestures.brow.size != n else gestures.brow
    gaze = gestures.gaze if len(gestures.gaze) == n else np.resize(gestures.gaze, (n, 2))
    names = set(names)
    for col in BROW_COLUMNS:
        if col in names:
            a = out[col].to_numpy(float) if col in out else np.zeros(n)
            out[col] = a + brow * (1.0 - a)
    for axis, cols in enumerate(GAZE_COLUMNS):
        for col in cols:
            if col in names:
                a = out[col].to_numpy(float) if col in out else np.zeros(n)
                out[col] = np.clip(a + gaze[:, axis], -1.0, 1.0)
    out.attrs = dict(track.attrs)
    return out


def rotation_matrices(head_deg: np.ndarray) -> np.ndarray:
    """(F, 3, 3) rotations of yaw, pitch, roll (degrees, module doc's signs): roll, then pitch, then yaw."""
    y, p, r = np.radians(np.asarray(head_deg, float)).T
    cy, sy, cp, sp, cr, sr = np.cos(y), np.sin(y), np.cos(p), np.sin(p), np.cos(r), np.sin(r)
    one, zero = np.ones_like(y), np.zeros_like(y)
    ry = np.stack([np.stack([cy, zero, sy], -1), np.stack([zero, one, zero], -1), np.stack([-sy, zero, cy], -1)], 1)
    rx = np.stack([np.stack([one, zero, zero], -1), np.stack([zero, cp, -sp], -1), np.stack([zero, sp, cp], -1)], 1)
    rz = np.stack([np.stack([cr, -sr, zero], -1), np.stack([sr, cr, zero], -1), np.stack([zero, zero, one], -1)], 1)
    return ry @ rx @ rz


def head_pivot(vertices: np.ndarray) -> np.ndarray:
    """Where the head turns about: below the face and behind it, near the top of the neck (the atlanto-occipital
    joint lies about 10 cm behind the nose tip, level with the bottom of the face)."""
    v = np.asarray(vertices, float)
    lo, hi = v.min(axis=0), v.max(axis=0)
    return np.array([(lo[0] + hi[0]) / 2, lo[1], hi[2] - 0.10])


def head_matrices(head_deg: np.ndarray, pivot: np.ndarray) -> np.ndarray:
    """(F, 4, 4) model matrices turning the head by (F, 3) (yaw, pitch, roll) degrees about ``pivot``
    (a renderer draws the turned head with them: :meth:`visemeface.render.renderer.Renderer.render`)."""
    rot = rotation_matrices(np.asarray(head_deg, float).reshape(-1, 3))
    m = np.zeros((len(rot), 4, 4))
    m[:, :3, :3], m[:, 3, 3] = rot, 1.0
    m[:, :3, 3] = pivot - rot @ np.asarray(pivot, float)
    return m


def rotate_head(vertices: np.ndarray, head_deg, pivot: np.ndarray) -> np.ndarray:
    """``vertices`` turned rigidly by one frame's (yaw, pitch, roll) degrees about ``pivot``."""
    m = head_matrices(head_deg, pivot)[0]
    v = np.asarray(vertices)
    return (v @ m[:3, :3].T + m[:3, 3]).astype(v.dtype, copy=False)


def _qmul(a, b):
    ax, ay, az, aw = np.moveaxis(a, -1, 0)
    bx, by, bz, bw = np.moveaxis(b, -1, 0)
    return np.stack([aw * bx + ax * bw + ay * bz - az * by, aw * by - ax * bz + ay * bw + az * bx,
                     aw * bz + ax * by - ay * bx + az * bw, aw * bw - ax * bx - ay * by - az * bz], -1)


def head_quaternions(head_deg: np.ndarray) -> np.ndarray:
    """(F, 4) unit quaternions (x, y, z, w; glTF's order) of :func:`rotation_matrices`' rotations."""
    y, p, r = np.radians(np.asarray(head_deg, float)).reshape(-1, 3).T / 2
    z = np.zeros_like(y)
    qy = np.stack([z, np.sin(y), z, np.cos(y)], -1)
    qx = np.stack([np.sin(p), z, z, np.cos(p)], -1)
    qz = np.stack([z, z, np.sin(r), np.cos(r)], -1)
    return _qmul(_qmul(qy, qx), qz)
