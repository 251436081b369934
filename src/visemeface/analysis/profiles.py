"""Mouth-opening profiles over time, their distance and plots (Leach & Maddock 2019, §4-5).

A *profile* is a pandas DataFrame, one row per frame, with columns

``frame``   int, 0-based frame index
``time``    seconds, ``frame / fps``
``count``   number of mouth openings
``area``    largest opening's area / w**2
``width``   largest opening's width / w
``height``  largest opening's height / w
``d_area``  :math:`\\Delta \\mathrm{area}_i = \\mathrm{area}_i - \\mathrm{area}_{i-1}` (NaN on frame 0)
``d_width`` :math:`\\Delta \\mathrm{width}_i` likewise

where ``w`` is the natural mouth width in pixels (the mouth box's width).
``df.attrs`` holds ``fps``, ``mouth_width`` (px) and ``source``. The
derivatives are per-frame differences, as in Leach & Maddock (2019): a jump of the width
when two openings merge shows up as one spike (Figs. 25-26).

Profiles are saved as CSV (:func:`write_profile`, :func:`read_profile`).
"""

from __future__ import annotations

from collections.abc import Callable, Iterable, Mapping
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np
import pandas as pd

from visemeface.errors import InputError
from visemeface.outputs import atomic_output
from visemeface.track import even_step

if TYPE_CHECKING:   # the detectors need OpenCV (the [render] extra); reading and comparing profiles does not
    from visemeface.analysis.openings import MouthBox, OpeningDetector, Openings

COLUMNS = ("frame", "time", "count", "area", "width", "height", "d_area", "d_width")
METRICS = ("area", "width", "height")
LABELS = {
    "count": "openings",
    "area": "area / w²",
    "width": "width / w",
    "height": "height / w",
    "d_area": "Δ area / frame",
    "d_width": "Δ width / frame",
}


def profile_from_openings(openings: Iterable[Openings], fps: float, source: str = "") -> pd.DataFrame:
    """Build a profile from per-frame detections (largest opening's metrics)."""
    if not (np.isfinite(fps) and fps > 0):
        raise InputError(f"fps must be a positive number, got {fps}")
    rows = [(o.count, o.largest_area, o.largest_width, o.largest_height, o.mouth_width) for o in openings]
    arr = np.asarray(rows, dtype=np.float64).reshape(-1, 5)
    n = arr.shape[0]
    frame = np.arange(n, dtype=np.int64)
    df = pd.DataFrame({
        "frame": frame,
        "time": frame / float(fps),
        "count": arr[:, 0].astype(np.int64),
        "area": arr[:, 1],
        "width": arr[:, 2],
        "height": arr[:, 3],
    })
    add_derivatives(df)
    df.attrs.update(fps=float(fps), mouth_width=int(arr[0, 4]) if n else 0, source=str(source))
    return df


def add_derivatives(df: pd.DataFrame) -> pd.DataFrame:
    """Set ``d_area`` and ``d_width``: differences to the previous frame (NaN on the first)."""
    df["d_area"] = df["area"].diff()
    df["d_width"] = df["width"].diff()
    return df


def analyze_frames(frames: Iterable[np.ndarray], box, fps: float, detector: OpeningDetector | None = None,
                   on_frame: Callable[[int, np.ndarray, Openings], None] | None = None,
                   source: str = "") -> pd.DataFrame:
    """Detect the openings of every frame and return the profile.

    Parameters
    ----------
    frames : iterable of ndarray (H, W, 3) uint8
        RGB frames.
    box : MouthBox or (x, y, w, h), or a sequence of them
        Mouth box, or one box per frame (an automatic box that follows the head,
        :func:`~visemeface.analysis.mouthbox.track_mouth`).
    fps : float
    detector : OpeningDetector, optional
        Settings (default ``OpeningDetector()``: the ``lips`` method, teeth and tongue counted as opening).
    on_frame : callable(index, frame, openings), optional
        Called after each frame (e.g. to write an overlay).
    """
    from visemeface.analysis.openings import OpeningDetector

    detector = detector or OpeningDetector()
    boxes = per_frame_boxes(box)
    found = []
    for i, frame in enumerate(frames):
        if i >= len(boxes):
            raise InputError(f"{len(boxes)} mouth boxes for more frames{' in ' + source if source else ''}")
        op = detector.detect(frame, boxes[i])
        found.append(op)
        if on_frame is not None:
            on_frame(i, frame, op)
    if not found:
        raise InputError(f"no frames to analyse{' in ' + source if source else ''}")
    return profile_from_openings(found, fps, source)


