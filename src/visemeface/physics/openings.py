"""Openings between the lips, measured on the mesh: at the seam vertices and along the film.

:func:`seam_openings` looks at the face mesh's paired seam vertices;
:func:`film_openings` at the saliva film's slabs (at least 48 across the
mouth, :mod:`visemeface.physics.film`), whose lip positions are the tissue's
own field between the seam vertices, so the open span it measures grows in
steps of a slab, not of a face-mesh element.
"""

from __future__ import annotations

import numpy as np

#: An opening: the lips further apart than the rest gap by this share of the mouth width.
OPEN_THRESHOLD = 0.02


def _runs(is_open):
    """(first, last) index of each run of True in a boolean array."""
    runs, start = [], None
    for i, o in enumerate(np.append(is_open, False)):
        if o and start is None:
            start = i
        elif not o and start is not None:
            runs.append((start, i - 1))
            start = None
    return runs


def seam_openings(fem, vertices, rest_gaps=None, threshold: float = OPEN_THRESHOLD) -> dict:
    """Openings along the lip seam, measured on the mesh.

    A seam pair is *open* when its gap exceeds the rest gap by more than
    ``threshold`` mouth widths. Contiguous open pairs form one opening.

    Returns
    -------
    dict
        ``count`` (number of openings), ``span`` (across-mouth extent of the
        widest opening, in mouth widths: (s_max − s_min)/2), ``open_fraction``
        (share of open pairs), ``centre_gap`` (gap growth at the pair nearest
        the centre, mouth widths), ``open`` (P,) bool.
    """
    gaps = fem.seam_gaps(vertices)
    if rest_gaps is None:
        rest_gaps = fem.seam_gaps(fem.face.vertices)
    growth = (gaps - rest_gaps) / fem.mouth_width
    is_open = growth > threshold
    runs = _runs(is_open)
    s = fem.seam_s
    spans = [(s[j] - s[i]) / 2.0 for i, j in runs]
    centre = int(np.argmin(np.abs(s)))
    return {"count": len(runs), "span": float(max(spans)) if spans else 0.0,
            "open_fraction": float(is_open.mean()), "centre_gap": float(growth[centre]), "open": is_open}


def film_openings(film, u, mouth_width: float, threshold: float = OPEN_THRESHOLD) -> dict:
    """Openings along the saliva film's slabs for node displacements ``u``.

    A slab is *open* when the lips at its skin-side centre are further apart than
    at rest by more than ``threshold`` mouth widths (the film's own gap, at
    :attr:`SalivaFilm.s` across the mouth). Slabs of all layers at one place
    across the mouth count once (the skin-side layer decides).

    Returns
    -------
    dict
        ``count`` openings, ``span`` (across-mouth extent of the widest, in mouth
        widths: slab count × slab width / 2), ``open`` (slabs,) bool, ``s`` their centres.
    """
    growth = (film.front_gaps(u) - film.rest_gap) / mouth_width
    n = len(film.s)
    order = np.argsort(film.s, kind="stable")
    s, is_open = film.s[order], growth[order] > threshold
    # one value per place across the mouth (several layers share it): open if any layer is
    keep = np.r_[True, np.diff(s) > 1e-9]
    place = np.cumsum(keep) - 1
    opened = np.zeros(int(place[-1]) + 1 if n else 0, dtype=bool)
    np.logical_or.at(opened, place, is_open)
    s_u = s[keep]
    width = np.diff(s_u).mean() if len(s_u) > 1 else 0.0
    spans = [(s_u[j] - s_u[i] + width) / 2.0 for i, j in _runs(opened)]
    return {"count": len(spans), "span": float(max(spans)) if spans else 0.0, "open": opened, "s": s_u}
