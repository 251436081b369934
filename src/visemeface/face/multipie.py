"""A face's regions and landmarks from its 68 Multi-PIE landmark vertices and its connectivity.

The Multi-PIE 68-point layout (Gross et al., "Multi-PIE", 2010; the iBUG 300-W annotation of Sagonas et al.,
2013) numbers the jaw contour 0-16 (the subject's right to left), the brows 17-26, the nose 27-35, the eyes
36-47, the outer lips 48-59 and the inner lips 60-67. From those vertices and the mesh's edges:

- the lip seams are the shortest surface paths through the inner-lip landmarks (a scanned head's lips touch
  in front and fold inward behind the contact line, so a height cut mislabels their inner surfaces);
- the lips are the surface vertices nearer (along the surface) to one seam than to the other, within the
  lip's height at the centre;
- the lids are the bands around each eye opening, above and below the eye's corners;
- the rig's named landmarks (mouth corners, lip centres, chin, nose, brows, jaw joints, cheeks) are the
  Multi-PIE vertices or points found from them.

The built-in ICT head (:mod:`visemeface.face.ict`) and a head prepared by ``face --prepare``
(:mod:`visemeface.face.prepare`) are labelled by these same functions.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp
from scipy.sparse.csgraph import connected_components, dijkstra
from scipy.sparse.linalg import spsolve

#: Multi-PIE 68 indices (0-based) of the landmarks the rig places itself by.
NAMED = {"mouth_corner_right": 48, "mouth_corner_left": 54, "upper_lip_mid": 62, "lower_lip_mid": 66,
         "upper_lip_top": 51, "lower_lip_bottom": 57, "chin": 8, "nose_tip": 30, "nasion": 27,
         "brow_inner_right": 21, "brow_inner_left": 22, "brow_outer_right": 17, "brow_outer_left": 26}
#: Inner-lip contour of the Multi-PIE 68 (corner, ..., corner): the upper then the lower lip.
UPPER_INNER = (60, 61, 62, 63, 64)
LOWER_INNER = (60, 67, 66, 65, 64)
#: Each eye's (outer corner, inner corner, lower lid points): the subject's right, then left.
EYES = ((36, 39, 40, 41), (45, 42, 46, 47))


def face_edges(quads: np.ndarray, tris: np.ndarray) -> np.ndarray:
    """(4Q + 3T, 2) the sides of each quad, then of each triangle, in order: side k of quad q is row
    ``k * Q + q``, side k of triangle t row ``4Q + k * T + t``."""
    quads = np.asarray(quads, np.int64).reshape(-1, 4)
    tris = np.asarray(tris, np.int64).reshape(-1, 3)
    return np.concatenate([quads[:, [0, 1]], quads[:, [1, 2]], quads[:, [2, 3]], quads[:, [3, 0]],
                           tris[:, [0, 1]], tris[:, [1, 2]], tris[:, [2, 0]]])


def edge_graph(vertices: np.ndarray, quads: np.ndarray, tris: np.ndarray, keep: np.ndarray) -> sp.csr_matrix:
    """Sparse (N, N) graph of the mesh's edges between ``keep`` vertices, weighted by length."""
    e = face_edges(quads, tris)
    e = e[keep[e].all(axis=1)]
    w = np.linalg.norm(vertices[e[:, 0]] - vertices[e[:, 1]], axis=1)
    n = len(vertices)
    g = sp.coo_matrix((w, (e[:, 0], e[:, 1])), shape=(n, n)).tocsr()
    return g.maximum(g.T)


def harmonic_extension(edges: np.ndarray, values: np.ndarray, fixed: np.ndarray, free: np.ndarray) -> np.ndarray:
    """``values`` (N,) with those of the ``free`` vertices replaced by the mesh graph's harmonic extension of
    the ``fixed`` ones (each free vertex the mean of its neighbours along ``edges``, (E, 2)): a smooth map over
    a region from its border. Free vertices in a part of the graph that reaches no fixed vertex keep their
    values."""
    n = len(values)
    use = (free | fixed)[edges].all(axis=1) & free[edges].any(axis=1)
    e = edges[use]
    A = sp.coo_matrix((np.ones(len(e)), (e[:, 0], e[:, 1])), shape=(n, n)).tocsr()
    A = ((A + A.T) > 0).astype(float)
    idx, fix = np.flatnonzero(free), np.flatnonzero(fixed & ~free)
    out = np.asarray(values, dtype=float).copy()
    Aff, Afx = A[idx][:, idx], A[idx][:, fix]
    _, label = connected_components(Aff, directed=False)
    touches = np.zeros(label.max() + 1 if len(label) else 0, bool)
    touches[label[np.asarray(Afx.sum(axis=1)).ravel() > 0]] = True
    m = touches[label]
    if m.any():
        deg = np.asarray(A[idx[m]].sum(axis=1)).ravel()
        L = sp.diags(deg) - Aff[m][:, m]
        out[idx[m]] = spsolve(L.tocsc(), Afx[m] @ out[fix])
    return out


