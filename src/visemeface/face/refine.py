"""Refine a face's quads along the lip seam, conformingly (no hanging nodes).

The saliva film parts one seam element at a time: on the default face
12 tissue elements span the mouth, so the film's 48 slabs cannot part separately
inside one of them. :func:`refine_lip_seam` splits every lip-seam edge into ``r``
equal parts, and with it every edge across from it: the split runs along the seam
edges' *dual chords* (the strips of quads reached by stepping from an edge to the
opposite edge of each quad on it), up through the upper lip and down through the
lower lip to the mesh's rim, so every quad it reaches is cut into ``r`` strips (or
``r × r`` where two split chords cross) and no quad keeps a hanging node.

The new vertices lie on the old quads' bilinear patches (linear along each split
edge), so the refined surface is the same surface: the face keeps its look. The old
vertices keep their indices (0 … N−1) and the new ones follow, so the first N
vertices of any posed refined face are the input face's. A new vertex is in a region
when both ends of its edge are (all four corners for a vertex inside a doubly split
quad); landmarks stay; colours are interpolated.
"""

from __future__ import annotations

import numpy as np

from visemeface.errors import InputError
from visemeface.face.mesh import FaceMesh

#: Least number of tissue elements along the lip seam, corner to corner, that
#: :func:`refine_lip_seam` aims for (the saliva film's :data:`~visemeface.physics.film.FILM_ELEMENTS`).
SEAM_ELEMENTS = 48


def seam_edges(face: FaceMesh) -> np.ndarray:
    """The quad edges along the two lip seams between the lips' last separate vertices (E, 2).

    The edges into the mouth corners (the vertex both seams share) are left out: the saliva
    film ends at the last separate pair (or runs on into the corner as one wedge), and a
    corner edge split would give the lips a pair closer to the corner than the rest gap.
    """
    edges = []
    q = face.quads
    shared = np.intersect1d(face.region("lip_seam_upper"), face.region("lip_seam_lower"))
    for name in ("lip_seam_upper", "lip_seam_lower"):
        seam = np.zeros(face.n_vertices, dtype=bool)
        seam[face.region(name)] = True
        seam[shared] = False
        for i in range(4):
            a, b = q[:, i], q[:, (i + 1) % 4]
            on = seam[a] & seam[b]
            edges.append(np.sort(np.stack([a[on], b[on]], axis=1), axis=1))
    if not edges or not sum(len(e) for e in edges):
        raise InputError("the face's lip seams share no quad edge: nothing to refine along the mouth")
    return np.unique(np.concatenate(edges), axis=0)


def seam_split(face: FaceMesh, elements: int = SEAM_ELEMENTS) -> int:
    """The split ``r`` that gives at least ``elements`` quad edges along the upper seam (1: none needed)."""
    upper = np.zeros(face.n_vertices, dtype=bool)
    upper[face.region("lip_seam_upper")] = True
    e = seam_edges(face)
    n = int((upper[e[:, 0]] & upper[e[:, 1]]).sum())
    return max(1, int(np.ceil(int(elements) / max(n, 1))))


def _chords(quads: np.ndarray, seeds: np.ndarray):
    """Split flags per quad, ``(Q, 2)`` bool (edges 0-1/3-2, edges 1-2/0-3), from the seed edges' chords."""
    Q = len(quads)
    edge_quads: dict = {}
    for qi in range(Q):
        for i in range(4):
            key = tuple(sorted((int(quads[qi, i]), int(quads[qi, (i + 1) % 4]))))
            edge_quads.setdefault(key, []).append((qi, i))
    split = np.zeros((Q, 2), dtype=bool)
    done = set()
    stack = [tuple(int(x) for x in e) for e in seeds]
    while stack:
        key = stack.pop()
        if key in done:
            continue
        done.add(key)
        for qi, i in edge_quads.get(key, ()):
            split[qi, i % 2] = True
            j = (i + 2) % 4
            stack.append(tuple(sorted((int(quads[qi, j]), int(quads[qi, (j + 1) % 4])))))
    return split, done


def refine_lip_seam(face: FaceMesh, elements: int = SEAM_ELEMENTS) -> FaceMesh:
    """The face with its lip seam (and the quad strips across it) split to ``elements`` or more along the mouth.

    Parameters
    ----------
    face : FaceMesh
        Needs the regions ``lip_seam_upper`` and ``lip_seam_lower`` on shared quad edges.
    elements : int
        Least number of quad edges along the upper seam between its two end pairs; each seam
        edge is split into ``ceil(elements / seam edges)`` parts. A face already that fine is
        returned as is.

    Returns
    -------
    FaceMesh
        Vertices 0 … N−1 are ``face``'s; see the module docstring.
    """
    return lip_refinement(face, elements)[0]


