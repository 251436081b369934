"""``visemeface speak`` / ``say`` and the pipeline glue: checks before work, resume, end to end."""

import json
import warnings

import numpy as np
import pytest
import soundfile as sf

from visemeface import pipeline
from visemeface.cli import main
from visemeface.errors import InputError
from visemeface.muscles.morphs import JAW_SAMPLES
from visemeface.render import export


# ----------------------------------------------------------------------------- checks before work

def test_outputs_are_checked_before_any_work(tmp_path, capsys, monkeypatch):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "s.txt").write_text(SHORT)
    (tmp_path / "a.mp4").write_bytes(b"user")
    cases = [
        (["-o", "a.mp4"], "a.mp4: output exists; use --force"),
        (["--track", "t.csv", "--measures", "t.csv"], "same path"),
        (["--gltf", "b.gltf"], ".glb"),
        (["--no-video"], "nothing to write"),
        (["--pc2", "no/x.pc2"], "folder does not exist"),
        (["--no-video", "-o", "c.mp4"], "--no-video"),
    ]
    for extra, message in cases:
        code = main(["speak", "s.txt", "--size", "32"] + extra)
        err = capsys.readouterr().err
        assert code == 2 and message in err and err.count("\n") == 1, (extra, err)
    (tmp_path / "fr").mkdir()
    assert main(["speak", "s.txt", "--size", "32", "--frames", "fr"]) == 2
    assert "fr: output exists" in capsys.readouterr().err
    (tmp_path / "fr").rmdir()
    assert (tmp_path / "a.mp4").read_bytes() == b"user"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["a.mp4", "s.txt"]


def test_a_folder_in_the_way_of_a_file_is_refused_even_with_force(tmp_path, capsys, monkeypatch):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "s.txt").write_text(SHORT)
    (tmp_path / "d.mp4").mkdir()
    assert main(["speak", "s.txt", "--size", "32", "-o", "d.mp4", "--force"]) == 2
    assert "d.mp4: output exists and is a folder" in capsys.readouterr().err


def test_check_audio(tmp_path):
    sf.write(tmp_path / "a.wav", np.zeros(8000, np.float32), 16000)
    assert pipeline.check_audio(tmp_path / "a.wav") == pytest.approx(0.5)
    (tmp_path / "bad.wav").write_bytes(b"RIFF....not a wave at all")
    with pytest.raises(InputError, match="bad.wav: unreadable audio \\(not a sound file"):
        pipeline.check_audio(tmp_path / "bad.wav")
    with pytest.raises(InputError, match="not found"):
        pipeline.check_audio(tmp_path / "none.wav")
    sf.write(tmp_path / "nan.wav", np.full(8000, np.nan, np.float32), 16000, subtype="FLOAT")
    with pytest.raises(InputError, match="nan.wav: audio holds non-finite samples"):
        pipeline.check_audio(tmp_path / "nan.wav")


def test_parse_emotions_checks_names():
    from visemeface.animate import parse_emotions

    assert parse_emotions(["happiness=0.6", "anger"], ["happiness", "anger"]) == {"happiness": 0.6, "anger": 1.0}
    with pytest.raises(InputError, match="did you mean: happiness"):
        parse_emotions(["hapiness=0.5"], ["happiness", "anger"])
    assert parse_emotions(None, ["happiness"]) == {}


# ----------------------------------------------------------------------------- CLI errors

def _run_cli(argv, capsys):
    code = main(argv)
    return code, capsys.readouterr().err


def test_speak_missing_transcript_exits_2(tmp_path, capsys, monkeypatch):
    monkeypatch.chdir(tmp_path)
    code, err = _run_cli(["speak", "nope.txt"], capsys)
    assert code == 2 and "nope.txt: transcript not found" in err
    assert err.count("\n") == 1
    assert list(tmp_path.iterdir()) == []


# ----------------------------------------------------------------------------- end to end
# Small on purpose (0.8 s of speech, 128^2 frames): CI has 2 cores and no GPU.

SHORT = """# short test utterance: silence, m, aa, p, silence
0.00 0.10 _
0.10 0.25 m
0.25 0.45 aa
0.45 0.60 p
0.60 0.80 _
"""
N_SHORT = 24  # ceil(0.8 s * 30 fps)