#: A clip whose decoded frames take at most this many bytes is decoded once and kept in memory
#: when the mouth box is found automatically (otherwise it is decoded twice: find, then measure).
BUFFER_BYTES = 512 * 2 ** 20


def analyze_source(source, box=None, detector: OpeningDetector | None = None,
                   on_frame: Callable[[int, np.ndarray, Openings], None] | None = None,
                   show_progress: bool = False) -> tuple[pd.DataFrame, list | None]:
    """Profile of a :class:`~visemeface.analysis.video.FrameSource`, and the per-frame boxes if found here.

    With ``box=None`` the mouth is found in every frame
    (:func:`~visemeface.analysis.mouthbox.track_mouth`) before it is measured;
    the frames are decoded once when they fit in :data:`BUFFER_BYTES`. A path (str or Path) is opened with
    :func:`~visemeface.analysis.video.open_frames`.
    """
    from visemeface.outputs import progress

    if isinstance(source, (str, Path)):
        from visemeface.analysis.video import open_frames

        source = open_frames(source)

    from visemeface.analysis.openings import OpeningDetector

    detector = detector or OpeningDetector()
    from visemeface.analysis import landmarks

    by_colour = detector.method == "lips" or (box is None and not landmarks.available())

    def frames(desc):
        it = source.frames()
        return progress(_in_colour(it, source.path, detector.method) if by_colour else it,
                        total=source.n_frames, desc=desc, show=show_progress)

    if box is not None:
        return analyze_frames(frames("analyze"), box, source.fps, detector, on_frame, str(source.path)), None
    from visemeface.analysis.mouthbox import track_mouth

    w, h = source.size
    small = source.n_frames is not None and (source.n_frames + 2) * w * h * 3 <= BUFFER_BYTES
    if small:
        kept = list(frames("decode"))
        boxes = track_mouth(kept, source=str(source.path))
        todo = kept
    else:
        boxes = track_mouth(frames("find mouth"), source=str(source.path))
        todo = frames("analyze")
    return analyze_frames(todo, boxes, source.fps, detector, on_frame, str(source.path)), boxes


#: Most a grey-scale frame's channels differ (0-255): a clip whose first frame's channels all lie within this
#: of each other has no colour (compression leaves a level or two).
GREY_CHANNEL_SPREAD = 3


def _in_colour(frames, path, method: str):
    """``frames``, refused with an InputError when the first has no colour (the lips, and the automatic box
    without landmarks, are found by colour; grey frames gave "openings max 0" for a talking face)."""
    for i, frame in enumerate(frames):
        if i == 0:
            f = frame.astype(np.int16)
            spread = max(int(np.abs(f[..., 0] - f[..., 1]).max()), int(np.abs(f[..., 1] - f[..., 2]).max()))
            if spread <= GREY_CHANNEL_SPREAD:
                how = ("the lips method finds the lips by colour: try --method seed" if method == "lips" else
                       "the automatic mouth box without face landmarks finds the face by colour: give --box "
                       "or pip install 'visemeface[track]'")
                raise InputError(f"the frames are grey-scale (no colour); {how}", path)
        yield frame


class _Repeat:
    """The same box for every frame."""

    def __init__(self, box: MouthBox):
        self.box = box

    def __len__(self) -> int:
        return 2 ** 62

    def __getitem__(self, i: int) -> MouthBox:
        return self.box


def per_frame_boxes(box):
    """An indexable of boxes, one per frame, from one box or a sequence of boxes."""
    from visemeface.analysis.openings import MouthBox

    if isinstance(box, MouthBox):
        return _Repeat(box)
    seq = list(box)
    if seq and all(isinstance(b, MouthBox) or (np.ndim(b) == 1 and len(b) == 4) for b in seq) \
            and not all(np.isscalar(b) for b in seq):
        return [MouthBox.of(b) for b in seq]
    return _Repeat(MouthBox.of(seq))


def write_profile(df: pd.DataFrame, path: str | Path, force: bool = False) -> None:
    """Write a profile as CSV (never overwrites without ``force``): measures to 8 significant digits, times
    to 12 (the frame rate is read back from them)."""
    out = df.loc[:, list(COLUMNS)].copy()
    out["time"] = [f"{t:.12g}" for t in out["time"].to_numpy(float)]
    with atomic_output(path, force) as tmp:
        out.to_csv(tmp, index=False, float_format="%.8g", lineterminator="\n")


