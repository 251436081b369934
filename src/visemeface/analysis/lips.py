"""Mouth opening as the region enclosed between the lips (the default method of ``analyze``).

Real mouths are rarely a dark hole: teeth and tongue fill most open frames, and
a grey threshold (Leach & Maddock's (2018) method, :mod:`~visemeface.analysis.openings`)
finds only dark specks there. Lips, however, are redder than the skin around
them and than teeth or the cavity, so this method segments the **lips** by
colour and calls *opening* whatever lies between the upper and the lower lip:

1. The analysed region is resampled so that the mouth is at least
   :data:`WORK_WIDTH` px wide (factor :math:`s = \\max(1, W_0 / w)`; never
   shrunk, so large renders are analysed at full resolution): a 40 px MPEG-1
   mouth gets sub-pixel outlines and every kernel below is a fixed fraction
   of the mouth width.
2. Lip chroma: CIE Lab :math:`a^*` (OpenCV's 8-bit scale, neutral = 128),
   Gaussian-smoothed with :math:`\\sigma = 0.75\\,s` (0.75 original pixels: MPEG noise). Lips: :math:`a^* \\ge t`
   with :math:`t` found by Otsu's method on the pixels of the mouth box (skin
   vs lips), accepted only if the classes differ by at least ``min_chroma``.
3. Dark-cavity cue (the seed's): pixels with luma
   :math:`Y \\le` ``dark_ratio`` :math:`\\times \\mathrm{median}(Y_{lips})` are
   never lip, whatever their hue (a dark red throat).
4. Lip components are kept when they reach into the central band of the box
   (the middle half of its width): a red nostril, the chin or a cheek far from
   the mouth do not count.
5. *Enclosed between the lips*: a non-lip pixel with a lip pixel above it and
   a lip pixel below it in the same column,
   :math:`E = \\neg L \\wedge \\mathrm{cummax}_{\\downarrow} L \\wedge \\mathrm{cummax}_{\\uparrow} L`.
   Teeth, tongue and cavity are all included; a moustache or the nostrils lie
   above the upper lip and never are.
6. A connected region less than ``min_height`` :math:`\\cdot w` thick is the
   seam between closed lips (a dark line one or two pixels high), not an
   opening; nor is one touching the analysed region's border or lying wholly
   below the box (see :func:`plausible_openings`), nor one with nothing darker
   or greyer than lip in it (:func:`not_seam`).

The mask is returned at the working scale; :class:`~visemeface.analysis.openings.OpeningDetector`
measures its outlines and divides by ``s``.
"""

from __future__ import annotations

import cv2
import numpy as np

from visemeface.numeric import quantile

#: The mouth is resampled to at least this width (px) before segmentation.
WORK_WIDTH = 120


def work_scale(mouth_width: float) -> float:
    """Resampling factor :math:`s = \\max(1, W_0 / w)`, :math:`W_0` = :data:`WORK_WIDTH`."""
    return max(1.0, WORK_WIDTH / float(mouth_width))


def _odd(n: float) -> int:
    return max(1, 2 * int(round((n - 1) / 2)) + 1)


def _otsu_float(values: np.ndarray) -> tuple[float, float, float]:
    """Otsu split of 8-bit-range values: threshold and the two class means."""
    hist = np.bincount(np.clip(values, 0, 255).astype(np.int64).ravel(), minlength=256).astype(np.float64)
    levels = np.arange(256, dtype=np.float64)
    w0 = np.cumsum(hist)
    m0 = np.cumsum(hist * levels)
    total, mtot = w0[-1], m0[-1]
    w1 = total - w0
    with np.errstate(divide="ignore", invalid="ignore"):
        mu0 = m0 / w0
        mu1 = (mtot - m0) / w1
        sb = np.where((w0 > 0) & (w1 > 0), w0 * w1 * (mu1 - mu0) ** 2, -1.0)
    t = int(np.argmax(sb))
    if sb[t] <= 0:
        return float(t), float(mtot / max(total, 1)), float(mtot / max(total, 1))
    return t + 0.5, float(mu0[t]), float(mu1[t])


