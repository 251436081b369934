"""The built-in ICT head: regions found from its landmarks and connectivity, and the rig fixes a real head needs
(the jaw off the neck, muscles off the scalp), measured on the head itself."""

from __future__ import annotations

import subprocess
import sys

import numpy as np
import pytest

from visemeface.errors import InputError
from visemeface.face import builtin_face
from visemeface.face.ict import N_IDENTITY_MODES, ict_face, identity_weights, parts


@pytest.fixture(scope="module")
def ict_rig():
    from visemeface.muscles.rig import MuscleRig

    return MuscleRig.from_file(ict_face())


def test_the_head_has_the_conventions_landmarks_and_regions(ict_rig):
    from visemeface.face.mesh import LANDMARK_NAMES

    face = ict_rig.face
    assert set(LANDMARK_NAMES) <= set(face.landmarks)
    up, lo = face.regions["upper_lip"], face.regions["lower_lip"]
    assert len(up) > 100 and len(lo) > 100 and not np.intersect1d(up, lo).size
    V = face.vertices
    # the lips lie each on its side of the mouth at the centre line, and the seams run corner to corner
    centre = np.abs(V[:, 0]) < 0.004
    assert V[np.intersect1d(up, np.flatnonzero(centre)), 1].min() > V[np.intersect1d(lo, np.flatnonzero(centre)), 1].max() - 1e-3
    for seam in ("lip_seam_upper", "lip_seam_lower"):
        x = V[face.regions[seam], 0]
        assert x.min() < -0.02 and x.max() > 0.02
    w = np.linalg.norm(face.landmark_position("mouth_corner_left") - face.landmark_position("mouth_corner_right"))
    assert 0.045 < w < 0.055                          # metres (ICT ships centimetres)
    assert np.allclose(0.5 * (face.landmark_position("mouth_corner_left")
                              + face.landmark_position("mouth_corner_right")), 0.0, atol=1e-9)


def test_the_jaw_leaves_the_neck_and_the_nape(ict_rig):
    """ICT's own jawOpen moves the neck at most 11.7 mm; without the fade past the chin our jaw turned the
    whole neck (32 mm at jaw 1)."""
    face = ict_rig.face
    a = np.zeros(len(ict_rig.names))
    a[ict_rig.index["jaw"]] = 1.0
    d = np.linalg.norm(ict_rig.displacement(a), axis=1)
    neck = parts()["head_and_neck"]
    assert d[neck].max() < 3e-3
    assert d[face.landmarks["lower_lip_mid"]] > 8e-3            # while the mouth opens
    assert d[face.landmarks["chin"]] > 5e-3                     # and the chin goes with it


def test_no_emotion_dents_the_scalp(ict_rig):
    from visemeface.postures.library import PostureLibrary

    face, V = ict_rig.face, ict_rig.face.vertices
    scalp = np.union1d(parts()["head_and_neck"],
                       np.flatnonzero(V[:, 1] > face.landmark_position("brow_inner_left")[1] + 0.06))
    lib = PostureLibrary(ict_rig)
    for name in lib.expressions.index:
        a = lib.expressions.loc[name].reindex(ict_rig.names, fill_value=0.0).to_numpy(float)
        assert np.linalg.norm(ict_rig.displacement(a), axis=1)[scalp].max() < 1e-3, name


def test_no_viseme_or_emotion_tears_icts_lips():
    """The mouth's lining goes with the lip it joins: by height alone the lining behind each lip corner split
    half and half between the lips while the lip went one way, and the triangles between stretched 4.6 times
    on surprise (the jaw open); measured now 2.75 (torn: over 3)."""
    from visemeface.face.prepare import lip_stretch

    assert lip_stretch(ict_face()) < 3.0