@pytest.fixture
def short(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "short.txt").write_text(SHORT)
    sf.write(tmp_path / "short.wav", 0.1 * np.sin(np.arange(12800) / 5.0).astype(np.float32), 16000)
    return tmp_path


def _glb_arrays(path):
    import pygltflib

    gl = pygltflib.GLTF2().load(str(path))
    blob = gl.binary_blob()

    def arr(i):
        acc = gl.accessors[i]
        view = gl.bufferViews[acc.bufferView]
        ncomp = {"SCALAR": 1, "VEC3": 3, "VEC4": 4}[acc.type]
        dtype = {5126: "<f4", 5123: "<u2", 5125: "<u4"}[acc.componentType]
        a = np.frombuffer(blob, dtype, acc.count * ncomp, view.byteOffset + (acc.byteOffset or 0))
        return a.reshape(acc.count, ncomp) if ncomp > 1 else a

    return gl, arr


def test_speak_end_to_end_all_exports(short, capsys):
    from visemeface.muscles.rig import default_rig
    from visemeface.render.renderer import Renderer
    from visemeface.speech.timeline import load_track

    code = main(["speak", "short.txt", "--size", "128", "--audio", "short.wav", "--frames", "fr",
                 "--obj", "obj", "--pc2", "s.pc2", "--gltf", "s.glb", "--track", "s.csv"])
    assert code == 0, capsys.readouterr().err
    assert "24 frames" in capsys.readouterr().out
    names = sorted(p.name for p in short.iterdir())
    assert names == ["fr", "fr.json", "obj", "s.csv", "s.glb", "s.pc2", "short.mp4", "short.mp4.json",
                     "short.txt", "short.wav"]

    # MP4: one frame per track row, audio muxed for exactly as long, starting at 0
    info = export.read_video_info(short / "short.mp4")
    assert info["n_frames"] == N_SHORT and info["size"] == (128, 128)
    assert info["audio_samples"] / info["audio_rate"] == pytest.approx(N_SHORT / 30, abs=2e-3)

    # the track, the point cache and the OBJ frames agree with the rig
    rig = default_rig()
    track = load_track(short / "s.csv")
    assert len(track) == N_SHORT and track.attrs["fps"] == 30
    pts, head = export.read_pc2(short / "s.pc2")
    assert pts.shape == (N_SHORT, len(rig.face.vertices), 3) and head["num_samples"] == N_SHORT
    a = rig.clamp(rig.track_matrix(track))
    for i in (0, 8, 13):
        np.testing.assert_allclose(pts[i], rig.pose(a[i]), atol=1e-6)
    text = (short / "obj" / export.frame_name(5, "obj")).read_text().splitlines()
    obj5 = np.array([line.split()[1:] for line in text if line.startswith("v ")], float)
    np.testing.assert_allclose(obj5, pts[5], atol=2e-6)
    assert len(list((short / "obj").glob("frame_*.obj"))) == N_SHORT and (short / "obj" / "face.mtl").is_file()

    # the mouth is shut on /m/ (t = 0.2 s) and open on /aa/ (t = 0.35 s): geometry and pixels
    lower, upper = rig.face.landmarks["lower_lip_mid"], rig.face.landmarks["upper_lip_mid"]
    gap = pts[:, upper, 1] - pts[:, lower, 1]
    assert gap[6] < 1e-3 and gap[10] > 5e-3
    x, y, w, h = Renderer(rig.face, size=128).mouth_box()
    dark = []
    for i in (6, 10):
        img = export.read_png(short / "fr" / export.frame_name(i))
        box = img[max(0, y - h):y + 2 * h, x:x + w].astype(float)
        dark.append(int(((box @ [0.299, 0.587, 0.114]) < 50).sum()))
    assert dark[1] > dark[0] + 10
    # the MP4 shows the same frames as the PNGs (lossy, so approximately)
    import imageio_ffmpeg
    gen = imageio_ffmpeg.read_frames(str(short / "short.mp4"))
    next(gen)
    for i, raw in enumerate(gen):
        if i == 10:
            vid = np.frombuffer(raw, np.uint8).reshape(128, 128, 3).astype(float)
            png = export.read_png(short / "fr" / export.frame_name(10)).astype(float)
            assert np.abs(vid - png).mean() < 4

    # the video's sidecar lets `analyze` find the mouth with no --box: shut on /m/, open on /aa/
    assert main(["analyze", "short.mp4", "-o", "profile.csv"]) == 0, capsys.readouterr().err
    import pandas as pd
    profile = pd.read_csv(short / "profile.csv")
    assert len(profile) == N_SHORT
    assert profile["count"][6] == 0 and profile["count"][10] >= 1 and profile["area"][10] > 0

    # glTF: 25 muscle and 5 tongue targets + jaw samples; plays the rig's poses; lasts the utterance
    gl, arr = _glb_arrays(short / "s.glb")
    prim = gl.meshes[0].primitives[0]
    tnames = gl.meshes[0].extras["targetNames"]
    m = len(rig.muscles)
    assert tnames[:m] == list(rig.names[:m]) and "tongue_tip_raise" in tnames
    assert all(n.startswith("jaw@") for n in tnames[m:]) and len(tnames) >= m + JAW_SAMPLES
    assert len(prim.targets) == len(tnames)
    sampler = gl.animations[0].samplers[0]
    times = arr(sampler.input)
    assert times[-1] == pytest.approx(0.8, abs=1e-6) and gl.accessors[sampler.input].max[0] == pytest.approx(0.8)
    weights = arr(sampler.output).reshape(len(times), len(tnames))
    rest = arr(prim.attributes.POSITION)
    targets = np.stack([arr(t.POSITION if hasattr(t, "POSITION") else t["POSITION"]) for t in prim.targets])
    for i in (0, 10, 13):
        posed = rest + np.tensordot(weights[i], targets, axes=1)
        np.testing.assert_allclose(posed, pts[i], atol=3e-5)  # jaw chord + float32