def lip_mask(crop: np.ndarray, box_in_crop: tuple[int, int, int, int], scale: float = 1.0,
             min_chroma: float = 6.0, dark_ratio: float = 0.45, dark_level: float | None = None) -> tuple[np.ndarray, float | None]:
    """Boolean lip mask of an RGB crop (already at working scale) and the :math:`a^*` threshold.

    ``box_in_crop`` is the mouth box ``(x, y, w, h)`` in crop pixels, ``scale``
    the resampling factor of the crop (smoothing is 0.75 original pixels). Returns an
    all-False mask and None when no lip class stands out by ``min_chroma``
    :math:`a^*` levels from the skin (no mouth to measure). ``dark_level``
    (a grey level) replaces the relative dark cue when given.
    """
    bx, by, bw, bh = box_in_crop
    sigma = 0.75 * scale
    lab = cv2.cvtColor(crop, cv2.COLOR_RGB2LAB)
    a = cv2.GaussianBlur(lab[..., 1].astype(np.float32), (0, 0), sigma)
    grey = cv2.GaussianBlur(cv2.cvtColor(crop, cv2.COLOR_RGB2GRAY).astype(np.float32), (0, 0), sigma)
    inside = a[max(0, by):by + bh, max(0, bx):bx + bw]
    t, mu_skin, mu_lip = _otsu_float(inside)
    if mu_lip - mu_skin < min_chroma:
        return np.zeros(a.shape, bool), None
    lips = a >= t
    if not lips.any():
        return lips, None
    cut = dark_level if dark_level is not None else dark_ratio * float(np.median(grey[lips]))
    lips &= grey > cut
    k = _odd(0.04 * bw)
    kernel = cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (k, k))
    m = cv2.morphologyEx(lips.view(np.uint8), cv2.MORPH_OPEN, kernel)
    n, labels, stats, _ = cv2.connectedComponentsWithStats(m, connectivity=8)
    keep = np.zeros(n, bool)
    cx0, cx1 = bx + bw // 4, bx + bw - bw // 4
    for i in range(1, n):
        x, y, w, h, area = stats[i]
        # In the box's rows, or a wide lip just below them (the lower lip of a dropped jaw).
        rows = y < by + bh and y + h > by or (by + bh <= y <= by + bh + 0.5 * bw and w >= 0.4 * bw)
        keep[i] = x < cx1 and x + w > cx0 and rows and area >= 0.002 * bw * bw
    if keep.any():          # a nostril or a fleck of red skin beside the lips is not a lip
        keep &= stats[:, cv2.CC_STAT_AREA] >= 0.1 * stats[keep, cv2.CC_STAT_AREA].max()
    return keep[labels], t


def enclosed_mask(lips: np.ndarray) -> np.ndarray:
    """Non-lip pixels with lip above and below in their column (boolean)."""
    above = np.maximum.accumulate(lips, axis=0)
    below = np.maximum.accumulate(lips[::-1], axis=0)[::-1]
    return ~lips & above & below


def lips_opening_mask(crop: np.ndarray, box_in_crop, mouth_width: int, min_height: float = 0.05,
                      min_chroma: float = 6.0, dark_ratio: float = 0.45,
                      dark_level: float | None = None) -> tuple[np.ndarray, float | None, float]:
    """uint8 opening mask (255 = opening) at the working scale, the lip threshold and the scale.

    Parameters
    ----------
    crop : ndarray (H, W, 3) uint8
        RGB region around the mouth (original pixels).
    box_in_crop : (x, y, w, h)
        The mouth box in ``crop`` pixels.
    mouth_width : int
        Natural mouth width ``w`` (px), which sets the working scale.
    min_height : float
        Openings thinner than this (fraction of ``w``) are a seam, narrower a speck, not an opening.
    """
    s = work_scale(mouth_width)
    if s > 1.0:
        crop = cv2.resize(crop, None, fx=s, fy=s, interpolation=cv2.INTER_LINEAR)
    box = tuple(int(round(v * s)) for v in box_in_crop)
    lips, t = lip_mask(crop, box, s, min_chroma, dark_ratio, dark_level)
    if t is None:
        return np.zeros(lips.shape, np.uint8), None, s
    opening = plausible_openings(enclosed_mask(lips).view(np.uint8), box, min_height * mouth_width * s)
    return not_seam(opening, lips, crop) * np.uint8(255), t, s


