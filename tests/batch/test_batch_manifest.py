"""Batch manifests: good rows become jobs, each bad row one line with its reason; the GRID grammar."""

import csv

import pytest

from visemeface.batch import BadRow, Job, defaults, read_manifest, write_manifest
from visemeface.batch.grid import grid_rows, n_sentences, sentence
from visemeface.errors import InputError

TINY = "0.00 0.05 _\n0.05 0.25 aa\n0.25 0.30 _\n"


def _manifest(tmp_path, text):
    (tmp_path / "t.txt").write_text(TINY)
    path = tmp_path / "jobs.csv"
    path.write_text(text)
    return path


def test_good_rows_take_the_defaults_and_paths_are_relative_to_the_manifest(tmp_path):
    path = _manifest(tmp_path, "clip,transcript,text,emotion,fps,outputs\n"
                     "a,t.txt,,happiness=0.6; anger=0.2,25,video gltf\n"
                     "b,,one five,,,\n")
    a, b = read_manifest(path, {"size": 64, "outputs": "track"})
    assert a == Job(clip="a", transcript=str((tmp_path / "t.txt").resolve()), emotion=(("anger", 0.2),
                    ("happiness", 0.6)), fps=25.0, size=64, outputs=("video", "gltf"))
    assert b.text == "one five" and b.transcript is None and b.outputs == ("track",) and b.fps == 30.0


def test_each_bad_row_is_one_line_naming_the_line_and_the_reason(tmp_path):
    path = _manifest(tmp_path, "clip,transcript,text,emotion,outputs,size\n"
                     "ok,t.txt,,,,\n"
                     "missing,nope.txt,,,,\n"
                     "emo,t.txt,,hapiness=0.3,,\n"
                     "nan,t.txt,,anger=nan,,\n"
                     "ok,t.txt,,,,\n"
                     ".hidden,t.txt,,,,\n"
                     "out,t.txt,,,mp5,\n"
                     "size,t.txt,,,,100\n"
                     "both,t.txt,hello,,,\n"
                     "batch_report.csv,t.txt,,,,\n"
                     "measured,t.txt,,,measures,\n")
    rows = read_manifest(path)
    assert isinstance(rows[0], Job)
    bad = {r.clip: r.error for r in rows[1:]}
    assert all(isinstance(r, BadRow) for r in rows[1:])
    assert all("\n" not in e and e.startswith("jobs.csv:") for e in bad.values())
    assert "jobs.csv:3:" in bad["missing"] and "transcript not found" in bad["missing"]
    assert "unknown emotion 'hapiness'" in bad["emo"] and "did you mean: happiness" in bad["emo"]
    assert "finite" in bad["nan"]
    assert "repeats line 2" in bad["ok"]
    assert "bad clip id" in bad[".hidden"]
    assert "unknown output 'mp5'" in bad["out"]
    assert "size must be a positive multiple of 16" in bad["size"]
    assert "one of them" in bad["both"]
    assert "name of the batch's report" in bad["batch_report.csv"]
    assert "measures writes a simulation's figures: it needs physics sticky" in bad["measured"]


@pytest.mark.parametrize("text,message", [
    ("name,text\na,hi\n", "'clip' column"),
    ("clip,txt\na,hi\n", "unknown column 'txt' (did you mean: text"),
    ("clip,emotion\na,anger\n", "'transcript' or 'text' column"),
    ("clip,text\n", "no rows"),
    ("clip,text\na,hi\nb,set red,EXTRA\n", "3 cells for the header's 2 columns (extra: 'EXTRA'; a value with a comma"),
])
def test_an_unusable_manifest_is_refused_whole(tmp_path, text, message):
    with pytest.raises(InputError, match=message.replace("(", r"\(")):
        read_manifest(_manifest(tmp_path, text))


def test_empty_trailing_cells_are_not_extra(tmp_path):
    jobs = read_manifest(_manifest(tmp_path, "clip,text\na,hi,,\n"))
    assert [(j.clip, j.text) for j in jobs] == [("a", "hi")]


def test_defaults_refuse_unknown_settings():
    with pytest.raises(InputError, match="unknown setting 'colour'"):
        defaults(colour="red")


def test_write_manifest_round_trips_and_never_overwrites(tmp_path):
    rows = [{"clip": "x1", "text": "bin blue", "emotion": "anger=0.5"}, {"clip": "x2", "text": "lay red"}]
    path = write_manifest(tmp_path / "m.csv", rows)
    with open(path, newline="") as fh:
        assert next(csv.reader(fh)) == ["clip", "text", "emotion"]
    jobs = read_manifest(path)
    assert [j.clip for j in jobs] == ["x1", "x2"] and jobs[0].emotion == (("anger", 0.5),)
    with pytest.raises(InputError, match="exists"):
        write_manifest(path, rows)


def test_grid_grammar_names_sentences_as_the_corpus_names_its_files():
    assert n_sentences() == 4 * 4 * 4 * 25 * 10 * 4 == 64000
    texts = dict(sentence(i) for i in range(n_sentences()))
    assert len(texts) == 64000                        # every id unique
    # the three clips of ../shared/realdata, whose file names spell their sentences
    assert texts["swwp2s"] == "set white with p two soon"
    assert texts["bbaf2n"] == "bin blue at f two now"
    assert texts["lbax4n"] == "lay blue at x four now"
    with pytest.raises(InputError):
        sentence(64000)


def test_grid_sample_is_deterministic_distinct_and_in_grammar_order():
    a, b = grid_rows(50, seed=3), grid_rows(50, seed=3)
    assert a == b and len({r["clip"] for r in a}) == 50
    assert grid_rows(50, seed=4) != a
    order = {sentence(i)[0]: i for i in range(n_sentences())}
    assert [order[r["clip"]] for r in a] == sorted(order[r["clip"]] for r in a)
    assert grid_rows(2, outputs="gltf")[0]["outputs"] == "gltf"
    with pytest.raises(InputError):
        grid_rows(0)


def test_a_default_rate_times_the_text_rows_and_leaves_the_recordings_alone(tmp_path):
    import shutil

    from visemeface.resources import transcripts_path

    shutil.copy(transcripts_path("set_white_with_p_two_soon.wav"), tmp_path / "a.wav")
    path = _manifest(tmp_path, "clip,text,audio,rate\n"
                     "said,set white with p two soon,a.wav,\n"
                     "typed,one five,,\n"
                     "both,one five,a.wav,200\n")
    said, typed, both = read_manifest(path, {"rate": 250})
    assert said.rate is None and said.audio is not None and typed.rate == 250.0
    assert isinstance(both, BadRow) and "rate and audio both time the text" in both.error


def test_force_remakes_a_clip_folder_only_while_it_holds_nothing_of_the_users(tmp_path):
    from visemeface.batch.clip import CLIP_RECORD, _our_clip

    clip = tmp_path / "c1"
    (clip / "frames").mkdir(parents=True)
    for name in (CLIP_RECORD, "video.mp4", "video.mp4.json", "track.csv"):
        (clip / name).write_text("x")
    assert _our_clip(clip)
    (clip / "frames_backup.txt").write_text("mine")
    assert not _our_clip(clip)
    (clip / "frames_backup.txt").unlink()
    (clip / CLIP_RECORD).unlink()
    assert not _our_clip(clip)                      # no record: not a batch's clip
