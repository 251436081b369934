r"""The default face's mouth interior: cavity walls, teeth, gums and tongue.

Everything here is built in the face's final frame (metres, origin the midpoint
of the mouth corners, lip seam at :math:`y = 0`, lips' front at
:math:`z \approx 10` mm on the centre line), after the skin is normalised.

Dental arches
-------------
Each arch is the parabola :math:`z = z_0 - k x^2` in the occlusal plane; teeth
are placed along it by arc length from the centre line with their crown widths
(mesio-distal, mm; Ash & Nelson, *Wheeler's Dental Anatomy*, mean values):
upper 8.5, 6.5, 7.5, 7.0, 6.5 (central and lateral incisors, canine, two
premolars), lower 5.0, 5.5, 7.0, 7.0, 7.0. :math:`k = 43\,\mathrm{m^{-1}}` puts
the first molars about 27 mm behind the incisors at 50 mm arch width. The
upper incisal edge sits 2.5 mm below the lip seam (incisor display at rest,
1–3 mm in adults); the lower incisors are 2 mm higher (overbite) and 2 mm
further back (overjet), so the arches overlap like a normal bite.
Each crown is a closed, tapered box (thin at the incisal edge, thick at the
gum); the gums are a three-row strip along each arch covering the crowns'
cervical ends.

Tongue
------
A grid surface (tip to back, left to right) lying on the floor of the mouth
inside the lower arch, its tip behind the lower incisors and below their edge.
The tongue's half width follows the lower arch's lingual side; its edges tuck
down so no rim shows. The rig moves it with the jaw (rigidly) and with its own
controls (``data/rig/default.toml``).

Cavity
------
A strip of quads per lip-slit column from the upper seam up and back, over the
back wall and down to the lower seam (a pouch 38 mm deep); its colour darkens
from the mucosa near the lips to near black at the back.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from visemeface.numeric import smoothstep

#: Crown widths (m), centre line outward: incisors, canine, premolars (see the module docstring).
UPPER_WIDTHS = np.array([8.5, 6.5, 7.5, 7.0, 6.5]) * 1e-3
LOWER_WIDTHS = np.array([5.0, 5.5, 7.0, 7.0, 7.0]) * 1e-3
#: Exposed crown heights (m), incisal edge to gum.
UPPER_HEIGHTS = np.array([10.0, 8.5, 9.5, 8.0, 7.0]) * 1e-3
LOWER_HEIGHTS = np.array([8.5, 8.5, 10.0, 8.0, 7.5]) * 1e-3
#: Edge rise along the arch (curve of Spee), m, per tooth.
EDGE_RISE = np.array([0.0, 0.3, 0.6, 1.2, 1.8]) * 1e-3
ARCH_K = 43.0                 # 1/m, parabola curvature of both arches
UPPER_EDGE_Y = -0.0025        # upper incisal edge below the seam
UPPER_LABIAL_Z = 0.0030       # upper incisors' labial face on the centre line
OVERBITE, OVERJET = 0.0020, 0.0020
CAVITY_DEPTH = 0.038
CAVITY_UP, CAVITY_DOWN = 0.016, 0.020

TOOTH = np.array([0.93, 0.91, 0.84])
GUM = np.array([0.78, 0.40, 0.42])
TONGUE = np.array([0.84, 0.47, 0.47])
MUCOSA = np.array([0.38, 0.12, 0.13])
THROAT = np.array([0.035, 0.008, 0.012])


@dataclass
class Part:
    """A piece of mesh: vertices, quads (indices local to the part) and colours."""

    vertices: np.ndarray
    quads: np.ndarray
    colors: np.ndarray


def lower_edge_y() -> float:
    """Height of the lower incisal edge at rest (m)."""
    return UPPER_EDGE_Y + OVERBITE


def _arch(z0: float, s: np.ndarray):
    """Points, labial normals and tangents at signed arc lengths ``s`` along :math:`z = z_0 - k x^2`."""
    x = np.linspace(0.0, 0.06, 3001)
    arc = np.concatenate([[0.0], np.cumsum(np.hypot(np.diff(x), np.diff(ARCH_K * x ** 2)))])
    ax = np.interp(np.abs(s), arc, x) * np.sign(s)
    z = z0 - ARCH_K * ax ** 2
    t = np.stack([np.ones_like(ax), np.zeros_like(ax), -2 * ARCH_K * ax], 1)
    t /= np.linalg.norm(t, axis=1, keepdims=True)
    n = np.stack([-t[:, 2], np.zeros_like(ax), t[:, 0]], 1)       # in the xz-plane, pointing forward/out
    return np.stack([ax, np.zeros_like(ax), z], 1), n, t


def _box_quads(start: int) -> np.ndarray:
    """Quads of a box whose 8 corners are ordered (edge/cervical, labial/lingual, mesial/distal) bits."""
    q = np.array([[0, 1, 3, 2], [4, 6, 7, 5], [0, 4, 5, 1], [2, 3, 7, 6], [0, 2, 6, 4], [1, 5, 7, 3]])
    return q + start


def _orient(vertices: np.ndarray, quads: np.ndarray, centre: np.ndarray) -> np.ndarray:
    """Flip quads whose normal points toward ``centre`` (closed convex pieces face outward)."""
    v = vertices[quads]
    n = np.cross(v[:, 2] - v[:, 0], v[:, 3] - v[:, 1])
    inward = np.einsum("ij,ij->i", n, v.mean(1) - centre) < 0
    out = quads.copy()
    out[inward] = out[inward][:, ::-1]
    return out


def _teeth(upper: bool) -> Part:
    """One arch of crowns (both sides, mirror-symmetric)."""
    widths = UPPER_WIDTHS if upper else LOWER_WIDTHS
    heights = UPPER_HEIGHTS if upper else LOWER_HEIGHTS
    z0 = UPPER_LABIAL_Z if upper else UPPER_LABIAL_Z - OVERJET
    y_edge = UPPER_EDGE_Y if upper else lower_edge_y()
    up = 1.0 if upper else -1.0          # from the edge toward the gum
    edges = np.concatenate([[0.0], np.cumsum(widths)])
    verts, quads, cols = [], [], []
    for side in (-1.0, 1.0):
        for i, w in enumerate(widths):
            gap = 0.00008          # crowns touch at their contact points
            s = side * np.array([edges[i] + gap, edges[i + 1] - gap])
            p, n, _ = _arch(z0, s)
            incisor = i < 2
            thick = (np.array([0.0012, 0.0055]) if incisor else np.array([0.0045, 0.0070]))
            corners = []
            for level, th in zip((0, 1), thick):          # incisal edge, then cervical end
                y = y_edge + up * (EDGE_RISE[i] + level * heights[i])
                for face_side in (0, 1):                    # labial, lingual
                    for k in (0, 1):                        # mesial, distal
                        q = p[k] - face_side * th * n[k]
                        # the labial face bulges a little toward the gum
                        q = q + (1 - face_side) * 0.0004 * level * n[k]
                        corners.append([q[0], y, q[2]])
            corners = np.array(corners)
            start = len(verts) * 8
            verts.append(corners)
            quads.append(_orient(corners, _box_quads(0), corners.mean(0)) + start)
            shade = 1.0 - 0.07 * i
            cols.append(np.tile(TOOTH * shade, (8, 1)))
    return Part(np.concatenate(verts), np.concatenate(quads), np.concatenate(cols))


def _gum(upper: bool, samples: int = 25) -> Part:
    """A strip of gum along an arch: over the crowns' cervical ends, up (down) and back to the palate."""
    widths = UPPER_WIDTHS if upper else LOWER_WIDTHS
    heights = UPPER_HEIGHTS if upper else LOWER_HEIGHTS
    z0 = UPPER_LABIAL_Z if upper else UPPER_LABIAL_Z - OVERJET
    y_edge = UPPER_EDGE_Y if upper else lower_edge_y()
    up = 1.0 if upper else -1.0
    total = widths.sum() + 0.003
    s = np.linspace(-total, total, samples)
    p, n, _ = _arch(z0, s)
    edges = np.concatenate([[0.0], np.cumsum(widths)])
    tooth = np.clip(np.searchsorted(edges, np.abs(s)) - 1, 0, len(widths) - 1)
    # scalloped margin: lower over a crown's middle, higher between crowns
    phase = (np.abs(s) - edges[tooth]) / widths[tooth]
    margin = heights[tooth] + EDGE_RISE[tooth] - 0.0018 + 0.0012 * np.cos(2 * np.pi * phase)
    rows = [(margin, 0.0005), (margin + 0.004, -0.0002), (np.full(len(s), heights.max() + 0.0055), -0.0035),
            (np.full(len(s), heights.max() + 0.0060), -0.011)]
    verts = []
    for height, out in rows:
        q = p + out * n
        q[:, 1] = y_edge + up * height
        verts.append(q)
    verts = np.concatenate(verts)
    m = len(s)
    quads = []
    for r in range(len(rows) - 1):
        for i in range(m - 1):
            a, b = r * m + i, (r + 1) * m + i
            quads.append((a, a + 1, b + 1, b) if upper else (a, b, b + 1, a + 1))
    cols = np.tile(GUM, (len(verts), 1))
    cols[-m:] *= 0.7
    return Part(verts, np.array(quads, np.int64), cols)


