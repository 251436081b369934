"""Small numeric helpers used across the stages (one home each)."""

from __future__ import annotations

import numpy as np


def smoothstep(x):
    """Cubic ease ``3x² − 2x³`` of ``x`` clipped to [0, 1]: 0 → 0, 1 → 1, zero slope at both ends.

    >>> smoothstep([-1.0, 0.5, 2.0]).tolist()
    [0.0, 0.5, 1.0]
    """
    x = np.clip(np.asarray(x, dtype=np.float64), 0.0, 1.0)
    return x * x * (3.0 - 2.0 * x)


def cosine_step(x):
    """Cosine ease ``(1 − cos πx) / 2`` of ``x`` clipped to [0, 1] (the timeline's ramps).

    >>> cosine_step([0.0, 0.5, 1.0]).round(12).tolist()
    [0.0, 0.5, 1.0]
    """
    x = np.clip(np.asarray(x, dtype=np.float64), 0.0, 1.0)
    return (1.0 - np.cos(np.pi * x)) / 2.0


def sphere_fit(points) -> tuple[np.ndarray, float]:
    """The least-squares sphere through ``points`` (n, 3): (centre, radius).

    >>> c, r = sphere_fit([[1, 0, 0], [-1, 0, 0], [0, 1, 0], [0, 0, 1], [0, 0, -1]])
    >>> (c.round(12) + 0.0).tolist(), round(r, 12)
    ([0.0, 0.0, 0.0], 1.0)
    """
    P = np.asarray(points, dtype=np.float64)
    A = np.column_stack([2.0 * P, np.ones(len(P))])
    sol, *_ = np.linalg.lstsq(A, (P * P).sum(axis=1), rcond=None)
    centre = sol[:3]
    return centre, float(np.sqrt(sol[3] + centre @ centre))



def quantile(values, q: float) -> float:
    """The ``q`` quantile (0..1) of ``values``, linearly interpolated as ``np.percentile(values, 100 q)``.

    One partial sort and none of ``np.percentile``'s general machinery, whose overhead dominates on the few
    hundred pixels of a per-frame statistic (3.5 us against 60 us for ``np.percentile`` and 22 us for
    ``np.median`` on 300 values).

    >>> quantile([4.0, 1.0, 3.0, 2.0], 0.5), quantile([4.0, 1.0, 3.0, 2.0], 0.9)
    (2.5, 3.7)
    """
    a = np.asarray(values).ravel()
    if a.size == 0:
        raise ValueError("quantile of an empty array")
    pos = min(max(float(q), 0.0), 1.0) * (a.size - 1)
    lo = int(pos)
    hi = min(lo + 1, a.size - 1)
    part = np.partition(a, (lo, hi))
    x, y, t = float(part[lo]), float(part[hi]), pos - lo
    return x + (y - x) * t if t < 0.5 else y - (y - x) * (1.0 - t)