def test_speak_resume_after_interruption_keeps_frames(short, capsys, monkeypatch):
    from visemeface.render import renderer

    calls = {"n": 0}
    real = renderer.Renderer.render

    def interrupted(self, vertices=None, model=None):
        if calls["n"] == 9:
            raise KeyboardInterrupt
        calls["n"] += 1
        return real(self, vertices, model)

    monkeypatch.setattr(renderer.Renderer, "render", interrupted)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        assert main(["speak", "short.txt", "--size", "64", "--frames", "fr", "-q"]) == 130
    assert "interrupted" in capsys.readouterr().err
    partial = short / "fr.partial"
    kept = sorted(partial.glob("frame_*.png"))
    assert len(kept) == 9 and not (short / "fr").exists() and not (short / "short.mp4").exists()
    before = {p.name: (p.stat().st_ino, p.stat().st_mtime_ns, p.read_bytes()) for p in kept}

    def counting(self, vertices=None, model=None):
        calls["n"] += 1
        return real(self, vertices, model)

    monkeypatch.setattr(renderer.Renderer, "render", counting)
    calls["n"] = 0
    # other settings cannot reuse them: refused before any rendering
    assert main(["speak", "short.txt", "--size", "128", "--frames", "fr", "--resume", "-q"]) == 2
    assert calls["n"] == 0
    assert main(["speak", "short.txt", "--size", "64", "--frames", "fr", "--resume"]) == 0
    assert "9 kept from the previous run" in capsys.readouterr().out
    assert calls["n"] == N_SHORT - 9  # only the missing frames were rendered
    for name, (ino, mtime, data) in before.items():
        p = short / "fr" / name
        assert (p.stat().st_ino, p.stat().st_mtime_ns) == (ino, mtime)
    assert len(list((short / "fr").glob("frame_*.png"))) == N_SHORT
    assert export.read_video_info(short / "short.mp4")["n_frames"] == N_SHORT
    # rendering is deterministic: a kept frame is what a fresh render gives
    monkeypatch.setattr(renderer.Renderer, "render", real)
    assert main(["speak", "short.txt", "--size", "64", "--frames", "fr2", "--no-video", "-q"]) == 0
    for name, (_, _, data) in before.items():
        np.testing.assert_array_equal(export.read_png(short / "fr2" / name), export.read_png(short / "fr" / name))


