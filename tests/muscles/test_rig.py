"""The muscle rig on the default face: placement, symmetry, trimming, jaw, superposition, errors."""

import warnings

import numpy as np
import pytest

from visemeface.errors import InputError
from scipy.spatial import cKDTree

from visemeface.face.procedural import default_face
from visemeface.muscles.measure import LipGauge, lip_changes, lip_dimensions
from visemeface.muscles.rig import MuscleRig, default_rig, mouth_frame
from visemeface.resources import data_path

PAIRS = ("zygomatic_major", "zygomatic_minor", "levator_labii_superioris",
         "levator_labii_superioris_alaeque_nasi", "levator_anguli_oris", "risorius",
         "depressor_anguli_oris", "depressor_labii_inferioris", "mentalis", "frontalis_medialis",
         "frontalis_lateralis", "corrugator")


@pytest.fixture(scope="module")
def rig():
    return default_rig()


TONGUE = ("tongue_tip_raise", "tongue_protrusion", "tongue_dorsum_raise", "tongue_groove", "tongue_retraction")
LIPS = ("lip_rounding", "lower_lip_tuck", "corner_seal")
LIDS = tuple(f"{n}_{s}" for n in ("upper_lid_close", "upper_lid_raise", "lower_lid_raise") for s in ("left", "right"))
GAZE = tuple(f"{n}_{s}" for n in ("eye_turn_horizontal", "eye_turn_vertical") for s in ("left", "right"))


def test_names_and_ranges(rig):
    expect = (tuple(f"{p}_{s}" for p in PAIRS for s in ("left", "right")) + ("orbicularis_oris",) + TONGUE
              + LIPS + LIDS + GAZE + ("jaw",))
    assert rig.names == expect and len(rig.muscles) == 43
    assert rig.ranges.shape == (44, 2) and np.all(rig.ranges[:, 0] < rig.ranges[:, 1])
    assert rig.bases.shape == (43, rig.face.n_vertices, 3)
    # Every muscle moves something, by millimetres, not metres.
    mags = np.linalg.norm(rig.bases, axis=2).max(axis=1)
    assert np.all(mags > 0.002) and np.all(mags < 0.02)


def lip_aware_mirror(face):
    """Index of each vertex's mirror image (x -> -x), keeping upper-lip copies with upper-lip copies."""
    tag = np.zeros(face.n_vertices)
    tag[face.regions["upper_lip"]] = 1.0
    tag[face.regions["lower_lip"]] = -1.0
    pts = np.column_stack([face.vertices, tag])
    mirrored = pts * np.array([-1.0, 1.0, 1.0, 1.0])
    dist, m = cKDTree(pts).query(mirrored)
    assert dist.max() < 1e-9
    return m


def test_left_muscles_mirror_right_partners_exactly(rig):
    m = lip_aware_mirror(rig.face)
    flip = np.array([-1.0, 1.0, 1.0])
    fractions = []
    for p in PAIRS:
        left = rig.bases[rig.index[f"{p}_left"]]
        right = rig.bases[rig.index[f"{p}_right"]]
        np.testing.assert_allclose(right[m] * flip, left, atol=1e-12, err_msg=p)
        # Left muscles move (mostly) the subject's left side, +x.
        mag = np.linalg.norm(left, axis=1)
        fractions.append(mag[rig.rest[:, 0] > 0].sum() / mag.sum())
        assert fractions[-1] > 0.6, p
    assert np.median(fractions) > 0.9
    # The unpaired functions are symmetric themselves.
    for name in ("orbicularis_oris",):
        b = rig.bases[rig.index[name]]
        np.testing.assert_allclose(b[m] * flip, b, atol=1e-12)
    d = rig.jaw_displacement(0.7)
    np.testing.assert_allclose(d[m] * flip, d, atol=1e-12)


def _central(rig, region):
    idx = rig.face.regions[region]
    u = mouth_frame(rig.face).to_local(rig.rest[idx])[:, 0] / (rig.frame.width / 2)
    return idx[np.abs(u) < 0.75], idx


