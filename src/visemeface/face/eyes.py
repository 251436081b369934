"""The default face's eyeballs: quad rings around a pupil fan on an ellipsoid."""

from __future__ import annotations

import numpy as np

from visemeface.face.shape import _IRIS, _PUPIL, _SCLERA

_HIGHLIGHT = np.array([0.97, 0.97, 0.96])
_HIGHLIGHT_SEGMENTS = 6


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
    ring_cols = [_IRIS * 0.8, _IRIS, _IRIS * 0.45, _SCLERA * 0.85] + [_SCLERA] * 5
    # the sclera is darker under the upper lid (its shadow and the lashes') and toward the corners
    # (the canthi, where the eyeball turns away): a white band round the iris reads as a stare
    shade = np.clip(1 - 0.30 * np.clip(s, 0, 1) ** 1.5, 0, 1)
    verts = [centre + np.array([0, 0, az + 0.0007])]
    cols = [_PUPIL]
    for k, (rx, ry) in enumerate(rings):
        x, y = rx * c, ry * s
        q = np.clip(1 - (x / ax) ** 2 - (y / ay) ** 2, 0, None)
        z = az * np.sqrt(q)
        if k < 4:  # corneal bulge over the iris
            z = z + 0.0007 * (1 - (np.hypot(x, y) / iris_r) ** 2).clip(0)
        verts.extend(centre + np.stack([x, y, z], 1))
        if k == 0:
            cols.extend([_PUPIL] * segments)
        elif k < 3:
            cols.extend([ring_cols[k]] * segments)
        else:
            side = np.clip((np.abs(x) - iris_r) / (ax - iris_r), 0, 1)
            cols.extend(ring_cols[k] * (shade * (1 - 0.22 * side ** 2))[:, None])
    # one ring behind the equator so the lids never show a gap
    verts.extend(centre + np.stack([ax * 0.97 * c, ay * 0.97 * s, np.full(segments, -0.35 * az)], 1))
    cols.extend([_SCLERA * 0.75] * segments)
    verts = np.array(verts)
    n_rings = len(rings) + 1
    ring_idx = start + 1 + np.arange(n_rings)[:, None] * segments + np.arange(segments)[None, :]
    nxt = np.roll(np.arange(segments), -1)
    tris = np.stack([np.full(segments, start), ring_idx[0], ring_idx[0][nxt]], 1)
    quads = []
    for k in range(n_rings - 1):
        # outward (toward +z at the front) ordering: inner -> outer ring, counter-clockwise from +z
        quads.append(np.stack([ring_idx[k], ring_idx[k + 1], ring_idx[k + 1][nxt], ring_idx[k][nxt]], 1))
    # the wet highlight: the lights' reflection on the cornea, a closed lens (two fans on one rim)
    # just in front of it, over the top of the pupil (straight up, so the face stays mirror-symmetric)
    hx, hy, hr = 0.0, 0.40 * iris_r, 0.11 * iris_r
    zc = az * np.sqrt(1 - (hx / ax) ** 2 - (hy / ay) ** 2) + 0.0007 * (1 - (hx ** 2 + hy ** 2) / iris_r ** 2)
    k = np.arange(_HIGHLIGHT_SEGMENTS)
    a = 2 * np.pi * k / _HIGHLIGHT_SEGMENTS
    lens = np.vstack([[hx, hy, zc + 0.00022], [hx, hy, zc - 0.0002],
                      np.stack([hx + hr * np.cos(a), hy + hr * np.sin(a), np.full(len(a), zc + 0.00012)], 1)])
    h0 = start + len(verts)
    rim = h0 + 2 + k
    rnext = h0 + 2 + (k + 1) % len(k)
    lens_tris = np.concatenate([np.stack([np.full(len(k), h0), rim, rnext], 1),
                                np.stack([np.full(len(k), h0 + 1), rnext, rim], 1)])
    verts = np.vstack([verts, centre + lens])
    cols = cols + [_HIGHLIGHT] * len(lens)
    return verts, np.concatenate(quads), np.concatenate([tris, lens_tris]), np.array(cols)
