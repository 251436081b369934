"""Relax the bone side of an extruded face where its hexahedra come out badly shaped."""

from __future__ import annotations

import numpy as np

from visemeface.physics.hexmesh import HexMesh, element_quality

#: Bone-side node relaxation target (least scaled Jacobian of a tissue hexahedron).
BONE_QUALITY = 0.4


def relax_bone_side(nodes, hexes, S: int, layers: int, q_min: float = BONE_QUALITY,
                    iterations: int = 60) -> np.ndarray:
    """Move bone-side nodes of badly shaped hexahedra toward their neighbours' mean.

    Where the surface is concave (the mouth corners) the extrusion normals
    converge and the bone-side nodes of neighbouring columns bunch up: hexahedra
    come out nearly flat (scaled Jacobian ~0.05,
    :func:`~visemeface.physics.hexmesh.element_quality`) and a
    wide jaw opening turns them inside out. The bone side is not seen; each pass
    moves the bone-side nodes of elements with quality < ``q_min`` halfway to the
    mean of their bone-side neighbours (Laplacian smoothing), the skin and the
    saliva layer stay put. Stops when every element reaches ``q_min`` or the
    worst one stops improving.
    """
    nodes = np.array(nodes, dtype=np.float64)
    hexes = np.asarray(hexes, dtype=np.int64)
    inner = layers * S
    # bone-side neighbours: nodes sharing a hexahedron face on the bone side
    rows, cols = [], []
    for h in hexes:
        b = h[h >= inner]
        for x in b:
            for y in b:
                if x != y:
                    rows.append(x)
                    cols.append(y)
    if not rows:
        return nodes
    import scipy.sparse as sp
    n = len(nodes)
    A = sp.csr_matrix((np.ones(len(rows)), (rows, cols)), shape=(n, n))
    A.data[:] = 1.0
    deg = np.asarray(A.sum(axis=1)).ravel()
    def quality(x):
        return element_quality(HexMesh(x, hexes))["scaled_jacobian"]

    q = quality(nodes)
    for _ in range(iterations):
        bad = q < q_min
        if not bad.any():
            break
        move = np.unique(hexes[bad])
        move = move[(move >= inner) & (deg[move] > 0)]
        mean = (A[move] @ nodes) / deg[move, None]
        trial = nodes.copy()
        trial[move] = 0.5 * (nodes[move] + mean)
        q_new = quality(trial)
        if q_new.min() <= q.min():
            break
        nodes, q = trial, q_new
    return nodes