#: An opening holds something unlike lips: its darkest tenth or its mean chroma is at most this
#: fraction of the lips' (median). Tuned on the three GRID clips: open frames <= 0.67, the dark
#: red seam of closed lips >= 0.79.
LIP_LIKENESS = 0.75


def not_seam(opening: np.ndarray, lips: np.ndarray, crop: np.ndarray) -> np.ndarray:
    """Drop regions of a 0/1 uint8 mask that look like lip: the shaded seam between closed lips.

    A region is kept when
    :math:`\\min(P_{10}(L) / \\tilde L_{lips},\\ \\bar C / \\tilde C_{lips}) \\le`
    :data:`LIP_LIKENESS`, with Lab lightness :math:`L`, chroma
    :math:`C = \\sqrt{a^{*2} + b^{*2}}` and :math:`P_{10}` the 10th percentile:
    cavity (dark) or teeth (grey) inside, not just darker lip.
    """
    if not opening.any() or not lips.any():
        return opening
    lab = cv2.cvtColor(crop, cv2.COLOR_RGB2LAB).astype(np.float32)
    light = lab[..., 0]
    chroma = np.hypot(lab[..., 1] - 128.0, lab[..., 2] - 128.0)
    l_lips = max(float(np.median(light[lips])), 1.0)
    c_lips = max(float(np.median(chroma[lips])), 1.0)
    n, labels = cv2.connectedComponents(opening, connectivity=8)
    keep = np.zeros(n, bool)
    for i in range(1, n):
        sel = labels == i
        likeness = min(float(np.percentile(light[sel], 10)) / l_lips, float(chroma[sel].mean()) / c_lips)
        keep[i] = likeness <= LIP_LIKENESS
    kept = keep[labels]
    # Trim the shaded inner lip off the kept regions: in each column, the span from the first
    # to the last pixel unlike lip (dark or grey) inside the region.
    unlike = kept & ((light <= LIP_LIKENESS * l_lips) | (chroma <= LIP_LIKENESS * c_lips))
    rows = np.arange(opening.shape[0])[:, None]
    big = opening.shape[0]
    first = np.where(unlike, rows, big).min(axis=0)
    last = np.where(unlike, rows, -1).max(axis=0)
    span = ((rows >= first) & (rows <= last) & kept).view(np.uint8)
    # Columns of shaded lip between two teeth would split one opening in two: bridge gaps of up
    # to half the regions' width, inside the untrimmed region.
    k = _odd(0.5 * max(1, int(np.count_nonzero(kept.any(axis=0)))))
    if k > 1:
        span = cv2.morphologyEx(span, cv2.MORPH_CLOSE, np.ones((1, k), np.uint8)) & kept.view(np.uint8)
    return span


def plausible_openings(opening: np.ndarray, box, min_px: float) -> np.ndarray:
    """Keep the connected regions of a 0/1 uint8 mask that can be a mouth opening (0/1 uint8).

    A region is dropped when it is less than ``min_px`` thick (the 90th
    percentile of its column heights: the seam of closed lips is a long thin
    curve, perhaps with a blob at a corner) or less than ``min_px`` wide (a
    corner's blob of compressed colour, taller than wide), touches the border
    of the analysed region (an opening is surrounded by lips; skin folds at the
    crop's edge are not), or lies wholly below the mouth box ``(x, y, w, h)``
    (skin between the lower lip and a reddish chin).
    """
    n, labels, stats, _ = cv2.connectedComponentsWithStats(opening, connectivity=8)
    x, y, w, h = (stats[:, i] for i in (cv2.CC_STAT_LEFT, cv2.CC_STAT_TOP, cv2.CC_STAT_WIDTH, cv2.CC_STAT_HEIGHT))
    rows, cols = opening.shape
    keep = (h >= min_px) & (w >= min_px) & (x > 0) & (y > 0) & (x + w < cols) & (y + h < rows) & (y < box[1] + box[3])
    keep[0] = False
    for i in np.flatnonzero(keep):
        cols = (labels[y[i]:y[i] + h[i], x[i]:x[i] + w[i]] == i).sum(axis=0)
        keep[i] = quantile(cols[cols > 0], 0.9) >= min_px
    return keep[labels].view(np.uint8)
