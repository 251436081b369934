"""Per-frame mouth-opening detection (Leach & Maddock 2019, §4).

The *mouth box* ``(x, y, w, h)`` is in pixel coordinates, origin top-left,
x to the right, y down; its left and right edges lie on the mouth corners at
rest, so ``w`` is the natural mouth width that normalises every metric. The
frame is cropped to the box grown by ``pad`` (fractions of ``w``: left, top,
right, bottom; default ``0.1, 0.1, 0.1, 0.4``, clipped to the frame) because
a box drawn on the rest lips -- as the renderer writes it -- would cut off a
jaw-opened mouth; ``pad=0`` analyses exactly the box, as Leach & Maddock (2019) do.
Inside that region:

1. Rec.601 luma, :math:`Y = 0.299 r + 0.587 g + 0.114 b`.
2. Median blur with an odd kernel scaled to the mouth width (applied to the
   thresholded image by threshold decomposition, see :func:`median_mask`),
   :math:`k = \\max(3, \\mathrm{odd}(\\mathrm{round}(11 w / 800)))` (Leach & Maddock 2019:
   11 px for an 800 px mouth), which removes noise and small highlights.
3. Binary threshold: the opening is *dark*, ``Y <= t``. ``t`` is fixed or found
   by Otsu's method (see :func:`otsu_threshold`).
4. Optional teeth handling: low-saturation, bright pixels (HSV) that touch a
   dark region are darkened, i.e. counted as opening.
5. Top-level contours only (``RETR_EXTERNAL``): a bright tongue or a specular
   highlight inside an opening is a hole, not a split. Optionally each
   contour is replaced by its convex hull. Openings smaller than
   ``min_area * w**2`` are dropped.
6. Metrics per opening (Leach & Maddock's (2019) four): the count; the area (pixels inside
   or on the filled contour); the width :math:`\\max x - \\min x + 1` and
   height :math:`\\max y - \\min y + 1` of those pixels (Leach & Maddock's (2019) extents,
   counted in covered pixel columns/rows so that a one-pixel slit is 1 px
   wide and a digitised ellipse of semi-axes ``a, b`` measures ``2a x 2b``). Widths and heights are divided by
   ``w``, areas by ``w**2``, so every value is dimensionless and independent
   of the video resolution.

Example
-------
>>> from visemeface.analysis.synthetic import Ellipse, mouth_image
>>> img = mouth_image((256, 256), (28, 78, 200, 100), [Ellipse(128, 128, 40, 12)])
>>> op = detect_openings(img, (28, 78, 200, 100))
>>> op.count
1
>>> abs(op.largest_width * 200 - 80) <= 2   # 2a = 80 px
True
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field

import cv2
import numpy as np

from visemeface.analysis.lips import lips_opening_mask
from visemeface.errors import InputError

#: Rec.601 luma weights for (r, g, b).
REC601 = (0.299, 0.587, 0.114)

#: Largest coordinate or side of a mouth box in pixels (frames are far smaller; 1e308 was echoed in 309 digits).
MAX_BOX_PX = 100_000

#: Opening detection methods: inside the face mesh's inner-lip contour by evidence relative to the lips
#: (default, :mod:`~visemeface.analysis.innerlip`), the region between the lips segmented by colour, and
#: Leach & Maddock's (2019) grey threshold.
METHODS = ("mesh", "lips", "seed")


@dataclass(frozen=True)
class MouthBox:
    """Pixel box ``(x, y, w, h)`` around the mouth; ``w`` spans corner to corner.

    ``natural_w`` (0: the same as ``w``) is the natural mouth width that
    normalises every metric, when the analysed box is not that wide: an
    automatic per-frame box follows the corners of a spread or rounded mouth
    while the scale stays the rest width (:mod:`~visemeface.analysis.mouthbox`).
    ``found`` is False for an automatic box taken from neighbouring frames
    because no face was found in and around this one. ``lips`` (None: not
    known) holds the face mesh's lip outlines in frame pixels, ``(40, 2)``:
    the outer contour's 20 points then the inner contour's 20
    (``data/models/face.toml`` ``mouth.outer`` and ``mouth.inner``), which
    bound where the default method looks for an opening.
    """

    x: int
    y: int
    w: int
    h: int
    natural_w: int = 0
    found: bool = True
    lips: np.ndarray | None = field(default=None, compare=False, repr=False)

    @property
    def mouth_width(self) -> int:
        """The natural mouth width in pixels: ``natural_w`` if set, else ``w``."""
        return self.natural_w or self.w

    @classmethod
    def of(cls, box) -> MouthBox:
        """Coerce a ``MouthBox`` or a 4-sequence of numbers (rounded to pixels)."""
        if isinstance(box, MouthBox):
            return box
        try:
            vals = [float(v) for v in box]
        except (TypeError, ValueError):
            raise InputError(f"mouth box must be 4 numbers x,y,w,h, got {box!r}") from None
        if len(vals) != 4 or not all(np.isfinite(vals)) or max(map(abs, vals)) > MAX_BOX_PX:
            shown = ",".join(f"{v:g}" for v in vals)
            raise InputError(f"mouth box must be 4 finite numbers x,y,w,h of at most {MAX_BOX_PX} px, got {shown}")
        x, y, w, h = (int(round(v)) for v in vals)
        if w < 4 or h < 4:
            raise InputError(f"mouth box {x},{y},{w},{h} is too small (w and h must be >= 4 px)")
        return cls(x, y, w, h)

    def check_inside(self, width: int, height: int) -> None:
        """Raise :class:`InputError` unless the box lies inside a ``width`` x ``height`` frame."""
        if self.x < 0 or self.y < 0 or self.x + self.w > width or self.y + self.h > height:
            raise InputError(
                f"mouth box {self.x},{self.y},{self.w},{self.h} (x,y,w,h) is outside the "
                f"{width}x{height} frame")

    def region(self, pad, width: int, height: int) -> tuple[int, int, int, int]:
        """``(x0, y0, x1, y1)`` of the box grown by ``pad`` (left, top, right, bottom) x the natural
        mouth width, clipped."""
        self.check_inside(width, height)
        left, top, right, bottom = (float(p) * self.mouth_width for p in pad)
        return (max(0, int(round(self.x - left))), max(0, int(round(self.y - top))),
                min(width, int(round(self.x + self.w + right))), min(height, int(round(self.y + self.h + bottom))))


@dataclass(frozen=True)
class Openings:
    """Mouth openings found in one frame, largest first.

    Attributes
    ----------
    area, width, height : ndarray (count,)
        Per opening, normalised: area / w**2, width / w, height / w.
    contours : tuple of ndarray (k, 1, 2) int32
        Outline of each opening in full-frame pixel coordinates (hull if asked).
    mouth_width : int
        The natural mouth width ``w`` in pixels.
    threshold : float or None
        The grey level used (None when Otsu found no dark class: no opening).
    box : MouthBox or None
        The mouth box the frame was measured in.
    """

    area: np.ndarray
    width: np.ndarray
    height: np.ndarray
    contours: tuple = field(repr=False)
    mouth_width: int
    threshold: float | None
    box: MouthBox | None = None

    @property
    def count(self) -> int:
        """Number of mouth openings."""
        return int(self.area.size)

    def _largest(self, arr: np.ndarray) -> float:
        return float(arr[0]) if arr.size else 0.0

    @property
    def largest_area(self) -> float:
        return self._largest(self.area)

    @property
    def largest_width(self) -> float:
        return self._largest(self.width)

    @property
    def largest_height(self) -> float:
        return self._largest(self.height)


def rec601_grey(rgb: np.ndarray) -> np.ndarray:
    """Rec.601 luma :math:`Y = 0.299 r + 0.587 g + 0.114 b` of a uint8 RGB image, uint8.

    OpenCV's ``COLOR_RGB2GRAY`` uses exactly these weights (fixed point, rounded).
    """
    if rgb.ndim != 3 or rgb.shape[2] != 3:
        raise InputError(f"expected an RGB image (H, W, 3), got shape {rgb.shape}")
    return cv2.cvtColor(np.ascontiguousarray(rgb, dtype=np.uint8), cv2.COLOR_RGB2GRAY)


def median_kernel(mouth_width: float) -> int:
    """Median-blur kernel for a mouth ``mouth_width`` px wide: 11 at 800 px, odd, >= 3.

    The odd integer nearest to :math:`11 w / 800`, at least 3.
    """
    s = 11.0 * float(mouth_width) / 800.0
    return max(3, 2 * int(np.floor((s - 1.0) / 2.0 + 0.5)) + 1)


def otsu_threshold(hist: np.ndarray, min_contrast: float = 40.0,
                   max_dark_ratio: float = 0.5) -> float | None:
    """Grey level separating the darkest clear class of a histogram, or None.

    Otsu's method picks :math:`t` maximising the between-class variance
    :math:`\\sigma_B^2(t) = \\omega_0 \\omega_1 (\\mu_1 - \\mu_0)^2` with
    :math:`\\omega_0 = \\sum_{i \\le t} p_i`, :math:`\\mu_0 = \\sum_{i \\le t} i p_i / \\omega_0`
    (and the same above ``t``). A crop of lips and skin around an opening has
    three levels (skin > lips > cavity), so the split is repeated inside the
    dark class while that class itself splits with contrast
    :math:`\\mu_1 - \\mu_0 \\ge` ``min_contrast``; this lands on the darkest
    mode. The last split is accepted as *opening vs lips* only if the dark
    class is clearly dark, :math:`\\mu_0 \\le` ``max_dark_ratio`` :math:`\\mu_1`
    (a mouth cavity is several times darker than lips, lips only a little
    darker than skin); otherwise -- a closed mouth, or noise that Otsu would
    cut in half -- there is no opening and None is returned.

    Parameters
    ----------
    hist : ndarray (256,)
        Histogram of grey levels.
    min_contrast : float
        Smallest difference of class means (grey levels) that counts as two classes.
    max_dark_ratio : float
        Largest ratio of dark to bright class mean of an opening.
    """
    hist = np.asarray(hist, dtype=np.float64)
    hi = hist.size
    best = None
    while hi > 1:
        p = hist[:hi]
        total = p.sum()
        if total <= 0:
            break
        levels = np.arange(hi, dtype=np.float64)
        w0 = np.cumsum(p)
        m0 = np.cumsum(p * levels)
        w1 = total - w0
        m1 = m0[-1] - m0
        valid = (w0 > 0) & (w1 > 0)
        if not valid.any():
            break
        with np.errstate(divide="ignore", invalid="ignore"):
            mu0 = m0 / w0
            mu1 = m1 / w1
            sigma_b = np.where(valid, w0 * w1 * (mu1 - mu0) ** 2, -1.0)
        t = int(np.argmax(sigma_b))
        if mu1[t] - mu0[t] < min_contrast:
            break
        best = (t, mu0[t], mu1[t])
        hi = t + 1
    if best is None or best[1] > max_dark_ratio * best[2]:
        return None
    return float(best[0])


def median_mask(binary: np.ndarray, k: int) -> np.ndarray:
    """k x k median filter of a boolean image (majority vote), replicated borders.

    Median filtering commutes with thresholding (threshold decomposition):
    :math:`\\mathrm{median}_k(Y) \\le t \\iff \\#\\{Y \\le t \\text{ in the window}\\} \\ge (k^2 + 1)/2`,
    so ``median_mask(Y <= t, k) == (cv2.medianBlur(Y, k) <= t)`` exactly, while a
    box sum costs O(1) per pixel instead of a large-kernel median.
    """
    counts = cv2.boxFilter(np.ascontiguousarray(binary, dtype=bool).view(np.uint8), cv2.CV_16U, (k, k),
                           normalize=False, borderType=cv2.BORDER_REPLICATE)
    return counts >= (k * k + 1) // 2


def teeth_mask(rgb: np.ndarray, saturation_max: int = 60, value_min: int = 150) -> np.ndarray:
    """Boolean mask of teeth-like pixels: HSV saturation <= ``saturation_max`` and value >= ``value_min``.

    Both on OpenCV's 0..255 scale. Lips are saturated red, the cavity dark;
    teeth (and white highlights) are bright and nearly colourless.
    """
    hsv = cv2.cvtColor(np.ascontiguousarray(rgb, dtype=np.uint8), cv2.COLOR_RGB2HSV)
    return (hsv[..., 1] <= saturation_max) & (hsv[..., 2] >= value_min)


@dataclass(frozen=True)
class OpeningDetector:
    """Settings of the Leach & Maddock (2019) opening detector; call :meth:`detect` per frame.

    Parameters
    ----------
    threshold : "otsu" or float
        Grey level (0..255) at or below which a pixel is opening, or Otsu's method.
    hull : bool
        Replace each opening's contour by its convex hull (Leach & Maddock 2019, Fig. 9).
    teeth : bool
        Count bright, unsaturated pixels touching a dark region as opening (Fig. 10).
    min_area : float
        Openings smaller than ``min_area * w**2`` pixels are dropped (specks).
    min_contrast : float
        Otsu only: smallest dark/bright class-mean difference that counts as an opening.
    max_dark_ratio : float
        Otsu only: an opening's mean grey is at most this fraction of the lips' (see
        :func:`otsu_threshold`).
    teeth_saturation, teeth_value : int
        HSV limits of :func:`teeth_mask`.
    pad : float or (left, top, right, bottom)
        Margins around the box that are analysed too, in units of ``w``.
    method : "mesh", "lips" or "seed"
        ``"mesh"`` (default): inside the face mesh's inner-lip contour
        (``MouthBox.lips``; without it, between the lips segmented by colour),
        the pixels unlike the speaker's own lips -- dark cavity, bright or grey
        teeth -- and what lies between them (:mod:`~visemeface.analysis.innerlip`);
        ``threshold`` and ``teeth`` are moot.
        ``"lips"``: the opening is the region enclosed between the
        lips segmented by colour, teeth and tongue included (:mod:`~visemeface.analysis.lips`);
        ``threshold`` then only sets the dark-cavity level (a number) or keeps
        it relative to the lips (``"otsu"``), and ``teeth`` is moot (teeth
        between the lips always count). ``"seed"``: Leach & Maddock's (2019) grey threshold.
    min_height : float
        ``"mesh"`` and ``"lips"``: an opening thinner than this (fraction of ``w``) is the
        seam of closed lips, one narrower a speck.
    min_chroma : float
        ``"lips"`` (and ``"mesh"`` without a face mesh): lips must be at least this much redder (Lab a*, 8-bit
        levels) than the skin, or there is no mouth to measure.
    """

    threshold: str | float = "otsu"
    hull: bool = False
    teeth: bool = False
    min_area: float = 5e-4
    min_contrast: float = 40.0
    max_dark_ratio: float = 0.5
    teeth_saturation: int = 60
    teeth_value: int = 150
    pad: tuple = (0.1, 0.1, 0.1, 0.4)
    method: str = "mesh"
    min_height: float = 0.05
    min_chroma: float = 6.0

    def __post_init__(self):
        if self.method not in METHODS:
            raise InputError(f"method must be one of {', '.join(METHODS)}, got {self.method!r}")
        if not (0 <= self.min_height < 1):
            raise InputError(f"min_height must be in [0, 1) (fraction of mouth width), got {self.min_height}")
        if isinstance(self.threshold, str):
            if self.threshold != "otsu":
                raise InputError(f"threshold must be a number 0..255 or 'otsu', got {self.threshold!r}")
        elif not (0 <= float(self.threshold) <= 255):
            raise InputError(f"threshold must be in 0..255, got {self.threshold!r}")
        if not (0 <= self.min_area < 1):
            raise InputError(f"min_area must be in [0, 1) (fraction of mouth width squared), got {self.min_area}")
        pad = np.atleast_1d(np.asarray(self.pad, dtype=float))
        if pad.size == 1:
            pad = np.repeat(pad, 4)
        if pad.size != 4 or not np.all(np.isfinite(pad)) or np.any(pad < 0):
            raise InputError(f"pad must be 1 or 4 numbers >= 0 (left, top, right, bottom), got {self.pad!r}")
        object.__setattr__(self, "pad", tuple(float(v) for v in pad))

    def opening_mask(self, crop: np.ndarray, w: int) -> tuple[np.ndarray, float | None]:
        """uint8 mask (255 = opening) of an RGB crop of a mouth ``w`` px wide, and the threshold used.

        The mask is ``median_k(Y) <= t`` with ``k = median_kernel(w)``,
        computed as :func:`median_mask` (exact, and O(1) per pixel for large
        kernels). Otsu's ``t`` comes from the histogram of ``Y`` median-blurred
        with ``min(k, 5)``, which already removes noise and specks.
        """
        k = median_kernel(w)
        grey = rec601_grey(crop)
        small = cv2.medianBlur(grey, min(k, 5))
        if self.threshold == "otsu":
            hist = cv2.calcHist([small], [0], None, [256], [0, 256]).ravel()   # (256,) or (256, 1)
            t = otsu_threshold(hist, self.min_contrast, self.max_dark_ratio)
            if t is None:
                return np.zeros(grey.shape, np.uint8), None
        else:
            t = float(self.threshold)
        dark = small <= t if k <= 5 else median_mask(grey <= t, k)
        if self.teeth:
            teeth = median_mask(teeth_mask(crop, self.teeth_saturation, self.teeth_value), k)
            both = (dark | teeth).view(np.uint8)
            n, labels = cv2.connectedComponents(both, connectivity=8)
            # Teeth count only where they touch the dark cavity: white skin
            # highlights far from any opening stay lip/skin.
            touches_dark = np.bincount(labels[dark], minlength=n) > 0
            touches_dark[0] = False
            dark = touches_dark[labels]
        return dark.view(np.uint8) * np.uint8(255), t

    def detect(self, frame: np.ndarray, box) -> Openings:
        """Find the mouth openings of one RGB uint8 frame inside ``box``.

        Returns
        -------
        Openings
            Largest first; ``count == 0`` when nothing is found.
        """
        frame = np.asarray(frame)
        if frame.dtype != np.uint8 or frame.ndim != 3 or frame.shape[2] != 3:   # floats 0..1 read as black
            raise InputError(f"a frame must be RGB uint8 (height, width, 3), got {frame.dtype} {frame.shape}")
        box = MouthBox.of(box)
        x0, y0, x1, y1 = box.region(self.pad, frame.shape[1], frame.shape[0])
        w = box.mouth_width
        crop = frame[y0:y1, x0:x1]
        if self.method == "seed":
            mask, t = self.opening_mask(crop, w)
            scale = 1.0
        elif self.method == "mesh":
            from visemeface.analysis.innerlip import mesh_opening_mask

            lips = None if box.lips is None else np.asarray(box.lips, float) - (x0, y0)
            mask, t, scale = mesh_opening_mask(np.ascontiguousarray(crop, dtype=np.uint8),
                                               (box.x - x0, box.y - y0, box.w, box.h), lips, w,
                                               self.min_height, self.min_chroma)
        else:
            dark = None if self.threshold == "otsu" else float(self.threshold)
            mask, t, scale = lips_opening_mask(np.ascontiguousarray(crop, dtype=np.uint8),
                                               (box.x - x0, box.y - y0, box.w, box.h), w, self.min_height,
                                               self.min_chroma, dark_level=dark)
        return dataclasses.replace(self.measure(mask, t, w, scale, (x0, y0)), box=box)

    def measure(self, mask: np.ndarray, t, w: int, scale: float, origin) -> Openings:
        """Openings of a uint8 ``mask`` drawn at ``scale`` x the frame, its corner at frame ``origin``."""
        empty = np.zeros(0)
        if t is None or not mask.any():
            return Openings(empty, empty, empty, (), w, t)
        contours, _ = cv2.findContours(mask, cv2.RETR_EXTERNAL, cv2.CHAIN_APPROX_SIMPLE)
        areas, widths, heights, outlines = [], [], [], []
        min_px = self.min_area * (w * scale) ** 2
        for c in contours:
            if self.hull:
                c = cv2.convexHull(c)
            bx, by, bw, bh = cv2.boundingRect(c)
            # Pixels inside or on the filled outline; cv2.contourArea (polygon
            # through boundary pixel centres) would under-count by ~perimeter/2.
            local = np.zeros((bh, bw), np.uint8)
            cv2.drawContours(local, [c - np.array([bx, by], np.int32)], -1, 1, thickness=cv2.FILLED)
            area = int(cv2.countNonZero(local))
            if area < min_px or area == 0:
                continue
            areas.append(area)
            # Columns (rows) covered, i.e. max x - min x + 1: a one-pixel slit is
            # 1 px wide, and a digitised ellipse of semi-axis a measures ~2a.
            widths.append(bw)
            heights.append(bh)
            if scale != 1.0:
                c = np.rint((c + 0.5) / scale - 0.5).astype(np.int32)
            outlines.append(c + np.array(origin, np.int32))
        if not areas:
            return Openings(empty, empty, empty, (), w, t)
        order = np.argsort(-np.asarray(areas), kind="stable")
        ws = w * scale
        a = np.asarray(areas, float)[order] / (ws * ws)
        ww = np.asarray(widths, float)[order] / ws
        hh = np.asarray(heights, float)[order] / ws
        return Openings(a, ww, hh, tuple(outlines[i] for i in order), w, t)


def detect_openings(frame: np.ndarray, box, **settings) -> Openings:
    """Detect mouth openings in one frame; ``settings`` are :class:`OpeningDetector` fields."""
    return OpeningDetector(**settings).detect(frame, box)


def draw_openings(frame: np.ndarray, openings: Openings, box, label: str | None = None) -> np.ndarray:
    """Copy of an RGB ``frame`` with the mouth box (blue) and opening outlines drawn (Leach & Maddock 2019, Figs. 7-15).

    The largest opening is outlined in green, the others in yellow; the count
    (and ``label``) is written above the box.
    """
    box = MouthBox.of(box)
    out = np.ascontiguousarray(frame, dtype=np.uint8).copy()
    thick = max(1, int(round(box.w / 200)))
    cv2.rectangle(out, (box.x, box.y), (box.x + box.w - 1, box.y + box.h - 1), (60, 120, 255), thick)
    for i, c in enumerate(openings.contours):
        cv2.drawContours(out, [c], -1, (0, 255, 0) if i == 0 else (255, 230, 0), thick, cv2.LINE_AA)
    text = f"openings: {openings.count}" + (f"  {label}" if label else "")
    scale = max(0.35, box.w / 500)
    (tw, th), base = cv2.getTextSize(text, cv2.FONT_HERSHEY_SIMPLEX, scale, 1)
    x0, y0 = box.x, max(0, box.y - th - base - 2 * thick - 2)
    cv2.rectangle(out, (x0, y0), (x0 + tw + 4, y0 + th + base + 4), (255, 255, 255), cv2.FILLED)
    cv2.putText(out, text, (x0 + 2, y0 + th + 2), cv2.FONT_HERSHEY_SIMPLEX, scale, (0, 0, 0), 1, cv2.LINE_AA)
    return out