def test_icts_mouth_corners_move_as_one_piece_and_no_pose_folds_them(ict_rig):
    """The scan's lip rows converge on each corner 0.1-0.2 mm apart, so any difference in their motion turned the
    triangles between them over: 64 beside the corners on /aa/ (the upper lip's corners hooked down). Moved as one
    piece near the corner (the modiolus), no viseme, nor /aa/ or /uw/ with any emotion, turns one over."""
    from visemeface.muscles.measure import corner_folds
    from visemeface.muscles.rig import MuscleRig
    from visemeface.postures.library import PostureLibrary

    lib = PostureLibrary(ict_rig)
    poses = [(v, None) for v in lib.visemes.index] + [(v, e) for v in ("aa", "uw") for e in lib.expressions.index]
    folded = {f"{v}+{e}": n for v, e in poses
              if (n := corner_folds(ict_rig.face, lib.posed_vertices(v, {e: 1.0} if e else None))[0])}
    assert not folded, folded
    bare = ict_face()
    bare.rig_defaults = {k: v for k, v in bare.rig_defaults.items() if k != "modiolus"}
    unblended = PostureLibrary(MuscleRig.from_file(bare))
    assert corner_folds(bare, unblended.posed_vertices("aa", None))[0] > 30      # the cause, shown


def test_a_harmonic_map_over_a_path_is_linear_and_an_island_keeps_its_value():
    from visemeface.face.multipie import harmonic_extension

    # a path 0-1-2-3-4 fixed at its ends, and an island 5-6 that touches no fixed vertex
    edges = np.array([[0, 1], [1, 2], [2, 3], [3, 4], [5, 6]])
    values = np.array([1.0, 0.0, 0.0, 0.0, -1.0, 7.0, 7.0])
    fixed = np.array([1, 0, 0, 0, 1, 0, 0], bool)
    out = harmonic_extension(edges, values, fixed, ~fixed)
    np.testing.assert_allclose(out, [1.0, 0.5, 0.0, -0.5, -1.0, 7.0, 7.0])


def _pupil_and_iris(img, renderer, face, side):
    """The rendered pupil's outline spread (std / mean of its edge's distance from its centroid: 0 for a
    circle), its diameter, the iris' width on the pupil's row and how far the pupil sits off the iris' middle
    (metres)."""
    from scipy import ndimage

    g = img.astype(float)
    lum = g.mean(axis=2)
    c = face.landmark_position(f"eye_centre_{side}")
    (u, v), (u2, _) = renderer.project(np.stack([c, c + [0.01, 0.0, 0.0]]))
    k = (u2 - u) / 0.01
    labels, _ = ndimage.label(lum < 40)
    window = labels[int(v) - 5:int(v) + 6, int(u) - 5:int(u) + 6]
    pupil = labels == np.bincount(window[window > 0]).argmax()
    ys, xs = np.nonzero(pupil)
    cx, cy = xs.mean(), ys.mean()
    ey, ex = np.nonzero(pupil & ~ndimage.binary_erosion(pupil))
    d = np.hypot(ex - cx, ey - cy)
    row = g[int(round(cy))]
    dark = (row[:, 0] - row[:, 2] > 25) & (row.mean(axis=1) < 150) | (lum[int(round(cy))] < 40)
    right = next(i for i in range(int(cx), img.shape[1]) if not dark[i])
    left = next(i for i in range(int(cx), 0, -1) if not dark[i])
    return d.std() / d.mean(), 2 * np.sqrt(pupil.sum() / np.pi) / k, (right - left - 1) / k, ((right + left) / 2 - cx) / k


def test_the_iris_and_pupil_are_round_an_adults_and_centred():
    from visemeface.render.renderer import Renderer

    face = ict_face()
    with Renderer(face, size=1024, view="face") as r:
        img = r.render()
    for side in ("left", "right"):
        spread, pupil, iris, off = _pupil_and_iris(img, r, face, side)
        assert spread < 0.07                 # a round pupil (a cut at the shell's uneven rings: a star, 0.12)
        assert 3.0e-3 < pupil < 5.0e-3        # about 4 mm in room light
        assert 11.0e-3 < iris < 12.5e-3       # an adult's iris, 11.8 mm across
        assert abs(off) < 0.7e-3              # the pupil in the iris' middle


