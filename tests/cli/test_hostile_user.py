"""Regressions from a hostile new user's second round (issue 20): one line on stderr, exit 2."""

import subprocess
import sys

import numpy as np
import pytest

from visemeface.cli import main


def _visemeface(cwd, *argv):
    proc = subprocess.run([sys.executable, "-m", "visemeface", *argv], cwd=cwd, capture_output=True, text=True,
                          timeout=120)
    return proc.returncode, proc.stderr


@pytest.mark.parametrize("command", [["lipsync", "fake.mp3", "-o", "f.lab"],
                                     ["speak", "t.txt", "--audio", "fake.mp3", "-o", "f.mp4"]])
def test_a_fake_mp3_is_one_line_without_decoder_noise(tmp_path, command):
    """libmpg123 printed "[src/libmpg123/parse.c:do_readahead():1083] warning: Cannot read next header,
    a one-frame stream? Duh..." on the C library's stderr before the error line."""
    (tmp_path / "fake.mp3").write_bytes(np.random.default_rng(0).integers(0, 256, 5000, np.uint8).tobytes())
    (tmp_path / "t.txt").write_text("0.00 0.05 _\n0.05 0.25 aa\n0.25 0.30 _\n")
    code, err = _visemeface(tmp_path, *command)
    assert code == 2 and err.count("\n") == 1 and err.startswith("visemeface: error: fake.mp3: "), err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["fake.mp3", "t.txt"]


TINY = "0.00 0.05 _\n0.05 0.25 aa\n0.25 0.30 _\n"


