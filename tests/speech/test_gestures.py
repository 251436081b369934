"""Head, brows and gaze from prosody: accents, sizes, determinism, and the outputs that carry them."""

import json
import struct

import numpy as np
import pandas as pd
import pytest

from visemeface.errors import InputError
from visemeface.speech.acoustics import Acoustics
from visemeface.speech.g2p import text_to_utterance
from visemeface.speech.gestures import (BROW_COLUMNS, accents, add_face_gestures, head_pivot, head_quaternions,
                                        rotate_head, rotation_matrices, speech_gestures)

TEXT = "I never said she stole my money. Then she left, and nobody saw her again."


def _with_pitch(utt, peaks):
    """Acoustics of ``utt`` with a flat 120 Hz voice and F0 bumps of +5 semitones at ``peaks`` (s)."""
    times = np.arange(0.005, utt.end, 0.01)
    f0 = np.full(times.size, 120.0)
    for p in peaks:
        f0 *= 2 ** (5 / 12 * np.exp(-0.5 * ((times - p) / 0.05) ** 2))
    speech = np.zeros(times.size, bool)
    for s, e, ph in zip(utt.segments["start"], utt.segments["end"], utt.segments["phoneme"]):
        if ph != "_":
            speech |= (times >= s) & (times < e)
    f0[~speech] = np.nan
    level = np.where(speech, -20.0, -60.0)
    nan = np.full(times.size, np.nan)
    return Acoustics(times, level, f0, nan, nan, utt.end)


def test_nods_fall_on_the_pitch_accents_and_stay_in_natural_ranges():
    utt = text_to_utterance(TEXT)
    seg = utt.segments
    vowels = seg[seg["phoneme"].isin(["eh", "ow", "ah"])]
    peaks = [float((r.start + r.end) / 2) for r in vowels.itertuples()][:3]
    ac = _with_pitch(utt, peaks)
    n = int(np.ceil(utt.end * 30))
    g = speech_gestures(utt, n, 30.0, ac)
    for p in peaks:                                     # every F0 bump is an accent found at its peak
        assert np.min(np.abs(g.f0_peak_times - p)) <= 0.02
    nods = g.nod_times()
    for p in peaks:                                     # and a nod (head pitch maximum) within 150 ms of it
        assert np.min(np.abs(nods - p)) <= 0.15
    a = np.abs(g.head)
    assert a[:, 0].max() <= 4.0 and a[:, 1].max() <= 5.0 and a[:, 2].max() <= 3.0
    assert (a.max(axis=1) < 2.0).mean() > 0.6 and a[:, 1].max() > 0.5
    assert 0 < g.brow.max() <= 1 and np.abs(g.gaze).max() <= 0.5


def test_the_same_seed_gives_the_same_motion():
    utt = text_to_utterance(TEXT)
    n = int(np.ceil(utt.end * 30))
    a, b, c = (speech_gestures(utt, n, 30.0, seed=s) for s in (3, 3, 4))
    np.testing.assert_array_equal(a.head, b.head)
    np.testing.assert_array_equal(a.gaze, b.gaze)
    assert not np.array_equal(a.head, c.head)


def test_without_a_recording_the_emphasised_word_carries_the_strongest_accent():
    utt = text_to_utterance("I never said she *stole* my money")
    when, prom, peaks = accents(utt)
    word = utt.words.iloc[4]
    k = int(np.argmax(prom))
    assert word["start"] <= when[k] <= word["end"] and np.isnan(peaks).all()


def test_face_gestures_move_the_brows_and_eyes_only():
    from visemeface.muscles.rig import default_rig
    from visemeface.postures.library import load_visemes
    from visemeface.speech.timeline import activation_track

    rig = default_rig()
    utt = text_to_utterance(TEXT)
    track = activation_track(utt, load_visemes(rig=rig), fps=30)
    g = speech_gestures(utt, len(track), 30.0)
    out = add_face_gestures(track, rig.names, g)
    moved = [c for c in out.columns if c not in track.columns or not np.allclose(out[c], track[c])]
    assert set(moved) <= set(BROW_COLUMNS) | {"eye_turn_horizontal_left", "eye_turn_horizontal_right",
                                              "eye_turn_vertical_left", "eye_turn_vertical_right"}
    assert set(BROW_COLUMNS) <= set(moved)
    assert out.attrs == track.attrs


def test_rotations_turn_the_face_the_documented_ways():
    r = rotation_matrices(np.array([[90.0, 0, 0], [0, 90.0, 0], [0, 0, 90.0]]))
    nose, top = np.array([0, 0, 1.0]), np.array([0, 1.0, 0])
    np.testing.assert_allclose(r[0] @ nose, [1, 0, 0], atol=1e-12)     # yaw +: toward the subject's left (+x)
    np.testing.assert_allclose(r[1] @ nose, [0, -1, 0], atol=1e-12)    # pitch +: chin down
    np.testing.assert_allclose(r[2] @ top, [-1, 0, 0], atol=1e-12)     # roll +: top toward the subject's right
    angles = np.array([[3.0, -2.0, 1.5], [0.0, 4.0, -1.0]])
    q = head_quaternions(angles)
    for qi, ri in zip(q, rotation_matrices(angles)):                 # the glb's quaternions are the same turns
        x, y, z, w = qi
        m = np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
                      [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
                      [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]])
        np.testing.assert_allclose(m, ri, atol=1e-12)
    v = np.random.default_rng(0).normal(size=(20, 3))
    pivot = head_pivot(v)
    turned = rotate_head(v, [2.0, 3.0, 1.0], pivot)
    d0 = np.linalg.norm(v - pivot, axis=1)
    np.testing.assert_allclose(np.linalg.norm(turned - pivot, axis=1), d0, rtol=1e-6)   # rigid about the pivot


