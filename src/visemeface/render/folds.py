r"""Folds: skin that an expression compresses shades darker.

Where facial skin is pushed together it buckles into folds and furrows (the nasolabial fold of a smile,
the glabellar furrows of a frown, the wrinkled nose of disgust, crow's feet beside a cheek raise), and the
folds' valleys are shaded. The mesh cannot hold the folds themselves (they are finer than its triangles),
but it knows where the skin is compressed: the vertex normal's unnormalised sum (:mod:`visemeface.face.normals`)
is twice the area around a vertex where the surface is flat and less where it bends, so its length posed
over its length at rest,

.. math:: c = 1 - \frac{\lVert\sum_t n_t\rVert_\mathrm{posed}}{\lVert\sum_t n_t\rVert_\mathrm{rest}},

is the local compression (and bending). The colour is darkened by :math:`D\,\mathrm{smoothstep}(c_0, c_1, c)`:
nothing at rest or where the skin is stretched (the pixels of a face at rest are unchanged), full where it
is compressed by two fifths.

The three constants are chosen by looking at the emotions' renders, not measured: the shade begins at 3 %
compression and ramps slowly, so a fold's shade has no edge (a steeper ramp made stains of the forehead), and
at its darkest it takes a fifth off the skin's colour (a third read more often to the expression judge of
``scripts/emotion_judge.py`` but looked like dirt on the cheeks).
"""

from __future__ import annotations

import numpy as np


#: Compression where the shade begins, and where it is full.
FOLD_START = 0.03
FOLD_FULL = 0.40
#: The darkest a fold makes the skin: a fraction of its colour.
FOLD_DEPTH = 0.22


def fold_shade(lengths: np.ndarray, rest_lengths: np.ndarray) -> np.ndarray:
    """The darkening (N,) float32 in [0, FOLD_DEPTH] of each vertex from its normal sums' lengths posed and at
    rest (0 where the rest length is 0). In float32 and in place: it runs every frame (about 0.1 ms a frame on the ICT head)."""
    rest = np.asarray(rest_lengths, dtype=np.float32)
    x = np.divide(np.asarray(lengths, dtype=np.float32), rest, out=np.ones_like(rest), where=rest > 0)
    np.subtract(np.float32(1.0 - FOLD_START), x, out=x)          # compression past the start
    x *= np.float32(1.0 / (FOLD_FULL - FOLD_START))
    np.clip(x, 0.0, 1.0, out=x)
    return x * x * (np.float32(3.0 * FOLD_DEPTH) - np.float32(2.0 * FOLD_DEPTH) * x)   # smoothstep, times the depth