def test_lip_trimming(rig):
    lower_c, lower = _central(rig, "lower_lip")
    upper_c, upper = _central(rig, "upper_lip")
    for m, b in zip(rig.muscles, rig.bases):
        mag = np.linalg.norm(b, axis=1)
        if m.lip == "upper":
            assert np.all(mag[lower_c] == 0.0), m.name
            assert mag[upper].max() > 0.0 or mag.max() > 0.0
        elif m.lip == "lower":
            assert np.all(mag[upper_c] == 0.0), m.name
    # The jaw is a lower-lip function: the upper lip's central part stays put; near the
    # corners (where the jaw's blend lets both lips stretch) it moves far less than the lower lip.
    d = np.linalg.norm(rig.jaw_displacement(1.0), axis=1)
    u = mouth_frame(rig.face).to_local(rig.rest[upper])[:, 0] / (rig.frame.width / 2)
    assert np.all(d[upper[np.abs(u) < 0.3]] == 0.0)
    assert d[upper[np.abs(u) < 0.9]].max() < 0.35 * d[lower].max()


def test_trim_weights_are_smooth_across_skin_edges(rig):
    # No tear, no crease: across any quad edge of the skin (not the lips' slit or the
    # cavity) the upper/lower split changes gradually.
    face = rig.face
    inner = np.zeros(face.n_vertices, bool)
    for r in ("upper_lip", "lower_lip", "mouth_cavity"):
        inner[face.regions[r]] = True
    q = face.quads
    edges = np.concatenate([q[:, [0, 1]], q[:, [1, 2]], q[:, [2, 3]], q[:, [3, 0]]])
    skin = ~inner[edges].any(axis=1)
    w = rig.upper_weight
    jump = np.abs(w[edges[skin, 0]] - w[edges[skin, 1]])
    assert jump.max() < 0.35
    # Coincident seam vertices: the upper copy belongs to the upper lip, the lower copy to the lower.
    up, lo = face.regions["lip_seam_upper"], face.regions["lip_seam_lower"]
    central_up, _ = _central(rig, "lip_seam_upper")
    central_lo, _ = _central(rig, "lip_seam_lower")
    assert np.all(w[central_up] == 1.0) and np.all(w[central_lo] == 0.0)
    assert len(up) and len(lo)


def test_orbicularis_narrows_and_protrudes(rig):
    rest = lip_dimensions(rig.face, rig.rest)
    d = lip_dimensions(rig.face, rig.pose({"orbicularis_oris": 1.0}))
    assert d["mouth_width"] < 0.8 * rest["mouth_width"]
    assert d["protrusion"] > 0.005
    half = lip_dimensions(rig.face, rig.pose({"orbicularis_oris": 0.5}))
    assert d["mouth_width"] < half["mouth_width"] < rest["mouth_width"]


def test_jaw_opens_with_largest_gap_at_centre(rig):
    gauge = LipGauge(rig.face)
    openings = [lip_dimensions(rig.face, rig.pose({"jaw": j}))["opening_height"] for j in (0, 0.25, 0.5, 1.0)]
    assert openings[0] == pytest.approx(0.0, abs=1e-12)
    assert np.all(np.diff(openings) > 0) and openings[-1] > 0.01
    # Gap along the seam, from corner to corner: largest at the centre, smooth curve.
    v = rig.pose({"jaw": 1.0})
    up, lo = gauge._pairs.T
    idx = gauge.indices
    x = rig.rest[idx[up], 0]
    gap = v[idx[up], 1] - v[idx[lo], 1]
    assert np.argmax(gap) == np.argmin(np.abs(x))
    order = np.argsort(np.abs(x))
    assert np.all(np.diff(gap[order][::2]) <= 1e-12)
    # Lower lip drops, chin drops and moves back; upper lip stays.
    ch = lip_changes(rig.face, v)
    assert ch["lower_lip_drop"] > 0.3 and ch["chin_drop"] > 0.3 and abs(ch["upper_lip_raise"]) < 0.01


