"""ARKit weights with ARKit's meaning: fitted on a real ARKit rig (the ICT Face Model's artist-made shapes)
and checked by playing them back on that rig as a client does, not on our own face."""

from __future__ import annotations

import json
import subprocess
import sys

import numpy as np
import pytest
from scipy.optimize import lsq_linear

from visemeface.errors import InputError
from visemeface.retarget import check
from visemeface.retarget.fit import box_qp
from visemeface.retarget.rigs import (arkit_names, canonical, load_client_rig, read_gltf_morphs,
                                      reference_rig)

#: Sentences rich in /p b m/, open and rounded vowels; nothing in the fit was tuned on them.
SENTENCES = ("bob moves five boats past my pool", "a map of the moon by the blue boom box",
             "we wove two woolly ropes", "papa bought maybe more apples")


@pytest.fixture(scope="module")
def ict():
    return reference_rig()


def _played(client, text, rig):
    from visemeface.postures.library import load_visemes
    from visemeface.speech.g2p import text_to_utterance
    from visemeface.speech.timeline import MODES, activation_track

    u = text_to_utterance(text)
    ranges = {n: tuple(r) for n, r in zip(rig.names, rig.ranges)}
    track = activation_track(u, load_visemes(rig=rig), fps=30.0, mode=MODES[0], ranges=ranges)
    W, R = client.track_weights(rig.track_matrix(track), rig.path)
    return u, W, R


def test_canonical_names_follow_arkit():
    assert canonical("mouthSmile_L") == "mouthSmileLeft"
    assert canonical("MouthSmileRight") == "mouthSmileRight"
    assert canonical("blendShape1.jawOpen") == "jawOpen"
    assert canonical("browInnerUp_R") == "browInnerUp_R"     # a half of ARKit's one browInnerUp
    assert canonical("eyeBlink_L") == "eyeBlinkLeft"


def test_the_reference_rig_is_icts_53_shapes_on_arkits_52_names(ict):
    assert len(ict.shapes.names) == 53
    names, M, missing = ict.arkit_map()
    assert names == arkit_names() and len(names) == 52
    assert missing == ["tongueOut"]                      # ICT has no tongue shape
    assert np.allclose(M[names.index("browInnerUp")].sum(), 1.0)     # the mean of its two halves
    assert ict.face.n_vertices == ict.shapes.deltas.shape[1]


def test_box_qp_is_the_bounded_least_squares_minimum():
    rng = np.random.default_rng(7)
    for t in range(60):
        k = int(rng.integers(1, 40))
        A = rng.normal(size=(int(rng.integers(k, 3 * k + 3)), k))
        b = rng.normal(size=len(A)) * 2
        H, c = A.T @ A + 1e-6 * np.eye(k), A.T @ b
        w = box_qp(H, c, rng.uniform(-1, 2, k) if t % 2 else None)
        ref = lsq_linear(np.vstack([A, 1e-3 * np.eye(k)]), np.concatenate([b, np.zeros(k)]), bounds=(0, 1),
                         method="bvls", tol=1e-12).x
        f = lambda x: 0.5 * x @ H @ x - c @ x  # noqa: E731
        assert np.all((w >= 0) & (w <= 1)) and f(w) <= f(ref) + 1e-9


@pytest.mark.parametrize("text", SENTENCES)
def test_speech_on_the_ict_rig_closes_opens_and_rounds_and_never_crosses_the_lips(ict, rig, text):
    u, W, R = _played(ict, text, rig)
    names = ict.shapes.names
    jaw, close = W[:, names.index("jawOpen")], W[:, names.index("mouthClose")]
    assert np.all(close <= jaw + 1e-9)                    # ARKit's corrective: never above jawOpen
    m = check.measure(ict.face, ict.fit().play(W))
    s = check.summary(m, check.phone_frames(u.segments, 30.0, len(W)))
    assert s["min_centre_gap_mm"] > -1.0 and s["min_seam_gap_mm"] > -1.5      # the lips never cross
    assert s["bilabial"]["max_abs_gap_mm"] <= 1.5                            # every /p b m/ closes
    if "open vowel" in s:
        assert 4.0 <= s["open vowel"]["gap_mm"] <= 16.0
    if "rounded" in s:
        assert s["rounded"]["width_ratio"] <= 0.9
    assert np.median(R) < 1.5e-3


def test_the_old_recipe_would_cross_icts_lips(ict):
    """The cause of the defect, kept measurable: ARKit's mouthClose alone (the old export wrote ~0.97 with
    jawOpen 0 on every bilabial) pushes ICT's lower lip up through the upper one."""
    w = np.zeros(len(ict.shapes.names))
    w[ict.shapes.names.index("mouthClose")] = 0.97
    m = check.measure(ict.face, ict.fit().play(w))
    assert m.gap[0] < -20.0


def _ict_glb(path, ict, scale=1.0):
    from visemeface.export.gltf import write_morph_animation_glb

    d = ict.shapes.deltas
    write_morph_animation_glb(path, ict.face.vertices * scale, ict.face.triangles, d * scale, ict.shapes.names,
                              np.array([0.0, 1.0]), np.zeros((2, len(d))))