def read_profile(path: str | Path) -> pd.DataFrame:
    """Read a profile CSV written by :func:`write_profile`; ``attrs["fps"]`` from the times (over their
    whole span, to 9 significant digits). Other ``attrs`` (the mouth width) are not in the CSV."""
    path = Path(path)
    if not path.is_file():
        raise InputError("no such file", path)
    try:
        df = pd.read_csv(path)
    except (pd.errors.ParserError, pd.errors.EmptyDataError, UnicodeDecodeError) as exc:
        raise InputError(f"not a profile CSV: {str(exc).splitlines()[0]}", path) from None
    missing = [c for c in ("time", *METRICS) if c not in df.columns]
    if missing:
        raise InputError(f"not a profile CSV: missing column(s) {', '.join(missing)}", path)
    if len(df) < 2:
        raise InputError("a profile needs at least 2 frames", path)
    for c in ("time", *METRICS):
        if not pd.api.types.is_numeric_dtype(df[c]):
            bad = pd.to_numeric(df[c], errors="coerce").isna() & df[c].notna()
            row = int(np.argmax(bad.to_numpy()))
            raise InputError(f"column {c!r} has a non-number {df[c].iloc[row]!r}", path, row + 2)
        finite = np.isfinite(df[c].to_numpy(float))
        if not finite.all():
            row = int(np.argmin(finite))
            raise InputError(f"column {c!r} has a non-finite value {float(df[c].iloc[row]):g}", path, row + 2)
    t = df["time"].to_numpy(float)
    if len(t) < 2:
        raise InputError("a profile needs at least 2 frames", path)
    if not np.all(np.diff(t) > 0):
        raise InputError("times must increase from row to row", path)
    if "d_area" not in df.columns or "d_width" not in df.columns:
        add_derivatives(df)
    fps = (len(t) - 1) / (t[-1] - t[0]) if even_step(t) else 1.0 / np.median(np.diff(t))
    df.attrs.update(fps=float(f"{fps:.9g}"), source=str(path))
    return df


def _fps(df: pd.DataFrame) -> float:
    fps = df.attrs.get("fps")
    if fps:
        return float(fps)
    return float(1.0 / np.median(np.diff(df["time"].to_numpy(float))))


def l2_distance(a: pd.DataFrame, b: pd.DataFrame, columns: Iterable[str] = METRICS) -> dict[str, float]:
    """L2 distance between two profiles, aligned by time.

    .. math:: d_c(a, b) = \\sqrt{\\sum_k (c_a(t_k) - c_b(t_k))^2}

    over the sample times :math:`t_k` of the profile with the *lower* frame
    rate (``a``'s if equal) that lie in the time span both profiles cover.
    Each profile is linearly interpolated in time onto those :math:`t_k`, so
    videos with different frame rates are compared at common instants; with
    equal rates and start times this is the plain L2 norm of the difference
    of the columns, as in Leach & Maddock (2019) §5.

    Returns
    -------
    dict
        ``{column: distance}``.
    """
    columns = list(columns)
    for name, df in (("first", a), ("second", b)):
        missing = [c for c in ("time", *columns) if c not in df.columns]
        if missing:
            raise InputError(f"{name} profile lacks column(s) {', '.join(missing)}")
    ref = a if _fps(a) <= _fps(b) else b
    ta, tb = a["time"].to_numpy(float), b["time"].to_numpy(float)
    lo, hi = max(ta[0], tb[0]), min(ta[-1], tb[-1])
    eps = 1e-9 * max(1.0, abs(hi))
    grid = ref["time"].to_numpy(float)
    grid = grid[(grid >= lo - eps) & (grid <= hi + eps)]
    if grid.size == 0:
        raise InputError(f"the profiles do not overlap in time ({ta[0]:.3f}-{ta[-1]:.3f} s vs "
                         f"{tb[0]:.3f}-{tb[-1]:.3f} s)")
    out = {}
    for c in columns:
        va = np.interp(grid, ta, a[c].to_numpy(float))
        vb = np.interp(grid, tb, b[c].to_numpy(float))
        out[c] = float(np.sqrt(np.nansum((va - vb) ** 2)))
    return out


def _common_grid(a: pd.DataFrame, b: pd.DataFrame) -> tuple[np.ndarray, float]:
    """Sample times of the lower-rate profile and its frame period."""
    ref = a if _fps(a) <= _fps(b) else b
    return ref["time"].to_numpy(float), 1.0 / _fps(ref)


