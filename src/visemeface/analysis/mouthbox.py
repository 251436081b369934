"""Automatic mouth box for real video without a sidecar: from face landmarks, else from colour.

**Landmarks** (default when the optional extra ``visemeface[track]`` is
installed; :func:`landmark_boxes`): MediaPipe's face mesh, tracked frame to
frame (:mod:`~visemeface.analysis.landmarks`), gives the mouth corners
(mesh points 61 and 291) and the outer lip outline in every frame.

- The *natural mouth width* :math:`w_0` that normalises every metric is the
  median corner distance over the frames with closed lips (inner-lip gap
  13-14 at most :data:`CLOSED_GAP` x the corner distance; the clip median when
  fewer than 3 frames are closed), the same for the whole clip
  (``MouthBox.natural_w``).
- The *analysed box* is per frame: the outer lip outline's extent, grown by
  :data:`CORNER_MARGIN` :math:`w_0` to the left and right, so it covers both
  corners of a spread or rounded mouth and the model's few-pixel error.
- Frames where the face is lost take their neighbours' points (linear
  interpolation; ``MouthBox.found`` False where no tracked frame on either side
  had a face: ``analyze`` names them in a warning); a clip where no frame shows a face is an
  :class:`~visemeface.errors.InputError`.

**Colour** (the fallback without the extra; :func:`colour_boxes`): the face by
skin colour, the lips in it by redness:

1. *Face*: skin pixels in YCrCb, :math:`135 \\le C_r \\le 185`,
   :math:`70 \\le C_b \\le 135`, :math:`Y \\ge 40` (the classic skin cluster of
   Chai & Ngan, widened for a warm camera); the largest 8-connected skin region
   of the frame (subsampled to at most 200 px wide), holes (eyes, mouth) filled. It must cover at
   least ``min_face`` of the frame, or there is no face.
2. *Lips*: inside the lower half of the face's bounding box (rows 0.5-0.95 of
   its height, columns 0.2-0.8 of its width) the Lab :math:`a^*` channel is
   split by Otsu's method, and its redder class split again (lips vs flushed
   skin); of the large red regions near the face's vertical axis the lowest is
   the mouth (the nose and the cheeks are above it), joined with a lip region
   straight above or below it (lips parted by an opening). Its left and right
   extremes are the corners.
3. *Tracking*: the face is found again every ``face_every`` frames (it moves
   little in 0.2 s) and at once when the lips are lost; the lips are searched
   in every frame (no drift), and the box centre
   is median-filtered over ``smooth`` frames; the box width -- here both the
   natural mouth width and the analysed extent -- is the median of the per-frame
   widths over the whole clip, so a wide-open or rounded frame does not
   change the scale. Every ``refine_every``-th frame the lips are segmented
   around the red region as the opening detector does
   (:func:`~visemeface.analysis.lips.lip_mask`: skin vs lips inside the box,
   not the whole face), which sets the width and re-centres the box: the
   face-wide red region can take in flushed skin. Their colour fades out just
   before the corners, so ``w`` is :data:`WIDEN` times their width. The box
   reaches from ``0.15 w`` above the red region (the paler upper vermilion) to
   its bottom; :class:`~visemeface.analysis.openings.OpeningDetector` pads it.
   On MPEG-1 (4:2:0 chroma) the lip colour fades 3-6 px before a corner, so
   this box can end inside the mouth (``docs/notes/analysis.md``).

A frame where no lips are found takes the neighbouring frames' box; a clip
where no frame shows a face is an :class:`~visemeface.errors.InputError`.
"""

from __future__ import annotations

from collections.abc import Iterable

import cv2
import numpy as np

from visemeface.analysis.openings import MouthBox
from visemeface.errors import InputError


#: Landmark box: margin beyond the outer lip outline, left and right, in natural mouth widths. Chosen
#: on the three GRID clips of ../shared/realdata: the mesh corners lie up to 3.3 px (0.08 w) inside
#: the hand-read corners (docs/notes/analysis.md).
CORNER_MARGIN = 0.1

#: Landmark box: the face mesh runs on every this-th frame, the frames between interpolated (speed:
#: benchmarks/analyze.py, docs/notes/analysis.md).
LANDMARK_EVERY = 2

#: Landmark box: lips count as closed (rest) when the inner-lip gap is at most this x the corner distance.
CLOSED_GAP = 0.05

