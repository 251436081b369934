"""Refining a face along the lip seam: conforming, the same surface, the old vertices first."""

from __future__ import annotations

import numpy as np
import pytest

from visemeface.errors import InputError
from visemeface.face.procedural import default_face, mirror_indices
from visemeface.face.refine import refine_lip_seam, seam_edges, seam_split


@pytest.fixture(scope="module")
def face():
    return default_face(resolution=1500)


@pytest.fixture(scope="module")
def fine(face):
    return refine_lip_seam(face, 48)


def _edges(quads):
    e = np.sort(np.concatenate([quads[:, [i, (i + 1) % 4]] for i in range(4)]), axis=1)
    return np.unique(e, axis=0, return_counts=True)


def _boundary_length(face):
    e, c = _edges(face.quads)
    b = e[c == 1]
    return float(np.linalg.norm(face.vertices[b[:, 0]] - face.vertices[b[:, 1]], axis=1).sum())


def test_the_seam_is_split_to_48_elements_and_the_old_vertices_stay_first(face, fine):
    N = face.n_vertices
    assert np.array_equal(fine.vertices[:N], face.vertices)
    assert fine.landmarks == face.landmarks
    upper = np.isin(seam_edges(fine), fine.region("lip_seam_upper")).all(axis=1).sum()
    assert upper >= 48 and seam_split(fine, 48) == 1
    assert len(fine.region("lip_seam_upper")) == len(fine.region("lip_seam_lower"))
    for name, idx in face.regions.items():                     # every old member stays a member
        assert np.isin(idx, fine.regions[name]).all()
    mirror_indices(fine.vertices, tol=1e-6)                     # still mirror-symmetric
    assert refine_lip_seam(fine, 48) is fine                    # already fine enough: unchanged


def test_refinement_is_conforming_and_keeps_the_surface(face, fine):
    _, counts = _edges(fine.quads)
    assert counts.max() == 2                                    # no edge shared by three quads
    # a hanging node would open a slit: more boundary than before
    assert _boundary_length(fine) == pytest.approx(_boundary_length(face), rel=1e-9)

    def area(f):
        p = f.vertices[f.quads]
        return 0.5 * np.linalg.norm(np.cross(p[:, 2] - p[:, 0], p[:, 3] - p[:, 1]), axis=1).sum()
    assert area(fine) == pytest.approx(area(face), rel=1e-3)


def test_refinement_refuses_bad_input(face):
    with pytest.raises(InputError, match="seam elements"):
        refine_lip_seam(face, 0)


def test_the_refined_face_is_shaded_as_the_face_it_refines(face, fine):
    """Its thin strips shaded by their own normals show the creases between the unrefined bilinear quads
    as streaks a strip wide; shaded by the interpolated normals of the face it refines, it renders as that
    face does."""
    from dataclasses import replace

    from visemeface.render.renderer import Renderer

    N = face.n_vertices
    assert np.allclose(fine.vertex_normals()[:N], face.vertex_normals(), atol=1e-12)
    own = replace(fine, shading_parent=None)
    images = []
    for f in (face, fine, own):
        with Renderer(f, size=(256, 256), view="mouth") as r:
            images.append(r.render(f.vertices).astype(float))
    shaded, streaked = (np.abs(images[0] - im).mean() for im in images[1:])
    assert shaded < 1.0 and streaked > 3 * shaded        # measured: 0.70 against 2.57 grey levels
