"""Altered copies of a real clip, to test an opening measure on appearances it was not tuned on.

Each alteration keeps the mouth's geometry (so a clip's hand labels hold for its copies; a mirrored
copy keeps its heights) and changes what a colour- or lightness-based measure relies on. They use
the face mesh's points of the *original* frame (``(468, 2)`` frame pixels,
:class:`~visemeface.analysis.landmarks.FaceTracker`) to know where the face and the lips are.

- :func:`darken_skin`: the face's skin and lips darkened as melanin does, multiplying linear
  reflectance (sRGB decoded) by a factor chosen so that the skin's median CIE lightness drops by
  ``drop`` L* units (at least 40: a GRID face at L* 58 ends near 18, Fitzpatrick VI), a little
  more in blue and green; the teeth (pixels inside the mouth brighter than the lips) are spared,
  as they are on a darker face.
- :func:`moustache`: a dark, streaked band of hair from the upper lip's outer edge (the face mesh's)
  to a fifth of the mouth width above it at the centre, thinning to the corners, and a sparser stubble on the chin
  from 0.15 to 0.5 mouth widths below the lower lip (a beard).
- :func:`grey`, :func:`low_contrast`, :func:`mirror`: grey-scale (Rec.601), contrast halved about the
  frame's mean, left-right flip.
"""

from __future__ import annotations

import cv2
import numpy as np

from visemeface.analysis.landmarks import settings


def _srgb_to_linear(x: np.ndarray) -> np.ndarray:
    return np.where(x <= 0.04045, x / 12.92, ((x + 0.055) / 1.055) ** 2.4)


def _linear_to_srgb(x: np.ndarray) -> np.ndarray:
    x = np.clip(x, 0.0, 1.0)
    return np.where(x <= 0.0031308, 12.92 * x, 1.055 * x ** (1 / 2.4) - 0.055)


def _lightness(rgb: np.ndarray) -> np.ndarray:
    return cv2.cvtColor(np.ascontiguousarray(rgb, np.float32) / 255.0, cv2.COLOR_RGB2LAB)[..., 0]


def _poly(shape, pts) -> np.ndarray:
    m = np.zeros(shape[:2], np.uint8)
    cv2.fillPoly(m, [np.round(np.asarray(pts) * 16).astype(np.int32)], 1, shift=4)
    return m


def face_weight(shape, pts: np.ndarray) -> np.ndarray:
    """Soft mask (0..1 float32) of the face: the convex hull of the mesh points, feathered 3 px."""
    m = np.zeros(shape[:2], np.uint8)
    cv2.fillConvexPoly(m, cv2.convexHull(np.round(pts).astype(np.int32)), 1)
    return cv2.GaussianBlur(m.astype(np.float32), (0, 0), 3.0)


def _mouth(shape, pts):
    mouth = settings()["mouth"]
    outer, inner = pts[mouth["outer"]], pts[mouth["inner"]]
    w = float(np.linalg.norm(pts[mouth["corners"][1]] - pts[mouth["corners"][0]]))
    return outer, inner, w