def test_speak_resume_from_finished_frames_renders_nothing(short, capsys, monkeypatch):
    from visemeface.render import renderer

    assert main(["speak", "short.txt", "--size", "32", "--frames", "fr", "--no-video", "-q"]) == 0
    calls = {"n": 0}
    real = renderer.Renderer.render

    def counting(self, vertices=None, model=None):
        calls["n"] += 1
        return real(self, vertices, model)

    monkeypatch.setattr(renderer.Renderer, "render", counting)
    assert main(["speak", "short.txt", "--size", "32", "--frames", "fr", "--resume", "-o", "v.mp4"]) == 0
    assert calls["n"] == 0 and f"{N_SHORT} kept" in capsys.readouterr().out
    assert export.read_video_info(short / "v.mp4")["n_frames"] == N_SHORT
    assert not (short / "fr.partial").exists() and len(list((short / "fr").glob("*.png"))) == N_SHORT


@pytest.mark.parametrize("content, audio, message", [
    ("0.0 0.2 _\n0.2 0.4 qq\n", None, "short.txt:2"),                 # unknown phone
    ("0.0 0.3 _\n0.2 0.4 m\n0.4 0.5 _\n", None, "short.txt:"),           # overlapping times
    (SHORT, "bad.wav", "bad.wav: unreadable audio (not a sound file"),                     # unreadable audio
])
def test_speak_bad_input_leaves_nothing(short, capsys, content, audio, message):
    (short / "short.txt").write_text(content)
    (short / "bad.wav").write_bytes(b"RIFF-garbage")
    before = sorted(p.name for p in short.iterdir())
    argv = ["speak", "short.txt", "--size", "64", "--frames", "fr", "--pc2", "a.pc2", "--gltf", "a.glb"]
    if audio:
        argv += ["--audio", audio]
    code = main(argv)
    err = capsys.readouterr().err
    assert code == 2 and message in err and err.count("\n") == 1, err
    assert sorted(p.name for p in short.iterdir()) == before


def test_speak_refuses_existing_output(short, capsys):
    (short / "short.mp4").write_bytes(b"mine")
    assert main(["speak", "short.txt", "--size", "64", "--pc2", "a.pc2"]) == 2
    assert "short.mp4: output exists; use --force" in capsys.readouterr().err
    assert (short / "short.mp4").read_bytes() == b"mine" and not (short / "a.pc2").exists()
    assert main(["speak", "short.txt", "--size", "64", "--force", "-q"]) == 0
    assert export.read_video_info(short / "short.mp4")["n_frames"] == N_SHORT


def test_speak_exports_only_needs_no_renderer(short, capsys, monkeypatch):
    from visemeface.render import renderer

    def no_gl(*a, **k):
        raise AssertionError("the renderer must not be created without video or frames")

    monkeypatch.setattr(renderer, "Renderer", no_gl)
    assert main(["speak", "short.txt", "--no-video", "--pc2", "a.pc2", "--gltf", "a.glb", "-q"]) == 0
    assert sorted(p.name for p in short.iterdir()) == ["a.glb", "a.pc2", "short.txt", "short.wav"]
    assert export.read_pc2(short / "a.pc2")[1]["num_samples"] == N_SHORT


def test_a_recording_longer_than_its_transcript_is_never_cut(short, capsys):
    sf.write(short / "long.wav", np.zeros(32000, np.float32), 16000)  # 2 s for 0.8 s of speech
    assert main(["speak", "short.txt", "--size", "32", "--audio", "long.wav", "--track", "t.csv", "-q"]) == 0
    err = capsys.readouterr().err
    assert ("warning: long.wav: the audio lasts 2.00 s, the transcript 0.80 s; the face rests after the last "
            "phone until the audio ends") in err
    info = export.read_video_info(short / "short.mp4")
    assert info["audio_samples"] / info["audio_rate"] == pytest.approx(2.0, abs=2e-3)
    assert info["n_frames"] == pytest.approx(2.0 * 30, abs=1)
    from visemeface.speech.timeline import load_track

    track = load_track(short / "t.csv")                    # at rest after the speech: the jaw shut
    assert track["jaw"].iloc[-1] == pytest.approx(0.0, abs=1e-6) and track["jaw"].max() > 0.05