def test_a_glb_in_icts_topology_round_trips_through_the_rig_reader(ict, rig, tmp_path):
    _ict_glb(tmp_path / "ict.glb", ict, scale=100.0)            # in centimetres, as ICT ships it
    client = load_client_rig(tmp_path / "ict.glb")
    assert client.scale == pytest.approx(0.01)
    assert client.shapes.names == ict.shapes.names
    _, W0, _ = _played(ict, SENTENCES[0], rig)
    _, W1, R1 = _played(client, SENTENCES[0], rig)
    assert np.abs(W1 - W0).max() < 2e-3 and np.median(R1) < 1.5e-3


def test_our_own_glb_export_round_trips_with_its_landmarks(rig, tmp_path):
    """The project's --gltf export (our face with ARKit-named morph targets) as a client rig: its shapes are
    our rig's, so our motion fits them almost exactly."""
    from visemeface.export.gltf import write_morph_animation_glb
    from visemeface.retarget import moving_vertices, vocabulary

    vocab = vocabulary("arkit", rig)
    face = rig.face
    glb = tmp_path / "ours.glb"
    write_morph_animation_glb(glb, face.vertices, face.triangles, vocab.shapes[vocab.made],
                              [n for n, m in zip(vocab.names, vocab.made) if m], np.array([0.0, 1.0]),
                              np.zeros((2, int(vocab.made.sum()))))
    side = {"format": "visemeface-landmarks", "version": 1, "landmarks": face.landmarks,
            "regions": {k: v.tolist() for k, v in face.regions.items()}}
    (tmp_path / "ours.landmarks.json").write_text(json.dumps(side))
    client = load_client_rig(glb)
    assert client.face.n_vertices == face.n_vertices and "mouthPressLeft" in client.shapes.names
    _, W, R = _played(client, SENTENCES[0], rig)
    assert np.median(R) < 0.5e-3
    assert moving_vertices(rig).sum() > 0


def test_a_rig_folder_of_objs(ict, tmp_path):
    folder = tmp_path / "rig"
    folder.mkdir()
    v, f = ict.face.vertices * 100, ict.face.quads + 1

    def obj(name, verts):
        lines = [f"v {x:.5f} {y:.5f} {z:.5f}" for x, y, z in verts] + [f"f {a} {b} {c} {d}" for a, b, c, d in f]
        (folder / f"{name}.obj").write_text("\n".join(lines) + "\n")
    obj("generic_neutral_mesh", v)
    for name in ("jawOpen", "mouthClose", "mouthPucker"):
        obj(name, v + 100 * ict.shapes.deltas[ict.shapes.names.index(name)])
    client = load_client_rig(folder)
    assert sorted(client.shapes.names) == ["jawOpen", "mouthClose", "mouthPucker"]
    names, M, missing = client.arkit_map()
    assert len(missing) == 49


def test_bad_rigs_are_refused_with_one_line(ict, tmp_path):
    from visemeface.export.gltf import write_morph_animation_glb

    with pytest.raises(InputError, match="no mesh with morph targets"):
        glb = tmp_path / "flat.glb"
        _ict_glb(glb, ict)
        data = bytearray(glb.read_bytes())
        text = data.replace(b'"targets"', b'"xargets"')
        glb.write_bytes(bytes(text))
        read_gltf_morphs(glb)
    empty = tmp_path / "empty"
    empty.mkdir()
    (empty / "jawOpen.obj").write_text("v 0 0 0\n")
    with pytest.raises(InputError, match="exactly one neutral"):
        load_client_rig(empty)
    (empty / "neutral.obj").write_text("v 0 0 0\nv 1 0 0\n")
    with pytest.raises(InputError, match="neutral's topology"):
        load_client_rig(empty)
    (empty / "jawOpen.obj").write_text("v nan 0 0\nv 1 0 0\n")
    with pytest.raises(InputError, match="non-finite"):
        load_client_rig(empty)
    small = tmp_path / "small.glb"
    write_morph_animation_glb(small, np.eye(3), np.array([[0, 1, 2]]), np.ones((1, 3, 3)), ["jawOpen"],
                              np.array([0.0, 1.0]), np.zeros((2, 1)))
    with pytest.raises(InputError, match="no landmarks for the rig"):
        load_client_rig(small)


@pytest.mark.slow
def test_speak_writes_arkit_weights_on_a_rig_and_refuses_a_bad_one(tmp_path):
    from pathlib import Path

    ROOT = Path(__file__).resolve().parents[2]
    run = lambda *a: subprocess.run([sys.executable, "-m", "visemeface", *a], cwd=tmp_path,  # noqa: E731
                                    capture_output=True, text=True)
    t = str(ROOT / "transcripts" / "bob_moves_five_boats.txt")
    p = run("speak", t, "--no-video", "--arkit", "a.csv", "--livelink", "l.csv")
    assert p.returncode == 0, p.stderr
    import pandas as pd

    a = pd.read_csv(tmp_path / "a.csv")
    assert list(a.columns[2:]) == arkit_names()
    assert (a["mouthClose"] <= a["jawOpen"] + 1e-6).all() and a["jawOpen"].max() > 0.05
    (tmp_path / "bad.glb").write_bytes(b"not a glb at all")
    p = run("speak", t, "--no-video", "--arkit", "b.csv", "--arkit-rig", "bad.glb")
    assert p.returncode == 2 and p.stderr.count("\n") == 1 and "glTF" in p.stderr
    assert not (tmp_path / "b.csv").exists()
    p = run("speak", t, "--no-video", "--arkit-rig", "bad.glb")
    assert p.returncode == 2 and "--arkit-rig is an option of --arkit" in p.stderr
