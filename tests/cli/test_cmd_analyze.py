"""`visemeface analyze` and `visemeface compare` end to end on synthetic videos."""

import cv2
import numpy as np
import pandas as pd
import pytest

from visemeface.analysis.synthetic import merging_mouth_frames
from visemeface.analysis.video import natural_key, open_frames, read_sidecar, write_sidecar
from visemeface.cli import main
from visemeface.errors import InputError

BOX = "28,78,200,100"
N, MERGE = 24, 13


@pytest.fixture(scope="module")
def frames():
    return list(merging_mouth_frames(N, MERGE, (256, 256)))


@pytest.fixture(scope="module")
def frame_dir(tmp_path_factory, frames):
    d = tmp_path_factory.mktemp("frames")
    for i, f in enumerate(frames):        # unpadded names: natural order needed
        cv2.imwrite(str(d / f"f{i}.png"), cv2.cvtColor(f, cv2.COLOR_RGB2BGR))
    return d


@pytest.fixture(scope="module")
def video(tmp_path_factory, frames):
    import imageio_ffmpeg
    path = tmp_path_factory.mktemp("video") / "take.mp4"
    w = imageio_ffmpeg.write_frames(str(path), (256, 256), fps=25, codec="libx264", quality=8)
    w.send(None)
    for f in frames:
        w.send(np.ascontiguousarray(f))
    w.close()
    write_sidecar(path.parent / "take.mp4.json", (28, 78, 200, 100), fps=25, size=(256, 256))
    return path


def _run(capsys, *argv):
    code = main([str(a) for a in argv])
    out, err = capsys.readouterr()
    return code, out, err


def _assert_merge(df, fps):
    assert len(df) == N
    assert list(df["count"]) == [2] * MERGE + [1] * (N - MERGE)
    assert int(df["d_width"].abs().idxmax()) == MERGE
    np.testing.assert_allclose(df["time"], np.arange(N) / fps, atol=1e-6)


def test_analyze_frame_folder_with_plot_and_overlay(tmp_path, capsys, frame_dir):
    csv, png, ov = tmp_path / "p.csv", tmp_path / "p.png", tmp_path / "ov"
    code, out, err = _run(capsys, "analyze", frame_dir, "--box", BOX, "-o", csv, "--plot", png, "--overlay", ov)
    assert code == 0, err
    _assert_merge(pd.read_csv(csv), 30)
    assert f"at frame {MERGE}" in out
    assert png.stat().st_size > 10_000
    overlays = sorted(ov.iterdir())
    assert len(overlays) == N
    img = cv2.imread(str(overlays[0]))
    green = (img[..., 1] > 200) & (img[..., 0] < 80) & (img[..., 2] < 80)     # the largest outline
    assert green.sum() > 50


def test_analyze_mp4_with_sidecar(tmp_path, capsys, video):
    csv = tmp_path / "m.csv"
    code, out, err = _run(capsys, "analyze", video, "-o", csv, "--hull")
    assert code == 0, err
    _assert_merge(pd.read_csv(csv), 25)                  # fps from the video, box from take.mp4.json
    assert "25 fps" in out


def test_output_is_deterministic_and_needs_force(tmp_path, capsys, frame_dir):
    a, b = tmp_path / "a.csv", tmp_path / "b.csv"
    assert _run(capsys, "analyze", frame_dir, "--box", BOX, "-o", a)[0] == 0
    assert _run(capsys, "analyze", frame_dir, "--box", BOX, "-o", b, "--fps", 30)[0] == 0
    assert a.read_bytes() == b.read_bytes()
    code, _, err = _run(capsys, "analyze", frame_dir, "--box", BOX, "-o", a)
    assert code == 2 and "exists" in err
    assert _run(capsys, "analyze", frame_dir, "--box", BOX, "-o", a, "--force", "--method", "seed", "--teeth",
                "--threshold", "70")[0] == 0


def test_compare_prints_l2_and_plots(tmp_path, capsys, frame_dir, video):
    a, b, png = tmp_path / "a.csv", tmp_path / "b.csv", tmp_path / "c.png"
    _run(capsys, "analyze", frame_dir, "--box", BOX, "-o", a)
    _run(capsys, "analyze", video, "-o", b)
    code, out, err = _run(capsys, "compare", a, a, b, "--plot", png)
    assert code == 0, err
    lines = out.splitlines()
    assert lines[0].split() == ["L2_area", "L2_width", "L2_height", "r_area", "r_width", "r_height",
                                "lag_frames", "r_height_at_lag"]
    same = [float(v) for v in lines[1].split()[-8:]]
    other = [float(v) for v in lines[2].split()[-8:]]
    assert same[:3] == [0.0, 0.0, 0.0] and same[3:6] == [1.0, 1.0, 1.0] and same[6] == 0
    assert other[1] > 0.3                  # merges at 13/30 s vs 13/25 s: width differs
    assert png.stat().st_size > 10_000


def _error(capsys, *argv):
    code, out, err = _run(capsys, *argv)
    assert code == 2
    assert err.startswith("visemeface: error: ") and err.count("\n") == 1
    return err


