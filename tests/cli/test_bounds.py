"""Numbers and sizes a hostile user typed: refused as bad input (exit 2, one line naming the option or the file,
nothing written) before the work, where they were tracebacks, never ended, or gave exit 0 with wrong numbers."""

import json

import numpy as np
import pytest

from visemeface.cli import main


@pytest.fixture
def here(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    return tmp_path


def _refused(capsys, argv, *words):
    code = main(argv)
    err = capsys.readouterr().err
    assert code == 2, f"exit {code}: {err}"
    assert err.count("\n") == 1 and err.startswith("visemeface: error: "), err
    assert "Traceback" not in err and not any(len(w) > 40 for w in err.split()), err    # no 309-digit echo
    for w in words:
        assert w in err, err
    return err


def _no_work(monkeypatch, *targets):
    def began(*a, **k):
        raise AssertionError("the work began before the bad value was refused")
    for t in targets:
        monkeypatch.setattr(t, began)


# ------------------------------------------------------------------------------------------------ analyze

@pytest.fixture
def frames(here):
    from visemeface.export.images import write_png

    (here / "fr").mkdir()
    for i in range(3):
        write_png(here / "fr" / f"f{i}.png", np.full((64, 64, 3), 120, np.uint8))
    return here


@pytest.mark.parametrize("option,value", [("--pad", "1e308"), ("--pad", "0.1,0.1,0.1,1e308"), ("--fps", "1e308"),
                                          ("--fps", "inf"), ("--threshold", "1e308"), ("--min-area", "1e308")])
def test_analyze_refuses_numbers_out_of_range_naming_the_option(frames, capsys, monkeypatch, option, value):
    """--pad 1e308 was an OverflowError traceback; --fps 1e308 gave times 0, 1e-308, ... and exit 0."""
    _no_work(monkeypatch, "visemeface.analysis.profiles.analyze_source")
    _refused(capsys, ["analyze", "fr", "--box", "10,20,30,10", option, value, "-o", "a.csv"], option)
    assert sorted(p.name for p in frames.iterdir()) == ["fr"]


def test_a_huge_box_is_refused_without_echoing_309_digits(frames, capsys):
    _refused(capsys, ["analyze", "fr", "--box", "1e308,20,30,10", "-o", "a.csv"], "mouth box", "1e+308")


# ------------------------------------------------------------------------------------------------ compare

def test_compare_bounds_the_lag_search(here, capsys, monkeypatch):
    """--max-lag 999999999999 never ended (100000 took 52 s)."""
    _no_work(monkeypatch, "visemeface.analysis.profiles.read_profile")
    _refused(capsys, ["compare", "a.csv", "b.csv", "--max-lag", "999999999999"], "--max-lag", "1000")


# ------------------------------------------------------------------------------------------------ landmarks

@pytest.fixture(scope="module")
def exported(tmp_path_factory):
    import os

    folder = tmp_path_factory.mktemp("face")
    cwd = os.getcwd()
    os.chdir(folder)
    try:
        assert main(["face", "--export", "f.obj", "--resolution", "800"]) == 0
    finally:
        os.chdir(cwd)
    return folder


def _landmarks(exported, folder, change):
    data = json.loads((exported / "f.landmarks.json").read_text())
    text = change(data)
    (folder / "f.landmarks.json").write_text(text if isinstance(text, str) else json.dumps(data))
    (folder / "f.obj").write_bytes((exported / "f.obj").read_bytes())


def _region_huge(d):
    d["regions"]["upper_lip"] = [99999999999999999999]


def _quad_huge(d):
    d["quads"][0] = [0, 1, 2, 99999999999999999999]


def _far_corner(d):
    d["landmarks"]["mouth_corner_left"] = [1e308, 0.0, 0.0]


@pytest.mark.parametrize("change,words", [
    (_region_huge, ["region 'upper_lip': vertex index out of range"]),
    (_quad_huge, ["'quads': vertex index out of range"]),
    (_far_corner, ["landmark 'mouth_corner_left'", "far outside the mesh"]),
    (lambda d: "[" * 200_000, ["nested too deeply"]),
    (lambda d: '{"landmarks": {"chin": 1' + "0" * 5000 + "}}", ["over 4300 digits"]),
])
@pytest.mark.parametrize("command", [["face", "--mesh", "f.obj", "-o", "x.png"],
                                     ["pose", "aa", "--face", "f.obj", "-o", "x.png"]])
def test_a_hostile_landmarks_file_is_one_line(here, capsys, exported, change, words, command):
    """Huge integers in regions/quads were OverflowError tracebacks, 200,000 '[' a RecursionError, and a
    landmark at 1e308 an overflow warning and "mouth corners coincide"."""
    _landmarks(exported, here, change)
    _refused(capsys, command, "f.landmarks.json", *words)
    assert not (here / "x.png").exists()


def test_a_mesh_vertex_at_1e308_is_refused(here, capsys, exported):
    _landmarks(exported, here, lambda d: None)
    obj = (here / "f.obj").read_text().replace("\nv ", "\nv 1e308 ", 1)
    (here / "f.obj").write_text(obj)
    _refused(capsys, ["face", "--mesh", "f.obj", "-o", "x.png"], "f.obj: vertex 0: coordinates must be finite")


# ------------------------------------------------------------------------------------------------ text sizes

def test_a_transcript_too_long_for_one_run_is_refused_before_its_words_are_read(here, capsys, monkeypatch):
    """A 2 MB one-line transcript ran 514 s and 1.08 GB before "lasts 160000 s, over the 10800 s limit"."""
    from visemeface.speech import g2p

    (here / "long.txt").write_text(" ".join(["hello"] * 400_000) + "\n")
    _no_work(monkeypatch, "visemeface.speech.g2p._phrase_items")
    _refused(capsys, ["speak", "long.txt", "-o", "l.mp4"], "long.txt", "400000 words", "10800 s limit")
    assert g2p.MAX_WORD_LETTERS >= 45                     # English's longest dictionary word
    assert sorted(p.name for p in here.iterdir()) == ["long.txt"]


def test_a_word_of_120000_letters_is_refused_at_once(here, capsys, monkeypatch):
    """It was accepted after 143 s of letter-to-sound."""
    _no_work(monkeypatch, "visemeface.speech.g2p._phrase_items")
    _refused(capsys, ["say", "a" * 120_000, "-o", "w.mp4"], "a word of 120000 letters", "at most 100")


def test_long_real_words_are_still_spoken(here, capsys):
    assert main(["say", "pneumonoultramicroscopicsilicovolcanoconiosis is long", "--no-video", "--track",
                 "t.csv", "-q", "--silent"]) == 0


# ------------------------------------------------------------------------------------------------ simulate

@pytest.mark.parametrize("argv,words", [
    (["--dt", "1e-308"], ["--dt", "1e-06"]),                   # was exit 3 "diverged ... Reduce dt"
    (["--damping", "1e308"], ["--damping", "10000"]),          # was exit 0, an overflow warning, nonsense
    (["--glue", "1e308"], ["--glue", "[0, 10]"]),             # was "time step must be a positive number, got 0.0"
    (["--glue-profile", "centre=1e308"], ["glue profile 'centre=1e308'", "from 0 to 10"]),
    (["--glue-file", "g.csv"], ["g.csv:2: glue must be from 0 to 10"]),
    (["--glue-profile", "centre=x"], ["glue profile"]),
    (["--threads", "999"], ["--threads"]),
    (["--jaw", "1e308"], ["--jaw"]),
])
def test_simulate_refuses_bad_numbers_before_the_fem_face_is_built(here, capsys, monkeypatch, argv, words):
    """--glue-profile/--glue-file/--threads were checked after the FEM face was built (6.5-7.7 s)."""
    (here / "g.csv").write_text("s,glue\n0,1e308\n")
    _no_work(monkeypatch, "visemeface.physics.face_model.build_fem_face", "visemeface.face.procedural.default_face")
    _refused(capsys, ["simulate", "part", *argv], *words)
    assert sorted(p.name for p in here.iterdir()) == ["g.csv"]


def test_say_refuses_a_huge_glue_naming_the_option(here, capsys, monkeypatch):
    _no_work(monkeypatch, "visemeface.physics.face_model.build_fem_face")
    _refused(capsys, ["say", "hi", "--physics", "sticky", "--glue", "1e308"], "--glue")


# ------------------------------------------------------------------------------------------------ the helper

def test_the_number_helper_names_the_option_the_range_and_shortens_the_value():
    from visemeface.commands._options import check_number
    from visemeface.errors import InputError

    assert check_number("2.5", "--x", 0, 10) == 2.5
    assert check_number("7", "--n", 1, 9, integer=True) == 7
    assert check_number("inf", "--l", 1, low_open=True, infinite=True) == float("inf")
    for value, kw in [("nan", {}), ("inf", {}), ("-1", {"low": 0}), ("0", {"low": 0, "low_open": True}),
                      ("11", {"high": 10}), ("1.5", {"integer": True}), ("9" * 400, {"high": 10}),
                      ("9" * 400, {"integer": True, "high": 10}), (True, {}), ("x", {})]:
        with pytest.raises(InputError) as e:
            check_number(value, "--opt", **kw)
        assert str(e.value).startswith("--opt must be ") and len(str(e.value)) < 90, e.value


# ------------------------------------------------------------------------------------------------ video

def _ffmpeg():
    import imageio_ffmpeg

    return imageio_ffmpeg.get_ffmpeg_exe()


def _clip(realdata, out, *vf, faststart=False):
    import subprocess

    args = [_ffmpeg(), "-v", "error", "-y", "-i", str(realdata / "swwp2s.mpg"), "-t", "1.9"]
    args += ["-vf", ",".join(vf)] if vf else []
    args += ["-movflags", "+faststart"] if faststart else []
    subprocess.run(args + [str(out)], check=True)
    return out


@pytest.mark.realdata
def test_a_grey_scale_clip_is_refused_by_the_lips_method(here, capsys, realdata):
    """It reported "openings max 0" for a talking face, exit 0. The colour method refuses grey frames; the
    default (mesh) method measures them (its cues are relative lightness)."""
    _clip(realdata, here / "grey.mp4", "format=gray", "format=yuv420p")
    _refused(capsys, ["analyze", "grey.mp4", "--method", "lips", "-o", "g.csv", "-q"], "grey.mp4", "grey-scale")
    assert not (here / "g.csv").exists()
    assert main(["analyze", "grey.mp4", "-o", "g.csv", "-q"]) == 0 and (here / "g.csv").exists()


@pytest.mark.realdata
def test_an_upside_down_face_is_refused(here, capsys, realdata):
    """The automatic box sat on the eyes and an eye was measured as the opening, exit 0."""
    from visemeface.analysis.landmarks import available

    if not available():
        pytest.skip("face landmarks (visemeface[track]) not installed")
    _clip(realdata, here / "up.mp4", "vflip", "hflip")
    _refused(capsys, ["analyze", "up.mp4", "-o", "u.csv", "-q"], "up.mp4", "upside down")
    _clip(realdata, here / "ok.mp4")
    assert main(["analyze", "ok.mp4", "-o", "ok.csv", "-q"]) == 0            # the same clip upright


@pytest.mark.realdata
def test_a_truncated_video_is_named_with_the_frames_expected_and_read(here, capsys, realdata):
    """A truncated MP4 was analysed as 21 of its 56 frames without a word."""
    whole = _clip(realdata, here / "whole.mp4", faststart=True).read_bytes()
    (here / "cut.mp4").write_bytes(whole[:len(whole) * 2 // 5])
    assert main(["analyze", "cut.mp4", "-o", "c.csv", "-q"]) == 0
    err = capsys.readouterr().err
    assert err.startswith("visemeface: warning: cut.mp4: read ") and "of the 48 frames its header gives" in err
    assert main(["analyze", "whole.mp4", "-o", "w.csv", "-q"]) == 0
    assert "truncated" not in capsys.readouterr().err


def test_a_corrupt_png_is_one_line_without_opencv_noise(here):
    """OpenCV printed "[ WARN:0@0.348] ..." and "[ERROR:...] IHDR chunk shall be first" before our line."""
    import subprocess
    import sys

    from visemeface.export.images import write_png

    (here / "fr").mkdir()
    rng = np.random.default_rng(0)
    for i in range(3):
        write_png(here / "fr" / f"f{i}.png", rng.integers(0, 255, (64, 64, 3), dtype=np.uint8))
    good = (here / "fr" / "f0.png").read_bytes()
    (here / "fr" / "f1.png").write_bytes(good[:12] + b"IHDX" + good[16:])
    proc = subprocess.run([sys.executable, "-m", "visemeface", "analyze", "fr", "--box", "10,20,30,10", "-o",
                           "a.csv"], cwd=here, capture_output=True, text=True, timeout=300)
    assert proc.returncode == 2 and proc.stderr == f"visemeface: error: {'fr/f1.png'}: cannot read image\n", proc.stderr


# ------------------------------------------------------------------------------------------------ outputs

def test_an_output_folder_that_takes_no_file_is_refused_before_aligning(here, capsys, monkeypatch):
    """`lipsync ... -o /proc/x.lab` aligned first and found the unwritable output after (2 lines)."""
    from pathlib import Path

    from visemeface.resources import transcripts_path

    if not Path("/proc").is_dir():
        pytest.skip("no /proc here")
    _no_work(monkeypatch, "visemeface.speech.align.utterance_from_audio")
    _refused(capsys, ["lipsync", str(transcripts_path("set_white_with_p_two_soon.wav")), "-o", "/proc/x.lab"],
             "/proc", "cannot write in the output folder")


def test_preview_beside_no_video_is_refused_clearly(here, capsys):
    """--preview with no path and --no-video wrote <stem>.html into the current folder, beside no MP4."""
    (here / "t.txt").write_text("0.00 0.05 _\n0.05 0.25 aa\n0.25 0.30 _\n")
    _refused(capsys, ["speak", "t.txt", "--no-video", "--preview", "--track", "t.csv"], "--preview", "--no-video")
    assert sorted(p.name for p in here.iterdir()) == ["t.txt"]


def test_a_silent_recording_is_refused_for_the_reason_that_holds():
    """A recording at -90 dBFS was refused as "loudest 112 dB above its floor, speech needs 8"."""
    from visemeface.errors import InputError
    from visemeface.speech.audio import speech_span

    rate = 16000
    quiet = 10 ** (-90 / 20) * np.sin(np.arange(rate) / 3.0)
    quiet[: rate // 2] = 0
    with pytest.raises(InputError, match=r"silent \(its loudest moment is -9\d dBFS"):
        speech_span(quiet, rate)
    with pytest.raises(InputError, match="steady noise"):
        speech_span(0.1 * np.sin(np.arange(rate) / 3.0), rate)


# ------------------------------------------------------------------------------------------------ compare --span

def test_compare_over_the_speech_span_of_a_recording(here, capsys):
    """README's correlations are over the speech span (as scripts/compare_realdata.py computes them), which
    compare could not select: `compare real.csv take.csv` printed r 0.22 where README quotes 0.50."""
    import pandas as pd
    import soundfile as sf

    rate = 16000
    sound = np.zeros(2 * rate)
    sound[rate // 2:rate] = 0.3 * np.random.default_rng(0).standard_normal(rate // 2)   # "speech" 0.5-1.0 s
    sf.write(here / "clip.wav", sound, rate)
    t = np.arange(60) / 30.0
    speaking = (t >= 0.5) & (t <= 1.0)
    a = np.where(speaking, np.sin(9 * t) + 1, np.cos(5 * t) + 1)
    b = np.where(speaking, np.sin(9 * t) + 1, -np.cos(5 * t) + 1)       # the same while speaking only
    for name, h in (("a.csv", a), ("b.csv", b)):
        pd.DataFrame({"frame": range(60), "time": t, "count": 1, "area": h / 10, "width": h / 2,
                      "height": h}).to_csv(here / name, index=False)

    def r_height(*more):
        assert main(["compare", "a.csv", "b.csv", "--max-lag", "0", *more]) == 0
        out = capsys.readouterr().out.splitlines()
        head, row = out[-2].split(), out[-1].split()
        return float(row[-5]), out                   # r_height: the third r column, before lag and r at lag

    whole, _ = r_height()
    speech, out = r_height("--span", "speech", "--audio", "clip.wav")
    assert speech > 0.99 and whole < 0.5, (whole, speech)
    assert out[0].startswith("over 0.49..1.01 s") and "clip.wav" in out[0]      # 20 ms frames
    assert r_height("--span", "0.5..1.0")[0] > 0.99
    _refused(capsys, ["compare", "a.csv", "b.csv", "--span", "speech"], "--span speech needs --audio")
    _refused(capsys, ["compare", "a.csv", "b.csv", "--span", "2..1"], "--span")
    _refused(capsys, ["compare", "a.csv", "b.csv", "--audio", "clip.wav"], "--audio", "--span speech")
