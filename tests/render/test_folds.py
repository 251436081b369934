"""Folds: compressed skin shades darker, stretched or resting skin not; the lengths behind it are areas."""

from __future__ import annotations

import numpy as np
import pytest

from visemeface.face.normals import NormalAccumulator
from visemeface.render.folds import FOLD_DEPTH, fold_shade


def _grid(n=12):
    """A flat n x n grid of unit squares (two triangles each) in the z = 0 plane."""
    x, y = np.meshgrid(np.arange(n, dtype=float), np.arange(n, dtype=float))
    V = np.column_stack([x.ravel(), y.ravel(), np.zeros(n * n)])
    i = np.arange(n * n).reshape(n, n)[:-1, :-1].ravel()
    T = np.concatenate([np.column_stack([i, i + 1, i + n + 1]), np.column_stack([i, i + n + 1, i + n])])
    return V, T


@pytest.mark.parametrize("compiled", [False, True])
def test_a_flat_vertex_normal_sum_is_twice_its_area(compiled, monkeypatch):
    import visemeface.runtime as rt

    V, T = _grid()
    monkeypatch.setattr(rt, "COMPILED_FROM_VERTICES", 1 if compiled else 10 ** 9)
    lengths = np.empty(len(V))
    NormalAccumulator(T, len(V))(V, lengths=lengths)
    area = np.zeros(len(V))
    np.add.at(area, T.ravel(), 0.5)          # each triangle's area (1/2) at each of its corners
    np.testing.assert_allclose(lengths, 2 * area)
    # squeezed along x to 80 %, every vertex's area shrinks by a fifth: a fold's shade, the same everywhere
    squeezed = V * [0.8, 1.0, 1.0]
    posed = np.empty(len(V))
    NormalAccumulator(T, len(V))(squeezed, lengths=posed)
    shade = fold_shade(posed, lengths)
    assert np.allclose(shade, shade[0]) and 0.2 * FOLD_DEPTH < shade[0] < FOLD_DEPTH
    # at rest nothing, stretched nothing
    assert not fold_shade(lengths, lengths).any()
    NormalAccumulator(T, len(V))(V * [1.3, 1.0, 1.0], lengths=posed)
    assert not fold_shade(posed, lengths).any()


def test_a_smile_shades_the_nasolabial_fold_and_an_open_jaw_shades_nothing():
    from visemeface.muscles.rig import default_rig
    from visemeface.render.renderer import Renderer

    rig = default_rig()
    face = rig.face
    acc = face.normal_accumulator()
    rest = np.empty(face.n_vertices)
    acc(face.vertices, lengths=rest)

    def shade(pose):
        out = np.empty(face.n_vertices)
        acc(rig.pose(pose), lengths=out)
        return fold_shade(out, rest)

    local = rig.frame.to_local(face.vertices) / rig.frame.width
    # beside and above each mouth corner, below the nose: where the cheek meets the lip
    fold = (np.abs(np.abs(local[:, 0]) - 0.55) < 0.2) & (local[:, 1] > 0.05) & (local[:, 1] < 0.6) & (local[:, 2] > -0.3)
    smile = shade({"zygomatic_major_left": 1.0, "zygomatic_major_right": 1.0})
    assert smile[fold].max() > 0.5 * FOLD_DEPTH
    chin = (np.abs(local[:, 0]) < 0.4) & (local[:, 1] < -0.2)
    assert shade({"jaw": 1.0})[chin].max() < 0.1 * FOLD_DEPTH           # the chin and lower lip are stretched
    # at rest a render is what it was without folds: every pixel
    with Renderer(face, size=128) as r:
        a = r.render()
        r._rest_lengths[:] = 0.0      # no rest lengths: no shade anywhere
        b = r.render()
    assert np.array_equal(a, b)
