"""``visemeface speak`` / ``say`` and the pipeline glue: checks before work, resume, end to end."""

import json
import warnings

import numpy as np
import pytest
import soundfile as sf

from visemeface import pipeline
from visemeface.cli import main
from visemeface.errors import InputError
from visemeface.render import export


# ----------------------------------------------------------------------------- checks before work

def test_plan_outputs_refuses_existing_and_duplicates(tmp_path):
    existing = tmp_path / "a.mp4"
    existing.write_bytes(b"user")
    with pytest.raises(InputError, match="exists"):
        pipeline.plan_outputs(pipeline.Outputs(video=existing))
    pipeline.plan_outputs(pipeline.Outputs(video=existing, force=True))
    with pytest.raises(InputError, match="same path"):
        pipeline.plan_outputs(pipeline.Outputs(video=tmp_path / "b.mp4", gltf=tmp_path / "b.mp4"))
    with pytest.raises(InputError, match="--resume needs --frames"):
        pipeline.plan_outputs(pipeline.Outputs(video=tmp_path / "b.mp4", resume=True))
    with pytest.raises(InputError, match=r"\.glb"):
        pipeline.plan_outputs(pipeline.Outputs(gltf=tmp_path / "b.gltf"))
    with pytest.raises(InputError, match="nothing to write"):
        pipeline.plan_outputs(pipeline.Outputs())
    with pytest.raises(InputError, match="folder does not exist"):
        pipeline.plan_outputs(pipeline.Outputs(pc2=tmp_path / "no" / "x.pc2"))
    assert existing.read_bytes() == b"user"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["a.mp4"]


def test_check_audio(tmp_path):
    sf.write(tmp_path / "a.wav", np.zeros(8000, np.float32), 16000)
    assert pipeline.check_audio(tmp_path / "a.wav") == pytest.approx(0.5)
    (tmp_path / "bad.wav").write_bytes(b"RIFF....not a wave at all")
    with pytest.raises(InputError, match="bad.wav: unreadable audio"):
        pipeline.check_audio(tmp_path / "bad.wav")
    with pytest.raises(InputError, match="not found"):
        pipeline.check_audio(tmp_path / "none.wav")


def test_parse_emotions_checks_names():
    assert pipeline.parse_emotions(["happiness=0.6", "anger"], ["happiness", "anger"]) == {
        "happiness": 0.6, "anger": 1.0}
    with pytest.raises(InputError, match="did you mean: happiness"):
        pipeline.parse_emotions(["hapiness=0.5"], ["happiness", "anger"])
    assert pipeline.parse_emotions(None, ["happiness"]) == {}


# ----------------------------------------------------------------------------- resumable frames

def _img(i):
    return np.full((16, 16, 3), i, np.uint8)


def test_frame_folder_interrupted_then_resumed(tmp_path):
    target = tmp_path / "frames"
    ff = pipeline.FrameFolder(target, key="k1")
    ff.check()
    with pytest.warns(UserWarning, match="2 finished frame"), pytest.raises(KeyboardInterrupt):
        with ff:
            ff.write(0, _img(0))
            ff.write(1, _img(1))
            raise KeyboardInterrupt
    partial = tmp_path / "frames.partial"
    assert sorted(p.name for p in partial.iterdir()) == [pipeline.MANIFEST, "frame_000000.png",
                                                         "frame_000001.png"]
    assert not target.exists()

    # other settings: refused before any work, nothing touched
    other = pipeline.FrameFolder(target, key="k2", resume=True)
    with pytest.raises(InputError, match="another transcript or other settings"):
        other.check()

    ff = pipeline.FrameFolder(target, key="k1", resume=True)
    ff.check()
    with ff:
        got = []
        for i in range(3):
            if ff.has(i):
                got.append(ff.read(i))
            else:
                ff.write(i, _img(i))
        ff.finish(3)
    assert (ff.kept, ff.rendered) == (2, 1)
    np.testing.assert_array_equal(got[1], _img(1))
    assert not partial.exists()
    assert sorted(p.name for p in target.glob("*.png")) == [export.frame_name(i) for i in range(3)]
    assert json.loads((target / pipeline.MANIFEST).read_text())["key"] == "k1"


def test_frame_folder_without_resume_refuses_existing_and_restarts_partial(tmp_path):
    target = tmp_path / "frames"
    target.mkdir()
    with pytest.raises(InputError, match="exists"):
        pipeline.FrameFolder(target, key="k").check()
    # a stale partial run of ours is discarded without --resume
    partial = tmp_path / "new.partial"
    partial.mkdir()
    (partial / pipeline.MANIFEST).write_text(json.dumps({"key": "old"}))
    export.write_png(partial / export.frame_name(0), _img(9))
    ff = pipeline.FrameFolder(tmp_path / "new", key="k")
    ff.check()
    with ff:
        assert not ff.has(0)
        ff.write(1, _img(1))
        ff.finish(2)
    assert sorted(p.name for p in (tmp_path / "new").glob("*.png")) == ["frame_000001.png"]
    # a folder we did not make is never deleted
    (tmp_path / "x.partial").mkdir()
    (tmp_path / "x.partial" / "mine.txt").write_text("user")
    with pytest.raises(InputError, match="not made by visemeface"):
        pipeline.FrameFolder(tmp_path / "x", key="k").check()
    assert (tmp_path / "x.partial" / "mine.txt").exists()


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