def surface_path(graph, a: int, b: int) -> list[int]:
    """The shortest path of vertices from ``a`` to ``b`` along the graph's edges (ValueError if none)."""
    _, pred = dijkstra(graph, indices=a, return_predecessors=True)
    out = [b]
    while out[-1] != a:
        p = pred[out[-1]]
        if p < 0:
            raise ValueError(f"no surface path between vertices {a} and {b}")
        out.append(int(p))
    return out[::-1]


def chain(graph, stops) -> np.ndarray:
    """The shortest surface paths between consecutive ``stops``, joined."""
    idx: list[int] = []
    for a, b in zip(stops[:-1], stops[1:]):
        idx.extend(surface_path(graph, int(a), int(b))[(1 if idx else 0):])
    return np.array(idx, dtype=np.int64)


def lip_regions(V: np.ndarray, graph, surface: np.ndarray, lm68: np.ndarray, exclusive: bool = False) -> dict:
    """``upper_lip``, ``lower_lip``, ``lip_seam_upper`` and ``lip_seam_lower`` of the ``surface`` vertices
    (a boolean mask; ``graph`` its :func:`edge_graph`). ``exclusive``: a vertex on both seams (the inner
    corners, where found landmarks put them on one lip's row of a slit mouth) is on neither."""
    upper_seam = chain(graph, lm68[list(UPPER_INNER)])
    lower_seam = chain(graph, lm68[list(LOWER_INNER)])
    corners = lm68[[48, 54]]
    both = np.intersect1d(upper_seam, lower_seam) if exclusive else corners
    upper_seam = np.setdiff1d(upper_seam, np.union1d(corners, both))
    lower_seam = np.setdiff1d(lower_seam, np.union1d(corners, both))
    du = dijkstra(graph, indices=upper_seam, min_only=True)
    dl = dijkstra(graph, indices=lower_seam, min_only=True)
    width = float(np.linalg.norm(V[lm68[54]] - V[lm68[48]]))
    up_h = float(np.linalg.norm(V[lm68[62]] - V[lm68[51]]))
    lo_h = float(np.linalg.norm(V[lm68[66]] - V[lm68[57]]))
    mid = V[lm68[[48, 54]]].mean(axis=0)
    # the vermilion's height falls from the centre to the corners (an ellipse's profile, a quarter left at them)
    x = np.clip(np.abs(V[:, 0] - mid[0]) / (0.5 * width), 0.0, 1.5)
    profile = np.sqrt(np.clip(1.0 - x ** 2, 0.0625, 1.0)) * (x <= 1.05)
    upper_lip = np.flatnonzero(surface & (du < dl) & (du <= up_h * profile))
    lower_lip = np.flatnonzero(surface & (dl < du) & (dl <= lo_h * profile))
    upper_lip = np.union1d(upper_lip, corners)
    return {"upper_lip": upper_lip, "lower_lip": lower_lip,
            "lip_seam_upper": upper_seam, "lip_seam_lower": lower_seam}


def lid_regions(V: np.ndarray, surface: np.ndarray, lm68: np.ndarray) -> dict:
    """``upper_lids`` and ``lower_lids``: the ``surface`` vertices within a band of each eye opening, split at
    the line between its corners."""
    upper_lids, lower_lids = [], []
    for outer, inner, lo_a, lo_b in EYES:
        c0, c1 = V[lm68[outer]], V[lm68[inner]]
        eye_w = float(np.linalg.norm(c1 - c0))
        centre = (c0 + c1) / 2
        q = V - centre
        near = surface & (np.abs(q[:, 0]) <= 0.6 * eye_w) & (np.abs(q[:, 1]) <= 0.55 * eye_w) & (q[:, 2] > -0.4 * eye_w)
        # height of the straight line between the eye's corners at each vertex's x
        t = np.clip((V[:, 0] - c0[0]) / (c1[0] - c0[0]), 0.0, 1.0)
        line_y = c0[1] + t * (c1[1] - c0[1])
        lower_y = np.mean([V[lm68[lo_a], 1], V[lm68[lo_b], 1]])
        upper_lids.append(np.flatnonzero(near & (V[:, 1] >= line_y)))
        lower_lids.append(np.flatnonzero(near & (V[:, 1] < line_y) & (V[:, 1] >= lower_y - 0.3 * eye_w)))
    return {"upper_lids": np.concatenate(upper_lids), "lower_lids": np.concatenate(lower_lids)}