def _tongue(nu: int = 11, nv: int = 11) -> Part:
    """The tongue's upper surface, tip to back, subject's right to left, curling under at the tip.

    Rows ``u < 0`` wrap under the tip (its underside, seen when the tip lifts).
    """
    y_l = lower_edge_y()
    z_tip = UPPER_LABIAL_Z - OVERJET - 0.0032
    length = 0.036
    u = np.concatenate([[-0.2, -0.1], np.linspace(0.0, 1.0, nu)])
    v = np.linspace(-1.0, 1.0, nv)
    U, V = np.meshgrid(u, v, indexing="ij")
    Up = np.clip(U, 0, None)
    dz = length * Up                                             # depth behind the tip
    # half width inside the lower arch's lingual side, rounded at the tip
    half = np.maximum(0.0035, np.sqrt((dz + 0.0012) / ARCH_K) - 0.0068)
    x = V * half
    # rounded tip: the sides of the first rows sit further back
    z = z_tip - dz - 0.004 * (1 - np.sqrt(np.clip(1 - V ** 2, 0, 1))) * (1 - smoothstep(Up / 0.3))
    dorsum = -0.0045 + 0.0062 * smoothstep(Up / 0.45) - 0.004 * smoothstep((Up - 0.8) / 0.2)
    y = y_l + dorsum - 0.0055 * np.abs(V) ** 3
    under = U < 0                                                # curl under the tip: down and back
    y = np.where(under, y + 0.030 * U, y)
    z = np.where(under, z + 0.012 * U, z)
    x = np.where(under, x * (1 + 1.5 * U), x)
    verts = np.stack([x, y, z], -1).reshape(-1, 3)
    n_u = len(u)
    quads = []
    for i in range(n_u - 1):
        for j in range(nv - 1):
            a, b = i * nv + j, (i + 1) * nv + j
            quads.append((a, a + 1, b + 1, b))      # normals up
    quads = np.array(quads, np.int64)
    shade = (1.0 - 0.55 * smoothstep((U - 0.25) / 0.75)) * (1.0 - 0.25 * np.abs(V) ** 2)
    shade = np.where(under, 0.8, shade)
    cols = (TONGUE[None, None, :] * shade[..., None]).reshape(-1, 3)
    return Part(verts, quads, cols)