@pytest.mark.slow
def test_say_text_to_video(short, capsys):
    from visemeface.speech.timeline import load_track

    assert main(["say", "mama", "--size", "64", "--track", "say.csv", "--emotion", "happiness=0.5"]) == 0
    track = load_track(short / "say.csv")
    info = export.read_video_info(short / "say.mp4")
    assert info["n_frames"] == len(track) > 5
    assert track["zygomatic_major_left"].max() > 0  # the emotion is in the track
    assert main(["say", "mama", "--size", "64", "--emotion", "hapiness", "-o", "x.mp4"]) == 2
    assert "did you mean: happiness" in capsys.readouterr().err


def test_speak_formats_match_reader():
    from visemeface.cli import build_parser
    from visemeface.speech.transcripts import FORMATS as READER_FORMATS

    speak = build_parser()._subparsers._group_actions[0].choices["speak"]
    fmt = next(a for a in speak._actions if a.dest == "format")
    assert set(fmt.choices) == {"auto", *READER_FORMATS}


def test_speak_plain_text_transcript_with_rate(short):
    from visemeface.speech.timeline import load_track

    (short / "plain.txt").write_text("Bob moves five boats.\n")
    for wpm in (120, 240):
        assert main(["speak", "plain.txt", "--format", "text", "--rate", str(wpm), "--no-video",
                     "--track", f"t{wpm}.csv", "-q"]) == 0
    slow, fast = len(load_track(short / "t120.csv")), len(load_track(short / "t240.csv"))
    assert 1.3 < slow / fast < 2.2  # twice the rate, about half the time (pauses do not all scale)


# ----------------------------------------------------------------------------- --physics sticky|elastic
# A coarse face (1500 vertices) and a 0.3 s utterance at 64^2: the FEM path stays a few seconds.

TINY = """0.00 0.05 _
0.05 0.25 aa
0.25 0.30 _
"""


@pytest.fixture
def coarse_rig(short):
    """A coarse default face (1500 vertices) exported as a user's mesh: speak --face coarse.obj."""
    from visemeface.face.mesh import load_face
    from visemeface.face.procedural import default_face
    from visemeface.muscles.rig import MuscleRig
    from visemeface.runtime import set_threads

    set_threads(1)
    default_face(resolution=1500).save(short / "coarse.obj")
    return MuscleRig.from_file(load_face(short / "coarse.obj"))


@pytest.mark.slow
def test_speak_physics_frames_come_from_the_fem_face(short, capsys, coarse_rig):
    (short / "tiny.txt").write_text(TINY)
    code = main(["speak", "tiny.txt", "--face", "coarse.obj", "--size", "64", "--msaa", "0", "--physics",
                 "elastic", "--pc2", "e.pc2", "--track", "e.csv", "-q"])
    assert code == 0, capsys.readouterr().err
    code = main(["speak", "tiny.txt", "--face", "coarse.obj", "--size", "64", "--msaa", "0", "--no-video",
                 "--pc2", "k.pc2", "-q"])
    assert code == 0, capsys.readouterr().err
    from visemeface.physics.face_model import build_fem_face

    fem = build_fem_face(coarse_rig.face)
    pts, _ = export.read_pc2(short / "e.pc2")
    kin, _ = export.read_pc2(short / "k.pc2")
    n = round(0.3 * 30)
    assert pts.shape == kin.shape == (n, coarse_rig.face.n_vertices, 3)
    assert (short / "tiny.mp4").exists() and export.read_video_info(short / "tiny.mp4")["n_frames"] == n
    # the FEM frames are not the rig's poses (a simulation ran), yet follow them: the mouth
    # opens on /aa/ by about as much
    assert np.abs(pts - kin).max() > 1e-6
    up, lo = coarse_rig.face.landmarks["upper_lip_mid"], coarse_rig.face.landmarks["lower_lip_mid"]
    gap_fem, gap_kin = pts[:, up, 1] - pts[:, lo, 1], kin[:, up, 1] - kin[:, lo, 1]
    i = int(np.argmax(gap_kin))
    assert gap_kin[i] > 0.004 and abs(gap_fem[i] - gap_kin[i]) < 0.25 * gap_kin[i]
    assert abs(gap_fem[0] - gap_kin[0]) < 5e-4          # starts in the first frame's posture
    lips = np.unique(np.concatenate([coarse_rig.face.region("upper_lip"), coarse_rig.face.region("lower_lip")]))
    rms = np.sqrt(np.mean(np.sum((pts[i, lips] - kin[i, lips]) ** 2, axis=1))) / fem.mouth_width
    assert rms < 0.05


