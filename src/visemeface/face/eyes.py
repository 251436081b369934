"""The default face's eyeballs: quad rings around a pupil fan on an ellipsoid."""

from __future__ import annotations

import numpy as np

from visemeface.face.shape import _IRIS, _PUPIL, _SCLERA

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