def cavity(seam_up: np.ndarray, seam_lo: np.ndarray, x_rel: np.ndarray, rows: int):
    """Cavity walls between the upper and lower seams (each (C, 3), one per slit column).

    ``x_rel`` is each column's lateral position over the half mouth width (-1..1).
    Returns the ``rows - 1`` inner rows of vertices ((rows - 1, C, 3)) and their
    colours, darkening toward the back wall.
    """
    taper = np.maximum(np.clip(1 - x_rel ** 2, 0, None) ** 0.35, 0.3)
    mid = 0.5 * (seam_up + seam_lo)
    out, cols = [], []
    for r in range(1, rows):
        t = r / rows
        p = mid.copy()
        p[:, 1] += np.sin(2 * np.pi * t) * (CAVITY_UP if t < 0.5 else CAVITY_DOWN) * taper
        p[:, 2] -= CAVITY_DEPTH * taper * np.sin(np.pi * t) + 0.002
        out.append(p)
        back = smoothstep(np.sin(np.pi * t) / 0.8)
        cols.append(np.tile(MUCOSA + back * (THROAT - MUCOSA), (len(p), 1)))
    return np.array(out), np.array(cols)


def interior_parts() -> dict[str, Part]:
    """Teeth, gums and tongue of the default face, by region name."""
    return {"upper_teeth": _teeth(True), "lower_teeth": _teeth(False),
            "upper_gum": _gum(True), "lower_gum": _gum(False), "tongue": _tongue()}
