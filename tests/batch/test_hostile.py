"""Regressions from a hostile user's batch runs (issue 20, second round)."""

import json
import os
import signal
import subprocess
import sys
import time

import pytest

from visemeface.batch.clip import CLIP_RECORD, clip_state
from visemeface.batch.manifest import Job


def test_a_clip_record_that_is_not_an_object_means_other_settings(tmp_path):
    """``clip.json`` holding ``[]`` (hand-edited, another tool's file) crashed --resume with AttributeError."""
    job = Job(clip="c1", text="one")
    (tmp_path / "c1").mkdir()
    for text in ("[]", "5", '"settings"', "null"):
        (tmp_path / "c1" / CLIP_RECORD).write_text(text)
        assert clip_state(job, tmp_path) == "other"
    (tmp_path / "c1" / CLIP_RECORD).write_text(json.dumps({"settings": job.settings()}))
    assert clip_state(job, tmp_path) == "done"


def test_a_sticky_clip_made_with_the_seed_lips_is_not_done(tmp_path):
    """A clip made by --physics sticky before the speech lips changed (issue 16: refined seam, rupture time)
    was "done" on --resume: its record has no ``lips``, so it now counts as made with other settings."""
    job = Job(clip="c1", text="one", physics="sticky")
    (tmp_path / "c1").mkdir()
    old = {k: v for k, v in job.settings().items() if k != "lips"}
    (tmp_path / "c1" / CLIP_RECORD).write_text(json.dumps({"settings": old}))
    assert clip_state(job, tmp_path) == "other"
    (tmp_path / "c1" / CLIP_RECORD).write_text(json.dumps({"settings": job.settings()}))
    assert clip_state(job, tmp_path) == "done"
    assert "lips" not in Job(clip="c2", text="one").settings()        # the kinematic face has no FEM lips


@pytest.mark.slow
def test_ctrl_c_on_a_terminal_ends_batch_with_one_line(tmp_path):
    """A terminal's Ctrl-C reaches the whole process group: each Dask worker printed a KeyboardInterrupt
    traceback (and the cancelled tasks a WARNING each) before "visemeface: interrupted"."""
    rows = "".join(f"c{i},bob moves five boats number {i}\n" for i in range(8))
    (tmp_path / "jobs.csv").write_text("clip,text\n" + rows)
    proc = subprocess.Popen([sys.executable, "-m", "visemeface", "batch", "jobs.csv", "-o", "out", "--size", "96",
                             "--msaa", "0", "--workers", "2", "-q"], cwd=tmp_path, stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True, start_new_session=True)
    try:
        t0 = time.monotonic()
        while not any((tmp_path / "out").glob("c*")) and time.monotonic() - t0 < 120:
            time.sleep(0.05)                       # a clip is being made or done: the workers are busy
        assert proc.poll() is None, proc.communicate()
        os.killpg(proc.pid, signal.SIGINT)
        _, err = proc.communicate(timeout=60)
    finally:
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGKILL)
    assert proc.returncode == 130 and err == "visemeface: interrupted\n", err


def test_a_huge_worker_count_is_refused_before_any_process_starts(tmp_path, monkeypatch, capsys):
    """`--workers 10000` with as many clips started 10,000 Python processes (the machine ran out of memory)."""
    from visemeface.cli import main

    monkeypatch.chdir(tmp_path)
    (tmp_path / "jobs.csv").write_text("clip,text\na,one\n")
    cores = os.cpu_count() or 1
    assert main(["batch", "jobs.csv", "-o", "out", "--workers", str(4 * cores + 1)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and f"over 4 processes a core ({cores} cores here)" in err, err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["jobs.csv"]


def test_a_recording_in_the_transcript_column_is_a_bad_row_saying_where_it_goes(tmp_path, vowels_wav):
    """`transcript=take.wav` failed on the worker with "take.wav:1: not UTF-8 text (byte 0x..)"."""
    import shutil

    from visemeface.batch.manifest import BadRow, read_manifest

    shutil.copy(vowels_wav, tmp_path / "take.wav")
    (tmp_path / "m.csv").write_text("clip,transcript\nc1,take.wav\n")
    [row] = read_manifest(tmp_path / "m.csv")
    assert isinstance(row, BadRow) and row.error.endswith(
        "take.wav: a recording is no transcript: put it in the audio column and its words in text")
