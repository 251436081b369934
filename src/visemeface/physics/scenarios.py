"""Activation tracks for the FEM face: Leach & Maddock's (2018) scenarios, ramps, keyframes.

Scenarios (:func:`scenario_track`) are small activation tracks for Leach & Maddock's (2018)
experiments (jaw lowered and raised, the mouth opened and closed twice).
"""

from __future__ import annotations

import numpy as np
import pandas as pd

from visemeface.errors import InputError, close_matches

#: Leach & Maddock's (2018, 2019) scenarios as (time s, value) keyframes of the jaw (and, for the
#: one-sided variants, the lower-lip depressor of one side), eased with a smoothstep.
SCENARIOS = {
    # the mouth opened and closed twice (Leach & Maddock 2019, Fig. 18: "closed and reopened twice")
    "open": [(0.0, 0.0), (0.05, 0.0), (0.40, 1.0), (0.60, 1.0), (0.85, 0.0), (0.95, 0.0),
             (1.30, 1.0), (1.50, 1.0), (1.75, 0.0), (1.80, 0.0)],
    # a single opening held open (equilibrium with and without glue, Leach & Maddock (2018) Fig. 8)
    "open-once": [(0.0, 0.0), (0.05, 0.0), (0.40, 1.0), (0.75, 1.0)],
    # a slight opening: sticky lips stay joined toward the corners (Leach & Maddock 2018, Fig. 7)
    "part": [(0.0, 0.0), (0.05, 0.0), (0.40, 0.45), (0.75, 0.45)],
}
SIDES = ("both", "left", "right")


def smoothstep_keyframes(t, keys) -> np.ndarray:
    """Value of keyframes ``[(t0, v0), (t1, v1), ...]`` at times ``t``.

    Between keys the value eases with s = 3x² − 2x³ (zero slope at each key,
    so the drive never jerks); it is held constant outside the keys.

    Examples
    --------
    >>> smoothstep_keyframes([0.0, 0.5, 1.0, 2.0], [(0.0, 0.0), (1.0, 2.0)])
    array([0., 1., 2., 2.])
    """
    k = np.asarray(keys, dtype=np.float64)
    t = np.asarray(t, dtype=np.float64)
    i = np.clip(np.searchsorted(k[:, 0], t, side="right") - 1, 0, len(k) - 2)
    t0, t1 = k[i, 0], k[i + 1, 0]
    x = np.clip((t - t0) / np.where(t1 > t0, t1 - t0, 1.0), 0.0, 1.0)
    s = x * x * (3.0 - 2.0 * x)
    return k[i, 1] + s * (k[i + 1, 1] - k[i, 1])


def make_track(times, values: dict, names, fps: float) -> pd.DataFrame:
    """An ActivationTrack (docs/conventions.md) with the given columns, zeros elsewhere."""
    df = pd.DataFrame(0.0, index=pd.Index(np.asarray(times, float), name="time"), columns=list(names))
    for k, v in values.items():
        df[k] = v
    df.attrs["fps"] = float(fps)
    return df


def ramp_track(names, fps: float, start: float, ramp: float, hold: float, jaw: float = 0.35,
               extra: dict | None = None) -> pd.DataFrame:
    """A single jaw opening: rest until ``start``, eased up over ``ramp`` s, held ``hold`` s.

    ``jaw`` is the jaw activation at the top, ``extra`` more columns ramped the
    same way ({name: activation at the top}).
    """
    keys = [(0.0, 0.0), (start, 0.0), (start + ramp, 1.0), (start + ramp + hold, 1.0)]
    t = np.arange(int(round(keys[-1][0] * fps)) + 1) / fps
    v = smoothstep_keyframes(t, keys)
    cols = {"jaw": jaw * v, **{k: a * v for k, a in (extra or {}).items()}}
    return make_track(t, cols, names, fps)


def scenario_track(name: str, names, fps: float = 60.0, jaw: float = 0.35, side: str = "both",
                   lip: float = 0.3) -> pd.DataFrame:
    """The activation track of a named scenario.

    Parameters
    ----------
    name : str
        One of :data:`SCENARIOS`.
    names : sequence of str
        Rig column names (``rig.names``); must include ``"jaw"``.
    fps : float
        Frame rate of the track.
    jaw : float
        Jaw activation at the keyframes' value 1.
    side : {"both", "left", "right"}
        ``left``/``right``: also pull the lower lip down on that side only
        (``depressor_labii_inferioris_<side>`` at ``lip`` × the keyframe
        value), an asymmetric opening (Leach & Maddock 2018, Fig. 10).
    lip : float
        Activation of that one-sided depressor at value 1.
    """
    if name not in SCENARIOS:
        raise InputError(f"unknown scenario {name!r}" + close_matches(name, SCENARIOS)
                         + f"; known: {', '.join(SCENARIOS)}")
    if side not in SIDES:
        raise InputError(f"side must be one of {', '.join(SIDES)}, got {side!r}")
    if fps <= 0:
        raise InputError(f"fps must be > 0, got {fps}")
    keys = SCENARIOS[name]
    n = int(np.floor(keys[-1][0] * fps + 1e-9)) + 1
    t = np.arange(n) / fps
    v = smoothstep_keyframes(t, keys)
    cols = {"jaw": jaw * v}
    if side != "both":
        cols[f"depressor_labii_inferioris_{side}"] = lip * v
    for c in cols:
        if c not in names:
            raise InputError(f"the rig has no {c!r} column" + close_matches(c, names))
    return make_track(t, cols, names, fps)


def activation_at(values: np.ndarray, fps: float, t: float) -> np.ndarray:
    """Linearly interpolated activation row of a (frames, M) track array at time ``t``."""
    f = t * fps
    i = int(np.clip(np.floor(f), 0, len(values) - 1))
    j = min(i + 1, len(values) - 1)
    w = float(np.clip(f - i, 0.0, 1.0))
    return (1.0 - w) * values[i] + w * values[j]


def track_values(track: pd.DataFrame, rig) -> tuple[np.ndarray, float]:
    """(frames, M) activations in ``rig.names`` order (:meth:`MuscleRig.track_matrix`) and the
    frame rate of an ActivationTrack."""
    if not isinstance(track, pd.DataFrame) or len(track) == 0:
        raise InputError("the activation track is empty")
    values = rig.track_matrix(track)
    fps = track.attrs.get("fps")
    if fps is None and len(track) > 1:
        fps = 1.0 / float(np.median(np.diff(track.index.to_numpy(dtype=float))))
    if fps is None or not np.isfinite(fps) or fps <= 0:
        raise InputError(f"activation track needs attrs['fps'] > 0, got {fps!r}")
    return values, float(fps)