def named_landmarks(V: np.ndarray, candidates: np.ndarray, lm68: np.ndarray) -> dict:
    """The rig's landmarks from the 68 (metres): :data:`NAMED`, the jaw joints and the cheeks, found among the
    ``candidates`` vertex indices (the eye centres are the caller's: an eyeball's front, where there is one)."""
    landmarks = {name: int(lm68[i]) for name, i in NAMED.items()}
    # the jaw joints: the face's contour halfway between Multi-PIE 1 and 2 (15 and 14), in front of the ear
    for side, (a, b) in (("right", (1, 2)), ("left", (15, 14))):
        target = (V[lm68[a]] + V[lm68[b]]) / 2
        landmarks[f"jaw_joint_{side}"] = int(candidates[np.argmin(np.linalg.norm(V[candidates] - target, axis=1))])
    # the cheeks: the front-most surface below the outer eye corner, halfway down to the nose's wing
    for side, (eye_o, nose) in (("left", (45, 35)), ("right", (36, 31))):
        target = np.array([V[lm68[eye_o], 0], (V[lm68[eye_o], 1] + V[lm68[nose], 1]) / 2])
        front = candidates[np.abs(V[candidates, 0] - target[0]) < 0.01]
        front = front[np.abs(V[front, 1] - target[1]) < 0.01]
        if not len(front):                      # a coarse mesh: the nearest vertex in the picture plane
            front = candidates[[np.argmin(np.linalg.norm(V[candidates, :2] - target, axis=1))]]
        landmarks[f"cheek_{side}"] = int(front[np.argmax(V[front, 2])])
    return landmarks


def mouth_interior(V: np.ndarray, upper_teeth: np.ndarray, lower_teeth: np.ndarray, soft: np.ndarray,
                   width: float) -> tuple[dict, dict]:
    """The mouth's inside from its teeth and its soft tissue (``soft``: gums and tongue, vertex indices): the gums
    are the soft vertices within 0.08 mouth widths (``width``, m) of the upper or the lower teeth, the tongue the
    rest above the lower teeth's lowest point, the floor of the mouth the rest below it (with the lower gum).
    Returns the regions and the landmarks of :data:`visemeface.face.mesh.INTERIOR_LANDMARKS` found."""
    from scipy.spatial import cKDTree

    du_t, _ = cKDTree(V[upper_teeth]).query(V[soft])
    dl_t, _ = cKDTree(V[lower_teeth]).query(V[soft])
    reach = 0.08 * width
    upper_gum = soft[(du_t < reach) & (du_t < dl_t)]
    lower_gum = soft[(dl_t < reach) & (dl_t <= du_t)]
    rest = np.setdiff1d(soft, np.concatenate([upper_gum, lower_gum]))
    tongue = rest[V[rest, 1] > V[lower_teeth, 1].min()]
    lower_gum = np.union1d(lower_gum, np.setdiff1d(rest, tongue))   # the floor of the mouth
    regions = {"upper_teeth": upper_teeth, "lower_teeth": lower_teeth, "upper_gum": upper_gum,
               "lower_gum": lower_gum, "tongue": tongue}
    landmarks = {"upper_incisor_edge": int(upper_teeth[np.argmin(V[upper_teeth, 1] - 0.5 * V[upper_teeth, 2])]),
                 "lower_incisor_edge": int(lower_teeth[np.argmax(V[lower_teeth, 1] + 0.5 * V[lower_teeth, 2])])}
    if len(tongue):
        landmarks["tongue_tip"] = int(tongue[np.argmax(V[tongue, 2])])
        landmarks["tongue_dorsum"] = int(tongue[np.argmax(V[tongue, 1])])
    return regions, landmarks