def test_negative_jaw_presses_lips(rig):
    d = lip_dimensions(rig.face, rig.pose({"jaw": rig.ranges[-1, 0]}))
    assert d["opening_height"] < 0 and d["lips_closed"] and d["lip_contact"] == 1.0


def test_lower_lip_can_rise_under_upper_lip(rig):
    # f/v: the lower lip moves up (and not forward) with mentalis.
    ch = lip_changes(rig.face, rig.pose({"mentalis_left": 1, "mentalis_right": 1}))
    assert ch["lower_lip_drop"] < -0.01


def test_superposition_except_jaw(rig):
    rng = np.random.default_rng(1)
    a = rng.uniform(0, 0.5, len(rig.names))
    b = rng.uniform(0, 0.5, len(rig.names))
    a[-1] = b[-1] = 0.0
    # Poses are computed in float32 (displacements of millimetres): equal to 10 nanometres.
    np.testing.assert_allclose(rig.displacement(a + b), rig.displacement(a) + rig.displacement(b), atol=1e-8)
    np.testing.assert_allclose(rig.pose(a), rig.rest + np.tensordot(a[:-1], rig.bases, 1), atol=1e-8)
    # The jaw adds its rotation to the muscles, but is not linear in its activation.
    ja = rig.activation_vector({"jaw": 0.4})
    np.testing.assert_allclose(rig.displacement(a + ja), rig.displacement(a) + rig.jaw_displacement(0.4),
                               atol=1e-8)
    # The fast path's jaw (a series in the angle) matches the exact rotation over the whole range.
    for j in np.linspace(*rig.ranges[-1], 7):
        np.testing.assert_allclose(rig.displacement(rig.activation_vector({"jaw": j})),
                                   rig.jaw_displacement(j), atol=1e-8)
    assert not np.allclose(rig.jaw_displacement(0.8), 2 * rig.jaw_displacement(0.4), atol=1e-6)


def test_poses_batch_matches_pose(rig):
    rng = np.random.default_rng(2)
    A = rng.uniform(0, 1, (4, len(rig.names)))
    P = rig.poses(A)
    assert P.shape == (4, rig.face.n_vertices, 3) and P.dtype == np.float32
    for k in range(4):
        np.testing.assert_allclose(P[k], rig.pose(A[k]), atol=1e-6)  # float32 positions


def test_same_rig_file_poses_other_resolution():
    small = MuscleRig.from_file(default_face(resolution=1500))
    ref = default_rig()
    assert small.face.n_vertices < ref.face.n_vertices
    pose = {"orbicularis_oris": 0.6, "jaw": 0.5, "zygomatic_major_left": 0.7, "depressor_labii_inferioris_right": 0.5}
    a = lip_changes(small.face, small.pose(pose))
    b = lip_changes(ref.face, ref.pose(pose))
    for k in ("mouth_width", "opening_height", "protrusion", "lower_lip_drop", "corner_height_left"):
        assert a[k] == pytest.approx(b[k], abs=0.03), k


def test_same_rig_file_poses_loaded_obj(tmp_path):
    from visemeface.face.mesh import load_face
    ref = default_rig()
    path, _ = ref.face.save(tmp_path / "face.obj")
    face = load_face(path)
    rig = MuscleRig.from_file(face)
    pose = {"levator_labii_superioris_left": 1.0, "jaw": 0.3, "risorius_right": 0.5}
    np.testing.assert_allclose(rig.pose(pose), ref.pose(pose), atol=1e-6)


def test_unknown_and_bad_activations(rig):
    with pytest.raises(InputError, match="did you mean: zygomatic_major_left"):
        rig.activation_vector({"zygomatic_major_lft": 0.5})
    with pytest.raises(InputError, match="risorius_left.*finite"):
        rig.activation_vector({"risorius_left": float("nan")})
    a = np.zeros(len(rig.names))
    a[rig.index["mentalis_right"]] = np.inf
    with pytest.raises(InputError, match="mentalis_right"):
        rig.pose(a)
    with pytest.raises(InputError, match="shape"):
        rig.pose(np.zeros(3))
    with pytest.raises(InputError, match="unknown muscle"):
        rig.muscle("buccinator")


