"""Culling the still triangles hidden at rest leaves every image as it was; the rig's pose and its still set."""

import warnings

import numpy as np
import pytest

from visemeface.face.ict import ict_face
from visemeface.face.procedural import default_face
from visemeface.muscles.rig import MuscleRig
from visemeface.render.renderer import Renderer

SIZE = 256


def _poses(rig, n=4):
    """Rest, the jaw wide open with rounded lips, and a few random mixes over the functions' ranges."""
    lo, hi = rig.ranges.T
    rng = np.random.default_rng(3)
    out = [np.zeros(len(lo)), rig.activation_vector(jaw=hi[-1], lip_rounding=1.0, tongue_tip_raise=1.0)]
    out += [rng.uniform(lo, hi) * (rng.random(len(lo)) < 0.4) for _ in range(n)]
    return out


@pytest.fixture(scope="module", params=["procedural", "ict"])
def rig(request):
    face = default_face(2500) if request.param == "procedural" else ict_face()
    return MuscleRig.from_file(face)


@pytest.mark.parametrize("view", ["face", "three-quarter"])
def test_culled_frames_are_the_unculled_ones_pixel_for_pixel(rig, view):
    poses = _poses(rig)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        poses = [rig.clamp(a) for a in poses]
    with Renderer(rig.face, size=SIZE, view=view, samples=0, still=rig.still_vertices()) as culled, \
            Renderer(rig.face, size=SIZE, view=view, samples=0) as full:
        assert culled.vao_shown is not None and culled.n_shown < len(rig.face.triangles)
        for a in poses:
            v = np.asarray(rig.pose(a), dtype=np.float32)       # as KinematicMotion's frames
            np.testing.assert_array_equal(culled.render(v), full.render(v))
        # a frame that moves a still vertex (a turned head) draws every triangle
        moved = rig.face.vertices + np.array([0.004, 0.0, 0.0])
        np.testing.assert_array_equal(culled.render(moved), full.render(moved))


def test_a_run_s_still_set_holds_the_vertices_its_poses_leave_at_rest(rig):
    a = rig.activation_vector(jaw=0.6, orbicularis_oris=0.4)
    run = rig.still_vertices(a[None])
    assert run.sum() > rig.still_vertices().sum()          # the functions left out move nothing
    assert (run | ~rig.still_vertices()).all()
    v = rig.pose(a)
    np.testing.assert_array_equal(v[run], rig.face.vertices[run])
    assert not np.array_equal(v[~run], rig.face.vertices[~run])
    # the pose is rest + coefficients @ matrix (float32 sums)
    ref = rig.face.vertices.reshape(-1) + rig._coefficients(a).astype(np.float64) @ rig._matrix.astype(np.float64)
    np.testing.assert_allclose(v.reshape(-1), ref, atol=1e-8)


def test_culling_is_off_with_multisampling():
    face = default_face(2500)
    rig = MuscleRig.from_file(face)
    with Renderer(face, size=64, samples=4, still=rig.still_vertices()) as r:
        assert r.vao_shown is None or r.samples <= 1


def test_icts_enclosed_iris_shells_are_never_drawn_and_no_pixel_changes():
    """ICT's iris shells lie inside its eyes' outer shells, on which the iris is painted: left out of the draw
    they change no pixel, looking anywhere, with the lids wide."""
    import copy

    rig = MuscleRig.from_file(ict_face())
    face = rig.face
    enclosed = face.regions["enclosed"]
    assert np.isin(enclosed, face.regions["eyeballs"]).all() and len(enclosed) == 1600
    whole = copy.deepcopy(face)
    del whole.regions["enclosed"]
    gazes = [rig.activation_vector(**{f"eye_turn_{d}_{s}": g for s in ("left", "right")},
                                   **{f"upper_lid_raise_{s}": 1.0 for s in ("left", "right")})
             for d in ("vertical", "horizontal") for g in (-1.0, 1.0)]
    with Renderer(face, size=SIZE, view="face", samples=0) as r, \
            Renderer(whole, size=SIZE, view="face", samples=0) as every:
        assert len(r._triangles) == len(face.triangles) - 3192 and len(every._triangles) == len(face.triangles)
        for a in gazes:
            v = np.asarray(rig.pose(a), dtype=np.float32)
            np.testing.assert_array_equal(r.render(v), every.render(v))