#: Landmark box: the analysis measures widths along the frame's rows and heights along its columns, so
#: a face turned in the frame by more than this (degrees; the median angle of the line between the
#: mouth corners) is an InputError rather than silently swapped metrics. Chosen, not tuned: at 30
#: degrees a width reads cos 30 = 0.87 of itself; the GRID clips of ../shared/realdata roll 1-4 degrees.
MAX_ROLL_DEG = 30.0

#: Landmark box: a face is upside down when the face detector scores the frame turned 180 degrees higher than
#: the frame itself by more than this. The face mesh then fits an upright face to it (its mouth on the eyes)
#: and the corner line reads level, so the roll check alone passed it. Chosen from one measurement, not
#: tuned: the best detection scores 0.88-0.97 upright against 0.57-0.69 turned on the three GRID clips of
#: ../shared/realdata and a grey-scale copy of one, and 0.63-0.64 against 0.88-0.89 on swwp2s turned over.
UPSIDE_DOWN_MARGIN = 0.1

#: Box width / width of the segmented lips. Tuned on the three GRID clips of ../shared/realdata:
#: the lips' colour fades out 1-3 px before the hand-read corners of a 35-40 px mouth.
WIDEN = 1.12


def face_mask(rgb: np.ndarray, min_face: float = 0.02) -> tuple[np.ndarray, tuple] | None:
    """Skin mask of the largest skin region (holes filled) and its box ``(x, y, w, h)``, or None."""
    ycc = cv2.cvtColor(rgb, cv2.COLOR_RGB2YCrCb)
    skin = cv2.inRange(ycc, (40, 135, 70), (255, 185, 135))
    skin = cv2.morphologyEx(skin, cv2.MORPH_OPEN, np.ones((3, 3), np.uint8))
    n, labels, stats, _ = cv2.connectedComponentsWithStats(skin, connectivity=8)
    if n < 2:
        return None
    i = 1 + int(np.argmax(stats[1:, cv2.CC_STAT_AREA]))
    if stats[i, cv2.CC_STAT_AREA] < min_face * skin.size:
        return None
    x, y, w, h = (int(v) for v in stats[i, :4])
    region = (labels[y:y + h, x:x + w] == i).astype(np.uint8)
    contours, _ = cv2.findContours(region, cv2.RETR_EXTERNAL, cv2.CHAIN_APPROX_SIMPLE)
    filled = np.zeros_like(region)
    cv2.drawContours(filled, contours, -1, 1, cv2.FILLED)
    return filled.view(bool), (x, y, w, h)