@pytest.mark.parametrize("extra, message", [
    (["--physics", "sticky", "--moisture", "-1"], "argument --moisture: must be a number >= 0"),
    (["--physics", "sticky", "--evaporation", "-2"], "argument --evaporation: must be a number >= 0"),
    (["--physics", "sticky", "--glue", "-0.1"], "argument --glue: must be a number in [0, 10]"),
    (["--glue", "0.1"], "--glue needs --physics sticky or elastic"),
    (["--physics", "sticky", "--glue-profile", "0.95..0.99=1"], "names no saliva element"),
    (["--physics", "sticky", "--seam-elements", "-1"], "argument --seam-elements: must be an integer from 0 to 192"),
    (["--physics", "sticky", "--seam-elements", "4800"], "argument --seam-elements: must be an integer from 0 to 192"),
    (["--seam-elements", "48"], "--seam-elements needs --physics sticky or elastic"),
    (["--physics", "sticky", "--tissue-limit", "1"], "argument --tissue-limit: must be a number > 1 (or inf)"),
    (["--physics", "sticky", "--tissue-limit", "nan"], "argument --tissue-limit: must be a number > 1 (or inf)"),
    (["--tissue-limit", "2.5"], "--tissue-limit needs --physics sticky or elastic"),
    (["--physics", "elastic", "--glue", "0.3"], "--glue sets the glue between the lips, which --physics elastic"),
    (["--physics", "elastic", "--moisture", "50"], "--moisture sets the glue"),
    (["--measures", "m.csv"], "--measures writes a simulation's figures: it needs --physics"),
])
def test_speak_physics_bad_input_exits_2_before_simulating(short, capsys, coarse_rig, monkeypatch, extra,
                                                           message):
    from visemeface.physics import drive

    def no_frames(self, start=None):
        raise AssertionError("simulated despite bad input")
        yield

    monkeypatch.setattr(drive.StickySimulation, "frames", no_frames)
    (short / "tiny.txt").write_text(TINY)
    code = main(["speak", "tiny.txt", "--face", "coarse.obj", "--size", "64"] + extra)
    err = capsys.readouterr().err
    assert code == 2 and message in err and err.count("\n") == 1
    assert not (short / "tiny.mp4").exists() and not (short / "m.csv").exists()


def test_the_speech_lips_glue_the_mouth_corners_unless_told_not_to():
    """The film runs into the corners by default (no unglued corner notches); --no-film-corners gives the
    seed's film, which ends at the last pair of lip vertices; --physics none refuses either."""
    import argparse

    from visemeface.commands._options import add_physics_arguments, physics_from_args
    from visemeface.errors import InputError
    p = argparse.ArgumentParser()
    add_physics_arguments(p, "none", ("none", "sticky", "elastic"))
    assert physics_from_args(p.parse_args(["--physics", "sticky"])).film_corners is True
    assert physics_from_args(p.parse_args(["--physics", "sticky", "--no-film-corners"])).film_corners is False
    with pytest.raises(InputError, match="--no-film-corners needs --physics"):
        physics_from_args(p.parse_args(["--no-film-corners"]))
    # the tissue: Gent at materials.TISSUE_LIMIT (the glue then lets go), another limit as given (elastic
    # too: it is no glue), the seed's neo-Hookean with inf
    from visemeface.physics.materials import TISSUE_LIMIT
    assert physics_from_args(p.parse_args(["--physics", "sticky"])).tissue.limiting_stretch == pytest.approx(TISSUE_LIMIT)
    gent = physics_from_args(p.parse_args(["--physics", "elastic", "--tissue-limit", "2.5"])).tissue
    assert gent.limiting_stretch == pytest.approx(2.5) and gent.mu == 800.0
    assert physics_from_args(p.parse_args(["--physics", "sticky", "--tissue-limit", "inf"])).tissue.ijm == 0.0
    assert f"default {TISSUE_LIMIT:g}" in " ".join(p.format_help().split())        # --help says the same


