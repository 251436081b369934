"""The FEM face: extrusion of the lower face, bone conditions, the saliva layer between the lips."""

from __future__ import annotations

import numpy as np
import pytest

from visemeface.errors import InputError
from visemeface.face.procedural import default_face
from visemeface.physics import face_model as fm
from visemeface.physics.hexmesh import element_quality
from visemeface.physics.materials import SALIVA, SOFT_TISSUE
from visemeface.physics.tled import TLEDSolver


@pytest.fixture(scope="module")
def face():
    return default_face(resolution=1500)


@pytest.fixture(scope="module")
def fem(face):
    return fm.build_fem_face(face)


def test_fem_face_is_valid_and_allows_the_seed_time_step(fem):
    q = element_quality(fem.mesh)
    assert (q["scaled_jacobian"] > 0.05).all()
    solver = TLEDSolver(fem.mesh, [SOFT_TISSUE, SALIVA], dt=1e-5, damping=80.0)
    assert solver.stable_dt >= 1e-5
    c = fem.counts()
    assert c["saliva"] >= 6 and c["tissue"] > 300
    assert c["nodes"] == fem.mesh.n_nodes and c["elements"] == c["tissue"] + c["saliva"]


def test_saliva_bridges_the_lips_with_y_across_them(fem, face):
    from visemeface.physics.saliva import element_frames
    X = fem.mesh.nodes[fem.mesh.hexes[fem.saliva]]
    y = element_frames(X)[:, 1]
    assert (y[:, 1] > 0.95).all()                      # local y runs up, lower lip to upper lip
    # Uniform thickness: every saliva element spans the same rest gap at its front.
    gaps = fem.rest_gaps
    np.testing.assert_allclose(gaps, fm.REST_GAP, rtol=1e-9)
    # Ordered from the subject's right corner (−x) to the left (+x), centred on the mouth.
    assert np.all(np.diff(fem.saliva_s) > 0) and abs(fem.saliva_s.mean()) < 1e-9
    up, lo = fem.seam_pairs.T
    assert set(up) <= set(face.region("lip_seam_upper")) and set(lo) <= set(face.region("lip_seam_lower"))


def test_bone_side_is_fixed_above_and_jaw_below(fem, face):
    S, L = fem.n_surface, fem.layers
    inner = fem.mesh.node_sets["inner"]
    assert np.array_equal(np.union1d(fem.mesh.node_sets["fixed"], fem.mesh.node_sets["jaw"]), inner)
    jaw_v = fem.surface_vertices[fem.mesh.node_sets["jaw"] - L * S]
    assert set(jaw_v) <= set(face.region("jaw"))
    # Bone side lies behind the skin, by the tissue depth (lips thinner).
    d = np.linalg.norm(fem.mesh.nodes[inner] - fem.mesh.nodes[inner - L * S], axis=1)
    assert d.max() == pytest.approx(fm.TISSUE_THICKNESS, rel=1e-6)
    assert d.min() == pytest.approx(fm.LIP_THICKNESS, rel=0.05)


def test_surface_round_trip_and_display_closes_the_rest_gap(fem):
    u = np.zeros((fem.mesh.n_nodes, 3))
    v = fem.surface(u)
    np.testing.assert_allclose(v, fem.face.vertices)
    shown = fem.display_vertices(v)
    assert np.allclose(fem.seam_gaps(shown), 0.0)                 # at rest the lips look closed
    u[: fem.n_surface][np.searchsorted(fem.surface_vertices, fem.seam_pairs[:, 1])] += [0, -0.002, 0]
    shown = fem.display_vertices(fem.surface(u))
    np.testing.assert_allclose(fem.seam_gaps(shown), 0.002, atol=1e-5)  # the opening beyond the film


def test_seam_openings_count_runs_of_open_pairs(fem):
    v = fem.face.vertices.copy()
    lo = fem.seam_pairs[:, 1]
    P = len(lo)
    drop = np.zeros(P)
    drop[1:3] = 0.003
    drop[P - 3:P - 1] = 0.003
    v[lo, 1] -= drop
    op = fm.seam_openings(fem, v)
    assert op["count"] == 2 and op["open"].sum() == 4
    v[lo, 1] -= 0.003
    op = fm.seam_openings(fem, v)
    assert op["count"] == 1 and op["open_fraction"] == 1.0
    assert op["span"] == pytest.approx((fem.seam_s[-1] - fem.seam_s[0]) / 2)


def test_bad_models_are_refused(face):
    with pytest.raises(InputError, match="saliva gap must be >= 0.3 mm"):
        fm.build_fem_face(face, saliva_gap=1e-4)
    with pytest.raises(InputError, match="tissue thickness must be > 0"):
        fm.build_fem_face(face, thickness=-1.0)
    with pytest.raises(InputError, match="rest gap between the lips"):
        fm.build_fem_face(face, saliva_gap=None)                   # the face's lips touch


def test_bone_side_relaxation_mends_flat_corner_elements():
    # The default face's mouth corners extrude into nearly flat deep hexahedra
    # (scaled Jacobian ~0.05); relaxing the hidden bone side lifts every element
    # to >= 0.3 and leaves the skin and the saliva layer where they were.
    face = default_face()
    raw = fm.relax_bone_side
    try:
        fm.relax_bone_side = lambda nodes, *a, **k: np.array(nodes)
        before = fm.build_fem_face(face)
    finally:
        fm.relax_bone_side = raw
    after = fm.build_fem_face(face)
    q0 = element_quality(before.mesh)["scaled_jacobian"]
    q1 = element_quality(after.mesh)["scaled_jacobian"]
    assert q0.min() < 0.1 and q1.min() >= 0.3
    S, L = after.n_surface, after.layers
    np.testing.assert_array_equal(after.mesh.nodes[:L * S], before.mesh.nodes[:L * S])
    moved = np.linalg.norm(after.mesh.nodes - before.mesh.nodes, axis=1)
    assert 0 < (moved > 0).sum() < 0.2 * S          # only around the corners


def test_seam_elements_slice_the_same_tissue_finer_along_the_lips(face, fem):
    from visemeface.face.refine import refine_lip_seam
    fine = fm.build_fem_face(face, seam_elements=48)
    assert len(fine.saliva) >= 48 and len(fine.seam_pairs) == len(fine.saliva) + 1
    assert np.allclose(fine.rest_gaps, fine.rest_gaps[0])        # the uniform rest gap, pair by pair
    assert fine.face.n_vertices == refine_lip_seam(face, 48).n_vertices   # a rig on the refined face fits

    def volume(m):
        from visemeface.physics.saliva import film_gradients
        return film_gradients(m.mesh.nodes[m.mesh.hexes[m.tissue]])[1].sum()
    # each new hexahedron is a slice of an old one: the same tissue, the same worst shape
    assert volume(fine) == pytest.approx(volume(fem), rel=1e-9)
    q, q0 = element_quality(fine.mesh), element_quality(fem.mesh)
    assert q["scaled_jacobian"][fine.tissue].min() == pytest.approx(q0["scaled_jacobian"][fem.tissue].min(), rel=1e-6)
    assert fine.lip_weight.max() == pytest.approx(fem.lip_weight.max())
