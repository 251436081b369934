"""The ActivationTrack and the frame clock: one home for frames, times and frame rates.

ActivationTrack
---------------
A pandas DataFrame, index ``time`` (seconds; frame ``k`` at ``k / fps``), one
column per rig function, ``attrs["fps"]`` the frame rate (docs/conventions.md).
Every track in the project is made by :func:`make_track`.

The frame clock (one rule everywhere)
-------------------------------------
Frame ``k`` is shown from ``k / fps`` to ``(k + 1) / fps``. So

- the frame showing time ``t`` is :func:`frame_of` ``= floor(t · fps)``;
- a video covering an utterance of ``T`` seconds has
  :func:`frame_count` ``= ceil(T · fps)`` frames (at least one);
- keyframes at ``0 … T`` that must all be seen need ``frame_of(T) + 1`` frames.

Both roundings forgive :data:`EPS` frames so that ``T · fps`` that is an
integer up to floating-point error (``0.1 · 30``) is not off by one.

The frame rate of a track (one rule)
------------------------------------
:func:`track_fps`: ``attrs["fps"]`` when present (an evenly sampled index must
agree with it); otherwise the time step of an evenly sampled index (every step
within 0.1% of the median); otherwise an :class:`~visemeface.errors.InputError`.
Nothing falls back to a silent 30 fps.
"""

from __future__ import annotations

import csv
import math
import re
from collections.abc import Mapping, Sequence
from pathlib import Path

import numpy as np
import pandas as pd

from visemeface.errors import InputError
from visemeface.textfile import read_text
from visemeface.outputs import atomic_output

#: Frames forgiven by the roundings of the frame clock (see the module docstring).
EPS = 1e-6
#: Highest frame rate accepted anywhere (a larger one means wrong units far more often).
MAX_FPS = 10_000.0


def check_fps(fps, what: str = "frame rate") -> float:
    """``fps`` as a float in (0, :data:`MAX_FPS`]; :class:`InputError` naming ``what`` otherwise."""
    try:
        value = float(fps)
    except (TypeError, ValueError):
        raise InputError(f"{what} must be a number, got {fps!r}") from None
    if not (math.isfinite(value) and 0 < value <= MAX_FPS):
        raise InputError(f"{what} must be in (0, {MAX_FPS:g}], got {value:g}")
    return value


def frame_of(t, fps: float):
    """Index of the frame showing time ``t`` (s): ``floor(t · fps)`` (array in, array out)."""
    k = np.floor(np.asarray(t, dtype=np.float64) * fps + EPS).astype(np.int64)
    return int(k) if k.ndim == 0 else k


def frame_count(duration: float, fps: float) -> int:
    """Frames of a video covering ``duration`` seconds: ``ceil(duration · fps)``, at least 1."""
    return max(1, int(math.ceil(float(duration) * fps - EPS)))


def frame_times(n: int, fps: float) -> np.ndarray:
    """Times (s) of frames ``0 … n-1``."""
    return np.arange(int(n), dtype=np.float64) / float(fps)


def even_step(times) -> float:
    """The time step of evenly sampled ``times`` (every step within 0.1% of the median), else 0."""
    step = np.diff(np.asarray(times, dtype=np.float64))
    med = float(np.median(step)) if len(step) else 0.0
    return med if med > 0 and bool(np.all(np.abs(step - med) <= 1e-3 * med)) else 0.0


def track_fps(track: pd.DataFrame) -> float:
    """The frame rate of an ActivationTrack (the one rule of the module docstring)."""
    fps = track.attrs.get("fps")
    med = even_step(track.index)                     # 0: not evenly sampled
    if fps is not None:
        fps = check_fps(fps, "the track's frame rate (attrs['fps'])")
        if med and abs(fps * med - 1.0) > 1e-3:      # a slice (track.iloc[::2]) keeps the old attrs
            raise InputError(f"the track's attrs['fps'] ({fps:g}) disagrees with its time step "
                             f"({1.0 / med:g} fps); set attrs['fps'] to the rate of its rows")
        return fps
    if med:
        return check_fps(1.0 / med, "the track's frame rate (from its time step)")
    raise InputError("the activation track has no frame rate: set attrs['fps'] "
                     "(its times are not evenly spaced, so none can be inferred)")