@pytest.mark.parametrize("argv,message", [
    (["--track", "t.csv", "--gltf-shapes", "arkit"], "--gltf-shapes is an option of --gltf, which is not given"),
    (["--track", "t.csv", "--dat-fps", "12"], "--dat-fps is an option of --rhubarb, which is not given"),
    (["--track", "t.csv", "--dat-preston-blair"], "--dat-preston-blair is an option of --rhubarb"),
    (["--rhubarb", "r.tsv", "--dat-fps", "12"], "r.tsv: --dat-fps is for a .dat file; this one is .tsv"),
    (["--rhubarb", "r.json", "--dat-preston-blair"], "--dat-preston-blair is for a .dat file"),
])
def test_an_option_of_an_output_not_written_is_refused_not_ignored(tmp_path, monkeypatch, capsys, argv, message):
    """`--gltf-shapes arkit` without --gltf, or --dat-fps with a .tsv, ran and silently ignored them."""
    from visemeface.cli import main

    monkeypatch.chdir(tmp_path)
    (tmp_path / "u.txt").write_text(TINY)
    assert main(["speak", "u.txt", "--no-video", *argv]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and message in err, err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["u.txt"]


def test_the_sub_options_still_work_with_their_output(tmp_path, monkeypatch):
    from visemeface.cli import main

    monkeypatch.chdir(tmp_path)
    (tmp_path / "u.txt").write_text(TINY)
    assert main(["speak", "u.txt", "--no-video", "-q", "--rhubarb", "r.dat", "--dat-fps", "12",
                 "--dat-preston-blair", "--gltf", "g.glb", "--gltf-shapes", "vrm"]) == 0
    assert "rest" in (tmp_path / "r.dat").read_text() and (tmp_path / "g.glb").stat().st_size > 0


def _profile(path, area):
    rows = "".join(f"{i},{0.04 * i:.2f},{int(float(a) > 0)},{a},0.5,0.1\n" for i, a in enumerate(area))
    path.write_text("frame,time,count,area,width,height\n" + rows)


def test_compare_names_a_non_finite_value_plainly(tmp_path, monkeypatch, capsys):
    """The message said "non-finite value np.float64(inf)"."""
    from visemeface.cli import main

    monkeypatch.chdir(tmp_path)
    _profile(tmp_path / "p.csv", ["0", "1e309", "0.2"])
    assert main(["compare", "p.csv", "p.csv"]) == 2
    assert capsys.readouterr().err == "visemeface: error: p.csv:3: column 'area' has a non-finite value inf\n"


def test_compare_of_flat_profiles_keeps_its_columns(tmp_path, monkeypatch, capsys):
    """A flat profile's correlation is NaN; it was printed left-aligned, run into the column before."""
    from visemeface.cli import main

    monkeypatch.chdir(tmp_path)
    _profile(tmp_path / "p.csv", ["0", "0", "0"])
    assert main(["compare", "p.csv", "p.csv"]) == 0
    head, row = capsys.readouterr().out.splitlines()
    cells = row.split()
    assert len(cells) == len(head.split()) + 3 and cells[-5:] == ["nan", "nan", "nan", "+0", "nan"], row
    assert len(row) == len(head)


def test_a_bad_tag_in_text_is_not_blamed_on_the_recordings_line_1(tmp_path, monkeypatch, capsys, vowels_wav):
    """`--text "[happiness nan] ..."` said "a.wav:1: bad emotion tag"; a --text-file names its own line."""
    import shutil

    from visemeface.cli import main

    monkeypatch.chdir(tmp_path)
    shutil.copy(vowels_wav, tmp_path / "a.wav")
    assert main(["lipsync", "a.wav", "--text", "[happiness nan] ah ee", "-o", "a.lab"]) == 2
    assert capsys.readouterr().err == ("visemeface: error: bad emotion tag '[happiness nan]'; "
                                       "write [name weight], e.g. [anger 0.8]\n")
    (tmp_path / "words.txt").write_text("ah\nee [anger 2]\n")
    assert main(["lipsync", "a.wav", "--text-file", "words.txt", "-o", "a.lab"]) == 2
    assert capsys.readouterr().err.startswith("visemeface: error: words.txt:2: emotion weight 2")
    assert not (tmp_path / "a.lab").exists()


@pytest.mark.parametrize("other", [["--arkit", "same.json"], ["--vrm", "same.json"]])
def test_save_transcript_onto_another_output_is_refused_before_work(tmp_path, monkeypatch, capsys, vowels_wav,
                                                                     other):
    """`--save-transcript same.json --arkit same.json`: a FileNotFoundError traceback after the whole run,
    and same.json held the weights, the transcript lost."""
    import shutil

    from visemeface.cli import main

    monkeypatch.chdir(tmp_path)
    shutil.copy(vowels_wav, tmp_path / "a.wav")
    assert main(["speak", "a.wav", "--text", "ah ee", "--no-video", "--save-transcript", "same.json", *other]) == 2
    assert capsys.readouterr().err == ("visemeface: error: same.json: --save-transcript and another output are "
                                       "the same path\n")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["a.wav"]


@pytest.mark.parametrize("face, message", [
    ("ictt", "--face ictt: no such mesh file, and no built-in face of that name (did you mean: ict?)"),
    ("nope.obj", "--face nope.obj: no such mesh file"),
])
def test_a_misspelt_face_is_named_with_the_built_in_ones(tmp_path, monkeypatch, capsys, face, message):
    monkeypatch.chdir(tmp_path)
    assert main(["pose", "aa", "--face", face, "-o", "x.png"]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and message in err and "built in: procedural, ict" in err, err
    assert list(tmp_path.iterdir()) == []


def test_a_built_in_face_in_capitals_is_the_built_in_one():
    from visemeface.face import chosen_face

    assert chosen_face("ICT").n_vertices == chosen_face("ict").n_vertices


def test_a_folder_given_as_the_transcript_is_named_a_folder(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "d").mkdir()
    assert main(["speak", "d", "-o", "x.mp4"]) == 2
    err = capsys.readouterr().err.strip()
    assert "d: transcript is a folder, not a file" in err and sorted(p.name for p in tmp_path.iterdir()) == ["d"]
