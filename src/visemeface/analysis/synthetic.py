"""Synthetic mouth images with known openings: ground truth for the detector.

A frame is skin, with an elliptical lip region filling the mouth box
horizontally (corners on the box's left and right edges), dark elliptical
openings of known semi-axes on the lips, optional lip-coloured *bridges*
(stuck saliva) splitting an opening, bright *tongue* blobs and white *teeth*
inside openings, Gaussian noise and small specular specks. Everything is
deterministic for a given ``seed``.

Shapes are rasterised by testing pixel centres, so a filled ellipse of
semi-axes ``a, b`` covers :math:`\\approx \\pi a b` pixels and spans
:math:`\\max x - \\min x \\approx 2a` (within one pixel).
"""

from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np

SKIN = (224, 178, 150)
LIPS = (176, 78, 88)
CAVITY = (38, 14, 18)
TONGUE = (214, 120, 130)
TEETH = (238, 236, 226)


@dataclass(frozen=True)
class Ellipse:
    """Axis-aligned ellipse: centre ``(cx, cy)``, semi-axes ``a`` (x) and ``b`` (y), pixels."""

    cx: float
    cy: float
    a: float
    b: float

    def mask(self, shape: tuple[int, int]) -> np.ndarray:
        """Pixels whose centres lie inside."""
        yy, xx = np.ogrid[:shape[0], :shape[1]]
        return ((xx - self.cx) / self.a) ** 2 + ((yy - self.cy) / self.b) ** 2 <= 1.0

    @property
    def area(self) -> float:
        return float(np.pi * self.a * self.b)


def mouth_image(size, box, openings=(), *, bridges=(), tongues=(), teeth=(), specks: int = 0,
                noise: float = 6.0, seed: int = 0) -> np.ndarray:
    """Render a synthetic RGB uint8 mouth frame.

    Parameters
    ----------
    size : (height, width)
        Frame size in pixels.
    box : (x, y, w, h)
        Mouth box; the lips are the ellipse inscribed in it horizontally
        (height ``0.8 h``), so the corners touch the box's left/right edges.
    openings : sequence of Ellipse
        Dark mouth openings.
    bridges : sequence of (x0, x1)
        Vertical lip-coloured strips ``x0 <= x < x1`` painted over openings
        (lips still stuck together there).
    tongues, teeth : sequence of Ellipse or boolean masks
        Bright regions painted inside the openings.
    specks : int
        Number of 3x3-pixel white specular highlights inside the openings
        (centres at least 3 px from the lips).
    noise : float
        Standard deviation of Gaussian noise per channel (grey levels).
    """
    h, w = size
    bx, by, bw, bh = box
    rng = np.random.default_rng(seed)
    img = np.empty((h, w, 3), np.float64)
    img[:] = SKIN
    lips = Ellipse(bx + (bw - 1) / 2, by + bh / 2, bw / 2, 0.4 * bh).mask((h, w))
    img[lips] = LIPS
    hole = np.zeros((h, w), bool)
    for e in openings:
        hole |= e.mask((h, w))
    xs = np.arange(w)
    for x0, x1 in bridges:
        hole[:, (xs >= x0) & (xs < x1)] = False
    img[hole] = CAVITY
    for t in tongues:
        img[(t.mask((h, w)) if isinstance(t, Ellipse) else t) & hole] = TONGUE
    for t in teeth:
        img[(t.mask((h, w)) if isinstance(t, Ellipse) else t) & hole] = TEETH
    # Speck centres >= 3 px from the lips, so they are holes inside an opening
    # (a highlight touching the lip edge would notch the outline instead).
    inner = cv2.erode(hole.view(np.uint8), np.ones((7, 7), np.uint8)).view(bool)
    if specks and inner.any():
        ys, xs_ = np.nonzero(inner)
        pick = rng.choice(ys.size, size=specks, replace=False)
        for y, x in zip(ys[pick], xs_[pick]):
            img[max(0, y - 1):y + 2, max(0, x - 1):x + 2] = 255
    img += rng.normal(0.0, noise, img.shape)
    return np.clip(np.rint(img), 0, 255).astype(np.uint8)


def merging_mouth_frames(n_frames: int = 40, merge_frame: int = 20, size=(256, 256), box=None,
                         noise: float = 6.0, seed: int = 0):
    """Yield frames of a mouth opening whose two halves merge at ``merge_frame``.

    One elliptical opening (semi-axes ``0.3 w`` and a height growing linearly
    from ``0.04 w`` to ``0.1 w``) is split by a central lip bridge ``0.06 w``
    wide -- stuck saliva -- on frames ``< merge_frame``; from ``merge_frame``
    on, the bridge is gone. So the count drops 2 -> 1 and the largest opening's
    width jumps from about ``0.27 w`` to ``0.6 w`` exactly at ``merge_frame``
    (Leach & Maddock 2019, Figs. 22 and 26).

    Parameters
    ----------
    box : (x, y, w, h), optional
        Mouth box; default: centred, ``w = 0.78`` of the frame width, ``h = w / 2``.
    """
    h, w = size
    if box is None:
        bw = int(round(0.78 * w))
        box = ((w - bw) // 2, (h - bw // 2) // 2, bw, bw // 2)
    bx, by, bw, bh = box
    cx, cy = bx + (bw - 1) / 2, by + bh / 2
    for i in range(n_frames):
        b = bw * (0.04 + 0.06 * i / max(1, n_frames - 1))
        bridge = [(cx - 0.03 * bw, cx + 0.03 * bw)] if i < merge_frame else []
        yield mouth_image(size, box, [Ellipse(cx, cy, 0.3 * bw, b)], bridges=bridge, noise=noise,
                          seed=seed + i)