def darkening_factor(frame: np.ndarray, pts: np.ndarray, drop: float = 42.0) -> float:
    """Linear-reflectance factor that lowers the median L* of the skin around the mouth by ``drop``."""
    outer, _, w = _mouth(frame.shape, pts)
    lips = _poly(frame.shape, outer)
    ring = cv2.dilate(lips, np.ones((2 * int(w) // 3 + 1,) * 2, np.uint8)).astype(bool) & ~lips.astype(bool)
    target = float(np.median(_lightness(frame)[ring])) - drop
    lin = _srgb_to_linear(frame[ring].astype(np.float64) / 255.0)
    lo, hi = 1e-4, 1.0
    for _ in range(40):                      # bisection on the factor: L* is monotone in it
        f = (lo * hi) ** 0.5
        out = _linear_to_srgb(lin * f * np.array([1.0, 0.9, 0.8])) * 255.0
        if np.median(_lightness(out.reshape(-1, 1, 3))) > target:
            hi = f
        else:
            lo = f
    return lo


def darken_skin(frame: np.ndarray, pts: np.ndarray, factor: float) -> np.ndarray:
    """The face's skin and lips darkened by linear ``factor`` (:func:`darkening_factor`), teeth spared."""
    outer, inner, w = _mouth(frame.shape, pts)
    face = face_weight(frame.shape, pts)
    lips = _poly(frame.shape, outer).astype(bool)
    g = max(1, int(round(0.05 * w)))
    mouth = cv2.dilate(_poly(frame.shape, inner), np.ones((2 * g + 1, 3), np.uint8)).astype(bool) & lips
    lab = cv2.cvtColor(np.ascontiguousarray(frame, np.float32) / 255.0, cv2.COLOR_RGB2LAB)
    light, chroma = lab[..., 0], np.hypot(lab[..., 1], lab[..., 2])
    ring = lips & ~mouth
    lip_l = float(np.median(light[ring])) if ring.any() else 100.0
    lip_c = float(np.median(chroma[ring])) if ring.any() else 0.0
    # teeth: inside the mouth, lighter and greyer than the lips
    teeth = np.where(mouth & (light >= lip_l + 4.0) & (chroma <= 0.75 * lip_c),
                     np.clip((light - lip_l - 4.0) / 6.0, 0.0, 1.0), 0.0)
    keep = np.clip(1.0 - face * (1.0 - teeth), 0.0, 1.0)[..., None]          # 1: unchanged
    lin = _srgb_to_linear(frame.astype(np.float64) / 255.0)
    dark = lin * factor * np.array([1.0, 0.9, 0.8])
    out = _linear_to_srgb(keep * lin + (1.0 - keep) * dark)
    return np.round(out * 255.0).astype(np.uint8)


def moustache(frame: np.ndarray, pts: np.ndarray, seed: int = 0) -> np.ndarray:
    """A dark moustache band above the upper lip and stubble below the lower lip (module notes)."""
    outer, _, w = _mouth(frame.shape, pts)
    h = frame.shape[0]
    rng = np.random.default_rng(seed)
    # face.toml's outer contour: corner 61, the lower lip (146 ... 375), corner 291, the upper lip (409 ... 185)
    upper, lower = np.vstack([outer[10:], outer[:1]]), outer[:11]
    cols = np.arange(frame.shape[1])
    order = np.argsort(upper[:, 0])
    top_of_lip = np.interp(cols, upper[order, 0], upper[order, 1])
    order = np.argsort(lower[:, 0])
    bottom_of_lip = np.interp(cols, lower[order, 0], lower[order, 1])
    x0, x1 = outer[:, 0].min(), outer[:, 0].max()
    rows = np.arange(h)[:, None]
    u = np.clip(np.abs(cols - (x0 + x1) / 2) / max(1.0, (x1 - x0) / 2), 0, 1)
    inside_x = ((cols >= x0) & (cols <= x1))[None, :]
    thick = (0.04 + 0.16 * np.sqrt(1 - u * u)) * w            # thickest at the philtrum, thin at the corners
    band = inside_x & (rows >= (top_of_lip - 0.5 - thick)[None, :]) & (rows <= top_of_lip[None, :] - 0.5)
    beard = inside_x & (rows >= bottom_of_lip[None, :] + 0.15 * w) & (rows <= bottom_of_lip[None, :] + 0.5 * w)
    # hair: vertical streaks (noise blurred along y), dark brown
    streaks = cv2.GaussianBlur(rng.normal(0, 1, frame.shape[:2]).astype(np.float32), (0, 0), sigmaX=0.5, sigmaY=2.0)
    hair = np.clip(0.85 + 0.6 * streaks, 0.0, 1.0)
    alpha = cv2.GaussianBlur(band.astype(np.float32), (0, 0), 0.7) * hair \
        + cv2.GaussianBlur((beard & (rng.random(frame.shape[:2]) < 0.6)).astype(np.float32), (0, 0), 0.8) * 0.6
    alpha = np.clip(alpha, 0.0, 0.95)[..., None]
    colour = np.array([38.0, 28.0, 22.0])
    return np.round(frame * (1 - alpha) + colour * alpha).astype(np.uint8)


def grey(frame: np.ndarray) -> np.ndarray:
    """Rec.601 grey-scale as three equal channels."""
    g = cv2.cvtColor(np.ascontiguousarray(frame), cv2.COLOR_RGB2GRAY)
    return np.repeat(g[..., None], 3, axis=2)


def low_contrast(frame: np.ndarray, factor: float = 0.5) -> np.ndarray:
    """Contrast scaled by ``factor`` about the frame's mean grey level."""
    m = float(frame.mean())
    return np.clip(np.round(m + factor * (frame.astype(np.float64) - m)), 0, 255).astype(np.uint8)


def mirror(frame: np.ndarray) -> np.ndarray:
    """Left-right flip."""
    return np.ascontiguousarray(frame[:, ::-1])