def test_a_blink_brings_the_upper_lid_down_to_the_lower(ict_rig):
    face = ict_rig.face
    a = np.zeros(len(ict_rig.names))
    for side in ("left", "right"):
        a[ict_rig.index[f"upper_lid_close_{side}"]] = 1.0
    v = ict_rig.pose(a)
    up, lo = face.regions["upper_lids"], face.regions["lower_lids"]
    for sign in (1, -1):                               # each eye: the upper lid's lowest point meets the lower lid
        u, low = up[np.sign(face.vertices[up, 0]) == sign], lo[np.sign(face.vertices[lo, 0]) == sign]
        rest_gap = face.vertices[low, 1].max() - face.vertices[u, 1].min()
        assert v[u, 1].min() <= v[low, 1].max() + 0.25 * abs(rest_gap) + 1e-3


def test_identity_is_deterministic_bounded_and_distinct():
    assert identity_weights(5) == identity_weights("5")
    assert len(identity_weights(5)) == N_IDENTITY_MODES and max(map(abs, identity_weights(5))) <= 3.0
    assert identity_weights("0.5,-1") == (0.5, -1.0)
    a, b = ict_face(identity_weights(1)), ict_face(identity_weights(2))
    assert np.abs(a.vertices - b.vertices).max() > 2e-3
    assert np.array_equal(a.vertices, ict_face(identity_weights(1)).vertices)
    for bad in ("4,nan", "x", "-3"):
        with pytest.raises(InputError, match="identity"):
            identity_weights(bad)
    with pytest.raises(InputError, match="outside"):
        identity_weights("0,5")
    with pytest.raises(InputError, match="--face ict"):
        builtin_face("procedural", identity=3)


def test_a_speaker_drawn_from_the_identity_modes_looks_ahead_as_the_neutral_does():
    """ICT's modes turn the eyeballs too (identity 3's right eye 2.6 degrees further out, identity 6's both 6 up);
    a drawn speaker's eyes are re-aimed, rigidly about their centres, to the neutral's primary gaze."""
    from visemeface.face.ict import _OUTER_SHELL, _eye_axis, _store

    neutral, p = ict_face(), parts()
    store = _store()
    for seed in (3, 6):
        w = identity_weights(seed)
        raw = store["vertices"].astype(float) + np.tensordot(np.asarray(w), store["identities"][: len(w)].astype(float),
                                                             axes=1)
        face = ict_face(w)
        turned = 0.0
        for side in ("left", "right"):
            ball = p[f"eyeball_{side}"]
            _, want = _eye_axis(neutral.vertices[ball[:_OUTER_SHELL]])
            centre, got = _eye_axis(face.vertices[ball[:_OUTER_SHELL]])
            _, before = _eye_axis(raw[ball[:_OUTER_SHELL]])
            assert np.degrees(np.arccos(min(1.0, got @ want))) < 0.1
            turned = max(turned, np.degrees(np.arccos(min(1.0, before @ want))))
            # rigid about the centre: every distance from it kept
            np.testing.assert_allclose(np.linalg.norm(face.vertices[ball] - centre, axis=1),
                                       np.linalg.norm(raw[ball] - centre, axis=1), atol=1e-9)
        assert turned > 2.0                                  # the modes had turned them
        eyes = np.concatenate([p["eyeball_left"], p["eyeball_right"]])
        rest = np.setdiff1d(np.arange(face.n_vertices), eyes)
        np.testing.assert_array_equal(face.vertices[rest], raw[rest])     # nothing else moved


def test_the_face_view_frames_a_whole_head_by_its_face():
    from visemeface.render.renderer import Renderer

    from visemeface.face.procedural import default_face

    with Renderer(ict_face(), size=(128, 128), view="face") as r:
        ict_mouth = r.mouth_box()[2]
    with Renderer(default_face(), size=(128, 128), view="face") as r:
        our_mouth = r.mouth_box()[2]
    # the mouth is as large in the frame as on the default face (framed whole, head, neck and shoulders, it
    # was 18 px of 128 against 26)
    assert ict_mouth >= 0.9 * our_mouth


