r"""A sheet muscle of parallel fibres (the frontalis): its skin shortens evenly along the fibres.

Waters' linear muscle (:func:`visemeface.muscles.functions.linear_muscle_displacement`) is a fan: its zone is a
cone from a point of bone, and its pull rises from 0 at that point to the full pull at the insertion as
:math:`\sin(\frac{\pi}{2} D / R_s)`. That suits the zygomatic and levator muscles, bundles that converge on a
bony origin. The frontalis is not one: it is a flat sheet of parallel vertical fibres from the galea
aponeurotica to the skin of the brows (Standring, *Gray's Anatomy*), so when it shortens the skin between the hairline and the brows is gathered
evenly and the horizontal forehead lines run the forehead's whole height. As a cone its pull near the
attachment rises over a narrow apex, and on a head with a scalp (where the attachment fade of the rig keeps the
skin over the fixed end still) the forehead's whole shortening is crowded into a band under the hairline: the
skin there was compressed by up to half (dark blotches in the fold shade, dents in the geometry).

Here, with :math:`s` the distance along the fibres from the attachment :math:`A` toward the insertion :math:`I`
(:math:`L = |I - A|`, unit axis :math:`\mathbf e`) and :math:`\rho` the distance from the axis,

.. math::
    \Delta\mathbf p = -k\, g(s / L)\, \cos\left(\frac{\pi}{2}\min(\rho / w, 1)\right) \mathbf e,\qquad
    g(u) = \begin{cases} u & 0 \le u \le 1 \\
    \cos\left(\frac{u - 1}{u_f - 1}\frac{\pi}{2}\right) & 1 < u \le u_f \end{cases}

and 0 elsewhere: the pull grows linearly from the attachment to the insertion (an even strain
:math:`k / L` along the fibres), falls off past the insertion over Waters' :math:`R_f` (:math:`u_f = R_f / L`),
and across the sheet over the half width :math:`w = L \tan\Omega` (the fan's width at its insertion, so the
same rig values place either).
"""

from __future__ import annotations

import numpy as np


def parallel_muscle_displacement(points: np.ndarray, attachment, insertion, zone_angle: float,
                                 falloff_end: float, k: float = 1.0) -> np.ndarray:
    """Displacement (N, 3) of a sheet of parallel fibres at activation 1 (module notes).

    ``falloff_end`` is Waters' :math:`R_f` (m from the attachment, beyond the insertion); ``k`` the pull at
    the insertion (m).

    Examples
    --------
    >>> import numpy as np
    >>> p = np.array([[0, 0.5, 0], [0, 1.0, 0], [0.2, 1.0, 0], [0, 1.5, 0]])
    >>> d = parallel_muscle_displacement(p, [0, 0, 0], [0, 1, 0], np.pi / 4, 1.5, k=0.1)
    >>> np.round(d[:, 1], 4).tolist()                  # even along the fibres; none at R_f
    [-0.05, -0.1, -0.0951, -0.0]
    """
    p = np.asarray(points, dtype=float)
    a = np.asarray(attachment, dtype=float)
    axis = np.asarray(insertion, dtype=float) - a
    length = float(np.linalg.norm(axis))
    if not length > 0:
        raise ValueError("insertion coincides with the attachment")
    if not 0.0 < zone_angle < np.pi / 2:
        raise ValueError(f"a sheet's zone_angle must be in (0, pi/2), got {zone_angle}")
    u_f = falloff_end / length
    if not u_f > 1.0:
        raise ValueError(f"falloff_end must lie past the insertion, got {falloff_end} for a length of {length}")
    axis /= length
    v = p - a
    u = (v @ axis) / length
    rho = np.linalg.norm(v - (u * length)[:, None] * axis, axis=1)
    across = np.cos(np.minimum(rho / (length * np.tan(zone_angle)), 1.0) * np.pi / 2)
    along = np.where(u <= 1.0, u, np.cos(np.clip((u - 1.0) / (u_f - 1.0), 0.0, 1.0) * np.pi / 2))
    f = np.where((u > 0.0) & (u < u_f), along * across, 0.0)
    return -k * f[:, None] * axis[None, :]