def test_the_renderer_turns_the_head_as_turned_vertices_would_and_culls_no_turned_frame():
    """A turned head is drawn by the GPU with its model matrix: the picture of the vertices turned on the CPU
    (to edge rounding), and a renderer that culls still triangles draws a turned frame whole."""
    from visemeface.muscles.rig import default_rig
    from visemeface.render.renderer import Renderer
    from visemeface.speech.gestures import head_matrices

    rig = default_rig()
    v = np.asarray(rig.pose({"jaw": 0.5, "zygomatic_major_left": 0.6}), np.float32)
    pivot = head_pivot(rig.face.vertices)
    angles = np.array([[4.0, -3.0, 2.0]])
    m = head_matrices(angles, pivot)[0]
    np.testing.assert_allclose(v @ m[:3, :3].T + m[:3, 3], rotate_head(v, angles[0], pivot), atol=1e-6)
    with Renderer(rig.face, size=256, samples=0) as plain, \
            Renderer(rig.face, size=256, samples=0, still=rig.still_vertices()) as culling:
        turned = plain.render(v, m)
        cpu = plain.render(rotate_head(v, angles[0], pivot))
        moved = np.abs(turned.astype(int) - plain.render(v)).max(axis=2) > 8
        off = np.abs(turned.astype(int) - cpu).max(axis=2) > 8
        assert moved.sum() > 2000 and off.sum() <= 10, (moved.sum(), off.sum())
        np.testing.assert_array_equal(culling.render(v, m), turned)
        np.testing.assert_array_equal(plain.render(v), plain.render(v, np.eye(4)))   # back to the rest view
        with pytest.raises(InputError, match="model must be a finite"):
            plain.render(v, np.full((4, 4), np.nan))


@pytest.fixture(scope="module")
def head_run(tmp_path_factory):
    from visemeface.cli import main

    root = tmp_path_factory.mktemp("gestures")
    for name, extra in (("on", []), ("off", ["--no-gestures", "--articulation", "0"])):
        assert main(["say", TEXT, "--silent", "--no-video", "-q", "--livelink", str(root / f"{name}.csv"),
                     "--gltf", str(root / f"{name}.glb"), "--track", str(root / f"{name}_t.csv"), *extra]) == 0
    return root


def _glb_json(path):
    b = path.read_bytes()
    n = struct.unpack("<I", b[12:16])[0]
    return json.loads(b[20:20 + n])


def test_live_link_and_glb_carry_the_head_and_no_gestures_keeps_it_still(head_run):
    on = pd.read_csv(head_run / "on.csv")
    off = pd.read_csv(head_run / "off.csv")
    deg = on[["HeadYaw", "HeadPitch", "HeadRoll"]].to_numpy() * 90
    assert np.abs(deg).max() > 0.5 and np.abs(deg[:, 0]).max() <= 4 and np.abs(deg[:, 1]).max() <= 5
    assert (off[["HeadYaw", "HeadPitch", "HeadRoll"]].to_numpy() == 0).all()
    assert (on[["LeftEyeYaw", "RightEyePitch"]].to_numpy() == 0).all()
    g = _glb_json(head_run / "on.glb")
    head = [i for i, nd in enumerate(g["nodes"]) if nd.get("name") == "head"]
    assert head and g["scenes"][0]["nodes"] == head and g["nodes"][head[0]]["children"] == [0]
    assert {"node": head[0], "path": "rotation"} in [c["target"] for c in g["animations"][0]["channels"]]
    assert [nd.get("name") for nd in _glb_json(head_run / "off.glb")["nodes"]] == ["face"]
    t_on, t_off = pd.read_csv(head_run / "on_t.csv", comment="#"), pd.read_csv(head_run / "off_t.csv", comment="#")
    assert t_on["frontalis_medialis_left"].max() > 0.1 and t_off["frontalis_medialis_left"].max() == 0


def test_articulation_zero_without_gestures_is_the_tabled_track(head_run):
    from visemeface.muscles.rig import default_rig
    from visemeface.postures.library import load_visemes
    from visemeface.speech.blinks import blink_utterance
    from visemeface.speech.timeline import activation_track
    from visemeface.speech.transcripts import timed_text

    rig = default_rig()
    utt = timed_text(TEXT, None, None)
    ranges = {n: tuple(r) for n, r in zip(rig.names, rig.ranges)}
    track = blink_utterance(activation_track(utt, load_visemes(rig=rig), fps=30, ranges=ranges), rig, utt)
    got = pd.read_csv(head_run / "off_t.csv", comment="#")
    np.testing.assert_allclose(got[track.columns].to_numpy(), track.to_numpy(), atol=2e-6)


@pytest.mark.parametrize("value", ["3", "-1", "nan", "lots"])
def test_a_bad_articulation_is_refused_before_any_work(tmp_path, capsys, value):
    from visemeface.cli import main

    out = tmp_path / "t.csv"
    assert main(["say", "hi", "--silent", "--no-video", "-q", "--track", str(out), "--articulation", value]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("visemeface:") and "--articulation" in err[0]
    assert not out.exists()
