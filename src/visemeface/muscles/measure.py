"""Lip dimensions measured on any posed face mesh (Edge & Maddock 2001, Table 1's lip dimensions).

All measures are taken in the *rest* mouth frame of the face
(:func:`visemeface.muscles.rig.mouth_frame`: x toward the subject's left
mouth corner, y up, z forward), from the face's landmarks and lip-seam regions,
so they work on any mesh with the landmarks of ``docs/conventions.md``.

Absolute measures (metres): ``mouth_width`` (corner to corner), ``opening_height``
(vertical gap between the seam-side lip mid-points; <= 0 when the lips touch or
press), ``upper_lip_height``/``lower_lip_height`` (vermilion heights). Changes
from rest (metres): ``protrusion`` (forward motion of the lip mid-points),
``upper_lip_raise``, ``lower_lip_drop``, ``corner_height`` (mean of both
corners; ``corner_height_left``/``_right`` each), ``corner_depth``,
``chin_drop``. Contact: ``lip_contact`` (fraction of the central lip seam
whose lips touch) and ``lips_closed`` (the centre touches).

:func:`lid_margin` finds the eyelid vertex over the pupil, to measure the lids the same way;
:func:`corner_folds` counts the triangles beside the mouth corners that a pose turns over.
"""

from __future__ import annotations

import numpy as np

from visemeface.errors import InputError

__all__ = ["LipGauge", "lip_dimensions", "lip_changes", "inner_opening", "lid_margin", "corner_folds",
           "TARGET_DIMENSIONS"]

#: Dimensions of the viseme target table (``data/visemes/targets.csv``).
TARGET_DIMENSIONS = ("mouth_width", "opening_height", "protrusion", "upper_lip_raise",
                     "lower_lip_drop", "corner_height")

_LANDMARKS = ("mouth_corner_left", "mouth_corner_right", "upper_lip_mid", "lower_lip_mid",
              "upper_lip_top", "lower_lip_bottom", "chin")


class LipGauge:
    """Measures lip dimensions of one face's posed vertices (setup done once).

    ``indices`` are the only vertices a measurement reads: callers that pose a
    subset (fitting) pass positions of just those, in that order, to
    :meth:`measure_subset`.
    """

    def __init__(self, face, contact_tolerance: float | None = None, central: float = 0.8):
        from visemeface.muscles.rig import mouth_frame

        missing = [n for n in _LANDMARKS if n not in face.landmarks]
        if missing:
            raise InputError(f"the face has no landmark {missing[0]!r}, needed to measure the lips")
        self.frame = mouth_frame(face)
        lm = [face.landmarks[n] for n in _LANDMARKS]
        up = np.asarray(face.regions.get("lip_seam_upper", []), dtype=np.int64)
        lo = np.asarray(face.regions.get("lip_seam_lower", []), dtype=np.int64)
        rest_local = self.frame.to_local(face.vertices)
        half = self.frame.width / 2
        pairs = np.zeros((0, 2), dtype=np.int64)
        if len(up) and len(lo):
            # Pair each central upper-seam vertex with the lower-seam vertex nearest in u.
            up = up[np.abs(rest_local[up, 0]) < central * half]
            if len(up):
                j = np.argmin(np.abs(rest_local[up, 0][:, None] - rest_local[lo, 0][None, :]), axis=1)
                pairs = np.column_stack([up, lo[j]])
        self.indices = np.unique(np.concatenate([lm, pairs.ravel()]))
        pos = {int(v): i for i, v in enumerate(self.indices)}
        self._lm = {n: pos[face.landmarks[n]] for n in _LANDMARKS}
        self._pairs = np.array([[pos[int(a)], pos[int(b)]] for a, b in pairs], dtype=np.int64).reshape(-1, 2)
        self._rest = self.frame.to_local(face.vertices[self.indices])
        self.tolerance = 0.01 * self.frame.width if contact_tolerance is None else contact_tolerance
        self.rest = self.measure_subset(face.vertices[self.indices])

    def measure(self, vertices: np.ndarray) -> dict:
        """Dimensions of a full posed vertex array (N, 3)."""
        return self.measure_subset(np.asarray(vertices, dtype=float)[self.indices])

    def measure_subset(self, points: np.ndarray) -> dict:
        """Dimensions from the positions of ``self.indices`` (len(indices), 3)."""
        p = self.frame.to_local(points)
        r = self._rest
        L = self._lm
        d = p - r
        cl, cr = L["mouth_corner_left"], L["mouth_corner_right"]
        um, lm = L["upper_lip_mid"], L["lower_lip_mid"]
        opening = float(p[um, 1] - p[lm, 1])
        out = {
            "mouth_width": float(np.linalg.norm(p[cl] - p[cr])),
            "opening_height": opening,
            "protrusion": float((d[um, 2] + d[lm, 2]) / 2),
            "upper_lip_raise": float(d[um, 1]),
            "lower_lip_drop": float(-d[lm, 1]),
            "corner_height": float((d[cl, 1] + d[cr, 1]) / 2),
            "corner_height_left": float(d[cl, 1]),
            "corner_height_right": float(d[cr, 1]),
            "corner_depth": float((d[cl, 2] + d[cr, 2]) / 2),
            "upper_lip_height": float(p[L["upper_lip_top"], 1] - p[um, 1]),
            "lower_lip_height": float(p[lm, 1] - p[L["lower_lip_bottom"], 1]),
            "chin_drop": float(-d[L["chin"], 1]),
        }
        if len(self._pairs):
            gaps = p[self._pairs[:, 0], 1] - p[self._pairs[:, 1], 1]
            out["lip_contact"] = float(np.mean(gaps <= self.tolerance))
        else:
            out["lip_contact"] = float(opening <= self.tolerance)
        out["lips_closed"] = bool(opening <= self.tolerance)
        return out

    def changes(self, vertices: np.ndarray) -> dict:
        """Target dimensions as change from rest in fractions of the rest mouth width."""
        return self.changes_subset(np.asarray(vertices, dtype=float)[self.indices])

    def changes_subset(self, points: np.ndarray) -> dict:
        m = self.measure_subset(points)
        W = self.frame.width
        out = {}
        for k in TARGET_DIMENSIONS + ("corner_height_left", "corner_height_right", "corner_depth", "chin_drop"):
            base = self.rest[k] if k in ("mouth_width", "opening_height") else 0.0
            out[k] = (m[k] - base) / W
        return out


