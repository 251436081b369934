r"""Per-vertex normals of a fixed topology, fast enough for every frame.

The vertex normal is the normalised sum of the area-weighted normals of the
triangles around it,

.. math:: n_i = \frac{\sum_{t \ni i} w_{it}\,(b_t - a_t) \times (c_t - a_t)}
                     {\lVert \sum_{t \ni i} w_{it}\,(b_t - a_t) \times (c_t - a_t) \rVert},

with :math:`w_{it} \in \{0, 1\}` from the smoothing groups: one sparse product
``S @ N_faces`` with the vertex-triangle incidence matrix ``S`` built once, or on
a large mesh (:data:`visemeface.runtime.COMPILED_FROM_VERTICES`) one compiled
loop (numba) that makes each triangle's normal and adds it to its corners. Both
sum a vertex's triangles in triangle order (the same normals; deterministic).
"""

from __future__ import annotations

import functools

import numpy as np


@functools.cache
def _accumulate():
    from numba import njit

    @njit(cache=True, boundscheck=False)
    def accumulate(v, tris, weight, out, lengths):
        out[:] = 0
        for t in range(tris.shape[0]):
            a, b, c = tris[t, 0], tris[t, 1], tris[t, 2]
            e1x, e1y, e1z = v[b, 0] - v[a, 0], v[b, 1] - v[a, 1], v[b, 2] - v[a, 2]
            e2x, e2y, e2z = v[c, 0] - v[a, 0], v[c, 1] - v[a, 1], v[c, 2] - v[a, 2]
            fx = e1y * e2z - e1z * e2y
            fy = e1z * e2x - e1x * e2z
            fz = e1x * e2y - e1y * e2x
            for k in range(3):
                if weight[t, k]:
                    i = tris[t, k]
                    out[i, 0] += fx
                    out[i, 1] += fy
                    out[i, 2] += fz
        for i in range(out.shape[0]):
            n = np.sqrt(out[i, 0] * out[i, 0] + out[i, 1] * out[i, 1] + out[i, 2] * out[i, 2])
            lengths[i] = n
            if n > 0:
                out[i, 0] /= n
                out[i, 1] /= n
                out[i, 2] /= n

    return accumulate


class NormalAccumulator:
    """Unit vertex normals (see the module docstring) of one topology.

    With ``groups`` (an int per vertex; a triangle belongs to the largest group
    among its vertices) a vertex sums only the triangles of its own group, when
    it has any.
    """

    def __init__(self, triangles: np.ndarray, n_vertices: int, groups: np.ndarray | None = None):
        self.triangles = np.ascontiguousarray(triangles, dtype=np.int64)
        self.n_vertices = int(n_vertices)
        weight = np.ones(self.triangles.shape, bool)
        if groups is not None:
            # smoothing groups: a vertex averages only the triangles of its own group
            # (when it has any), so e.g. the dark mouth cavity does not bend the normals
            # of the lip seam it hangs from.
            groups = np.asarray(groups)
            same = groups[self.triangles] == groups[self.triangles].max(axis=1, keepdims=True)
            has_own = np.bincount(self.triangles[same], minlength=n_vertices) > 0
            weight = same | ~has_own[self.triangles]
        from visemeface.runtime import COMPILED_FROM_VERTICES
        self._weight = np.ascontiguousarray(weight) if n_vertices >= COMPILED_FROM_VERTICES else None
        if self._weight is None:
            t = len(self.triangles)
            import scipy.sparse

            self._incidence = scipy.sparse.csr_matrix(
                (weight.ravel().astype(np.float64), (self.triangles.ravel(), np.repeat(np.arange(t), 3))),
                shape=(n_vertices, t))
            self._incidence32 = self._incidence.astype(np.float32)
            self._a, self._b, self._c = (np.ascontiguousarray(self.triangles[:, k]) for k in range(3))

    def __call__(self, vertices: np.ndarray, dtype=np.float64, lengths: np.ndarray | None = None) -> np.ndarray:
        """Unit normals (N, 3) of ``vertices`` in ``dtype`` (``np.float32`` for per-frame rendering).

        ``lengths`` (N,), if given, receives each sum's length before it is normalised: twice the area around
        the vertex where the surface is flat, less where it bends (see :mod:`visemeface.render.folds`)."""
        v = np.ascontiguousarray(vertices, dtype=dtype)
        if v.shape != (self.n_vertices, 3):
            raise ValueError(f"expected ({self.n_vertices}, 3) vertices, got {v.shape}")
        if self._weight is not None:
            out = np.empty_like(v)
            _accumulate()(v, self.triangles, self._weight, out,
                          np.empty(self.n_vertices, dtype=v.dtype) if lengths is None else lengths)
            return out
        p0 = v[self._a]
        e1 = v[self._b] - p0
        e2 = v[self._c] - p0
        f = np.empty_like(e1)          # e1 x e2, written out: np.cross is slower on many rows
        f[:, 0] = e1[:, 1] * e2[:, 2] - e1[:, 2] * e2[:, 1]
        f[:, 1] = e1[:, 2] * e2[:, 0] - e1[:, 0] * e2[:, 2]
        f[:, 2] = e1[:, 0] * e2[:, 1] - e1[:, 1] * e2[:, 0]
        return unit_rows((self._incidence32 if v.dtype == np.float32 else self._incidence) @ f, lengths)


def unit_rows(n: np.ndarray, lengths: np.ndarray | None = None) -> np.ndarray:
    """Each row of ``n`` scaled to unit length (zero rows kept); ``lengths`` receives the rows' lengths."""
    length = np.sqrt(np.einsum("ij,ij->i", n, n))
    if lengths is not None:
        lengths[:] = length
    length[length == 0] = 1.0
    return n / length[:, None]


def vertex_normals(vertices: np.ndarray, triangles: np.ndarray) -> np.ndarray:
    """Unit area-weighted vertex normals (see :class:`NormalAccumulator`)."""
    return NormalAccumulator(triangles, len(vertices))(vertices)