def pearson(x: np.ndarray, y: np.ndarray) -> float:
    """Pearson correlation :math:`r = \\mathrm{cov}(x, y) / (\\sigma_x \\sigma_y)`; NaN if either is constant."""
    x = np.asarray(x, float) - np.mean(x)
    y = np.asarray(y, float) - np.mean(y)
    den = np.sqrt(np.sum(x * x) * np.sum(y * y))
    return float(np.sum(x * y) / den) if den > 1e-15 else float("nan")


def lagged(a: pd.DataFrame, b: pd.DataFrame, column: str, lag: int) -> tuple[np.ndarray, np.ndarray]:
    """``a(t)`` and ``b(t + lag * dt)`` on the common grid where both are defined.

    ``dt`` is the frame period of the lower-rate profile; a positive ``lag``
    means ``b`` is late (its events happen ``lag`` frames after ``a``'s).
    """
    grid, dt = _common_grid(a, b)
    ta, tb = a["time"].to_numpy(float), b["time"].to_numpy(float)
    shifted = grid + lag * dt
    eps = 1e-9 * max(1.0, float(np.abs(grid).max(initial=0.0)))
    ok = (grid >= ta[0] - eps) & (grid <= ta[-1] + eps) & (shifted >= tb[0] - eps) & (shifted <= tb[-1] + eps)
    va = np.interp(grid[ok], ta, a[column].to_numpy(float))
    vb = np.interp(shifted[ok], tb, b[column].to_numpy(float))
    return va, vb


def within(df: pd.DataFrame, t0: float, t1: float) -> pd.DataFrame:
    """The frames of a profile at times ``t0 <= time <= t1`` (its ``attrs`` kept): the span a comparison is
    made over, e.g. a clip's speech span (:func:`visemeface.speech.audio.speech_span`)."""
    cut = df[(df["time"] >= t0) & (df["time"] <= t1)].reset_index(drop=True)
    cut.attrs.update(df.attrs)
    return cut


def correlation(a: pd.DataFrame, b: pd.DataFrame, columns: Iterable[str] = METRICS, column: str = "height",
                max_lag: int = 5) -> dict:
    """Pearson correlation of two profiles and the time offset that maximises it.

    Returns ``{"r": {column: r at lag 0}, "lag": k, "lag_s": k * dt, "r_lag": r of ``column`` at k}``,
    with ``k`` the integer lag in ``[-max_lag, max_lag]`` frames (of the lower-rate profile) maximising
    the correlation of ``column`` between ``a(t)`` and ``b(t + k dt)`` (see :func:`lagged`); at
    least 3 common samples are needed for a lag to count.
    """
    if max_lag < 0:
        raise InputError(f"max_lag must be >= 0, got {max_lag}")
    for name, df in (("first", a), ("second", b)):
        missing = [c for c in ("time", *columns, column) if c not in df.columns]
        if missing:
            raise InputError(f"{name} profile lacks column(s) {', '.join(missing)}")
    r0 = {c: pearson(*lagged(a, b, c, 0)) for c in columns}
    best, best_r = 0, -np.inf
    for k in range(-max_lag, max_lag + 1):
        va, vb = lagged(a, b, column, k)
        r = pearson(va, vb) if va.size >= 3 else float("nan")
        if np.isfinite(r) and (r > best_r + 1e-12 or (abs(r - best_r) <= 1e-12 and abs(k) < abs(best))):
            best, best_r = k, r
    _, dt = _common_grid(a, b)
    return {"r": r0, "lag": best, "lag_s": best * dt, "r_lag": best_r if np.isfinite(best_r) else float("nan")}


#: An opening's rise ends on its first frame at this share of its highest: the highest frame itself
#: can lie far out on a plateau whose height only wobbles, and a fit through the plateau tapers
#: whatever the rise did.
RISE_TOP = 0.95


def rise_exponent(height) -> float:
    """Power-law exponent :math:`p` of an opening's height rising as :math:`h \\propto t^p`.

    ``height`` holds the opening's heights on the frames since the last closed one, so that the
    first is :math:`t = 1`. The fit (least squares of :math:`\\log h` over :math:`\\log t`) runs up
    to the first frame at :data:`RISE_TOP` of the highest, over the frames with :math:`h > 0`.
    Leach & Maddock (2019), Fig. 19: :math:`p < 1` opens fast and tapers, :math:`p > 1` opens slowly, then faster.
    NaN with fewer than 3 such frames, or with a NaN height anywhere in ``height``.
    """
    h = np.asarray(height, dtype=float)
    if not h.size or not np.isfinite(h).all() or h.max() <= 0:
        return float("nan")
    top = int(np.flatnonzero(h >= RISE_TOP * h.max())[0]) + 1
    t, h = np.arange(1, top + 1, dtype=float), h[:top]
    ok = h > 0
    if ok.sum() < 3:
        return float("nan")
    return float(np.polyfit(np.log(t[ok]), np.log(h[ok]), 1)[0])


