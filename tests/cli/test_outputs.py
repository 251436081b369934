import pytest

from visemeface.errors import InputError
from visemeface.outputs import atomic_dir, atomic_output


def test_atomic_output_refuses_existing(tmp_path):
    target = tmp_path / "a.txt"
    target.write_text("user data")
    with pytest.raises(InputError, match="--force"):
        with atomic_output(target):
            pass
    assert target.read_text() == "user data"


def test_atomic_output_leaves_nothing_on_error(tmp_path):
    target = tmp_path / "a.txt"
    with pytest.raises(RuntimeError):
        with atomic_output(target) as tmp:
            tmp.write_text("half")
            raise RuntimeError("boom")
    assert list(tmp_path.iterdir()) == []


def test_atomic_output_force_replaces(tmp_path):
    target = tmp_path / "a.txt"
    target.write_text("old")
    with atomic_output(target, force=True) as tmp:
        tmp.write_text("new")
    assert target.read_text() == "new"
    assert [p.name for p in tmp_path.iterdir()] == ["a.txt"]


def test_atomic_dir(tmp_path):
    target = tmp_path / "frames"
    with atomic_dir(target) as tmp:
        (tmp / "0001.png").write_bytes(b"x")
    assert (target / "0001.png").exists()
    with pytest.raises(InputError):
        with atomic_dir(target):
            pass


def test_atomic_output_mode_follows_umask(tmp_path):
    import os

    old = os.umask(0o022)
    try:
        with atomic_output(tmp_path / "a.png") as tmp:
            tmp.write_bytes(b"x")
    finally:
        os.umask(old)
    assert (tmp_path / "a.png").stat().st_mode & 0o777 == 0o644


def test_choose_normalises_and_suggests():
    from visemeface.errors import choose

    assert choose(" TextGrid ", ["textgrid", "lab"], "format") == "textgrid"
    assert choose("tg", ["textgrid"], "format", aliases={"tg": "textgrid"}) == "textgrid"
    with pytest.raises(InputError, match=r"unknown format 'textgrd'; choose one of textgrid, lab \(did you mean: textgrid"):
        choose("textgrd", ["textgrid", "lab"], "format")


def test_output_under_a_file_is_a_one_line_error(tmp_path):
    (tmp_path / "file.bin").write_bytes(b"x")
    with pytest.raises(InputError, match="not a folder"):
        with atomic_output(tmp_path / "file.bin" / "a.png"):
            pass
    with pytest.raises(InputError, match="not a folder"):
        with atomic_dir(tmp_path / "file.bin" / "frames"):
            pass


@pytest.mark.parametrize("argv", [
    ["sheet", "-o", "s.txt"],
    ["pose", "ah", "-o", "p.jpg"],
    ["analyze", "in.mp4", "--box", "1,1,8,8", "-o", "a.txt"],
])
def test_wrong_output_suffix_is_refused_before_work(tmp_path, monkeypatch, capsys, argv):
    from visemeface.cli import main

    monkeypatch.chdir(tmp_path)
    (tmp_path / "in.mp4").write_bytes(b"not a video")
    assert main(argv) == 2
    assert "must end in" in capsys.readouterr().err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["in.mp4"]