def lip_refinement(face: FaceMesh, elements: int = SEAM_ELEMENTS):
    """:func:`refine_lip_seam`'s face, its interpolation ``P`` (sparse (N', N): refined = P @ face's
    vertex values) and each refined quad's quad of ``face``, (Q',) int."""
    import scipy.sparse as sp
    if int(elements) < 1:
        raise InputError(f"seam elements must be >= 1, got {elements}")
    r = seam_split(face, elements)
    N = face.n_vertices
    if r == 1:
        return face, sp.identity(N, format="csr"), np.arange(len(face.quads))
    split, edges = _chords(face.quads, seam_edges(face))
    tri_edges = {tuple(sorted((int(t[i]), int(t[(i + 1) % 3])))) for t in face.tris for i in range(3)}
    if tri_edges & edges:
        raise InputError("a lip-seam chord runs into a triangle of the face: only quads can be split")
    rows, cols, vals = [np.arange(N)], [np.arange(N)], [np.ones(N)]
    n = N
    on_edge = {}
    w = np.arange(1, r) / r
    for a, b in sorted(edges):                                 # r − 1 new vertices on each split edge, from a
        on_edge[(a, b)] = n + np.arange(r - 1)
        rows += [on_edge[(a, b)]] * 2
        cols += [np.full(r - 1, a), np.full(r - 1, b)]
        vals += [1.0 - w, w]
        n += r - 1
    quads, parent = [], []
    for qi, qd in enumerate(face.quads):
        ns, nt = (r if split[qi, 0] else 1), (r if split[qi, 1] else 1)
        if ns == 1 and nt == 1:
            quads.append(qd[None, :])
            parent.append(qi)
            continue
        grid = np.full((ns + 1, nt + 1), -1, dtype=np.int64)
        grid[0, 0], grid[ns, 0], grid[ns, nt], grid[0, nt] = qd
        for (i0, j0), (i1, j1), steps in (((0, 0), (ns, 0), ns), ((0, nt), (ns, nt), ns),
                                          ((0, 0), (0, nt), nt), ((ns, 0), (ns, nt), nt)):
            if steps == 1:
                continue
            a, b = int(grid[i0, j0]), int(grid[i1, j1])
            mid = on_edge[(min(a, b), max(a, b))]
            k = np.arange(1, steps)
            grid[i0 + (i1 - i0) * k // steps, j0 + (j1 - j0) * k // steps] = mid if a < b else mid[::-1]
        for i in range(1, ns if nt > 1 else 1):                  # two chords cross: bilinear interior vertices
            for j in range(1, nt):
                s, t = i / ns, j / nt
                rows.append(np.full(4, n))
                cols.append(qd)
                vals.append(np.array([(1 - s) * (1 - t), s * (1 - t), s * t, (1 - s) * t]))
                grid[i, j] = n
                n += 1
        i, j = np.meshgrid(np.arange(ns), np.arange(nt), indexing="ij")
        i, j = i.ravel(), j.ravel()
        quads.append(np.stack([grid[i, j], grid[i + 1, j], grid[i + 1, j + 1], grid[i, j + 1]], axis=1))
        parent.extend([qi] * len(i))
    P = sp.csr_matrix((np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))), shape=(n, N))
    colors = None if face.colors is None else P @ face.colors
    fine = FaceMesh(P @ face.vertices, np.concatenate(quads), face.tris, _regions(face, P), dict(face.landmarks),
                    colors, face.landmarks_file, shading_parent=(P, face))
    return fine, P, np.array(parent, dtype=np.int64)


def _regions(face: FaceMesh, P) -> dict:
    """The face's regions, each new vertex in those that hold every vertex it is interpolated from."""
    N = face.n_vertices
    n_parents = np.diff(P.indptr)
    out = {}
    for name, idx in face.regions.items():
        member = np.zeros(N)
        member[idx] = 1.0
        hits = P.copy()
        hits.data = member[hits.indices]
        inside = np.add.reduceat(hits.data, P.indptr[:-1]) == n_parents
        inside[:N] = member.astype(bool)
        out[name] = np.flatnonzero(inside)
    return out
