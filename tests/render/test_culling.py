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


def _all_triangles_at_rest(r):
    """Make renderer ``r`` draw every triangle where it would leave the hidden still ones out (the same sides)."""
    r.vao_shown, r.vao_shown_front, r._split_shown = r.vao, r.vao_front, r._split
    return r


@pytest.mark.parametrize("view", ["face", "three-quarter"])
def test_culled_frames_are_the_unculled_ones_pixel_for_pixel(rig, view):
    poses = _poses(rig)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        poses = [rig.clamp(a) for a in poses]
    still = rig.still_vertices()
    with Renderer(rig.face, size=SIZE, view=view, samples=0, still=still) as culled, \
            _all_triangles_at_rest(Renderer(rig.face, size=SIZE, view=view, samples=0, still=still)) as full, \
            Renderer(rig.face, size=SIZE, view=view, samples=0) as plain:
        assert culled.vao_shown is not None and culled.n_shown < len(rig.face.triangles)
        for a in poses:
            v = np.asarray(rig.pose(a), dtype=np.float32)       # as KinematicMotion's frames
            np.testing.assert_array_equal(culled.render(v), full.render(v))
        # a frame that moves a still vertex (a turned head) draws every triangle, as a renderer told nothing
        moved = rig.face.vertices + np.array([0.004, 0.0, 0.0])
        np.testing.assert_array_equal(culled.render(moved), plain.render(moved))


def _cube(flip=False, open_top=False):
    v = np.array([[x, y, z] for x in (0, 1) for y in (0, 1) for z in (0, 1)], float)
    quads = [(0, 1, 3, 2), (4, 6, 7, 5), (0, 4, 5, 1), (2, 3, 7, 6), (0, 2, 6, 4), (1, 5, 7, 3)]  # out, ccw
    quads = quads[:3] + quads[4:] if open_top else quads          # the y = 1 face left open
    t = np.array([tri for a, b, c, d in quads for tri in ((a, b, c), (a, c, d))])
    return v, (t[:, ::-1] if flip else t)


def test_one_sided_surfaces_are_the_closed_outward_ones_and_a_holed_one_names_its_rim():
    from visemeface.render.culling import one_sided, outside_frustum
    v, t = _cube()
    closed, holed = one_sided(t, v)
    assert closed.all() and holed == []
    closed, holed = one_sided(_cube(flip=True)[1], v)              # facing in: two-sided
    assert not closed.any() and holed == []
    v, t = _cube(open_top=True)
    closed, holed = one_sided(t, v)
    assert not closed.any() and len(holed) == 1 and holed[0][0].all()
    np.testing.assert_array_equal(np.unique(holed[0][1]), [2, 3, 6, 7])  # the y = 1 square's corners
    sheet = np.array([[0, 1, 2], [1, 3, 2]])                       # no volume: two-sided
    closed, holed = one_sided(sheet, np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0]], float))
    assert not closed.any() and holed == []
    twice = np.concatenate([_cube()[1], _cube()[1][:1]])           # an edge used twice the same way
    closed, holed = one_sided(twice, v)
    assert not closed.any() and holed == []
    eye = np.eye(4)                                                # the clip cube [-1, 1]^3
    assert outside_frustum(eye, [[2, 0, 0], [3, 0.5, 0]]) and outside_frustum(eye, [[0, -1.5, 0], [5, -2, 0]])
    assert not outside_frustum(eye, [[2, 0, 0], [-2, 0, 0]]) and not outside_frustum(eye, [[0.5, 0, 0]])


def test_icts_skin_teeth_and_eyes_are_drawn_one_sided_and_only_back_face_specks_change():
    """ICT's skin with its mouth socket is closed but for the cut at the neck, its teeth and eyeballs closed:
    drawn one-sided, a frame differs from the two-sided one only at lone pixels where a back face won the
    depth test by rounding (the cap over the neck cut shows at no pixel of the face view)."""
    from scipy import ndimage

    rig = MuscleRig.from_file(ict_face())
    poses = [rig.clamp(a) for a in _poses(rig, n=2)]
    with Renderer(rig.face, size=512, view="face", samples=0, still=rig.still_vertices()) as r, \
            Renderer(rig.face, size=512, view="face", samples=0) as two:
        two._split = (0, 0, two._split[2])                          # every triangle two-sided
        closed, holed, total = r._split_shown
        assert r._capped == [True] and holed - closed > 0.6 * total   # the skin, at rest
        assert r._split[0] > 0.25 * r._split[2]                        # teeth and eyeballs in every frame
        for a in poses:
            v = np.asarray(rig.pose(a), dtype=np.float32)
            diff = (r.render(v) != two.render(v)).any(axis=2)
            labels, _ = ndimage.label(diff)
            assert diff.sum() <= 12 and np.bincount(labels.ravel())[1:].max(initial=0) <= 1


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
