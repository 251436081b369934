"""The rig's pose product, on the functions in use.

A pose is :math:`X_0 + \\mathbf c \\cdot B` (:meth:`visemeface.muscles.rig.MuscleRig.pose`), a float32
product added to the float64 rest positions. A small product stays on one thread (a multithreaded BLAS
call costs 1-10 ms on a busy machine). On a large mesh (:data:`visemeface.runtime.COMPILED_FROM_VERTICES`)
one compiled loop (numba) runs it on the moving columns only: most of a scanned head (scalp, neck, the back
of the skull) has zero columns in ``B`` for every function, and the rows the product would copy out of the
matrix cost more than the product. Vertices no function in use moves are the rest positions exactly.
"""

from __future__ import annotations

import functools

import numpy as np


@functools.cache
def _kernel():
    from numba import njit

    @njit(cache=True, boundscheck=False)
    def pose(rest, matrix, c, cols, out):
        out[:] = rest
        acc = np.zeros(matrix.shape[1], np.float32)
        for r in range(matrix.shape[0]):
            cr = c[r]
            if cr != 0:
                row = matrix[r]
                for j in range(row.shape[0]):
                    acc[j] += cr * row[j]
        for j in range(cols.shape[0]):
            out[cols[j]] += acc[j]

    return pose


class MovingProduct:
    """``rest + c @ matrix`` on the nonzero columns of ``matrix`` ((K, 3N) float32; ``rest`` (3N,) float64)."""

    def __init__(self, matrix: np.ndarray, rest: np.ndarray):
        moving = (matrix.reshape(len(matrix), -1, 3) != 0).any(axis=(0, 2))
        #: (N,) bool: the vertices some function moves (the others stay at rest in every pose).
        self.moving = moving
        from visemeface.runtime import COMPILED_FROM_VERTICES
        self._compiled = len(moving) >= COMPILED_FROM_VERTICES
        self._cols = np.flatnonzero(np.repeat(moving, 3))
        self._full = matrix
        self._matrix = np.ascontiguousarray(matrix[:, self._cols], dtype=np.float32)
        self._rest = np.ascontiguousarray(rest, dtype=np.float64)

    def still(self, rows: np.ndarray | None = None) -> np.ndarray:
        """(N,) bool: the vertices at rest in every product whose nonzero coefficients lie in ``rows``
        ((K,) bool; None: any)."""
        if rows is None:
            return ~self.moving
        cols = self._matrix[np.asarray(rows, dtype=bool)]
        still = ~self.moving
        still[self.moving] = ~(cols.reshape(len(cols), -1, 3) != 0).any(axis=(0, 2))
        return still

    def __call__(self, c: np.ndarray) -> np.ndarray:
        if not self._compiled:
            used = np.flatnonzero(c)
            return self._rest + c[used] @ self._full[used]
        out = np.empty_like(self._rest)
        _kernel()(self._rest, self._matrix, np.ascontiguousarray(c, dtype=np.float32), self._cols, out)
        return out
