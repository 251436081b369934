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
