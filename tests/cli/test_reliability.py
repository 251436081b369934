"""Defects a hostile new user found (issue 20), each with the test that failed before its fix."""

import json

import numpy as np
import pytest

from visemeface.cli import main


@pytest.fixture
def here(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    return tmp_path


def _one_line_error(capsys):
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and err.startswith("visemeface: error: "), err
    return err


def test_usage_errors_are_one_line_with_the_prefix(here, capsys):
    assert main(["pose", "aa"]) == 2                                   # -o missing: 6 lines before
    err = _one_line_error(capsys)
    assert "pose: the following arguments are required: -o/--output" in err and "--help" in err
    assert main(["speak"]) == 2
    _one_line_error(capsys)
    assert main(["nonsense"]) == 2
    _one_line_error(capsys)


def test_a_negative_value_needs_no_equals_sign(here, capsys):
    from visemeface.export.images import write_png

    (here / "fr").mkdir()
    write_png(here / "fr" / "f0.png", np.zeros((16, 16, 3), np.uint8))
    assert main(["analyze", "fr", "--box", "-10,-10,50,20", "-o", "a.csv"]) == 2
    err = _one_line_error(capsys)
    assert "expected one argument" not in err                       # the box itself is refused, not parsed away


@pytest.mark.parametrize("spec", ["", "happiness=", " , "])
def test_empty_emotion_weights_are_refused(here, capsys, spec):
    (here / "t.txt").write_text("0 0.2 aa\n")
    assert main(["speak", "t.txt", "--emotion", spec, "-q"]) == 2
    assert "weight" in _one_line_error(capsys)
    assert sorted(p.name for p in here.iterdir()) == ["t.txt"]


def test_a_latin1_comment_in_an_obj_loads_and_garbage_is_not_an_obj(here, capsys):
    assert main(["face", "--export", "f.obj"]) == 0
    capsys.readouterr()
    (here / "g.obj").write_bytes(b"# caf\xe9 na\xefve\n" + (here / "f.obj").read_bytes())
    (here / "g.landmarks.json").write_bytes((here / "f.landmarks.json").read_bytes())
    assert main(["face", "--mesh", "g.obj", "-o", "g.png"]) == 0
    capsys.readouterr()
    for name, content in [("bin.obj", bytes(range(256)) * 4), ("txt.obj", b"hello\nworld\n")]:
        (here / name).write_bytes(content)
        (here / name.replace(".obj", ".landmarks.json")).write_bytes((here / "f.landmarks.json").read_bytes())
        assert main(["face", "--mesh", name, "-o", "x.png"]) == 2
        assert "not a valid OBJ" in _one_line_error(capsys)


def test_a_landmark_missing_from_the_face_is_blamed_on_its_landmarks_file(here, capsys):
    assert main(["face", "--export", "f.obj"]) == 0
    capsys.readouterr()
    side = json.loads((here / "f.landmarks.json").read_text())
    del side["landmarks"]["mouth_corner_left"]
    (here / "f.landmarks.json").write_text(json.dumps(side))
    assert main(["pose", "aa", "--face", "f.obj", "-o", "p.png"]) == 2
    err = _one_line_error(capsys)
    assert "f.landmarks.json: no landmark 'mouth_corner_left'" in err and "default.toml" not in err


def test_big_and_nan_numbers_are_written_plainly(here, capsys):
    (here / "t.txt").write_text("0 0.2 aa\n")
    for value in ("nan", "1e308"):
        assert main(["speak", "t.txt", "--fps", value]) == 2
        err = _one_line_error(capsys)
        assert "np.float64" not in err and not any(len(w) > 30 for w in err.split())


def test_a_fake_mp3_is_refused_in_plain_words(here, capsys):
    """libsndfile's wording ("possibly a pipe?") is not a message for the user."""
    from visemeface.resources import transcripts_path

    (here / "fake.mp3").write_bytes(b"xx")
    assert main(["speak", str(transcripts_path("bob_moves_five_boats.txt")), "--audio", "fake.mp3", "-o", "f.mp4"]) == 2
    err = capsys.readouterr().err.strip()
    assert err == "visemeface: error: fake.mp3: unreadable audio (not a sound file, and no audio stream in it)"
    assert not (here / "f.mp4").exists()