def test_out_of_range_clamped_with_warning(rig):
    with pytest.warns(UserWarning, match="jaw=3 -> 1.*|.*jaw"):
        a = rig.activation_vector({"jaw": 3.0, "risorius_left": 0.5})
    assert a[rig.index["jaw"]] == 1.0 and a[rig.index["risorius_left"]] == 0.5
    with pytest.warns(UserWarning, match="orbicularis_oris"):
        p = rig.pose({"orbicularis_oris": -1})
    np.testing.assert_array_equal(p, rig.rest)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        rig.pose({"jaw": 1.0})


def _write(tmp_path, text):
    p = tmp_path / "rig.toml"
    p.write_text(text)
    return p


def _default_text():
    return data_path("rig", "default.toml").read_text()


@pytest.mark.parametrize("old,new,field", [
    ('zone_angle_deg = 28.0\nfalloff_start = 1.0\nfalloff_end = 1.5\nk = 0.19',
     'zone_angle_deg = 200.0\nfalloff_start = 1.0\nfalloff_end = 1.5\nk = 0.19', "zone_angle_deg"),
    ('attachment = {at = "cheek_{side}", offset = [0.35, 0.15, -0.1]}',
     'attachment = {at = "cheeck_{side}", offset = [0.35, 0.15, -0.1]}', "attachment"),
    ('insertion = {at = "mouth_corner_{side}", offset = [0.06, 0.02, -0.02]}',
     'insertion = {at = "mouth_corner_{side}", offset = [0.06, 0.02]}', "insertion"),
    ('insertion = {at = "mouth_corner_{side}", offset = [0.06, 0.02, -0.02]}',
     'insertion = {at = "mouth_corner_{side}", offset = [nan, 0.02, -0.02]}', "insertion"),
    ('kind = "linear"\nsides = ["left", "right"]\nlip = "both"\nrange = [0.0, 1.0]\nattachment = {at = "cheek_{side}", offset = [0.35',
     'kind = "linear"\nsides = ["left", "right"]\nlip = "both"\nrange = [1.0, 0.0]\nattachment = {at = "cheek_{side}", offset = [0.35',
     "range"),
])
def test_rig_file_errors_name_file_entry_field(tmp_path, old, new, field):
    text = _default_text()
    assert old in text
    path = _write(tmp_path, text.replace(old, new, 1))
    with pytest.raises(InputError) as exc:
        MuscleRig.from_file(default_rig().face, path)
    msg = str(exc.value)
    assert str(path) in msg and "'zygomatic_major'" in msg and repr(field) in msg
    # The line of the entry is given too.
    assert f"{path}:" in msg


def test_a_sheet_muscle_that_cannot_be_one_is_refused_naming_the_field(tmp_path):
    text = _default_text()
    assert text.count('fibres = "parallel"') == 2
    i = text.index('name = "frontalis_medialis"')
    short = text[:i] + text[i:].replace("falloff_start = 1.0\nfalloff_end = 1.35", "falloff_start = 0.5\nfalloff_end = 0.9", 1)
    for t, why in ((text.replace('fibres = "parallel"', 'fibres = "paralel"', 1), "expected 'fan' or 'parallel'"),
                   (short, "falloff_end past the insertion")):
        with pytest.raises(InputError, match=f"'frontalis_medialis'.*'fibres'.*{why}"):
            MuscleRig.from_file(default_rig().face, _write(tmp_path, t))


def test_a_gaze_whose_lids_follow_from_nowhere_is_refused_naming_the_field(tmp_path):
    text = _default_text()
    assert "lid_radius = 0.3" in text
    path = _write(tmp_path, text.replace("lid_radius = 0.3", "lid_radius = -0.3", 1))
    with pytest.raises(InputError, match="'eye_turn_vertical'.*'lid_radius'.*must be positive"):
        MuscleRig.from_file(default_rig().face, path)


