r"""The embedded default face: a procedural, quad-structured face mask in metres.

Construction
------------
1. **A warped grid.** Columns sit at lateral arc positions :math:`X_i`
   (uniform across the mouth, then growing quadratically toward the ears;
   the mouth corners are columns). Rows follow *feature curves* of
   :math:`X`: lower vermilion border :math:`-L(X)`, lip seam :math:`0`, upper
   vermilion border :math:`U(X)` (with a Cupid's bow), subnasale, lower and
   upper eyelid margins, between bottom and top rims. Inside a band the rows
   are linear between its two curves, so a row keeps its anatomical role
   across the face. Each row has a *canonical height* :math:`Y_c`: its height on
   the centre line.
2. **The lip slit.** Between the mouth corners the seam row has two copies,
   upper and lower (``rest_gap`` apart at the centre, tapering to 0 at the
   corners); quads above use the upper copies, quads below the lower ones.
   Outside the corners the seam row is shared. A dark *mouth cavity* strip
   of quads joins the upper seam to the lower seam behind the lips.
3. **Relief.** A forward offset :math:`h(X, Y, Y_c)` sums smooth bumps: lip
   volume (profile in :math:`Y_c` so it follows the vermilion), philtrum,
   nose (dorsum, tip, alae, nostrils), brow ridge, cheekbones, chin,
   nasolabial fold, eye sockets.
4. **Wrapping.** :math:`(X, Y, h)` is wrapped onto an egg-shaped head: with
   half-width :math:`a(Y)`, depth :math:`b(Y)` and :math:`\psi = X / a`,

   .. math:: x = a\sin\psi,\quad z = z_s(Y) - b(1 - \cos\psi) + h\cos\psi,

   and the sagittal profile :math:`(y, z_s)` curls back under the chin and over
   the forehead.
5. **Eyes.** The eyelid opening is the grid band between the two lid rows
   (removed between the canthi, an open boundary); behind it sits an
   eyeball of quad rings around a pupil fan, with a circular iris.
6. Exact mirror symmetry (``x -> -x``) is enforced, then the mesh is scaled
   so the mouth width is exactly :data:`MOUTH_WIDTH` and moved so the
   midpoint of the mouth corners is the origin.
7. **Mouth interior** (:mod:`visemeface.face.mouth`), in the final frame: a
   dark cavity pouch behind the lips, teeth and gums on two dental arches, and
   a tongue on the floor of the mouth. They are all in the ``mouth_cavity``
   region (kinematic, never tissue) and in their own regions ``cavity_wall``,
   ``upper_teeth``, ``lower_teeth``, ``upper_gum``, ``lower_gum``, ``tongue``.

The shape lives in :mod:`visemeface.face.shape`, the eyeballs in
:mod:`visemeface.face.eyes`, the skin colours in :mod:`visemeface.face.colouring`.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from visemeface.errors import InputError
from visemeface.face import mouth
from visemeface.face.colouring import skin_colours, skin_tone
from visemeface.face.eyes import _eyeball
from visemeface.face.mesh import FaceMesh
from visemeface.face.shape import (_BAND_MIN, _BAND_ROWS, _EYE_HALF_W, _EYE_X, _EYE_Y, _IRIS_R, _L0, _SEAM_KNOT, _U0,
                                   _X_END, _XC, _Y_SUBNASALE, _Y_TOP, DEFAULT_RESOLUTION, MOUTH_WIDTH, _knots,
                                   _relief, _wrap)
from visemeface.numeric import smoothstep as _smoothstep

__all__ = ["DEFAULT_RESOLUTION", "MOUTH_WIDTH", "default_face", "mirror_indices"]

#: Interior parts, in the order their vertices follow the cavity walls.
INTERIOR = ("upper_teeth", "lower_teeth", "upper_gum", "lower_gum", "tongue")


# ------------------------------------------------------------------ layout
def _layout(scale):
    """Grid sizes at a resolution scale: (jc, half columns, band rows, cavity rows, eye segments)."""
    jc = max(4, int(round(8 * scale)))
    n_half = jc + max(8, int(round(22 * scale)))
    counts = [max(mn, int(round(n * scale))) if n > 1 else 1 for n, mn in zip(_BAND_ROWS, _BAND_MIN)]
    n_cav = max(4, int(round(6 * scale)))
    segments = 4 * max(3, int(round(6 * scale)))
    return jc, n_half, counts, n_cav, segments


def _n_vertices(layout):
    """Vertices of the skin, eyes and cavity walls (the interior parts add a fixed number)."""
    jc, n_half, counts, n_cav, segments = layout
    nc, nr = 2 * n_half + 1, sum(counts) + 1
    return nc * nr + (2 * jc - 1) + (n_cav - 1) * (2 * jc + 1) + 2 * (1 + 10 * segments)


def _scale_for(resolution):
    """The grid scale whose skin, eye and cavity-wall vertex count is closest to ``resolution``.

    The interior parts (about 500 vertices at every resolution) come on top, so a
    resolution gives the same skin grid as before the face had teeth.
    """
    scales = np.geomspace(0.2, 8.0, 400)
    counts = np.array([_n_vertices(_layout(s)) for s in scales])
    return float(scales[np.argmin(np.abs(counts - resolution))])


def _columns(jc, n_half):
    """Half-row of lateral positions X >= 0; the mouth corner is column ``jc``."""
    m = n_half - jc
    j = np.arange(n_half + 1)
    h = _XC / jc
    alpha = (_X_END - _XC - h * m) / m ** 2
    x = np.where(j <= jc, h * j, _XC + h * (j - jc) + alpha * np.clip(j - jc, 0, None) ** 2)
    return x


def _snap_canthi(xh):
    """Move the columns nearest the canthi onto them so the eye opening ends at columns."""
    xh = xh.copy()
    for target in (_EYE_X - _EYE_HALF_W, _EYE_X + _EYE_HALF_W):
        k = int(np.argmin(np.abs(xh - target)))
        xh[k] = target
    return xh


# ------------------------------------------------------------------ grid
@dataclass
class _Grid:
    """The warped grid: columns ``X``, row heights, vertex indices and arc coordinates."""

    X: np.ndarray
    Yg: np.ndarray
    counts: list
    idx_up: np.ndarray
    idx_lo: np.ndarray
    js: int                 # the seam row
    jlid: int               # the lower-lid row (the eye band lies between jlid and jlid + 1)
    ic: int
    icr: int
    icl: int
    Xv: np.ndarray = None
    Yv: np.ndarray = None
    Ycv: np.ndarray = None
    h: np.ndarray = None

    @property
    def n(self) -> int:
        return len(self.Xv)


def _rows(X, counts):
    """Row heights (nr, nc) and canonical heights (nr,) from the feature curves."""
    lid_band = 0.5 * ((_EYE_Y - _Y_SUBNASALE) / counts[4] + (_Y_TOP - _EYE_Y) / (counts[7] + 1))
    knots = _knots(X, lid_band)
    knots0 = _knots(np.zeros(1), lid_band)
    rows_y, rows_yc = [], []
    for b, n in enumerate(counts):
        for r in range(n + (1 if b == len(counts) - 1 else 0)):
            f = r / n
            rows_y.append(knots[b] + (knots[b + 1] - knots[b]) * f)
            rows_yc.append(float((knots0[b] + (knots0[b + 1] - knots0[b]) * f)[0]))
    return np.array(rows_y), np.array(rows_yc)


def _indices(nr, nc, js, icr, icl):
    """Vertex indices of the grid's upper and lower copies; the seam row is split in the slit,
    allocated so both seam regions are index- and x-sorted."""
    idx_up = -np.ones((nr, nc), np.int64)
    idx_lo = -np.ones((nr, nc), np.int64)
    counter = 0
    for j in range(nr):
        if j != js:
            idx_up[j] = idx_lo[j] = np.arange(counter, counter + nc)
            counter += nc
            continue
        for cols, both in ((np.arange(0, icr + 1), True), (np.arange(icr + 1, icl), False),
                           (np.arange(icl, nc), True)):
            idx_up[j, cols] = counter + np.arange(len(cols))
            counter += len(cols)
            if both:
                idx_lo[j, cols] = idx_up[j, cols]
            else:
                idx_lo[j, cols] = counter + np.arange(len(cols))
                counter += len(cols)
    return idx_up, idx_lo


def _grid(jc, n_half, counts, rest_gap) -> _Grid:
    xh = _snap_canthi(_columns(jc, n_half))
    X = np.concatenate([-xh[:0:-1], xh])
    nc = len(X)
    ic = nc // 2
    Yg, rows_yc = _rows(X, counts)
    nr = len(Yg)
    js = sum(counts[:_SEAM_KNOT])
    idx_up, idx_lo = _indices(nr, nc, js, ic - jc, ic + jc)
    g = _Grid(X, Yg, counts, idx_up, idx_lo, js, sum(counts[:5]), ic, ic - jc, ic + jc)
    n_grid = int(idx_lo.max()) + 1
    g.Xv, g.Yv, g.Ycv = np.empty(n_grid), np.empty(n_grid), np.empty(n_grid)
    Xg = np.broadcast_to(X, (nr, nc))
    Ycg = np.repeat(rows_yc[:, None], nc, axis=1)
    for idx in (idx_up, idx_lo):
        g.Xv[idx], g.Yv[idx], g.Ycv[idx] = Xg, Yg, Ycg
    gap = float(rest_gap) * np.sqrt(np.clip(1 - (X / _XC) ** 2, 0, None))
    g.Yv[idx_up[js]] = gap * 0.5
    g.Yv[idx_lo[js]] = -gap * 0.5
    g.Ycv[idx_up[js]] = 0.0
    g.Ycv[idx_lo[js]] = 0.0
    g.h = _relief(g.Xv, g.Yv, g.Ycv)
    return g


def _grid_quads(g: _Grid) -> np.ndarray:
    """Grid quads, counter-clockwise seen from the front; none across the palpebral fissures."""
    X = g.X
    in_eye = np.abs(np.abs(X) - _EYE_X) <= _EYE_HALF_W + 1e-12
    quads = []
    for j in range(len(g.Yg) - 1):
        lower = g.idx_up[j]          # the upper copy of row j is the bottom of quads above it
        upper = g.idx_lo[j + 1]      # the lower copy of row j+1 is the top of quads below it
        for i in range(len(X) - 1):
            if j == g.jlid and in_eye[i] and in_eye[i + 1]:
                continue
            quads.append((lower[i], lower[i + 1], upper[i + 1], upper[i]))
    return np.array(quads, dtype=np.int64)


def _eyes(g: _Grid, V: np.ndarray, segments: int):
    """Shape the lids over the eyeballs (in place on ``V``); returns the two eyeball parts."""
    parts = []
    start = g.n
    for side in (-1.0, 1.0):
        cx = np.array([side * _EYE_X])
        c = _wrap(cx, np.array([_EYE_Y]), _relief(cx, np.array([_EYE_Y]), np.array([_EYE_Y])))[0]
        axes = (0.0150, 0.0125, 0.0105)          # lid ellipsoid semi-axes
        centre = c - np.array([0.0, 0.0, axes[2] - 0.0005])
        rr = np.hypot((V[:, 0] - centre[0]) / axes[0], (V[:, 1] - centre[1]) / axes[1])
        w = _smoothstep((1.55 - rr) / 0.75)
        near = (w > 0) & (np.abs(g.Xv - side * _EYE_X) < 0.03) & (np.sign(g.Xv) == side)
        zl = centre[2] + axes[2] * np.sqrt(np.clip(1 - rr ** 2, 0, None))
        V[near, 2] = (1 - w[near]) * V[near, 2] + w[near] * np.maximum(zl[near], V[near, 2] - 0.004)
        t = 0.0012                                # lid thickness over the eyeball
        part = _eyeball(centre, (axes[0] - t, axes[1] - t, axes[2] - t), segments, _IRIS_R, 0.0022, start)
        parts.append(part)
        start += len(part[0])
    return parts


def _symmetrise(vertices, colours=None):
    """Exact mirror symmetry (x -> -x) of positions (and colours)."""
    mirror = mirror_indices(vertices, tol=1e-6)
    v = np.stack([(vertices[:, 0] - vertices[mirror, 0]) / 2,
                  (vertices[:, 1] + vertices[mirror, 1]) / 2,
                  (vertices[:, 2] + vertices[mirror, 2]) / 2], axis=1)
    return v if colours is None else (v, (colours + colours[mirror]) / 2)


def _mouth_inside(g: _Grid, V: np.ndarray, n_cav: int):
    """Cavity walls and interior parts after the skin (final frame).

    Returns (vertices, quads, colours, cavity index grid (n_cav+1, C), part index ranges).
    """
    slit = np.arange(g.icr, g.icl + 1)
    cav_idx = np.empty((n_cav + 1, len(slit)), np.int64)
    cav_idx[0] = g.idx_up[g.js, slit]
    cav_idx[n_cav] = g.idx_lo[g.js, slit]
    rows, cav_cols = mouth.cavity(V[cav_idx[0]], V[cav_idx[n_cav]], g.X[slit] / _XC, n_cav)
    start = len(V)
    cav_idx[1:n_cav] = start + np.arange((n_cav - 1) * len(slit)).reshape(n_cav - 1, len(slit))
    quads = []
    for r in range(n_cav):
        a, b = cav_idx[r], cav_idx[r + 1]
        for k in range(len(slit) - 1):
            quads.append((a[k + 1], a[k], b[k], b[k + 1]))
    verts, cols, ranges = [rows.reshape(-1, 3)], [cav_cols.reshape(-1, 3)], {}
    quads = [np.array(quads, np.int64)]
    start += len(verts[0])
    for name, part in mouth.interior_parts().items():
        verts.append(part.vertices)
        quads.append(part.quads + start)
        cols.append(part.colors)
        ranges[name] = np.arange(start, start + len(part.vertices))
        start += len(part.vertices)
    return np.concatenate(verts), np.concatenate(quads), np.concatenate(cols), cav_idx, ranges


def _regions(g: _Grid, V: np.ndarray, eye_sets, cav_idx, n_cav, parts) -> dict:
    """Named vertex sets of docs/conventions.md (plus the interior parts)."""
    grid_all = np.arange(g.n)
    Xv, Yv, Ycv, js, icr, icl = g.Xv, g.Yv, g.Ycv, g.js, g.icr, g.icl
    in_mouth = np.abs(Xv) <= _XC + 1e-12
    upper_lip = grid_all[in_mouth & (Ycv >= 0) & (Ycv <= _U0 + 1e-9)]
    upper_lip = upper_lip[np.isin(upper_lip, g.idx_lo[js, icr + 1:icl], invert=True)]
    lower_lip = grid_all[in_mouth & (Ycv <= 0) & (Ycv >= -_L0 - 1e-9)]
    lower_lip = lower_lip[np.isin(lower_lip, g.idx_up[js, icr + 1:icl], invert=True)]
    walls = cav_idx[1:n_cav].ravel()
    cav_lower = cav_idx[(n_cav + 1) // 2:n_cav].ravel()
    lower_parts = np.concatenate([parts[k] for k in ("lower_teeth", "lower_gum", "tongue")])
    jaw = np.concatenate([g.idx_up[:js].ravel(), g.idx_lo[js, icr + 1:icl], cav_lower, lower_parts])
    boundary = np.unique(np.concatenate([g.idx_up[0], g.idx_up[-1], g.idx_up[:, 0], g.idx_lo[:, 0],
                                         g.idx_up[:, -1], g.idx_lo[:, -1]]))
    fixed = np.unique(np.concatenate([grid_all[Yv >= 0.095], boundary[Yv[boundary] > 0.01]]))
    brow = grid_all[(np.abs(Xv) > 0.008) & (np.abs(Xv) < 0.062)
                    & (np.abs(Yv - 0.088 + 0.004 * (Xv / 0.05) ** 2) < 0.011)]
    cheek = grid_all[(np.abs(Xv) > 0.030) & (np.abs(Xv) < 0.075) & (Yv > -0.012) & (Yv < 0.052)]
    nose = grid_all[(np.abs(Xv) < 0.022) & (Yv > _Y_SUBNASALE - 0.002) & (Yv < 0.07) & (g.h > 0.003)]
    in_eye = np.abs(np.abs(g.X) - _EYE_X) <= _EYE_HALF_W + 1e-12
    lid_margin = np.unique(np.concatenate([g.idx_up[g.jlid][in_eye], g.idx_up[g.jlid + 1][in_eye]]))
    # the lids: skin over the eyeball from each margin to 12 mm above (upper) or 9 mm below (lower)
    near_eye = np.abs(np.abs(Xv) - _EYE_X) <= _EYE_HALF_W + 0.004
    upper_lids = grid_all[near_eye & (Yv >= Yv[g.idx_up[g.jlid + 1, g.ic]] - 1e-9) & (Yv <= _EYE_Y + 0.017)
                          & (np.abs(Yv - _EYE_Y) < 0.02)]
    upper_lids = np.union1d(upper_lids, g.idx_up[g.jlid + 1][in_eye])
    lower_lids = grid_all[near_eye & (Yv <= _EYE_Y) & (Yv >= _EYE_Y - 0.013)]
    lower_lids = np.union1d(np.setdiff1d(lower_lids, upper_lids), g.idx_up[g.jlid][in_eye])
    regions = {
        "upper_lip": upper_lip, "lower_lip": lower_lip,
        "lip_seam_upper": g.idx_up[js, icr:icl + 1], "lip_seam_lower": g.idx_lo[js, icr:icl + 1],
        "jaw": jaw, "fixed": fixed, "brow": brow, "cheek": cheek, "nose": nose,
        "eyes": np.concatenate(eye_sets + [lid_margin]),
        "mouth_cavity": np.concatenate([walls] + list(parts.values())), "cavity_wall": walls,
        "upper_lids": upper_lids, "lower_lids": lower_lids, "eyeballs": np.concatenate(eye_sets),
        "boundary": boundary,
    }
    regions.update(parts)
    return regions


def _landmarks(g: _Grid, V: np.ndarray, eye_sets, parts) -> dict:
    """The landmark vertices of docs/conventions.md, plus the incisor edges and the tongue tip."""
    grid_all = np.arange(g.n)

    def nearest(x, y, pool=grid_all):
        return int(pool[np.argmin((g.Xv[pool] - x) ** 2 + (g.Yv[pool] - y) ** 2)])

    def lowest(idx, sign):          # the part's vertex furthest toward -y (sign 1) or +y, on the centre line
        near = idx[np.abs(V[idx, 0]) < 0.0045]
        key = sign * V[near, 1] - 1e-3 * V[near, 2]
        return int(near[np.argmin(key)])

    js, ic, counts = g.js, g.ic, g.counts
    centre_col = g.idx_up[:, ic]
    tongue = parts["tongue"]
    on_mid = tongue[np.abs(V[tongue, 0]) < 1e-9]
    return {
        "mouth_corner_left": int(g.idx_up[js, g.icl]), "mouth_corner_right": int(g.idx_up[js, g.icr]),
        "upper_lip_mid": int(g.idx_up[js, ic]), "lower_lip_mid": int(g.idx_lo[js, ic]),
        "upper_lip_top": int(g.idx_up[sum(counts[:3]), ic]),
        "lower_lip_bottom": int(g.idx_up[counts[0], ic]),
        "chin": nearest(0.0, -0.036),
        "nose_tip": int(centre_col[np.argmax(V[centre_col, 2])]),
        "nasion": int(g.idx_up[g.jlid, ic]),
        "brow_inner_left": nearest(0.016, 0.085), "brow_inner_right": nearest(-0.016, 0.085),
        "brow_outer_left": nearest(0.052, 0.088), "brow_outer_right": nearest(-0.052, 0.088),
        "jaw_joint_left": int(g.idx_up[int(np.argmin(np.abs(g.Yg[:, -1] - 0.025))), -1]),
        "jaw_joint_right": int(g.idx_up[int(np.argmin(np.abs(g.Yg[:, 0] - 0.025))), 0]),
        "eye_centre_left": int(eye_sets[1][0]), "eye_centre_right": int(eye_sets[0][0]),
        "cheek_left": nearest(0.045, 0.030), "cheek_right": nearest(-0.045, 0.030),
        "upper_incisor_edge": lowest(parts["upper_teeth"], 1.0),
        "lower_incisor_edge": lowest(parts["lower_teeth"], -1.0),
        "tongue_tip": int(on_mid[np.argmax(V[on_mid, 2])]),
        "tongue_dorsum": int(on_mid[np.argmax(V[on_mid, 1])]),
    }


def default_face(resolution: int | None = None, rest_gap: float = 0.0, skin: str | None = None) -> FaceMesh:
    """Build the embedded default face.

    Parameters
    ----------
    resolution : int, optional
        Target number of vertices (default :data:`DEFAULT_RESOLUTION`, about
        4,500, plus about 500 of teeth, gums and tongue; accepted range 800..200,000). Rows and columns scale with
        :math:`\\sqrt{\\text{resolution}/\\text{default}}`.
    rest_gap : float
        Opening between the lips at the centre of the mouth at rest (m), 0 to
        0.01; tapers to 0 at the corners.
    skin : str, optional
        Skin-tone preset of the skin and lip colours (``data/face/skin_tones.toml``: Fitzpatrick
        types ``"I"`` to ``"VI"``, light to dark; default ``"III"``, the original colours). Only
        colours change.

    Returns
    -------
    FaceMesh
        Deterministic: the same arguments give bit-identical arrays.

    Examples
    --------
    >>> face = default_face()
    >>> sorted(face.landmarks)[:3]
    ['brow_inner_left', 'brow_inner_right', 'brow_outer_left']
    """
    if resolution is None:
        resolution = DEFAULT_RESOLUTION
    if not isinstance(resolution, (int, np.integer)) or not 800 <= resolution <= 200_000:
        raise InputError(f"resolution must be an integer from 800 to 200000, got {resolution!r}")
    if not 0.0 <= float(rest_gap) <= 0.01:
        raise InputError(f"rest_gap must be between 0 and 0.01 m, got {rest_gap!r}")
    skin_tone(skin)                     # an unknown preset is refused before any work
    jc, n_half, counts, n_cav, segments = _layout(_scale_for(resolution))
    g = _grid(jc, n_half, counts, rest_gap)
    V = _wrap(g.Xv, g.Yv, g.h)
    quads = _grid_quads(g)
    eye_parts = _eyes(g, V, segments)
    eye_sets, start = [], g.n
    for p in eye_parts:
        eye_sets.append(np.arange(start, start + len(p[0])))
        start += len(p[0])
    margins = np.zeros((3, g.n), bool)          # the lower lid margin, the upper one, the lash ledge above it
    for k in range(3):
        margins[k, g.idx_up[g.jlid + k]] = True
    colours = np.concatenate([skin_colours(g.Xv, g.Yv, g.Ycv, margins, skin)] + [p[3] for p in eye_parts])
    # the inner lip line: a darker vermilion along the seam (shows as the closed-lip line)
    for seam in (g.idx_up[g.js, g.icr + 1:g.icl], g.idx_lo[g.js, g.icr + 1:g.icl]):
        colours[seam] *= 0.62
    V = _symmetrise(np.concatenate([V] + [p[0] for p in eye_parts]))
    # normalise: the mouth width and the origin
    cl, cr = g.idx_up[g.js, g.icl], g.idx_up[g.js, g.icr]
    V = V * (MOUTH_WIDTH / (V[cl, 0] - V[cr, 0]))
    origin = 0.5 * (V[cl] + V[cr])
    origin[0] = 0.0
    V = V - origin
    inside, inside_quads, inside_cols, cav_idx, parts = _mouth_inside(g, V, n_cav)
    V, colours = _symmetrise(np.concatenate([V, inside]), np.concatenate([colours, inside_cols]))
    all_quads = np.concatenate([quads] + [p[1] for p in eye_parts] + [inside_quads])
    tris = np.concatenate([p[2] for p in eye_parts])
    regions = _regions(g, V, eye_sets, cav_idx, n_cav, parts)
    landmarks = _landmarks(g, V, eye_sets, parts)
    return FaceMesh(V, all_quads, tris, regions, landmarks, colours)


def mirror_indices(vertices: np.ndarray, tol: float = 1e-9) -> np.ndarray:
    """Index ``m`` with ``vertices[m[i]]`` the mirror image (x -> -x) of ``vertices[i]``.

    Coincident vertices (the two copies of a closed lip seam) pair with each
    other in order. Raises ``ValueError`` if some vertex has no mirror within
    ``tol``.
    """
    from scipy.spatial import cKDTree
    v = np.asarray(vertices, dtype=float)
    mirrored = v * np.array([-1.0, 1.0, 1.0])
    tree = cKDTree(v)
    dist, m = tree.query(mirrored, k=1)
    if np.any(dist > tol):
        raise ValueError(f"{int(np.sum(dist > tol))} vertices have no mirror image within {tol}")
    return m
