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


def test_force_replaces_a_folder_of_ours_but_never_a_users_files(tmp_path):
    ours = tmp_path / "frames"
    ours.mkdir()
    for name in ("frame_000000.png", "frame_000001.obj", "face.mtl", ".visemeface-frames.json",
                 ".frame_000002.png.tmp"):
        (ours / name).write_bytes(b"old")
    with atomic_dir(ours, force=True) as tmp:
        (tmp / "frame_000000.png").write_bytes(b"new")
    assert sorted(p.name for p in ours.iterdir()) == ["frame_000000.png"]
    (ours / "thesis.txt").write_text("a user's own file")
    with pytest.raises(InputError, match="holds files visemeface did not write"):
        with atomic_dir(ours, force=True):
            pass
    assert (ours / "thesis.txt").read_text() == "a user's own file"


def test_speak_force_into_the_transcripts_own_folder_deletes_nothing(tmp_path, monkeypatch, capsys):
    from visemeface.cli import main

    monkeypatch.chdir(tmp_path)
    work = tmp_path / "work"
    work.mkdir()
    (work / "b.txt").write_text("0.0 0.1 b\n0.1 0.3 aa\n")
    (work / "notes.md").write_text("mine")
    assert main(["speak", "work/b.txt", "--no-video", "--frames", "work", "--force", "-q"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "did not write" in err
    assert sorted(p.name for p in work.iterdir()) == ["b.txt", "notes.md"]


@pytest.mark.parametrize("folder", [".", ".."])
def test_the_current_folder_is_never_an_output_folder(tmp_path, monkeypatch, capsys, folder):
    from visemeface.cli import main

    here = tmp_path / "here"
    here.mkdir()
    monkeypatch.chdir(here)
    (tmp_path / "b.txt").write_text("0.0 0.1 b\n0.1 0.3 aa\n")
    assert main(["speak", str(tmp_path / "b.txt"), "--no-video", "--frames", folder, "--force", "-q"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "current folder" in err
    assert here.is_dir() and list(here.iterdir()) == []


def test_force_and_resume_leave_a_users_files_and_links_alone(tmp_path, monkeypatch, capsys):
    """A user's frame_0001.jpg, a symbolic link to a folder, an output inside a folder output, an overlay
    over its own input frames, a resumed folder holding a user's file: each refused in one line."""
    from visemeface.cli import main

    monkeypatch.chdir(tmp_path)
    (tmp_path / "b.txt").write_text("0.0 0.1 b\n0.1 0.3 aa\n")
    speak = ["speak", "b.txt", "--no-video", "--size", "64", "-q"]
    (tmp_path / "shots").mkdir()
    (tmp_path / "shots" / "frame_0001.jpg").write_bytes(b"a user's picture")
    (tmp_path / "real").mkdir()
    (tmp_path / "link").symlink_to(tmp_path / "real")
    assert main(speak + ["--frames", "fr", "-q"]) == 0
    (tmp_path / "mine").mkdir()
    cases = [(speak + ["--frames", "shots", "--force"], "did not write"),
             (speak + ["--frames", "link", "--force"], "symbolic link"),
             (["speak", "b.txt", "--size", "64", "--frames", "fr", "-o", "fr/v.mp4", "--force"], "inside the frames"),
             (speak + ["--frames", "mine", "--obj", "mine/objs", "--force"], "inside the frames"),
             (["analyze", "fr", "-o", "fr.csv", "--overlay", "fr", "--force"], "overwrite the input")]
    for argv, message in cases:
        assert main(argv) == 2, argv
        err = capsys.readouterr().err
        assert err.count("\n") == 1 and message in err, (argv, err)
    (tmp_path / "fr" / "notes.txt").write_text("mine")
    assert main(speak + ["--frames", "fr", "--resume"]) == 2
    assert "did not write" in capsys.readouterr().err
    assert (tmp_path / "fr" / "notes.txt").read_text() == "mine"
    assert (tmp_path / "shots" / "frame_0001.jpg").exists() and not list((tmp_path / "real").iterdir())


def test_only_the_timed_phones(tmp_path, monkeypatch, capsys):
    from visemeface.cli import main

    monkeypatch.chdir(tmp_path)
    assert main(["say", "bob moves", "--no-video", "--save-transcript", "t.lab", "-q"]) == 0
    assert sorted(p.name for p in tmp_path.iterdir()) == ["t.lab"]
    assert main(["say", "bob", "--no-video"]) == 2
    assert "nothing to write" in capsys.readouterr().err


def test_quiet_writes_its_output_and_prints_nothing(tmp_path, monkeypatch, capsys):
    from visemeface.cli import main
    monkeypatch.chdir(tmp_path)
    for argv, out in ((["face", "-o", "f.png", "--size", "64"], "f.png"),
                      (["pose", "aa", "-o", "p.png", "--size", "64"], "p.png"),
                      (["sheet", "--emotions", "--size", "16", "-o", "s.png"], "s.png"),
                      (["analyze", "s.png", "-o", "s.csv"], "s.csv")):
        assert main([*argv, "-q"]) == 0, capsys.readouterr().err
        assert (tmp_path / out).is_file() and capsys.readouterr().out == "", argv


@pytest.mark.parametrize("option", ["--arkit", "--livelink"])
def test_an_output_refused_as_it_opens_leaves_no_temporary(tmp_path, monkeypatch, capsys, option):
    """A rig that is not there is found when its output opens, after every output's temporary was made:
    none of them is left behind (a run writes all of its outputs or none)."""
    from visemeface.cli import main

    (tmp_path / "t.txt").write_text("bob moves\n")
    monkeypatch.chdir(tmp_path)
    status = main(["speak", "t.txt", "--no-video", "-q", "--track", "a.csv", option, "c.csv",
                   f"{option}-rig", "nothere.glb"])
    assert status == 2 and "nothere.glb" in capsys.readouterr().err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["t.txt"]