def test_lid_shares_one_per_lids_region_or_refused_naming_the_field(tmp_path):
    text = _default_text()
    assert "lid_follow = [1.0, 0.3]" in text
    for bad in ("[1.0]", "[1.0, 3.0]", '"x"'):
        path = _write(tmp_path, text.replace("lid_follow = [1.0, 0.3]", f"lid_follow = {bad}", 1))
        with pytest.raises(InputError, match="'eye_turn_vertical'.*'lid_follow'.*one per lids region"):
            MuscleRig.from_file(default_rig().face, path)
    # one number for every lids region
    rig = MuscleRig.from_file(default_rig().face,
                              _write(tmp_path, text.replace("lid_follow = [1.0, 0.3]", "lid_follow = 1.0", 1)))
    m = next(m for m in rig.muscles if m.name == "eye_turn_vertical_left")
    assert set(np.unique(m.lids)) == {0.0, 1.0}


def test_rig_file_syntax_and_missing(tmp_path):
    face = default_rig().face
    with pytest.raises(InputError, match="not valid TOML"):
        MuscleRig.from_file(face, _write(tmp_path, "[trim\n"))
    with pytest.raises(InputError, match="rig file not found"):
        MuscleRig.from_file(face, tmp_path / "missing.toml")
    text = _default_text().replace('name = "mentalis"', 'name = "risorius"')
    with pytest.raises(InputError, match="defined twice"):
        MuscleRig.from_file(face, _write(tmp_path, text))


def test_rig_follows_a_moved_scaled_face():
    # Placement is relative to landmarks: a face scaled, rotated and moved gets the same
    # muscles, so every basis field is the rotated, scaled original.
    import dataclasses

    ref = default_rig()
    s = 1.3
    c, sn = np.cos(0.4), np.sin(0.4)
    rot = np.array([[c, 0, sn], [0, 1, 0], [-sn, 0, c]]) @ np.array([[1, 0, 0], [0, np.cos(0.2), -np.sin(0.2)],
                                                                      [0, np.sin(0.2), np.cos(0.2)]])
    moved = dataclasses.replace(ref.face, vertices=s * ref.rest @ rot.T + np.array([0.1, -0.2, 0.3]))
    rig = MuscleRig.from_file(moved)
    np.testing.assert_allclose(rig.bases, s * ref.bases @ rot.T, atol=1e-12)
    np.testing.assert_allclose(rig.jaw_displacement(0.6), s * ref.jaw_displacement(0.6) @ rot.T, atol=1e-12)
    pose = {"orbicularis_oris": 0.5, "jaw": 0.4, "risorius_left": 0.3}
    a, b = lip_changes(moved, rig.pose(pose)), lip_changes(ref.face, ref.pose(pose))
    for k in a:
        assert a[k] == pytest.approx(b[k], abs=1e-6), k


def test_mesh_without_eyes_region_still_rigs():
    import dataclasses

    ref = default_rig()
    regions = {k: v for k, v in ref.face.regions.items() if k != "eyes"}
    rig = MuscleRig.from_file(dataclasses.replace(ref.face, regions=regions))
    assert "eyes" not in rig.muscles[0].exclude and "tongue" in rig.muscles[0].exclude
    text = _default_text().replace('exclude = ["eyes", "upper_teeth"', 'exclude = ["eyse", "upper_teeth"')
    with pytest.raises(InputError, match="unknown region 'eyse'.*did you mean: eyes"):
        import tempfile
        from pathlib import Path
        with tempfile.TemporaryDirectory() as d:
            MuscleRig.from_file(ref.face, _write(Path(d), text))


def test_binary_rig_file_is_a_one_line_error(tmp_path):
    p = tmp_path / "garbage.toml"
    p.write_bytes(bytes(range(200, 256)) * 4)
    with pytest.raises(InputError, match="not UTF-8"):
        MuscleRig.from_file(default_rig().face, p)