def _subsample(img: np.ndarray, k: int) -> np.ndarray:
    """Every ``k``-th pixel of every ``k``-th row (nearest neighbour), contiguous."""
    if k <= 1:
        return np.ascontiguousarray(img)
    h, w = img.shape[:2]
    return cv2.resize(img, ((w + k - 1) // k, (h + k - 1) // k), interpolation=cv2.INTER_NEAREST)


def find_face(rgb: np.ndarray, min_face: float = 0.02):
    """The face for :func:`find_lips`: its skin mask and box on the lips' grid, or None."""
    f = max(1, int(np.ceil(rgb.shape[1] / 400)))
    k = max(1, int(np.ceil(rgb.shape[1] / 200 / f)))          # the face's grid is k times coarser
    found = face_mask(_subsample(rgb, f * k), min_face)
    if found is None:
        return None
    coarse, (fx, fy, fw, fh) = found
    hs, ws = (rgb.shape[0] + f - 1) // f, (rgb.shape[1] + f - 1) // f
    fx, fy, fw, fh = fx * k, fy * k, min(fw * k, ws - fx * k), min(fh * k, hs - fy * k)
    face = cv2.resize(coarse.view(np.uint8), (fw, fh), interpolation=cv2.INTER_NEAREST).view(bool) \
        if k > 1 else coarse
    return face, (fx, fy, fw, fh)


def find_lips(rgb: np.ndarray, min_face: float = 0.02, face=None) -> tuple[float, float, float, float] | None:
    """Lip extent ``(x_left, x_right, y_top, y_bottom)`` in frame pixels, or None (no face or no lips).

    The face (:func:`find_face`, or ``face`` found in a nearby frame) is
    found on a frame subsampled to at most 200 px wide, the lips on one at most
    400 px wide; see the module notes.
    """
    f = max(1, int(np.ceil(rgb.shape[1] / 400)))
    small = _subsample(rgb, f)
    found = face if face is not None else find_face(rgb, min_face)
    if found is None:
        return None
    face, (fx, fy, fw, fh) = found
    y0, y1 = int(0.5 * fh), int(0.95 * fh)
    x0, x1 = int(0.2 * fw), int(0.8 * fw)
    if y1 - y0 < 4 or x1 - x0 < 4:
        return None
    sub = np.ascontiguousarray(small[fy + y0:fy + y1, fx + x0:fx + x1])
    inside = face[y0:y1, x0:x1]
    a = cv2.GaussianBlur(cv2.cvtColor(sub, cv2.COLOR_RGB2LAB)[..., 1], (3, 3), 0)
    vals = a[inside]
    if vals.size < 16:
        return None
    t, _ = cv2.threshold(vals.reshape(1, -1), 0, 255, cv2.THRESH_BINARY + cv2.THRESH_OTSU)
    upper = vals[vals > t]          # the redder half of the face, split again: lips vs flushed skin
    if upper.size >= 16:
        t, _ = cv2.threshold(upper.reshape(1, -1), 0, 255, cv2.THRESH_BINARY + cv2.THRESH_OTSU)
    red = ((a > t) & inside).view(np.uint8)
    red = cv2.morphologyEx(red, cv2.MORPH_OPEN, np.ones((2, 2), np.uint8))
    n, labels, stats, cents = cv2.connectedComponentsWithStats(red, connectivity=8)
    if n < 2:
        return None
    axis = fw / 2 - x0
    area = stats[1:, cv2.CC_STAT_AREA].astype(float)
    near = np.abs(cents[1:, 0] - axis) <= 0.15 * fw
    big = near & (area >= 0.2 * area[near].max()) if near.any() else area >= 0.2 * area.max()
    # The mouth is the lowest of the large red regions near the face's axis (the nose is above it).
    i = 1 + int(np.argmax(np.where(big, cents[1:, 1], -np.inf)))
    x, y, w, h = (int(v) for v in stats[i, :4])
    # Lips parted by the opening are two regions: join those straight above or below this one.
    for j in range(1, n):
        xj, yj, wj, hj = (int(v) for v in stats[j, :4])
        if j != i and area[j - 1] >= 0.2 * area[i - 1] and abs(cents[j, 0] - cents[i, 0]) <= 0.25 * w \
                and 0.5 * w <= wj <= 1.5 * w and min(abs(yj + hj - y), abs(y + h - yj)) <= 0.25 * w:
            x1_, y1_ = max(x + w, xj + wj), max(y + h, yj + hj)
            x, y = min(x, xj), min(y, yj)
            w, h = x1_ - x, y1_ - y
    if w < 3:
        return None
    ox, oy = fx + x0, fy + y0
    return ((ox + x) * f, (ox + x + w) * f, (oy + y) * f, (oy + y + h) * f)


def _median_filter(v: np.ndarray, k: int) -> np.ndarray:
    if k <= 1 or v.size < 3:
        return v
    r = k // 2
    padded = np.pad(v, r, mode="edge")
    return np.median(np.lib.stride_tricks.sliding_window_view(padded, 2 * r + 1), axis=1)


def lip_extent(frame: np.ndarray, red) -> tuple[float, float, float] | None:
    """Left and right end of the lips segmented by :func:`~visemeface.analysis.lips.lip_mask`
    around a red region ``(x_left, x_right, y_top, y_bottom)``, and the region's centre x."""
    from visemeface.analysis.lips import lip_mask, work_scale

    x_l, x_r, y_t, y_b = red
    w = max(4.0, x_r - x_l)
    box = MouthBox.of((x_l, y_t - 0.15 * w, w, y_b - y_t + 0.15 * w))
    x0, y0 = max(0, int(box.x - 0.25 * w)), max(0, int(box.y - 0.1 * w))
    x1, y1 = min(frame.shape[1], int(box.x + 1.25 * w)), min(frame.shape[0], int(box.y + box.h + 0.4 * w))
    s = work_scale(box.w)
    crop = cv2.resize(np.ascontiguousarray(frame[y0:y1, x0:x1]), None, fx=s, fy=s, interpolation=cv2.INTER_LINEAR)
    lips, t = lip_mask(crop, tuple(int(round(v * s)) for v in (box.x - x0, box.y - y0, box.w, box.h)), s)
    cols = np.flatnonzero(lips.any(axis=0))
    if t is None or cols.size < 2:
        return None
    return (cols[0] + 0.5) / s - 0.5 + x0, (cols[-1] + 0.5) / s - 0.5 + x0, (x_l + x_r) / 2


def track_mouth(frames: Iterable[np.ndarray], source: str = "", method: str | None = None) -> list[MouthBox]:
    """One mouth box per frame (see the module notes); raises InputError if no frame shows a face.

    ``method`` is ``"landmarks"``, ``"colour"`` or None: landmarks when the
    optional extra ``visemeface[track]`` is installed, else colour.
    """
    from visemeface.analysis import landmarks

    if method is None:
        method = "landmarks" if landmarks.available() else "colour"
    if method == "landmarks":
        return landmark_boxes(frames, source)
    if method == "colour":
        return colour_boxes(frames, source=source)
    raise InputError(f"mouth box method must be 'landmarks' or 'colour', got {method!r}")


def _no_face(n: int, source: str) -> InputError:
    where = f" in {source}" if source else ""
    if not n:
        return InputError(f"no frames{where}")
    return InputError(f"no face found{where}: give the mouth box with --box X,Y,W,H or --box-json FILE")


def _fill_gaps(values: np.ndarray, ok: np.ndarray) -> np.ndarray:
    """Rows of ``values`` (frames x ...) where ``ok`` is False, interpolated linearly from the others."""
    flat = values.reshape(len(values), -1).astype(float)
    idx = np.arange(len(values))
    for j in range(flat.shape[1]):
        flat[:, j] = np.interp(idx, idx[ok], flat[ok, j])
    return flat.reshape(values.shape)


def natural_width(corners: np.ndarray, gap: np.ndarray) -> float:
    """Median corner distance over the closed-lip frames (gap <= CLOSED_GAP x it), else over all.

    ``corners`` is ``(n, 2, 2)`` (frame, corner, xy), ``gap`` the inner-lip gap ``(n,)`` in pixels.
    """
    dist = np.linalg.norm(corners[:, 1] - corners[:, 0], axis=1)
    closed = gap <= CLOSED_GAP * dist
    return float(np.median(dist[closed] if closed.sum() >= 3 else dist))


def _check_upright(corners: np.ndarray, source: str) -> None:
    """InputError when the mouth-corner line ``corners`` ``(n, 2, 2)`` turns more than MAX_ROLL_DEG."""
    d = corners[:, 1] - corners[:, 0]
    roll = float(np.degrees(np.arctan2(np.median(d[:, 1]), np.median(d[:, 0]))))
    if abs(roll) > MAX_ROLL_DEG:
        where = f"{source}: " if source else ""
        raise InputError(f"{where}the face is turned {roll:+.0f} degrees in the frame (more than "
                         f"{MAX_ROLL_DEG:.0f}); the analysis needs an upright face: rotate the video first "
                         f"(e.g. ffmpeg -vf transpose=1 or 2)")


def _check_not_upside_down(frame: np.ndarray, models, source: str) -> None:
    """InputError when ``frame``'s face is upside down (:data:`UPSIDE_DOWN_MARGIN`)."""
    def best(img):
        faces = models.detect(np.ascontiguousarray(img))
        return faces[0].score if faces else 0.0

    own, turned = best(frame), best(frame[::-1, ::-1])
    if turned > own + UPSIDE_DOWN_MARGIN:
        where = f"{source}: " if source else ""
        raise InputError(f"{where}the face is upside down (the face detector scores the frame turned over "
                         f"{turned:.2f}, as it is {own:.2f}); the analysis needs an upright face: rotate the "
                         "video first (e.g. ffmpeg -vf transpose=1,transpose=1)")


def landmark_boxes(frames: Iterable[np.ndarray], source: str = "", tracker=None,
                   every: int | None = None) -> list[MouthBox]:
    """Per-frame boxes from face-mesh landmarks tracked on every ``every``-th frame (default
    :data:`LANDMARK_EVERY`) and the last, the frames between interpolated (module notes);
    ``tracker`` a :class:`~visemeface.analysis.landmarks.FaceTracker` (default: a new one)."""
    from visemeface.analysis.landmarks import FaceTracker, settings

    tracker = tracker or FaceTracker()
    every = max(1, int(every or LANDMARK_EVERY))
    cfg = settings()["mouth"]
    keep = np.array(cfg["outer"] + cfg["corners"] + [cfg["upper_inner"], cfg["lower_inner"]] + cfg["inner"])
    found, size, last = [], None, None
    for i, frame in enumerate(frames):
        size = frame.shape[1], frame.shape[0]
        pts = tracker(frame) if i % every == 0 else None
        if pts is not None and not any(f is not None for f in found) and hasattr(tracker, "models"):
            _check_not_upside_down(frame, tracker.models, source)       # once, on the first face found
        found.append(None if pts is None else pts[keep])
        last = frame
    if found and found[-1] is None and (len(found) - 1) % every:
        pts = tracker(last)
        found[-1] = None if pts is None else pts[keep]
    ok = np.array([f is not None for f in found])
    if not ok.any():
        raise _no_face(len(found), source)
    pts = _fill_gaps(np.array([f if f is not None else np.full((len(keep), 2), np.nan) for f in found]), ok)
    n_out = len(cfg["outer"])
    outer, corners, inner = pts[:, :n_out], pts[:, n_out:n_out + 2], pts[:, n_out + 2:n_out + 4]
    contours = np.concatenate([outer, pts[:, n_out + 4:]], axis=1)          # (n, 40, 2): outer, inner
    _check_upright(corners, source)
    w0 = natural_width(corners, np.linalg.norm(inner[:, 1] - inner[:, 0], axis=1))
    lo = np.minimum(outer.min(axis=1), corners.min(axis=1))
    hi = np.maximum(outer.max(axis=1), corners.max(axis=1))
    margin = CORNER_MARGIN * w0
    x0 = np.clip(np.floor(lo[:, 0] - margin), 0, size[0] - 4).astype(int)
    x1 = np.clip(np.ceil(hi[:, 0] + margin), x0 + 3, size[0] - 1).astype(int)
    y0 = np.clip(np.floor(lo[:, 1]), 0, size[1] - 4).astype(int)
    y1 = np.clip(np.ceil(hi[:, 1]), y0 + 3, size[1] - 1).astype(int)
    nat = max(4, int(round(w0)))
    tried = np.arange(len(found)) % every == 0
    tried[-1] = True                        # the last frame is always tracked (see above)
    # a frame has no face when the tried frames on both sides of it (those that exist) had none
    idx = np.flatnonzero(tried)
    lost = np.interp(np.arange(len(found)), idx, (~ok[idx]).astype(float)) == 1.0
    return [MouthBox(int(a), int(b), int(c - a + 1), int(d - b + 1), nat, not bool(g), lips)
            for a, b, c, d, g, lips in zip(x0, y0, x1, y1, lost, contours)]


def colour_boxes(frames: Iterable[np.ndarray], smooth: int = 5, min_face: float = 0.02,
                 source: str = "", face_every: int = 5, refine_every: int = 5) -> list[MouthBox]:
    """One mouth box per frame by skin and lip colour (module notes, the fallback); raises
    InputError if no frame shows a face."""
    found, size, face, age, fine = [], None, None, 0, []
    for frame in frames:
        size = frame.shape[1], frame.shape[0]
        if face is None or age >= face_every:
            face, age = find_face(frame, min_face), 0
        lips = find_lips(frame, min_face, face) if face is not None else None
        if lips is None and age > 0:            # lost: look for the face again
            face, age = find_face(frame, min_face), 0
            lips = find_lips(frame, min_face, face) if face is not None else None
        age += 1
        found.append(lips)
        if lips is not None and len(found) % refine_every == 1:
            fine.append(lip_extent(frame, lips))
    ok = np.array([f is not None for f in found], bool)
    if not ok.any():
        raise _no_face(len(found), source)
    # frames without lips: interpolate from their neighbours
    ext = _fill_gaps(np.array([f if f is not None else (np.nan,) * 4 for f in found], float), ok)
    cx = _median_filter((ext[:, 0] + ext[:, 1]) / 2, smooth)
    fine = np.array([f for f in fine if f is not None], float).reshape(-1, 3)
    if len(fine):
        # The lips as the opening detector segments them (the box's own skin/lip split) set the
        # width and shift the centre: the face-wide red region can take in flushed skin.
        width = WIDEN * float(np.median(fine[:, 1] - fine[:, 0]))
        cx = cx + float(np.median((fine[:, 0] + fine[:, 1]) / 2 - fine[:, 2]))
    else:
        width = WIDEN * float(np.median(ext[:, 1] - ext[:, 0]))
    top = _median_filter(ext[:, 2], smooth)
    bottom = _median_filter(ext[:, 3], smooth)
    w = max(4, int(round(width)))
    boxes = []
    for x, y0, y1, has in zip(cx, top, bottom, ok):
        # From a little above the red region (the pale upper vermilion) to its bottom.
        h = max(4, int(round(y1 - y0 + 0.15 * w)))
        bx = int(np.clip(round(x - w / 2), 0, size[0] - w))
        by = int(np.clip(round(y0 - 0.15 * w), 0, size[1] - h))
        boxes.append(MouthBox(bx, by, w, h, found=bool(has)))
    return boxes