def lip_dimensions(face, vertices: np.ndarray) -> dict:
    """Lip dimensions (metres, see the module docstring) of ``vertices`` on ``face``.

    Examples
    --------
    >>> from visemeface.muscles.rig import default_rig
    >>> rig = default_rig()
    >>> d = lip_dimensions(rig.face, rig.pose({"jaw": 0.5}))
    >>> d["opening_height"] > lip_dimensions(rig.face, rig.face.vertices)["opening_height"]
    True
    """
    return LipGauge(face).measure(vertices)


def lip_changes(face, vertices: np.ndarray) -> dict:
    """:data:`TARGET_DIMENSIONS` (and a few more) as change from rest / rest mouth width.

    The units of the viseme target table: ``mouth_width = -0.2`` means the mouth
    is a fifth of its rest width narrower.
    """
    return LipGauge(face).changes(vertices)


def inner_opening(face, vertices: np.ndarray, tolerance: float = 2e-4) -> dict:
    """The inner opening between the lips: its ``width``, ``height`` (m) and ``aspect`` (width/height).

    The upper and lower seams are paired column by column (both regions are
    sorted by x on a quad-structured face with one lower copy per upper seam
    vertex); the height is the largest vertical gap, the width the lateral
    extent (mouth frame) of the columns whose gap exceeds ``tolerance``,
    extended linearly to where the gap closes. ``aspect`` is inf for a closed
    mouth.
    """
    from visemeface.muscles.rig import mouth_frame

    frame = mouth_frame(face)
    up, lo = face.region("lip_seam_upper"), face.region("lip_seam_lower")
    if len(up) != len(lo):
        raise InputError("the lip seams have different lengths: cannot pair them column by column")
    p_up = frame.to_local(np.asarray(vertices, dtype=float)[up])
    p_lo = frame.to_local(np.asarray(vertices, dtype=float)[lo])
    x = 0.5 * (p_up[:, 0] + p_lo[:, 0])
    gap = p_up[:, 1] - p_lo[:, 1] - tolerance
    open_ = np.flatnonzero(gap > 0)
    if len(open_) == 0:
        return {"width": 0.0, "height": 0.0, "aspect": float("inf")}
    i0, i1 = open_[0], open_[-1]
    left = x[i0] if i0 == 0 else x[i0 - 1] + (x[i0] - x[i0 - 1]) * (-gap[i0 - 1]) / (gap[i0] - gap[i0 - 1])
    right = x[i1] if i1 == len(x) - 1 else x[i1] + (x[i1 + 1] - x[i1]) * gap[i1] / (gap[i1] - gap[i1 + 1])
    width, height = float(right - left), float(gap.max() + tolerance)
    return {"width": width, "height": height, "aspect": width / height}


def lid_margin(face, side: str, lid: str = "upper", reach: float = 0.002) -> tuple[int, np.ndarray]:
    """The ``lid`` ("upper" or "lower") eyelid's margin over the pupil of eye ``side``: (the margin vertex,
    the lid's vertices of that eye). The margin is the lid vertex within ``reach`` (m) of the pupil's x
    nearest the eye's opening (the lowest of the upper lid, the highest of the lower)."""
    rest = face.vertices
    pupil = face.landmarks[f"eye_centre_{side}"]
    lids = face.region(f"{lid}_lids")
    lids = lids[np.sign(rest[lids, 0]) == np.sign(rest[pupil, 0])]
    over = lids[np.abs(rest[lids, 0] - rest[pupil, 0]) < reach]
    pick = np.argmin if lid == "upper" else np.argmax
    return int(over[pick(rest[over, 1])]), lids


def corner_folds(face, vertices: np.ndarray, reach: float = 0.15, behind: float = 0.011) -> tuple[int, int]:
    """Triangles within ``reach`` mouth widths of either mouth corner whose normal turns over (more than 90°
    from rest) in the posed ``vertices`` (N, 3), and how many of them lie in front of the mouth's lining (the
    centroid less than ``behind`` metres behind the upper lip's front; the others are inside the mouth)."""
    T, V, L = face.triangles, face.vertices, face.landmarks
    corners = V[[L["mouth_corner_left"], L["mouth_corner_right"]]]
    width = np.linalg.norm(corners[0] - corners[1])
    centroids = V[T].mean(axis=1)
    near = np.min(np.linalg.norm(centroids[:, None] - corners[None], axis=2), axis=1) / width
    T, centroids = T[near < reach], centroids[near < reach]

    def normals(P):
        return np.cross(P[T[:, 1]] - P[T[:, 0]], P[T[:, 2]] - P[T[:, 0]])

    turned = (normals(V) * normals(np.asarray(vertices, dtype=float))).sum(axis=1) < 0
    front = centroids[:, 2] > V[L["upper_lip_mid"], 2] - behind
    return int(turned.sum()), int((turned & front).sum())
