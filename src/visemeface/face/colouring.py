"""The default face's skin colours: vermilion, rosy cheeks, brows, lashes, nostrils, hair.

Colours are functions of the grid's arc coordinates (see :mod:`visemeface.face.shape`),
so they follow the features at every resolution.
"""

from __future__ import annotations

import functools

import numpy as np

from visemeface.face.shape import (_A, _BROW, _EYE_HALF_W, _EYE_X, _EYE_Y, _HAIR, _L0, _NOSTRIL, _SKIN,
                                   _U0, _XC, _gauss)
from visemeface.numeric import smoothstep as _smoothstep

_LASHES = np.array([0.10, 0.07, 0.06])
#: The rosy cheeks are the skin times this (a little less green and blue): the original face's
#: cheek colour (0.84, 0.55, 0.50) over its skin (0.87, 0.67, 0.56), so a darker skin gets darker cheeks.
_ROSY = np.array([0.84, 0.55, 0.50]) / _SKIN


@functools.lru_cache(maxsize=1)
def _table() -> dict:
    import tomllib

    from visemeface.resources import data_path

    with open(data_path("face", "skin_tones.toml"), "rb") as fh:
        return tomllib.load(fh)


def default_skin() -> str:
    """The preset the default face has when none is asked for (its original colours)."""
    return _table()["default"]


def skin_tones() -> dict[str, tuple[np.ndarray, np.ndarray]]:
    """Skin-tone presets ``{name: (skin rgb, lip rgb)}`` from ``data/face/skin_tones.toml``, light to dark."""
    return {k: (np.array(v["skin"], float), np.array(v["lip"], float)) for k, v in _table()["tone"].items()}


def skin_tone(name: str | None) -> tuple[np.ndarray, np.ndarray]:
    """The ``(skin, lip)`` colours of preset ``name`` (None: :func:`default_skin`); InputError if unknown."""
    from visemeface.errors import InputError, close_matches

    tones = skin_tones()
    key = default_skin() if name is None else str(name).strip().upper()
    if key not in tones:
        raise InputError(f"unknown skin tone {name!r}{close_matches(str(name), list(tones))}; "
                         f"choose from {', '.join(tones)} (Fitzpatrick types, light to dark)")
    return tones[key]


def skin_colours(Xv: np.ndarray, Yv: np.ndarray, Ycv: np.ndarray, margins: np.ndarray,
                 skin: str | None = None) -> np.ndarray:
    """(n, 3) colours of the grid vertices at arc coordinates ``(Xv, Yv)``, canonical heights ``Ycv``.

    ``margins`` (3, n) marks the vertices of the lower-lid margin row, the upper-lid margin row and
    the row of the lash ledge just above it; ``skin`` names the skin and lip colours (:func:`skin_tone`,
    default :func:`default_skin`).
    """
    skin_rgb, lip_rgb = skin_tone(skin)
    g = np.tile(skin_rgb, (len(Xv), 1))
    ax = np.abs(Xv)
    # vermilion: rows between the borders, faded just past the corners
    lipw = np.where(Ycv >= 0, _smoothstep((_U0 * 1.02 - Ycv) / (0.08 * _U0)),
                    _smoothstep((_L0 * 1.02 + Ycv) / (0.08 * _L0)))
    lipw = lipw * _smoothstep((_XC * 1.02 - ax) / 0.002)
    # cheeks slightly rosy
    rosy = 0.35 * _gauss(((ax - 0.045) / 0.016) ** 2 + ((Yv - 0.030) / 0.014) ** 2)
    # the brows lie on the orbital rim, their lower edge about 11 mm over the upper lid margin at
    # mid-pupil and a low arch (Farkas 1994; higher, arched brows read as raised: AU1+2)
    brow_line = 0.083 + 0.003 * np.sin(np.pi * np.clip((ax - 0.012) / 0.048, 0, 1)) ** 1.5 \
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
    g = g + rosy[:, None] * (_ROSY * skin_rgb - g)
    g = g + lipw[:, None] * (lip_rgb - g)
    g = g + 0.92 * np.clip(brow_w, 0, 1)[:, None] * (_BROW - g)
    # the lash line: the upper lid's margin and its ledge dark (the lashes and their shadow), the
    # lower margin a little darker (its fine lashes); a shadowed crease above
    in_eye = np.abs(ax - _EYE_X) <= _EYE_HALF_W + 1e-12
    for row, depth in zip(margins, (0.35, 0.92, 0.70)):
        m = row & in_eye
        g[m] = g[m] + depth * (_LASHES - g[m])
    g = g + np.clip(nostril_w, 0, 1)[:, None] * (_NOSTRIL - g)
    g = g * (1 - 0.16 * crease)[:, None]
    g = g + hair_w[:, None] * (_HAIR - g)
    # the mask fades toward its rim (behind the ears, over the crown, down the neck) so the cut
    # edges do not read as part of the face
    psi = np.abs(Xv) / _A(np.clip(Yv, -0.10, 0.21))
    rim = np.clip(np.maximum.reduce([(psi - 1.15) / 0.55, (Yv - 0.150) / 0.035,
                                     (-0.060 - Yv) / 0.025]), 0, 1)
    return g * (1 - 0.6 * _smoothstep(rim))[:, None]
