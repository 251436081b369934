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
    >>> c.round(12).tolist(), round(r, 12)
    ([0.0, 0.0, 0.0], 1.0)
    """
    P = np.asarray(points, dtype=np.float64)
    A = np.column_stack([2.0 * P, np.ones(len(P))])
    sol, *_ = np.linalg.lstsq(A, (P * P).sum(axis=1), rcond=None)
    centre = sol[:3]
    return centre, float(np.sqrt(sol[3] + centre @ centre))

