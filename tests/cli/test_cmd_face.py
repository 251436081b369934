"""``visemeface face``: render, export, user meshes, errors (exit 2) and --force."""

import json

import cv2
import numpy as np
import pytest

from visemeface.cli import main
from visemeface.face.mesh import load_face


def test_render_png(tmp_path, capsys):
    out = tmp_path / "face.png"
    assert main(["face", "-o", str(out), "--size", "96", "--resolution", "1500"]) == 0
    img = cv2.imread(str(out))
    assert img.shape == (96, 96, 3)
    assert (img.sum(axis=2) > 150).mean() > 0.25          # a lit face fills a good part
    assert "wrote" in capsys.readouterr().out


def test_existing_output_needs_force(tmp_path, capsys):
    out = tmp_path / "face.png"
    out.write_bytes(b"keep me")
    assert main(["face", "-o", str(out), "--size", "64", "--resolution", "1000"]) == 2
    err = capsys.readouterr().err
    assert "exists" in err and "--force" in err and err.count("\n") == 1
    assert out.read_bytes() == b"keep me"
    assert main(["face", "-o", str(out), "--size", "64", "--resolution", "1000", "--force"]) == 0
    assert cv2.imread(str(out)).shape == (64, 64, 3)


def test_export_and_render_users_mesh(tmp_path):
    mesh = tmp_path / "head.obj"
    assert main(["face", "--export", str(mesh), "--resolution", "1000"]) == 0
    side = tmp_path / "head.landmarks.json"
    assert mesh.exists() and side.exists()
    face = load_face(mesh)
    assert "nose_tip" in face.landmarks and len(face.quads) > 0
    # render it back, with the landmarks given explicitly under another name
    moved = tmp_path / "marks.json"
    side.rename(moved)
    out = tmp_path / "mine.png"
    cam = tmp_path / "mine.json"
    assert main(["face", "--mesh", str(mesh), "--landmarks", str(moved), "-o", str(out),
                 "--view", "mouth", "--size", "64", "--camera-json", str(cam)]) == 0
    assert cv2.imread(str(out)).shape == (64, 64, 3)
    info = json.loads(cam.read_text())
    x, y, w, h = info["mouth_box"]
    assert info["size"] == [64, 64] and 0 <= x and x + w <= 64 and w > 20


def test_render_and_export_match_the_rest_face(tmp_path):
    a, b = tmp_path / "a.png", tmp_path / "b.png"
    assert main(["face", "-o", str(a), "--size", "64", "--resolution", "1000",
                 "--export", str(tmp_path / "m.ply")]) == 0
    assert main(["face", "--mesh", str(tmp_path / "m.ply"), "-o", str(b), "--size", "64"]) == 0
    diff = np.abs(cv2.imread(str(a)).astype(int) - cv2.imread(str(b)).astype(int))
    assert diff.max() <= 3                                  # float32 file positions and 8-bit colours


@pytest.mark.parametrize("make, args, message", [
    (None, ["--mesh", "{d}/missing.obj"], "missing.obj: mesh file not found"),
    ("garbage", ["--mesh", "{d}/bad.ply"], "bad.ply: cannot read mesh"),
    ("mesh_only", ["--mesh", "{d}/m.obj"], "m.landmarks.json: landmarks file not found"),
    ("bad_json", ["--mesh", "{d}/m.obj", "--landmarks", "{d}/l.json"], "l.json:2: not valid JSON"),
    (None, ["--size", "100"], "multiples of 16"),
    (None, ["--resolution", "5"], "--resolution must be a vertex count from 800 to 200000, got 5"),
    (None, ["--rest-gap", "5"], "--rest-gap must be from 0 to 0.01 (metres"),
    (None, ["--camera-json", "{d}/cam.txt"], "cam.txt: the camera file must be a .json file"),
    (None, ["--mesh", "{d}/m.obj", "--resolution", "2000"], "--resolution applies"),
    (None, ["--face", "ict", "--skin", "II"], "--skin colours the embedded face, not ict"),
    (None, ["--face", "ict", "--mesh", "{d}/m.obj"], "not both"),
    (None, ["--identity", "3"], "--identity needs --face ict"),
    (None, ["--face", "procedural", "--identity", "3"], "--identity draws a speaker of the ICT head"),
])
def test_errors_exit_2_with_one_line(tmp_path, capsys, make, args, message):
    d = str(tmp_path)
    if make == "garbage":
        (tmp_path / "bad.ply").write_bytes(b"ply\nformat ascii 1.0\nelement vertex 3\nend_header\n1 2\n")
        (tmp_path / "bad.landmarks.json").write_text('{"landmarks": {}}')
    if make in ("mesh_only", "bad_json"):
        assert main(["face", "--export", f"{d}/m.obj", "--resolution", "1000"]) == 0
        (tmp_path / "m.landmarks.json").unlink()
        capsys.readouterr()
    if make == "bad_json":
        (tmp_path / "l.json").write_text('{\n "landmarks": oops\n}')
    argv = ["face", "-o", f"{d}/out.png", "--size", "64"] + [a.format(d=d) for a in args]
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert message in err
    assert err.count("\n") == 1
    assert not (tmp_path / "out.png").exists()


def test_nothing_to_do(capsys):
    assert main(["face"]) == 2
    assert "nothing to do" in capsys.readouterr().err


def test_unknown_view_is_a_usage_error(capsys):
    assert main(["face", "-o", "x.png", "--view", "side"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "face: argument --view: invalid choice: 'side'" in err


def test_the_built_in_ict_head_and_its_speakers_render_as_on_every_command(tmp_path):
    a, b, c = (tmp_path / f"{n}.png" for n in "abc")
    for out, more in ((a, []), (b, ["--identity", "7"]), (c, ["--identity", "7"])):
        assert main(["face", "--face", "ict", "-o", str(out), "--size", "64", "-q", *more]) == 0
    ia, ib, ic = (cv2.imread(str(p)).astype(int) for p in (a, b, c))
    assert np.array_equal(ib, ic) and np.abs(ia - ib).max() > 30     # a speaker of its own, deterministic
    assert main(["face", "--face", "procedural", "--skin", "V", "-o", str(tmp_path / "d.png"), "--size", "64",
                 "-q"]) == 0
