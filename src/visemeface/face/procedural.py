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
"""

from __future__ import annotations

import numpy as np
from scipy.interpolate import PchipInterpolator

from visemeface.errors import InputError
from visemeface.face.mesh import CAVITY, FaceMesh

#: Corner-to-corner mouth width of the default face (m).
MOUTH_WIDTH = 0.05
#: Default target number of vertices.
DEFAULT_RESOLUTION = 4500

_XC = MOUTH_WIDTH / 2          # mouth corner (pre-wrap arc coordinate)
_X_END = 0.128                  # lateral rim (arc length from the centre line)
_Y_BOTTOM, _Y_TOP = -0.082, 0.185
_Y_SUBNASALE = 0.0185
_EYE_X, _EYE_Y = 0.0322, 0.066  # eye centre
_EYE_HALF_W = 0.0135            # half the palpebral fissure width
_LID_GAP = 0.0008               # lid band height outside the eye opening
_L0, _U0 = 0.0105, 0.0082       # lower / upper vermilion heights at the centre

_SKIN = np.array([0.87, 0.67, 0.56])
_LIP = np.array([0.78, 0.40, 0.41])
_BROW = np.array([0.36, 0.25, 0.19])
_NOSTRIL = np.array([0.30, 0.17, 0.15])
_HAIR = np.array([0.20, 0.135, 0.095])
_SCLERA = np.array([0.93, 0.91, 0.87])
_IRIS = np.array([0.30, 0.20, 0.12])
_PUPIL = np.array([0.03, 0.03, 0.03])


def _smoothstep(t):
    t = np.clip(t, 0.0, 1.0)
    return t * t * (3 - 2 * t)


def _gauss(d2):
    return np.exp(-d2)


# ----------------------------------------------------------------- feature curves
def _lower_border(X):
    """Height below the seam of the lower vermilion border, :math:`L(X) > 0`."""
    s = np.clip(1 - (np.abs(X) / _XC) ** 2, 0, None)
    L = _L0 * s ** 0.55
    # pinched at the corner, back to a normal band height away from the mouth
    out = (0.0090 - 0.0022) * _smoothstep((np.abs(X) - _XC) / 0.016)
    return np.sqrt(L ** 2 + 0.0022 ** 2) + out


def _upper_border(X):
    """Height of the upper vermilion border (Cupid's bow), :math:`U(X) > 0`."""
    ax = np.abs(X)
    s = np.clip(1 - (ax / _XC) ** 2, 0, None)
    bow = 0.0016 * _gauss(((ax - 0.0062) / 0.0042) ** 2) - 0.0006 * _gauss((ax / 0.0025) ** 2)
    U = (_U0 + bow) * s ** 0.5
    out = (0.0080 - 0.0022) * _smoothstep((ax - _XC) / 0.016)
    return np.sqrt(U ** 2 + 0.0022 ** 2) + out


def _eye_opening(X, band=0.003):
    """(lower, upper) lid offsets from the eye-centre height; open between the canthi.

    Outside the eye the two lid rows part again to an ordinary row spacing
    ``band``, so no thin crease runs across the face.
    """
    ax = np.abs(X)
    t = np.clip((ax - (_EYE_X - _EYE_HALF_W)) / (2 * _EYE_HALF_W), 0, 1)
    lower = 0.0043 * np.sin(np.pi * t) ** 0.9
    # the upper lid peaks a little medially of centre
    upper = 0.0049 * np.sin(np.pi * t ** 0.85) ** 0.8
    outside = np.clip(np.abs(ax - _EYE_X) - _EYE_HALF_W, 0, None)
    part = 0.5 * (band - _LID_GAP) * _smoothstep(outside / 0.008)
    return -(_LID_GAP / 2 + lower + part), _LID_GAP / 2 + upper + part


def _knots(X, lid_band=0.003):
    """Row feature curves (bottom to top) at lateral positions ``X``."""
    X = np.asarray(X, dtype=float)
    lo, up = _eye_opening(X, lid_band)
    one = np.ones_like(X)
    return [
        _Y_BOTTOM * one,
        -_lower_border(X),
        0.0 * one,
        _upper_border(X),
        _Y_SUBNASALE * one,
        _EYE_Y + lo,
        _EYE_Y + up,
        _Y_TOP * one,
    ]


#: Rows per band at resolution scale 1 (bands between consecutive knots).
_BAND_ROWS = (16, 4, 4, 4, 16, 1, 26)
_BAND_MIN = (6, 2, 2, 2, 6, 1, 8)
_SEAM_KNOT = 2


# ------------------------------------------------------------------ relief
def _relief(X, Y, Yc):
    r"""Forward offset :math:`h(X, Y, Y_c)` (m) of the features over the head shape.

    ``Yc`` is the row's canonical height (its height on the centre line), so
    the lip profile follows the vermilion borders laterally.
    """
    ax = np.abs(X)
    h = np.zeros_like(X)
    xc = _XC
    # muzzle: the dental arch pushes the whole mouth region forward
    h += 0.0105 * _gauss((ax / 0.034) ** 2 + ((Y + 0.004) / 0.030) ** 2)
    # lips: sagittal profile in canonical height, tapered to the corners
    lip_taper = np.clip(1 - (ax / xc) ** 2, 0, None) ** 0.6
    lip = np.where(
        Yc >= 0,
        0.0020 + 0.0034 * np.sin(np.pi * np.clip(Yc / _U0, 0, 1.35) / 1.5) ** 1.2,
        0.0020 + 0.0048 * np.sin(np.pi * np.clip(-Yc / _L0, 0, 1.3) / 1.45) ** 1.1,
    )
    fade = np.where(Yc >= 0, _smoothstep(1 - (Yc - _U0) / 0.007), _smoothstep(1 - (-Yc - _L0) / 0.006))
    h += lip * lip_taper * fade
    # vermilion border ridge ("white roll") on the upper lip
    h += 0.0007 * lip_taper * _gauss(((Yc - _U0) / 0.0012) ** 2)
    # philtrum: two ridges with a groove between, from the border to the nose
    phil = _smoothstep((Yc - _U0 * 0.9) / 0.002) * _smoothstep((_Y_SUBNASALE - Yc) / 0.003)
    h += phil * (0.0008 * _gauss(((ax - 0.0048) / 0.0017) ** 2) - 0.0005 * _gauss((ax / 0.0025) ** 2))
    # mentolabial sulcus and chin
    h -= 0.0030 * _gauss((ax / 0.022) ** 2 + ((Y + 0.019) / 0.006) ** 2)
    h += 0.0085 * _gauss((ax / 0.018) ** 2 + ((Y + 0.034) / 0.011) ** 2)
    # nose: dorsum from nasion to tip, tip lobule, columella underside
    t = np.clip((Y - _Y_SUBNASALE) / (0.068 - _Y_SUBNASALE), 0, 1.4)   # 0 subnasale .. 1 nasion
    prof = PchipInterpolator([0, 0.07, 0.2, 0.32, 0.6, 1.0, 1.2, 1.4],
                             [0.0, 0.011, 0.0215, 0.0230, 0.0170, 0.0085, 0.0030, 0.0])(t)
    width = PchipInterpolator([0, 0.2, 0.32, 0.6, 1.0, 1.4],
                              [0.0085, 0.0095, 0.0085, 0.0060, 0.0068, 0.0090])(t)
    on = Y > _Y_SUBNASALE - 0.003
    nose = prof * _gauss((ax / width) ** 2.4) * on
    h += nose
    # alae (nostril wings) and the alar crease around them
    ala = _gauss(((ax - 0.0125) / 0.0062) ** 2 + ((Y - 0.0235) / 0.0062) ** 2)
    h += 0.0088 * ala
    h -= 0.0016 * _gauss(((np.hypot(ax - 0.0125, (Y - 0.0235) * 1.0) - 0.0078) / 0.0016) ** 2) \
        * (Y > 0.017)
    # nostrils: shallow pits on the underside
    h -= 0.0022 * _gauss(((ax - 0.0062) / 0.0028) ** 2 + ((Y - 0.0212) / 0.0022) ** 2)
    # nasolabial fold: cheek fullness lateral to the line ala -> past the mouth corner
    p0, p1 = np.array([0.018, 0.022]), np.array([0.036, -0.012])
    d = p1 - p0
    n = np.array([d[1], -d[0]]) / np.hypot(*d)      # points laterally
    s = ((ax - p0[0]) * d[0] + (Y - p0[1]) * d[1]) / (d @ d)
    off = (ax - p0[0]) * n[0] + (Y - p0[1]) * n[1]
    along = _smoothstep(s / 0.15) * _smoothstep((1.1 - s) / 0.3)
    h += 0.0042 * along * _smoothstep(off / 0.006) * _gauss((off / 0.03) ** 2)
    # cheekbones and cheeks
    h += 0.0070 * _gauss(((ax - 0.047) / 0.018) ** 2 + ((Y - 0.045) / 0.014) ** 2)
    h += 0.0040 * _gauss(((ax - 0.040) / 0.020) ** 2 + ((Y - 0.010) / 0.020) ** 2)
    # brow ridge and glabella
    h += 0.0062 * _gauss(((Y - 0.087 + 0.004 * (ax / 0.05) ** 2) / 0.010) ** 2) * _gauss((ax / 0.060) ** 4)
    # eye sockets: the orbit is recessed; the lids are shaped over the eyeball later
    h -= 0.0075 * _gauss(((ax - _EYE_X) / 0.017) ** 2 + ((Y - _EYE_Y - 0.002) / 0.0125) ** 2)
    # temples
    h -= 0.0040 * _gauss(((ax - 0.070) / 0.015) ** 2 + ((Y - 0.085) / 0.025) ** 2)
    return h


# ------------------------------------------------------------------ head shape
_A = PchipInterpolator([-0.10, -0.045, -0.01, 0.03, 0.07, 0.11, 0.17, 0.21],
                       [0.050, 0.055, 0.065, 0.074, 0.075, 0.073, 0.068, 0.066])


def _wrap(X, Y, h):
    r"""Map arc coordinates and relief to 3-D (see the module docstring)."""
    a = _A(np.clip(Y, -0.10, 0.21))
    b = 1.25 * a
    # sagittal profile: chin curls under below y_m, forehead curls back above y_f
    y_m = -0.050 + 0.040 * _smoothstep((np.abs(X) - 0.012) / 0.100)
    r_c = 0.020
    d = np.clip(y_m - Y, 0, None)
    y = np.where(d > 0, y_m - r_c * np.sin(np.minimum(d / r_c, np.pi / 2))
                 - np.clip(d - r_c * np.pi / 2, 0, None) * 0.15, Y)
    zs = -r_c * (1 - np.cos(np.minimum(d / r_c, np.pi / 2))) - np.clip(d - r_c * np.pi / 2, 0, None)
    y_f, r_t = 0.095, 0.085
    e = np.clip(Y - y_f, 0, None)
    y = np.where(e > 0, y_f + r_t * np.sin(e / r_t), y)
    zs = zs - r_t * (1 - np.cos(e / r_t))
    psi = np.abs(X) / a
    # relief moves along z only, so features do not push the mouth corners apart
    x = np.sign(X) * a * np.sin(psi)
    z = zs - b * (1 - np.cos(psi)) + h * np.cos(psi)
    return np.stack([x, y, z], axis=1)


# ------------------------------------------------------------------ eyes
def _eyeball(centre, axes, segments, iris_r, pupil_r, start):
    """Quad rings around a pupil fan on an ellipsoid; circular iris in front view.

    Returns (vertices, quads, tris, colours); indices offset by ``start``.
    """
    ax, ay, az = axes
    phi = np.linspace(0, 2 * np.pi, segments, endpoint=False)
    c, s = np.cos(phi), np.sin(phi)
    # projected (x, y) radii of the rings: pupil, iris, limbus, then sclera to the equator
    rings = [(pupil_r, pupil_r), (0.5 * (pupil_r + iris_r),) * 2, (iris_r * 0.93,) * 2, (iris_r,) * 2]
    for f in (0.45, 0.65, 0.82, 0.93, 0.995):
        rings.append((iris_r + f * (ax - iris_r), iris_r + f * (ay - iris_r)))
    ring_cols = [_IRIS * 0.8, _IRIS, _IRIS * 0.6, _SCLERA * 0.9] + [_SCLERA] * 5
    verts = [centre + np.array([0, 0, az + 0.0007])]
    cols = [_PUPIL]
    for k, (rx, ry) in enumerate(rings):
        x, y = rx * c, ry * s
        q = np.clip(1 - (x / ax) ** 2 - (y / ay) ** 2, 0, None)
        z = az * np.sqrt(q)
        if k < 4:  # corneal bulge over the iris
            z = z + 0.0007 * (1 - (np.hypot(x, y) / iris_r) ** 2).clip(0)
        verts.extend(centre + np.stack([x, y, z], 1))
        cols.extend([_PUPIL if k == 0 else ring_cols[k]] * segments)
    # one ring behind the equator so the lids never show a gap
    verts.extend(centre + np.stack([ax * 0.97 * c, ay * 0.97 * s, np.full(segments, -0.35 * az)], 1))
    cols.extend([_SCLERA] * segments)
    verts = np.array(verts)
    n_rings = len(rings) + 1
    ring_idx = start + 1 + np.arange(n_rings)[:, None] * segments + np.arange(segments)[None, :]
    nxt = np.roll(np.arange(segments), -1)
    tris = np.stack([np.full(segments, start), ring_idx[0], ring_idx[0][nxt]], 1)
    quads = []
    for k in range(n_rings - 1):
        # outward (toward +z at the front) ordering: inner -> outer ring, counter-clockwise from +z
        quads.append(np.stack([ring_idx[k], ring_idx[k + 1], ring_idx[k + 1][nxt], ring_idx[k][nxt]], 1))
    return verts, np.concatenate(quads), tris, np.array(cols)


# ------------------------------------------------------------------ builder
def _layout(scale):
    """Grid sizes at a resolution scale: (jc, half columns, band rows, cavity rows, eye segments)."""
    jc = max(4, int(round(8 * scale)))
    n_half = jc + max(8, int(round(22 * scale)))
    counts = [max(mn, int(round(n * scale))) if n > 1 else 1 for n, mn in zip(_BAND_ROWS, _BAND_MIN)]
    n_cav = max(4, int(round(6 * scale)))
    segments = 4 * max(3, int(round(6 * scale)))
    return jc, n_half, counts, n_cav, segments


def _n_vertices(layout):
    jc, n_half, counts, n_cav, segments = layout
    nc, nr = 2 * n_half + 1, sum(counts) + 1
    return nc * nr + (2 * jc - 1) + (n_cav - 1) * (2 * jc + 1) + 2 * (1 + 10 * segments)


def _scale_for(resolution):
    """The grid scale whose vertex count is closest to ``resolution`` (deterministic search)."""
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


def default_face(resolution: int | None = None, rest_gap: float = 0.0) -> FaceMesh:
    """Build the embedded default face.

    Parameters
    ----------
    resolution : int, optional
        Target number of vertices (default :data:`DEFAULT_RESOLUTION`, about
        4,500; accepted range 800..200,000). Rows and columns scale with
        :math:`\\sqrt{\\text{resolution}/\\text{default}}`.
    rest_gap : float
        Opening between the lips at the centre of the mouth at rest (m), 0 to
        0.01; tapers to 0 at the corners.

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
    scale = _scale_for(resolution)
    jc, n_half, counts, n_cav, segments = _layout(scale)

    # ---- columns (exactly mirrored) and rows
    xh = _snap_canthi(_columns(jc, n_half))
    X = np.concatenate([-xh[:0:-1], xh])
    nc = len(X)
    ic = nc // 2                       # centre column
    icr, icl = ic - jc, ic + jc        # right (-x) and left (+x) mouth corners
    lid_band = 0.5 * ((_EYE_Y - _Y_SUBNASALE) / counts[4] + (_Y_TOP - _EYE_Y) / counts[6])
    knots = _knots(X, lid_band)
    knots0 = _knots(np.zeros(1), lid_band)
    rows_y, rows_yc = [], []
    for b, n in enumerate(counts):
        for r in range(n + (1 if b == len(counts) - 1 else 0)):
            f = r / n
            rows_y.append(knots[b] + (knots[b + 1] - knots[b]) * f)
            rows_yc.append(float((knots0[b] + (knots0[b + 1] - knots0[b]) * f)[0]))
    Yg = np.array(rows_y)              # (nr, nc)
    Ycg = np.repeat(np.array(rows_yc)[:, None], nc, axis=1)
    nr = len(Yg)
    js = sum(counts[:_SEAM_KNOT])      # the seam row
    jlid = sum(counts[:5])             # the lower-lid row (the eye band lies between jlid and jlid+1)

    # ---- vertex indices; seam row allocated so both seam regions are index- and x-sorted
    idx_up = -np.ones((nr, nc), np.int64)
    idx_lo = -np.ones((nr, nc), np.int64)
    counter = 0
    for j in range(nr):
        if j != js:
            idx_up[j] = idx_lo[j] = np.arange(counter, counter + nc)
            counter += nc
            continue
        cols_right = np.arange(0, icr + 1)
        idx_up[j, cols_right] = idx_lo[j, cols_right] = counter + np.arange(len(cols_right))
        counter += len(cols_right)
        slit = np.arange(icr + 1, icl)
        idx_up[j, slit] = counter + np.arange(len(slit))
        counter += len(slit)
        idx_lo[j, slit] = counter + np.arange(len(slit))
        counter += len(slit)
        cols_left = np.arange(icl, nc)
        idx_up[j, cols_left] = idx_lo[j, cols_left] = counter + np.arange(len(cols_left))
        counter += len(cols_left)
    n_grid = counter

    # arc coordinates per vertex
    Xv = np.empty(n_grid)
    Yv = np.empty(n_grid)
    Ycv = np.empty(n_grid)
    Xg = np.broadcast_to(X, (nr, nc))
    gap = float(rest_gap) * np.sqrt(np.clip(1 - (X / _XC) ** 2, 0, None))
    for idx in (idx_up, idx_lo):
        Xv[idx] = Xg
        Yv[idx] = Yg
        Ycv[idx] = Ycg
    Yv[idx_up[js]] = gap * 0.5
    Yv[idx_lo[js]] = -gap * 0.5
    Ycv[idx_up[js]] = 0.0
    Ycv[idx_lo[js]] = 0.0

    h = _relief(Xv, Yv, Ycv)
    V = _wrap(Xv, Yv, h)

    # ---- grid quads (counter-clockwise seen from the front)
    quads = []
    for j in range(nr - 1):
        lower = idx_up[j]          # the upper copy of row j is the bottom of quads above it
        upper = idx_lo[j + 1]      # the lower copy of row j+1 is the top of quads below it
        for i in range(nc - 1):
            if j == jlid and _EYE_X - _EYE_HALF_W - 1e-12 <= abs(X[i]) <= _EYE_X + _EYE_HALF_W + 1e-12 \
                    and _EYE_X - _EYE_HALF_W - 1e-12 <= abs(X[i + 1]) <= _EYE_X + _EYE_HALF_W + 1e-12:
                continue           # the palpebral fissure
            quads.append((lower[i], lower[i + 1], upper[i + 1], upper[i]))
    quads = np.array(quads, dtype=np.int64)

    # ---- eyelids shaped over the eyeballs (final coordinates)
    eye_parts = []
    eye_vertex_sets = []
    start = n_grid
    lid_margin = np.unique(np.concatenate([
        idx_up[jlid][np.abs(np.abs(X) - _EYE_X) <= _EYE_HALF_W + 1e-12],
        idx_up[jlid + 1][np.abs(np.abs(X) - _EYE_X) <= _EYE_HALF_W + 1e-12]]))
    for side in (-1.0, 1.0):
        cx = np.array([side * _EYE_X])
        c = _wrap(cx, np.array([_EYE_Y]), _relief(cx, np.array([_EYE_Y]), np.array([_EYE_Y])))[0]
        axes = (0.0150, 0.0125, 0.0105)          # lid ellipsoid semi-axes
        centre = c - np.array([0.0, 0.0, axes[2] - 0.0005])
        dx = (V[:, 0] - centre[0]) / axes[0]
        dy = (V[:, 1] - centre[1]) / axes[1]
        rr = np.hypot(dx, dy)
        w = _smoothstep((1.55 - rr) / 0.75)
        near = (w > 0) & (np.abs(Xv - side * _EYE_X) < 0.03) & (np.sign(Xv) == side)
        zl = centre[2] + axes[2] * np.sqrt(np.clip(1 - rr ** 2, 0, None))
        V[near, 2] = (1 - w[near]) * V[near, 2] + w[near] * np.maximum(zl[near], V[near, 2] - 0.004)
        t = 0.0012                                # lid thickness over the eyeball
        ev, eq, et, ecol = _eyeball(centre, (axes[0] - t, axes[1] - t, axes[2] - t), segments,
                                    0.0058, 0.0022, start)
        eye_parts.append((ev, eq, et, ecol))
        eye_vertex_sets.append(np.arange(start, start + len(ev)))
        start += len(ev)

    # ---- mouth cavity: quad strip from the upper seam, up-back, down-back, to the lower seam
    slit_cols = np.arange(icr, icl + 1)
    cav_idx = np.empty((n_cav + 1, len(slit_cols)), np.int64)
    cav_idx[0] = idx_up[js, slit_cols]
    cav_idx[n_cav] = idx_lo[js, slit_cols]
    cav_verts = []
    taper = np.maximum(np.sqrt(np.clip(1 - (X[slit_cols] / _XC) ** 2, 0, None)), 0.3)
    mid = 0.5 * (V[cav_idx[0]] + V[cav_idx[n_cav]])
    for r in range(1, n_cav):
        t = r / n_cav
        p = mid.copy()
        p[:, 1] += 0.0085 * taper * np.sin(2 * np.pi * t) * (1 if t < 0.5 else 0.8)
        p[:, 2] -= 0.0120 * taper * np.sin(np.pi * t) + 0.002
        cav_idx[r] = start + np.arange(len(slit_cols))
        start += len(slit_cols)
        cav_verts.append(p)
    cav_quads = []
    for r in range(n_cav):
        a, b = cav_idx[r], cav_idx[r + 1]
        for k in range(len(slit_cols) - 1):
            cav_quads.append((a[k + 1], a[k], b[k], b[k + 1]))
    cav_quads = np.array(cav_quads, np.int64)

    vertices = np.concatenate([V] + [p[0] for p in eye_parts] + cav_verts)
    all_quads = np.concatenate([quads] + [p[1] for p in eye_parts] + [cav_quads])
    tris = np.concatenate([p[2] for p in eye_parts])

    # ---- exact mirror symmetry, then normalise: mouth width and origin
    mirror = mirror_indices(vertices, tol=1e-6)
    vertices = np.stack([(vertices[:, 0] - vertices[mirror, 0]) / 2,
                         (vertices[:, 1] + vertices[mirror, 1]) / 2,
                         (vertices[:, 2] + vertices[mirror, 2]) / 2], axis=1)
    cl, cr = idx_up[js, icl], idx_up[js, icr]
    vertices = vertices * (MOUTH_WIDTH / (vertices[cl, 0] - vertices[cr, 0]))
    origin = 0.5 * (vertices[cl] + vertices[cr])
    origin[0] = 0.0
    vertices = vertices - origin

    # ---- regions
    n = len(vertices)
    grid_all = np.arange(n_grid)
    in_mouth = np.abs(Xv) <= _XC + 1e-12
    upper_lip = grid_all[in_mouth & (Ycv >= 0) & (Ycv <= _U0 + 1e-9)]
    upper_lip = upper_lip[np.isin(upper_lip, idx_lo[js, icr + 1:icl], invert=True)]
    lower_lip = grid_all[in_mouth & (Ycv <= 0) & (Ycv >= -_L0 - 1e-9)]
    lower_lip = lower_lip[np.isin(lower_lip, idx_up[js, icr + 1:icl], invert=True)]
    seam_up = idx_up[js, icr:icl + 1]
    seam_lo = idx_lo[js, icr:icl + 1]
    cav_all = np.concatenate([cav_idx[1:n_cav].ravel()])
    cav_lower = cav_idx[(n_cav + 1) // 2:n_cav].ravel() if n_cav > 1 else np.zeros(0, np.int64)
    below_seam = np.concatenate([idx_up[:js].ravel(), idx_lo[js, icr + 1:icl]])
    jaw = np.concatenate([below_seam, cav_lower])
    boundary = np.unique(np.concatenate([idx_up[0], idx_up[-1], idx_up[:, 0], idx_lo[:, 0],
                                         idx_up[:, -1], idx_lo[:, -1]]))
    fixed = np.unique(np.concatenate([grid_all[Yv >= 0.095],
                                      boundary[Yv[boundary] > 0.01]]))
    brow = grid_all[(np.abs(Xv) > 0.008) & (np.abs(Xv) < 0.062)
                    & (np.abs(Yv - 0.088 + 0.004 * (Xv / 0.05) ** 2) < 0.011)]
    cheek = grid_all[(np.abs(Xv) > 0.030) & (np.abs(Xv) < 0.075) & (Yv > -0.012) & (Yv < 0.052)]
    nose = grid_all[(np.abs(Xv) < 0.022) & (Yv > _Y_SUBNASALE - 0.002) & (Yv < 0.07) & (h > 0.003)]
    eyes = np.concatenate(eye_vertex_sets + [lid_margin])
    regions = {
        "upper_lip": upper_lip, "lower_lip": lower_lip,
        "lip_seam_upper": seam_up, "lip_seam_lower": seam_lo,
        "jaw": jaw, "fixed": fixed, "brow": brow, "cheek": cheek, "nose": nose,
        "eyes": eyes, "mouth_cavity": cav_all, "boundary": boundary,
    }

    # ---- landmarks
    def nearest(x, y, pool=grid_all):
        return int(pool[np.argmin((Xv[pool] - x) ** 2 + (Yv[pool] - y) ** 2)])

    centre_col = idx_up[:, ic]
    z_centre = vertices[centre_col, 2]
    lid_row_centre = idx_up[jlid, ic]
    landmarks = {
        "mouth_corner_left": int(cl), "mouth_corner_right": int(cr),
        "upper_lip_mid": int(idx_up[js, ic]), "lower_lip_mid": int(idx_lo[js, ic]),
        "upper_lip_top": int(idx_up[sum(counts[:3]), ic]),
        "lower_lip_bottom": int(idx_up[counts[0], ic]),
        "chin": nearest(0.0, -0.036),
        "nose_tip": int(centre_col[np.argmax(z_centre)]),
        "nasion": int(lid_row_centre),
        "brow_inner_left": nearest(0.016, 0.085), "brow_inner_right": nearest(-0.016, 0.085),
        "brow_outer_left": nearest(0.052, 0.088), "brow_outer_right": nearest(-0.052, 0.088),
        "jaw_joint_left": int(idx_up[int(np.argmin(np.abs(Yg[:, -1] - 0.025))), -1]),
        "jaw_joint_right": int(idx_up[int(np.argmin(np.abs(Yg[:, 0] - 0.025))), 0]),
        "eye_centre_left": int(eye_vertex_sets[1][0]), "eye_centre_right": int(eye_vertex_sets[0][0]),
        "cheek_left": nearest(0.045, 0.030), "cheek_right": nearest(-0.045, 0.030),
    }

    # ---- colours
    colours = np.tile(_SKIN, (n, 1))
    ax = np.abs(Xv)
    # vermilion: rows between the borders, faded just past the corners
    lipw = np.where(Ycv >= 0, _smoothstep((_U0 * 1.02 - Ycv) / (0.08 * _U0)),
                    _smoothstep((_L0 * 1.02 + Ycv) / (0.08 * _L0)))
    lipw = lipw * _smoothstep((_XC * 1.02 - ax) / 0.002)
    # cheeks slightly rosy
    rosy = 0.35 * _gauss(((ax - 0.045) / 0.016) ** 2 + ((Yv - 0.030) / 0.014) ** 2)
    brow_line = 0.088 + 0.006 * np.sin(np.pi * np.clip((ax - 0.012) / 0.048, 0, 1)) ** 1.5 \
        - 0.002 * (ax / 0.05)
    brow_w = (_smoothstep(1.15 - np.abs(Yv - brow_line) / (0.0062 - 0.0028 * np.clip((ax - 0.012) / 0.045, 0, 1)))
              * _smoothstep((ax - 0.010) / 0.004) * _smoothstep((0.060 - ax) / 0.005))
    # a soft shadow in the upper-lid crease
    crease = _gauss(((Yv - _EYE_Y - 0.0088 + 0.004 * ((ax - _EYE_X) / _EYE_HALF_W) ** 2) / 0.0018) ** 2) \
        * _gauss(((ax - _EYE_X) / (1.05 * _EYE_HALF_W)) ** 4)
    # hair above an arched hairline, lower at the temples
    hairline = 0.132 - 0.028 * _smoothstep((ax - 0.030) / 0.045)
    hair_w = _smoothstep((Yv - hairline) / 0.013)
    nostril_w = _gauss(((ax - 0.0062) / 0.0030) ** 2 + ((Yv - 0.0208) / 0.0022) ** 2)
    g = colours[:n_grid]
    g = g + rosy[:, None] * (np.array([0.84, 0.55, 0.50]) - g)
    g = g + lipw[:, None] * (_LIP - g)
    g = g + 0.8 * np.clip(brow_w, 0, 1)[:, None] * (_BROW - g)
    # lash line along the upper lid margin, a shadowed crease above it
    upper_margin = np.zeros(n_grid, bool)
    upper_margin[idx_up[jlid + 1]] = True
    lash = upper_margin & (np.abs(ax - _EYE_X) <= _EYE_HALF_W + 1e-12)
    g[lash] = g[lash] + 0.85 * (np.array([0.12, 0.08, 0.07]) - g[lash])
    g = g + np.clip(nostril_w, 0, 1)[:, None] * (_NOSTRIL - g)
    g = g * (1 - 0.16 * crease)[:, None]
    g = g + hair_w[:, None] * (_HAIR - g)
    # the mask fades toward its rim (behind the ears, over the crown, down the neck) so the cut
    # edges do not read as part of the face
    psi = np.abs(Xv) / _A(np.clip(Yv, -0.10, 0.21))
    rim = np.clip(np.maximum.reduce([(psi - 1.15) / 0.55, (Yv - 0.150) / 0.035,
                                     (-0.060 - Yv) / 0.025]), 0, 1)
    g = g * (1 - 0.6 * _smoothstep(rim))[:, None]
    colours[:n_grid] = g
    # the inner lip line: a darker vermilion along the seam (shows as the closed-lip line)
    colours[seam_up[1:-1]] *= 0.62
    colours[seam_lo[1:-1]] *= 0.62
    off = n_grid
    for p in eye_parts:
        colours[off:off + len(p[0])] = p[3]
        off += len(p[0])
    colours[cav_all] = CAVITY
    colours = (colours + colours[mirror]) / 2   # exact symmetry of colours too

    return FaceMesh(vertices, all_quads, tris, regions, landmarks, colours)


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