def opening_onsets(df: pd.DataFrame, window: int = 6) -> pd.DataFrame:
    """How each mouth opening grows: one row per onset (an open frame after a closed one).

    For each onset frame ``k`` (``count > 0`` at ``k``, ``0`` at ``k - 1``) the opening's run is the
    frames up to the next closed one, at most ``window`` long. Columns: ``frame`` and ``time`` of the
    onset, ``frames`` (the run's length), ``peak_width`` (widest in the run), ``frames_to_90pct`` (the
    run's first frame at >= 90 % of that width, 1 = the onset frame itself: a release that is full
    width as soon as it is seen) and ``height_exponent``: :func:`rise_exponent` of the run's heights.
    """
    count = df["count"].to_numpy()
    width, height = df["width"].to_numpy(float), df["height"].to_numpy(float)
    rows = []
    for k in np.flatnonzero((count[1:] > 0) & (count[:-1] == 0)) + 1:
        run = k + np.arange(min(window, len(count) - k))
        run = run[:np.argmax(count[run] == 0)] if (count[run] == 0).any() else run
        w, h = width[run], height[run]
        rows.append((int(k), float(df["time"].iloc[k]), len(run), float(w.max()),
                     int(np.argmax(w >= 0.9 * w.max())) + 1, rise_exponent(h)))
    return pd.DataFrame(rows, columns=["frame", "time", "frames", "peak_width", "frames_to_90pct",
                                       "height_exponent"])


def shifted_profile(df: pd.DataFrame, seconds: float) -> pd.DataFrame:
    """Copy of a profile with its times moved by ``-seconds`` (undo a lag for plotting)."""
    out = df.copy()
    out["time"] = out["time"] - seconds
    out.attrs.update(df.attrs)
    return out


def plot_profiles(profiles: Mapping[str, pd.DataFrame], path: str | Path,
                  metrics: Iterable[str] = ("count", "area", "width", "height", "d_area", "d_width"),
                  title: str | None = None, force: bool = False) -> None:
    """Plot profiles over time, several videos overlaid (Leach & Maddock 2019, Figs. 16-26), as PNG.

    One panel per metric, stacked with a shared time axis; one line per
    profile, labelled with its key in ``profiles``.
    """
    import matplotlib
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    metrics = list(metrics)
    if not profiles:
        raise InputError("nothing to plot: no profiles")
    for c in metrics:
        if c not in LABELS:
            raise InputError(f"unknown metric {c!r}; known: {', '.join(LABELS)}")
    fig = Figure(figsize=(8, 1.9 * len(metrics) + 0.6), dpi=100, layout="constrained")
    FigureCanvasAgg(fig)
    axes = fig.subplots(len(metrics), 1, sharex=True, squeeze=False)[:, 0]
    for label, df in profiles.items():
        t = df["time"].to_numpy(float)
        mark = "o" if len(t) == 1 else None         # a line through one point (a still image) draws nothing
        for ax, c in zip(axes, metrics):
            y = df[c].to_numpy(float)
            if c == "count":
                ax.step(t, y, where="post", label=label, lw=1.4, marker=mark)
            else:
                ax.plot(t, y, label=label, lw=1.4, marker=mark)
    for ax, c in zip(axes, metrics):
        ax.set_ylabel(LABELS[c])
        ax.grid(True, alpha=0.3)
        if c == "count":
            ax.yaxis.get_major_locator().set_params(integer=True)
        if c.startswith("d_"):
            ax.axhline(0.0, color="0.5", lw=0.6)
    axes[-1].set_xlabel("time (s)")
    axes[0].legend(loc="best", fontsize="small")
    if title:
        fig.suptitle(title)
    # the format follows the suffix (.png, .pdf, .svg); no date and fixed SVG ids: reruns are identical
    fmt = Path(path).suffix.lower().lstrip(".")
    fmt = fmt if fmt in ("pdf", "svg") else "png"
    meta = {"pdf": {"CreationDate": None}, "svg": {"Date": None}}.get(fmt)
    with atomic_output(path, force) as tmp, matplotlib.rc_context({"svg.hashsalt": "visemeface"}):
        fig.savefig(tmp, format=fmt, metadata=meta)
