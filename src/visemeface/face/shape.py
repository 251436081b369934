r"""The default face's shape: feature curves, relief and the head it is wrapped on.

Arc coordinates :math:`(X, Y)` on the face mask, the forward relief
:math:`h(X, Y, Y_c)` and the wrap onto an egg-shaped head (see
:mod:`visemeface.face.procedural` for the construction). Pure functions of numpy
arrays; lengths in metres before the final normalisation.
"""

from __future__ import annotations

import numpy as np
from scipy.interpolate import PchipInterpolator

from visemeface.numeric import smoothstep as _smoothstep

#: Corner-to-corner mouth width of the default face (m).
MOUTH_WIDTH = 0.05
#: Default target number of skin, eye and cavity-wall vertices (teeth, gums and tongue add about 500).
DEFAULT_RESOLUTION = 4500

_XC = MOUTH_WIDTH / 2          # mouth corner (pre-wrap arc coordinate)
_X_END = 0.128                  # lateral rim (arc length from the centre line)
_Y_BOTTOM, _Y_TOP = -0.082, 0.185
_Y_SUBNASALE = 0.0185
_EYE_X, _EYE_Y = 0.0322, 0.066  # eye centre
_EYE_HALF_W = 0.0135            # half the palpebral fissure width
_LID_GAP = 0.0008               # lid band height outside the eye opening
_IRIS_R = 0.0058                # iris radius (before the final scaling to MOUTH_WIDTH, about x1.025)
_L0, _U0 = 0.0105, 0.0082       # lower / upper vermilion heights at the centre

_SKIN = np.array([0.87, 0.67, 0.56])
_LIP = np.array([0.78, 0.40, 0.41])
_BROW = np.array([0.30, 0.21, 0.16])
_NOSTRIL = np.array([0.30, 0.17, 0.15])
_HAIR = np.array([0.20, 0.135, 0.095])
_SCLERA = np.array([0.93, 0.91, 0.87])
_IRIS = np.array([0.30, 0.20, 0.12])
_PUPIL = np.array([0.03, 0.03, 0.03])


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
    # At rest the upper lid margin covers the top 1.5 mm of the iris (radius 5.8 mm here, 5.95 mm
    # once scaled) and the lower lid lies at the iris' lower edge, a fissure of about 10 mm: an
    # adult's (Farkas 1994: palpebral fissure 8-11 mm high, 27-31 mm wide; upper lid 1-2 mm over
    # the limbus, the lower at it). Higher margins show sclera above the iris, the stare of AU5.
    lower = (_IRIS_R - 0.0001 - _LID_GAP / 2) * np.sin(np.pi * t) ** 0.9
    # the upper lid peaks a little medially of centre
    upper = (_IRIS_R - 0.0015 - _LID_GAP / 2) * np.sin(np.pi * t ** 0.85) ** 0.8
    outside = np.clip(np.abs(ax - _EYE_X) - _EYE_HALF_W, 0, None)
    part = 0.5 * (band - _LID_GAP) * _smoothstep(outside / 0.008)
    return -(_LID_GAP / 2 + lower + part), _LID_GAP / 2 + upper + part


def _knots(X, lid_band=0.003):
    """Row feature curves (bottom to top) at lateral positions ``X``."""
    X = np.asarray(X, dtype=float)
    lo, up = _eye_opening(X, lid_band)
    one = np.ones_like(X)
    # the upper lid's margin is a ledge about 1.2 mm deep with the lashes on it (one row above the
    # margin, so the lash line is a sharp dark band, not a shadow fading over a whole row);
    # outside the eye the row parts to an ordinary spacing
    outside = np.clip(np.abs(np.abs(X) - _EYE_X) - _EYE_HALF_W, 0, None)
    lash = _LASH + (lid_band - _LASH) * _smoothstep(outside / 0.008)
    return [
        _Y_BOTTOM * one,
        -_lower_border(X),
        0.0 * one,
        _upper_border(X),
        _Y_SUBNASALE * one,
        _EYE_Y + lo,
        _EYE_Y + up,
        _EYE_Y + up + lash,
        _Y_TOP * one,
    ]


#: Rows per band at resolution scale 1 (bands between consecutive knots).
_BAND_ROWS = (16, 4, 4, 4, 16, 1, 1, 25)
_BAND_MIN = (6, 2, 2, 2, 6, 1, 1, 7)
_LASH = 0.0012                  # height of the upper lid's lash ledge
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