def test_one_track_conversion_for_every_consumer():
    """Rendering, exports and the FEM drive read a track the same way: missing rig functions are
    rest (0), unknown columns and non-finite values are errors, clamping warns."""
    import pandas as pd

    rig = default_rig()
    track = pd.DataFrame({"jaw": [0.0, 0.5, 2.0], "orbicularis_oris": [0.0, 0.3, 0.3]},
                         index=pd.Index([0.0, 1 / 30, 2 / 30], name="time"))
    A = rig.track_matrix(track)
    assert A.shape == (3, len(rig.names)) and A[:, rig.names.index("zygomatic_major_left")].sum() == 0
    with pytest.warns(UserWarning, match="jaw=2 -> 1 in 1 frames"):
        clamped = rig.clamp(rig.track_matrix(track))
    assert clamped[2, rig.names.index("jaw")] == rig.ranges[rig.names.index("jaw"), 1]
    with pytest.warns(UserWarning):
        np.testing.assert_allclose(rig.poses(track)[1], rig.pose(clamped[1]), atol=1e-6)
    with pytest.raises(InputError, match="unknown muscle 'zygomatic_mayor_left'.*zygomatic_major_left"):
        rig.track_matrix(track.assign(zygomatic_mayor_left=0.1))
    with pytest.raises(InputError, match="'jaw' at t=0.0333"):
        rig.track_matrix(track.assign(jaw=[0.0, np.nan, 0.0]))


def test_the_shared_default_rig_cannot_be_changed_by_one_caller():
    from visemeface.muscles.rig import default_rig

    shared = default_rig()
    with pytest.raises(ValueError):
        shared.rest[0, 0] = 1.0
    with pytest.raises(ValueError):
        shared.face.vertices[0, 0] = 1.0
    assert default_rig() is shared


def test_teeth_are_bone_and_the_tongue_has_its_own_functions(rig):
    face = rig.face
    r = face.regions
    up = np.concatenate([r["upper_teeth"], r["upper_gum"]])
    lower = np.concatenate([r["lower_teeth"], r["lower_gum"]])
    tongue = r["tongue"]
    for i, m in enumerate(rig.muscles):
        b = np.linalg.norm(rig.bases[i], axis=1)
        assert b[up].max() == 0 and b[lower].max() == 0, m.name        # no function bends a tooth
        if m.name in TONGUE:
            assert b[tongue].max() > 0.002                            # millimetres of tongue
            assert np.delete(b, tongue).max() == 0, m.name            # and nothing else
        else:
            assert b[tongue].max() == 0, m.name
    # the jaw turns the lower teeth rigidly (distances kept) and leaves the upper teeth
    open_ = rig.pose({"jaw": 1.0})
    rest = face.vertices
    assert np.abs(open_[up] - rest[up]).max() == 0
    d0 = np.linalg.norm(rest[lower][:, None] - rest[lower][None], axis=2)
    d1 = np.linalg.norm(open_[lower][:, None] - open_[lower][None], axis=2)
    assert np.abs(d1 - d0).max() < 1e-6
    drop = rest[face.landmarks["lower_incisor_edge"], 1] - open_[face.landmarks["lower_incisor_edge"], 1]
    lip_drop = rest[face.landmarks["lower_lip_mid"], 1] - open_[face.landmarks["lower_lip_mid"], 1]
    assert 0.012 < drop and abs(drop - lip_drop) < 0.006             # the teeth go down with the lip


def test_tongue_functions_skip_a_face_without_a_tongue(tmp_path):
    face = default_face(resolution=1500)
    keep = {k: v for k, v in face.regions.items() if k != "tongue"}
    from visemeface.face.mesh import FaceMesh
    bare = FaceMesh(face.vertices, face.quads, face.tris, keep,
                    {k: v for k, v in face.landmarks.items() if not k.startswith("tongue")}, face.colors)
    rig = MuscleRig.from_file(bare)
    i = rig.names.index("tongue_tip_raise")
    assert np.abs(rig.bases[i]).max() == 0


