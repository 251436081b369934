r"""What a render shows inside the lips: the opening's pixels, and which are teeth or tongue.

The *opening* is the polygon of the posed inner lip line (the upper seam left to
right, then the lower seam right to left) projected by the renderer's camera.
Pixels are classified by colour (8-bit RGB, :math:`M = \max(R,G,B)`,
:math:`m = \min(R,G,B)`):

- **teeth**: bright and pale, :math:`M \ge 150` and :math:`(M - m)/M \le 0.25`;
- **tongue** (and gum): red but lit, :math:`R \ge 90` and :math:`R \ge 1.35\,G`;
- the rest of the opening is the dark cavity.

The thresholds separate the default face's tooth, tongue and cavity colours
under the renderer's lighting (``tests/render/test_mouth_interior.py``); they are
not tuned to a viseme.
"""

from __future__ import annotations

import numpy as np

TEETH_MIN_BRIGHT = 150
TEETH_MAX_SATURATION = 0.25
TONGUE_MIN_RED = 90
TONGUE_RED_OVER_GREEN = 1.35


def teeth_pixels(image: np.ndarray) -> np.ndarray:
    """(H, W) bool: bright, low-saturation pixels."""
    img = np.asarray(image, dtype=np.float32)
    hi, lo = img.max(axis=2), img.min(axis=2)
    return (hi >= TEETH_MIN_BRIGHT) & ((hi - lo) <= TEETH_MAX_SATURATION * np.maximum(hi, 1.0))


def tongue_pixels(image: np.ndarray) -> np.ndarray:
    """(H, W) bool: lit red pixels (tongue, gums; lips too, outside the opening)."""
    img = np.asarray(image, dtype=np.float32)
    r, g = img[..., 0], img[..., 1]
    return (r >= TONGUE_MIN_RED) & (r >= TONGUE_RED_OVER_GREEN * g)


def opening_mask(renderer, vertices: np.ndarray) -> np.ndarray:
    """(H, W) bool: the pixels inside the projected inner lip line of the posed ``vertices``."""
    import cv2

    face = renderer.face
    up, lo = face.region("lip_seam_upper"), face.region("lip_seam_lower")
    ring = np.concatenate([up, lo[::-1]])           # both sorted by x: left to right, then back
    pts = renderer.project(np.asarray(vertices, dtype=np.float64)[ring])
    w, h = renderer.size
    mask = np.zeros((h, w), np.uint8)
    cv2.fillPoly(mask, [np.round(pts * 4).astype(np.int32)], 1, lineType=cv2.LINE_8, shift=2)
    return mask.astype(bool)


def interior_features(renderer, image: np.ndarray, vertices: np.ndarray) -> dict:
    """Counts of the opening's pixels: ``opening``, and teeth/tongue in its upper and lower halves.

    The halves split the opening's bounding rows at their middle. Fractions are of
    the opening's pixels (0 when the lips are closed).
    """
    mask = opening_mask(renderer, vertices)
    rows = np.flatnonzero(mask.any(axis=1))
    out = {"opening": int(mask.sum())}
    upper = np.zeros_like(mask)
    if len(rows):
        upper[: (rows[0] + rows[-1] + 1) // 2] = True
    teeth, tongue = teeth_pixels(image) & mask, tongue_pixels(image) & mask
    for name, sel in (("teeth", teeth), ("tongue", tongue)):
        out[f"{name}_upper"] = int((sel & upper).sum())
        out[f"{name}_lower"] = int((sel & ~upper).sum())
    return out