def test_pose_speaks_on_the_ict_face_from_the_command_line(tmp_path):
    p = subprocess.run([sys.executable, "-m", "visemeface", "pose", "m", "--face", "ict", "--identity", "3",
                        "--size", "128", "-o", "m.png"], cwd=tmp_path, capture_output=True, text=True)
    assert p.returncode == 0, p.stderr
    assert (tmp_path / "m.png").stat().st_size > 1000
    p = subprocess.run([sys.executable, "-m", "visemeface", "pose", "m", "--identity", "3", "-o", "n.png"],
                       cwd=tmp_path, capture_output=True, text=True)
    assert p.returncode == 2 and "--identity needs --face ict" in p.stderr and not (tmp_path / "n.png").exists()


def test_the_physical_face_on_the_ict_head_is_refused_in_one_line_before_any_work(tmp_path):
    (tmp_path / "b.txt").write_text("bob")
    p = subprocess.run([sys.executable, "-m", "visemeface", "speak", "b.txt", "--face", "ict", "--physics", "sticky",
                        "--gltf", "b.glb"], cwd=tmp_path, capture_output=True, text=True)
    assert p.returncode == 2, p.stderr
    err = p.stderr.strip()
    assert len(err.splitlines()) == 1 and "no 'jaw' region" in err and "--physics none" in err, err
    assert sorted(f.name for f in tmp_path.iterdir()) == ["b.txt"]


def test_a_manifest_gives_each_clip_an_identity_of_the_ict_head(tmp_path):
    from visemeface.batch.manifest import BadRow, read_manifest

    jobs = tmp_path / "jobs.csv"
    jobs.write_text("clip,text,identity\na,bob,1\nb,bob,0.5;-1\nc,bob,\nd,bob,7;nan\n")
    rows = read_manifest(jobs, {"face": "ict"})
    assert [getattr(r, "identity", None) for r in rows[:3]] == ["1", "0.5;-1", None]
    assert isinstance(rows[3], BadRow) and "identity" in rows[3].error
    rows = read_manifest(jobs, {})
    assert isinstance(rows[0], BadRow) and "--face ict" in rows[0].error
    from visemeface.batch.clip import _rig

    a, b = _rig("ict", None, None, "1"), _rig("ict", None, None, "2")
    assert np.abs(a.face.vertices - b.face.vertices).max() > 2e-3


@pytest.mark.parametrize("face_name", ["procedural", "ict"])
def test_a_raised_brow_gathers_the_whole_forehead_not_a_band_under_the_hairline(face_name):
    """The frontalis is a sheet of parallel fibres: in surprise the forehead shortens evenly from the hairline
    to the brows. Modelled as Waters' fan (a cone from a point under the hairline, its pull faded in from the
    attachment) the shortening crowded into a band there: the skin compressed by 0.41-0.45 (p99 over the
    upper face; blotches in the fold shade), where evenly it is 0.18-0.19, while the brows rise as much."""
    from visemeface.muscles.rig import MuscleRig
    from visemeface.postures.library import posed_vertices

    face = builtin_face(face_name)
    rig = MuscleRig.from_file(face)
    lengths = np.empty(face.n_vertices)
    acc = face.normal_accumulator()
    acc(face.vertices, lengths=lengths)
    rest = lengths.copy()
    v = posed_vertices(rig, "_", {"surprise": 1.0})
    acc(v, lengths=lengths)
    moved = np.linalg.norm(v - face.vertices, axis=1)
    upper = (face.vertices[:, 1] > np.percentile(face.vertices[:, 1], 75)) & (moved > 5e-4) & (rest > 0)
    compression = 1 - lengths[upper] / rest[upper]
    assert np.percentile(compression, 99) < 0.25
    brows = [face.landmarks[f"brow_{p}_{s}"] for p in ("inner", "outer") for s in ("left", "right")]
    assert (v[brows, 1] - face.vertices[brows, 1]).min() > 5e-3        # the brows still rise