def test_a_blink_closes_both_eyes_and_moves_nothing_else(rig):
    face = rig.face
    lids = {f"{n}_{s}": v for n, v in (("upper_lid_close", 1.0), ("lower_lid_raise", 0.4))
            for s in ("left", "right")}
    shut = rig.pose(lids)
    moved = np.linalg.norm(shut - face.vertices, axis=1) > 1e-9
    assert np.isin(np.flatnonzero(moved), np.union1d(face.regions["upper_lids"], face.regions["lower_lids"])).all()
    for side in ("left", "right"):
        eye = face.landmark_position(f"eye_centre_{side}")
        near = lambda idx: idx[np.abs(face.vertices[idx, 0] - eye[0]) < 0.002]      # noqa: E731
        up = near(face.regions["upper_lids"])
        lo = near(face.regions["lower_lids"])
        upper_margin = up[np.argmin(face.vertices[up, 1])]
        lower_margin = lo[np.argmax(face.vertices[lo, 1])]
        # open at rest (about 9 mm), shut in the blink: the upper margin comes 0.5 mm past the lower (the rig
        # file's overlap: margins about 2 mm thick pressed together) and the blink's lower lid rises 0.9 mm more
        assert face.vertices[upper_margin, 1] - face.vertices[lower_margin, 1] > 0.007
        assert 0.0 < shut[lower_margin, 1] - shut[upper_margin, 1] < 0.0015
        # the closed lid stays in front of the eyeball's front (no eye showing through)
        assert shut[upper_margin, 2] > eye[2]


def test_gaze_turns_each_iris_and_nothing_else(rig):
    face = rig.face
    for side in ("left", "right"):
        pupil = face.landmarks[f"eye_centre_{side}"]
        this_side = np.flatnonzero(np.sign(face.vertices[:, 0]) == (1 if side == "left" else -1))
        mine = np.intersect1d(face.regions["eyeballs"], this_side)
        for name, axis, deg in ((f"eye_turn_horizontal_{side}", 0, 20.0), (f"eye_turn_vertical_{side}", 1, 15.0)):
            b = rig.bases[rig.names.index(name)]
            moved = np.flatnonzero(np.linalg.norm(b, axis=1) > 0)
            lids = np.intersect1d(np.union1d(face.regions["upper_lids"], face.regions["lower_lids"]), this_side)
            # one eyeball, and for a vertical gaze its lids (which follow it), nothing else
            assert np.isin(moved, np.union1d(mine, lids) if axis == 1 else mine).all()
            assert np.isin(moved, lids).any() == (axis == 1)
            # the pupil moves sideways (up) by about r sin(angle), r = 9.5 mm behind the pupil
            assert b[pupil, axis] == pytest.approx(0.0095 * np.radians(deg), rel=0.1)


def test_a_modiolus_table_is_checked_naming_its_field(tmp_path):
    text = _default_text()
    for table, message in (('radius = -0.2\ncore = 0.3', "'radius'.*must be positive"),
                           ('radius = 0.2\ncore = 1.5', "'core'.*must be in"),
                           ('radius = 0.2\ncore = 0.3\nexclude = ["teeth_typo"]', "unknown region 'teeth_typo'")):
        path = _write(tmp_path, text.replace("version = 1\n", f"version = 1\n\n[modiolus]\n{table}\n", 1))
        with pytest.raises(InputError, match=message):
            MuscleRig.from_file(default_rig().face, path)


def test_a_landmark_asked_for_by_number_is_an_input_error():
    """Landmarks are named; a number (a Multi-PIE index) is refused as an unknown landmark, with the
    named ones suggested where one is close, not with a TypeError from the suggestion."""
    face = default_rig().face
    with pytest.raises(InputError, match="unknown landmark 48"):
        face.landmark_position(48)
    with pytest.raises(InputError, match="did you mean: chin"):
        face.landmark_position("chinn")