def make_track(times, columns: Mapping[str, Sequence[float]] | np.ndarray, names: Sequence[str],
               fps: float) -> pd.DataFrame:
    """An ActivationTrack with columns ``names``.

    Parameters
    ----------
    times : (F,) array
        Frame times (s), usually :func:`frame_times`.
    columns : mapping or (F, len(names)) array
        Values per column name (names not given are 0), or the whole matrix.
    names : sequence of str
        Column names in order (usually ``rig.names``).
    fps : float
    """
    index = pd.Index(np.asarray(times, dtype=np.float64), name="time")
    if isinstance(columns, Mapping):
        df = pd.DataFrame(0.0, index=index, columns=list(names))
        for k, v in columns.items():
            if k not in df.columns:
                from visemeface.errors import close_matches

                raise InputError(f"the rig has no {k!r} column" + close_matches(str(k), list(names)))
            df[k] = np.asarray(v, dtype=np.float64)
    else:
        df = pd.DataFrame(np.asarray(columns, dtype=np.float64), index=index, columns=list(names))
    df.attrs["fps"] = check_fps(fps)
    return df


# ----------------------------------------------------------------------------- CSV

_FPS_LINE = re.compile(r"fps\s*=\s*([0-9.eE+-]+)")


def save_track(track: pd.DataFrame, path, force: bool = False) -> Path:
    """Write an ActivationTrack as CSV: a ``# ... fps=<fps>`` line, then ``time`` and the columns.

    Written atomically (never half a file; refuses to overwrite unless ``force``).
    Floats are written with full precision, so :func:`load_track` returns the same numbers.
    """
    fps = track_fps(track)
    with atomic_output(path, force) as tmp:
        with open(tmp, "w", encoding="utf-8", newline="") as f:
            f.write(f"# visemeface activation track; fps={fps!r}\n")
            track.to_csv(f, index=True, index_label="time", lineterminator="\n")
    return Path(path)


def _header_fps(lines: list[str], path) -> tuple[float | None, int]:
    """The ``fps=`` of the leading comment lines, and how many lines they take."""
    fps, skip = None, 0
    while skip < len(lines) and lines[skip].lstrip().startswith("#"):
        m = _FPS_LINE.search(lines[skip])
        if m:
            try:
                fps = check_fps(float(m.group(1)))
            except (ValueError, InputError):
                raise InputError(f"bad frame rate {m.group(1)!r}", path, skip + 1) from None
        skip += 1
    return fps, skip


def load_track(path) -> pd.DataFrame:
    """Read an ActivationTrack CSV (from :func:`save_track`, or any CSV with a ``time`` column).

    The frame rate comes from the ``fps=`` comment line, else from the time step
    (:func:`track_fps`).

    Raises
    ------
    InputError
        Missing file, no ``time`` column, a cell that is not a finite number
        (with its line), times not increasing, no frame rate.
    """
    path = Path(path)
    text = read_text(path, "track")
    lines = text.splitlines()
    fps, skip = _header_fps(lines, path)
    rows = list(csv.reader(lines[skip:]))
    if not rows or "time" not in [h.strip() for h in rows[0]]:
        raise InputError("track CSV has no 'time' column", path, skip + 1)
    header = [h.strip() for h in rows[0]]
    data = []
    for k, rec in enumerate(rows[1:], start=skip + 2):
        if not any(c.strip() for c in rec):
            continue
        if len(rec) != len(header):
            raise InputError(f"expected {len(header)} values, got {len(rec)}", path, k)
        vals = []
        for c in rec:
            try:
                vals.append(float(c))
            except ValueError:
                raise InputError(f"value {c!r} is not a number", path, k) from None
        if not all(math.isfinite(v) for v in vals):
            raise InputError("non-finite value", path, k)
        data.append(vals)
    if not data:
        raise InputError("track CSV has no frames", path, skip + 1)
    arr = np.array(data)
    ti = header.index("time")
    times = arr[:, ti]
    if (np.diff(times) <= 0).any():
        k = int(np.flatnonzero(np.diff(times) <= 0)[0])
        raise InputError("times must increase", path, skip + 3 + k)
    cols = [h for j, h in enumerate(header) if j != ti]
    track = pd.DataFrame(np.delete(arr, ti, axis=1), index=pd.Index(times, name="time"), columns=cols)
    if fps is not None:
        track.attrs["fps"] = fps
    try:
        track.attrs["fps"] = track_fps(track)      # the header's rate checked against the times
    except InputError as exc:
        more = "" if fps is not None else " (or write a '# fps=<rate>' line first)"
        raise InputError(exc.reason + more, path) from None
    return track
