"""The `pose` and `muscles` commands: rendering, overlays, errors and exit codes."""

import cv2
import numpy as np
import pytest

from visemeface.cli import main


def read(path):
    img = cv2.imread(str(path))
    assert img is not None
    return img[:, :, ::-1]


def test_pose_renders_and_differs_from_rest(tmp_path, capsys):
    rest, posed = tmp_path / "rest.png", tmp_path / "open.png"
    assert main(["pose", "-o", str(rest), "--size", "128", "--view", "mouth"]) == 0
    assert main(["pose", "--set", "jaw=0.8", "--set", "orbicularis_oris=0.3", "-o", str(posed),
                 "--size", "128", "--view", "mouth"]) == 0
    out = capsys.readouterr().out
    assert "jaw=0.8" in out and "opening_height=" in out
    a, b = read(rest).astype(int), read(posed).astype(int)
    assert a.shape == (128, 128, 3)
    # The open mouth shows the dark cavity: many more dark pixels than at rest.
    dark = lambda im: int((im.sum(axis=2) < 120).sum())  # noqa: E731
    assert dark(b) > dark(a) + 200


def test_show_muscles_draws_over_render(tmp_path):
    plain, drawn = tmp_path / "plain.png", tmp_path / "drawn.png"
    assert main(["pose", "--set", "risorius_left=1", "-o", str(plain), "--size", "128"]) == 0
    assert main(["pose", "--set", "risorius_left=1", "--show-muscles", "-o", str(drawn), "--size", "128"]) == 0
    diff = np.abs(read(plain).astype(int) - read(drawn).astype(int)).sum(axis=2)
    assert (diff > 60).sum() > 300


def test_existing_output_needs_force(tmp_path, capsys):
    out = tmp_path / "p.png"
    out.write_bytes(b"x")
    assert main(["pose", "-o", str(out), "--size", "64"]) == 2
    assert "--force" in capsys.readouterr().err
    assert out.read_bytes() == b"x"
    assert main(["pose", "-o", str(out), "--size", "64", "--force"]) == 0
    assert read(out).shape == (64, 64, 3)


@pytest.mark.parametrize("argv,message", [
    (["--set", "zygomatic_major_lft=0.5"], "did you mean: zygomatic_major_left"),
    (["--set", "jaw"], "NAME=VALUE"),
    (["--set", "jaw=wide"], "not a number"),
    (["--set", "jaw=nan"], "'jaw'"),
    (["--size", "100"], "multiples of 16"),
])
def test_bad_input_exits_2_with_one_line(tmp_path, capsys, argv, message):
    out = tmp_path / "bad.png"
    assert main(["pose", *argv, "-o", str(out)]) == 2
    err = capsys.readouterr().err.strip()
    assert message in err and len(err.splitlines()) == 1
    assert not out.exists()


def test_clamping_warns(tmp_path, capsys):
    assert main(["pose", "--set", "jaw=2", "-o", str(tmp_path / "c.png"), "--size", "64"]) == 0
    assert "clamped" in capsys.readouterr().err


def test_muscles_lists_all_functions(capsys):
    assert main(["muscles", "--csv"]) == 0
    lines = capsys.readouterr().out.strip().splitlines()
    assert lines[0].startswith("name,kind,side,min,max,lip")
    assert len(lines) == 1 + 44          # 25 muscles, 5 tongue, 3 lip-shaping, 6 lid, 4 gaze functions, the jaw
    assert any(line.startswith("tongue_tip_raise,local,centre,0.0,1.0,both") for line in lines)
    assert any(line.startswith("orbicularis_oris,sphincter,centre,0.0,1.0,both") for line in lines)
    assert main(["muscles"]) == 0
    assert "depressor_labii_inferioris_left" in capsys.readouterr().out


def test_posture_and_emotion_from_library(tmp_path, capsys):
    pytest.importorskip("visemeface.postures.library")
    out = tmp_path / "aa.png"
    assert main(["pose", "aa", "--emotion", "happiness=0.5", "-o", str(out), "--size", "64"]) == 0
    text = capsys.readouterr().out
    assert "jaw=" in text and "zygomatic_major_left=" in text
    assert main(["pose", "aaa", "-o", str(tmp_path / "x.png"), "--size", "64"]) == 2


def test_pose_a_loaded_mesh_with_landmarks(tmp_path, capsys):
    from visemeface.face.procedural import default_face
    mesh, _ = default_face(resolution=1500).save(tmp_path / "mine.obj")
    out = tmp_path / "mine.png"
    assert main(["pose", "--face", str(mesh), "--set", "jaw=0.5", "-o", str(out), "--size", "64"]) == 0
    assert "opening_height=" in capsys.readouterr().out and out.exists()
    assert main(["pose", "--face", str(tmp_path / "none.obj"), "-o", str(tmp_path / "n.png")]) == 2


@pytest.mark.parametrize("command", [["pose", "aa"], ["sheet", "--emotions"], ["face"]])
def test_still_pictures_take_msaa_as_the_animating_commands_do(tmp_path, capsys, command):
    """`pose`, `sheet` and `face` render at --msaa N like `speak` (0: hard edges, as a frame of a fast run),
    and refuse a count the renderer has not in one line, writing nothing."""
    size = ["--size", "64"]
    smooth, hard = tmp_path / "smooth.png", tmp_path / "hard.png"
    assert main([*command, *size, "-q", "-o", str(smooth)]) == 0
    assert main([*command, *size, "-q", "--msaa", "0", "-o", str(hard)]) == 0
    a, b = read(smooth).astype(int), read(hard).astype(int)
    assert a.shape == b.shape and (np.abs(a - b).sum(axis=2) > 30).sum() > 20     # the edges differ
    assert main([*command, *size, "-q", "--msaa", "3", "-o", str(tmp_path / "bad.png")]) == 2
    assert "--msaa must be one of 0, 2, 4, 8, 16, got 3" in capsys.readouterr().err
    assert not (tmp_path / "bad.png").exists()