@pytest.mark.parametrize("method,option", [("mesh", ["--threshold", "70"]), ("mesh", ["--teeth"]),
                                           ("lips", ["--teeth"]), ("seed", ["--min-height", "0.1"])])
def test_an_option_the_method_does_not_read_is_refused(tmp_path, capsys, frame_dir, method, option):
    """Given to a method that ignores it, an option would leave the CSV as it was while the user believes it
    changed the measure: it is refused in one line, naming the methods that read it, and nothing is written."""
    out = tmp_path / "x.csv"
    err = _error(capsys, "analyze", frame_dir, "--box", BOX, "-o", out, "--method", method, *option)
    assert option[0] in err and "applies to --method" in err and method in err
    assert not out.exists()


def test_bad_inputs_exit_2_with_one_line(tmp_path, capsys, frame_dir):
    out = tmp_path / "x.csv"
    bad = tmp_path / "bad.mp4"
    bad.write_bytes(np.random.default_rng(0).integers(0, 256, 4000, dtype=np.uint8).tobytes())
    assert "cannot read video" in _error(capsys, "analyze", bad, "--box", BOX, "-o", out)
    empty = tmp_path / "empty"
    empty.mkdir()
    assert "no .png/.jpg frames" in _error(capsys, "analyze", empty, "--box", BOX, "-o", out)
    assert "outside the 256x256 frame" in _error(capsys, "analyze", frame_dir, "--box", "100,100,200,100", "-o", out)
    assert "4 numbers" in _error(capsys, "analyze", frame_dir, "--box", "1,2,three,4", "-o", out)
    blue = tmp_path / "blue"               # no face in it: no automatic mouth box either
    blue.mkdir()
    for i in range(3):
        cv2.imwrite(str(blue / f"b{i}.png"), np.full((64, 80, 3), (200, 120, 40), np.uint8))
    err = _error(capsys, "analyze", blue, "-o", out)
    assert "no face found" in err and "--box" in err
    assert "--method" in _error(capsys, "analyze", frame_dir, "--box", BOX, "-o", out, "--method", "dark")
    assert "--min-height" in _error(capsys, "analyze", frame_dir, "--box", BOX, "-o", out, "--min-height", "2")
    assert "no such file" in _error(capsys, "analyze", tmp_path / "none.mp4", "--box", BOX, "-o", out)
    assert "--threshold" in _error(capsys, "analyze", frame_dir, "--box", BOX, "-o", out, "--threshold", "dark")
    assert "--pad" in _error(capsys, "analyze", frame_dir, "--box", BOX, "-o", out, "--pad", "a,b")
    assert "pad must be" in _error(capsys, "analyze", frame_dir, "--box", BOX, "-o", out, "--pad", "0,1")
    side = tmp_path / "side.json"
    side.write_text('{"mouth_box": [1, 2, 3]}')
    assert "side.json" in _error(capsys, "analyze", frame_dir, "--box-json", side, "-o", out)
    side.write_text('{"mouth_box": [28, 78, 200, 100], "size": [512, 512]}')
    assert "512x512" in _error(capsys, "analyze", frame_dir, "--box-json", side, "-o", out)
    assert not out.exists()
    assert "not a profile CSV" in _error(capsys, "compare", bad, bad)


def test_mismatched_frame_size_in_folder(tmp_path, capsys, frames):
    d = tmp_path / "mixed"
    d.mkdir()
    cv2.imwrite(str(d / "a1.png"), frames[0])
    cv2.imwrite(str(d / "a2.png"), frames[0][:128])
    assert "a2.png" in _error(capsys, "analyze", d, "--box", BOX, "-o", tmp_path / "o.csv")
    assert not (tmp_path / "o.csv").exists()


def test_sidecar_round_trip_and_errors(tmp_path):
    p = tmp_path / "v.json"
    write_sidecar(p, (10, 20, 300, 120), fps=50, size=(640, 480))
    s = read_sidecar(p)
    assert (s.mouth_box.x, s.mouth_box.y, s.mouth_box.w, s.mouth_box.h) == (10, 20, 300, 120)
    assert s.fps == 50 and s.size == (640, 480)
    p.write_text('{"mouth_box": [10, 20, 300, 120],\n "fps": }')
    with pytest.raises(InputError, match=r"v.json:2: not valid JSON"):
        read_sidecar(p)


def test_folder_order_is_natural(frame_dir):
    src = open_frames(frame_dir, fps=12)
    assert [f.name for f in src.files][:3] == ["f0.png", "f1.png", "f2.png"]
    assert src.files[10].name == "f10.png" and src.fps == 12 and src.size == (256, 256)
    assert sorted(["f10", "f9", "F1"], key=natural_key) == ["F1", "f9", "f10"]