def test_absurd_transcript_length_and_msaa_are_refused_before_work(short, capsys):
    (short / "huge.txt").write_text("0.0 20000 _\n20000 20000.2 aa\n")   # plausible phones, 5.6 h
    assert main(["speak", "huge.txt", "--size", "32", "-q"]) == 2
    assert "limit" in capsys.readouterr().err
    assert main(["speak", "short.txt", "--size", "32", "--msaa", "3", "-q"]) == 2
    assert "--msaa" in capsys.readouterr().err
    assert not (short / "huge.mp4").exists() and not (short / "short.mp4").exists()


def test_say_blinks_by_default_and_not_with_no_blink(short):
    from visemeface.speech.timeline import load_track

    text = "the quick brown fox jumps over the lazy dog " * 3
    assert main(["say", text, "--no-video", "--track", "b.csv", "-q"]) == 0
    assert main(["say", text, "--no-video", "--track", "n.csv", "--no-blink", "-q"]) == 0
    blink, none = load_track(short / "b.csv"), load_track(short / "n.csv")
    shut = blink["upper_lid_close_left"].to_numpy()
    assert shut.max() > 0.9 and (shut > 0.5).sum() >= 2                 # blinks in the lid channel
    assert "upper_lid_close_left" not in none or none["upper_lid_close_left"].max() == 0
    # the tongue's channels are in the track too
    assert blink["tongue_tip_raise"].max() > 0.5
    # deterministic: the same command blinks the same
    assert main(["say", text, "--no-video", "--track", "c.csv", "-q"]) == 0
    assert (short / "b.csv").read_bytes() == (short / "c.csv").read_bytes()


@pytest.mark.parametrize("argv", [["pose", "ah", "--emotion", "happiness=5", "-o", "p.png"],
                                  ["speak", "short.txt", "--emotion", "happiness=1.5", "-o", "s.mp4"],
                                  ["sheet", "--emotion", "anger=2", "-o", "s.png"]])
def test_every_command_takes_emotion_weights_in_0_to_1_as_text_tags_do(short, capsys, argv):
    assert main(argv) == 2
    assert "is not in 0..1" in capsys.readouterr().err
    assert sorted(p.name for p in short.iterdir()) == ["short.txt", "short.wav"]


def test_pose_takes_a_bare_emotion_name_as_speak_does(short, capsys):
    assert main(["pose", "ah", "--emotion", "happiness", "--size", "64", "-o", "p.png"]) == 0
    assert main(["pose", "ah", "--emotion", "hapiness", "--size", "64", "-o", "q.png"]) == 2
    assert "did you mean: happiness" in capsys.readouterr().err


def test_a_video_spoken_as_the_recording_or_as_audio_gives_the_same_animation(tmp_path, capsys):
    """``speak CLIP.mp4 --text WORDS`` and ``speak WORDS.txt --audio CLIP.mp4`` animate the same words to the same
    sound, so the same track, articulation and gestures included. The recording's sound used to be analysed from
    a 16-bit copy written for the muxer: the mean of two channels lost its last bit, the jaw moved by 0.005."""
    import subprocess

    import imageio_ffmpeg

    from visemeface.resources import transcripts_path

    wav = transcripts_path("set_white_with_p_two_soon.wav")
    clip = tmp_path / "clip.mp4"
    # two channels that differ (the second a little later and quieter), with a picture
    subprocess.run([imageio_ffmpeg.get_ffmpeg_exe(), "-v", "error", "-f", "lavfi", "-i", "color=c=gray:s=64x64:r=25",
                    "-i", str(wav), "-filter_complex", "[1:a]asplit[a][b];[b]adelay=3,volume=0.7[c];[a][c]amerge=inputs=2",
                    "-shortest", "-c:v", "libx264", "-c:a", "aac", str(clip)], check=True)
    (tmp_path / "words.txt").write_text("set white with p two soon\n")
    a, b = tmp_path / "a.csv", tmp_path / "b.csv"
    assert main(["speak", str(clip), "--text", "set white with p two soon", "--no-video", "--track", str(a),
                 "--livelink", str(tmp_path / "a_ll.csv"), "-q"]) == 0
    assert main(["speak", str(tmp_path / "words.txt"), "--audio", str(clip), "--no-video", "--track", str(b),
                 "--livelink", str(tmp_path / "b_ll.csv"), "-q"]) == 0
    assert a.read_bytes() == b.read_bytes()
    assert (tmp_path / "a_ll.csv").read_bytes() == (tmp_path / "b_ll.csv").read_bytes()   # the head's turns too
