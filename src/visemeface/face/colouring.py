"""The default face's skin colours: vermilion, rosy cheeks, brows, lashes, nostrils, hair.

Colours are functions of the grid's arc coordinates (see :mod:`visemeface.face.shape`),
so they follow the features at every resolution.
"""

from __future__ import annotations

import numpy as np

from visemeface.face.shape import (_A, _BROW, _EYE_HALF_W, _EYE_X, _EYE_Y, _HAIR, _L0, _LIP, _NOSTRIL, _SKIN,
                                   _U0, _XC, _gauss)
from visemeface.numeric import smoothstep as _smoothstep


def skin_colours(Xv: np.ndarray, Yv: np.ndarray, Ycv: np.ndarray, upper_margin: np.ndarray) -> np.ndarray:
    """(n, 3) colours of the grid vertices at arc coordinates ``(Xv, Yv)``, canonical heights ``Ycv``.

    ``upper_margin`` marks the vertices of the upper-lid margin row (the lash line).
    """
    g = np.tile(_SKIN, (len(Xv), 1))
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
    g = g + rosy[:, None] * (np.array([0.84, 0.55, 0.50]) - g)
    g = g + lipw[:, None] * (_LIP - g)
    g = g + 0.8 * np.clip(brow_w, 0, 1)[:, None] * (_BROW - g)
    # lash line along the upper lid margin, a shadowed crease above it
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
    return g * (1 - 0.6 * _smoothstep(rim))[:, None]