@pytest.mark.realdata
@pytest.mark.slow
def test_analyze_real_clip_with_automatic_box(tmp_path, capsys, realdata):
    """A real GRID clip without any box: the mouth is found, open frames are found open."""
    csv, ov = tmp_path / "real.csv", tmp_path / "ov"
    code, out, err = _run(capsys, "analyze", realdata / "swwp2s.mpg", "-o", csv, "--overlay", ov)
    assert code == 0, err
    assert "automatic mouth box" in out and "75 frames at 25 fps" in out
    df = pd.read_csv(csv)
    assert len(df) == 75 and len(list(ov.iterdir())) == 75
    # "set white with p two soon", speech 0.49-2.21 s: open in most speech frames, closed after
    speech = df[(df["time"] >= 0.5) & (df["time"] < 2.2)]
    assert (speech["count"] > 0).mean() > 0.6
    assert (df[df["time"] >= 2.4]["count"] == 0).all()
    seed = tmp_path / "seed.csv"
    assert _run(capsys, "analyze", realdata / "swwp2s.mpg", "-o", seed, "--method", "seed")[0] == 0
    assert (pd.read_csv(seed)["count"] > 0).sum() < (df["count"] > 0).sum()


def test_overlay_of_a_small_mouth_is_enlarged_with_its_label_inside(tmp_path, capsys, frames):
    """A 50 px mouth (GRID's are 40 px): the overlay is enlarged to >= OVERLAY_MIN_BOX px across the box
    and the white label above the box ends inside the image (it used to run off a 65 px crop)."""
    from visemeface.commands.analyze import OVERLAY_MIN_BOX

    d = tmp_path / "small"
    d.mkdir()
    for i, f in enumerate(frames[:3]):
        cv2.imwrite(str(d / f"f{i}.png"), cv2.cvtColor(cv2.resize(f, (64, 64), interpolation=cv2.INTER_AREA),
                                                       cv2.COLOR_RGB2BGR))
    ov = tmp_path / "ov"
    code, out, err = _run(capsys, "analyze", d, "--box", "7,19,50,25", "-o", tmp_path / "s.csv", "--overlay", ov)
    assert code == 0, err
    assert "warning" not in err
    img = cv2.imread(str(sorted(ov.iterdir())[0]))
    assert img.shape[1] >= OVERLAY_MIN_BOX
    white_cols = np.flatnonzero((img[:12] == 255).all(axis=2).any(axis=0))
    assert white_cols.size > 20 and white_cols.max() < img.shape[1] - 1
    green = (img[..., 1] > 200) & (img[..., 0] < 80) & (img[..., 2] < 80)     # the outline, drawn enlarged
    assert green.sum() > 50


def test_a_tiny_mouth_is_measured_with_a_warning(tmp_path, capsys, frames):
    """A 12 px mouth: openings are likely missed (a GRID clip at 12 px finds none); say so on stderr."""
    d = tmp_path / "tiny"
    d.mkdir()
    for i, f in enumerate(frames[:2]):
        cv2.imwrite(str(d / f"f{i}.png"), cv2.cvtColor(cv2.resize(f, (16, 16), interpolation=cv2.INTER_AREA),
                                                       cv2.COLOR_RGB2BGR))
    code, out, err = _run(capsys, "analyze", d, "--box", "2,5,12,6", "-o", tmp_path / "t.csv")
    assert code == 0 and (tmp_path / "t.csv").exists()
    assert err.count("\n") == 1 and "warning: the mouth is only 12 px wide" in err


def test_frames_without_a_face_are_named_in_a_warning(tmp_path, capsys, monkeypatch):
    """An automatic box held over frames where no face was found: the CSV is written, one stderr line
    says which frames (their openings read 0, not a closed mouth)."""
    from visemeface.analysis import mouthbox
    from visemeface.analysis.openings import MouthBox

    d = tmp_path / "f"
    d.mkdir()
    for i in range(8):                                           # in colour: grey frames are refused
        cv2.imwrite(str(d / f"f{i}.png"), np.full((64, 64, 3), (110, 128, 150), np.uint8))
    monkeypatch.setattr(mouthbox, "track_mouth", lambda frames, source="": [
        MouthBox(10, 20, 40, 20, found=i not in (2, 3, 4, 7)) for i, _ in enumerate(frames)])
    code, out, err = _run(capsys, "analyze", d, "-o", tmp_path / "p.csv")
    assert code == 0 and len(pd.read_csv(tmp_path / "p.csv")) == 8
    assert err.count("\n") == 1 and "no face in 4 of 8 frames (frames 2-4, 7)" in err


def test_an_audio_only_file_says_it_has_no_video_stream(tmp_path, capsys):
    """An .mp4 with only a sound track: a plain one-line reason, not ffmpeg's last log line."""
    import subprocess

    import imageio_ffmpeg

    audio = tmp_path / "sound only.mp4"
    subprocess.run([imageio_ffmpeg.get_ffmpeg_exe(), "-loglevel", "error", "-f", "lavfi", "-i", "sine=duration=0.2",
                    str(audio)], check=True)
    code, out, err = _run(capsys, "analyze", audio, "-o", tmp_path / "a.csv")
    assert code == 2 and not (tmp_path / "a.csv").exists()
    assert err.count("\n") == 1 and "no video stream found" in err
