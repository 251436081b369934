"""Batches on a real local Dask cluster: bad rows reported while good clips finish, resume, worker loss.

Clips are kinematic, 32 px, 15 fps and a few words long, so each takes a fraction of a second on a
warm worker; one two-worker cluster is shared by the fast tests (the CLI test reaches it through
``--scheduler``), the worker-loss test starts its own.
"""

import json
import os
import signal
import time

import pytest

from visemeface.batch import REPORT, read_manifest, read_report, run
from visemeface.export.video import read_video_info
from visemeface.outputs import is_temporary

SMALL = {"size": 32, "fps": 15, "msaa": 0}
WORDS = ["bin blue", "lay red", "set white", "place green", "bin white", "lay blue", "set red", "place blue"]


def _cluster():
    from distributed import Client, LocalCluster

    cluster = LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=":0")
    return Client(cluster)


@pytest.fixture(scope="module")
def client():
    c = _cluster()
    yield c
    cluster = c.cluster
    c.close()
    cluster.close()


def _jobs(tmp_path, n, bad=""):
    path = tmp_path / "jobs.csv"
    lines = ["clip,transcript,text,emotion,outputs"] + [f"c{i},,{WORDS[i % len(WORDS)]},,video track"
                                                        for i in range(n)]
    path.write_text("\n".join(lines) + "\n" + bad)
    return read_manifest(path, SMALL)


def _temporaries(folder):
    return [p for p in folder.rglob("*") if is_temporary(p)]


def _check_clip(folder):
    """A finished clip: its record, and a video holding exactly the recorded frames."""
    record = json.loads((folder / "clip.json").read_text())
    assert read_video_info(folder / "video.mp4")["n_frames"] == record["frames"] > 0
    assert (folder / "track.csv").is_file()
    return record


@pytest.mark.slow
def test_bad_rows_are_one_line_each_and_the_good_clips_finish(client, tmp_path):
    bad = ("gone,missing.txt,,,video\n"                # a transcript that is not there
           "emo,,lay red,hapiness=0.3,video\n"         # unknown emotion
           "nan,,lay red,anger=nan,video\n")           # NaN weight
    jobs = _jobs(tmp_path, 3, bad)
    out = tmp_path / "out"
    rows = run(jobs, out, client=client, show_progress=False)
    report = read_report(out / REPORT)
    assert [r["clip"] for r in report] == [r["clip"] for r in rows] == ["c0", "c1", "c2", "gone", "emo", "nan"]
    assert [r["status"] for r in report[:3]] == ["done"] * 3
    for r in report[3:]:
        assert r["status"] == "error" and r["error"] and "\n" not in r["error"]
    assert "transcript not found" in report[3]["error"]
    assert "hapiness" in report[4]["error"] and "finite" in report[5]["error"]
    for i in range(3):
        _check_clip(out / f"c{i}")
    assert sorted(p.name for p in out.iterdir()) == ["batch_report.csv", "c0", "c1", "c2"]


@pytest.mark.slow
def test_a_clip_failing_on_the_worker_is_reported_and_the_others_finish(client, tmp_path):
    (tmp_path / "bad.txt").write_text("0.0 0.5 aa\n0.5 0.7 zz\n")     # read by the worker: no phone zz
    path = tmp_path / "jobs.csv"
    path.write_text("clip,transcript,text\nok,,bin blue\nbroken,bad.txt,\n")
    rows = run(read_manifest(path, SMALL), tmp_path / "out", client=client, show_progress=False)
    assert rows[0]["status"] == "done"
    assert rows[1]["status"] == "error" and "bad.txt:2: unknown dectalk phone 'zz'" in rows[1]["error"]
    assert not (tmp_path / "out" / "broken").exists()


@pytest.mark.slow
def test_resume_after_an_interrupted_batch_does_only_the_missing_clips(client, tmp_path):
    jobs = _jobs(tmp_path, 8)
    out = tmp_path / "out"
    seen = []

    def interrupt_after_two(row):
        seen.append(row)
        if len(seen) == 2:
            raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        run(jobs, out, client=client, show_progress=False, on_result=interrupt_after_two)
    deadline = time.monotonic() + 60
    while _temporaries(out) and time.monotonic() < deadline:   # clips in flight when interrupted finish or vanish
        time.sleep(0.2)
    assert not _temporaries(out)
    report = {r["clip"]: r["status"] for r in read_report(out / REPORT)}
    made = {p.name: (p / "clip.json").stat().st_mtime_ns for p in out.iterdir() if p.is_dir()}
    assert 2 <= len(made) < 8
    # clips still running when the report was written finish after it (the cluster is not ours to stop)
    assert {c for c, s in report.items() if s == "done"} <= set(made)
    assert {c for c, s in report.items() if s == "failed"} >= set(report) - set(made)

    rows = run(jobs, out, client=client, resume=True, show_progress=False)
    status = {r["clip"]: r["status"] for r in rows}
    assert {c for c, s in status.items() if s == "skipped"} == set(made)
    assert {c for c, s in status.items() if s == "done"} == {f"c{i}" for i in range(8)} - set(made)
    for name, mtime in made.items():            # the finished clips were not touched
        assert (out / name / "clip.json").stat().st_mtime_ns == mtime
    for i in range(8):
        _check_clip(out / f"c{i}")


def test_a_clip_made_with_other_settings_is_not_skipped_silently(client, tmp_path):
    jobs = _jobs(tmp_path, 1)
    out = tmp_path / "out"
    run(jobs, out, client=client, show_progress=False)
    other = read_manifest(tmp_path / "jobs.csv", {**SMALL, "fps": 10})
    rows = run(other, out, client=client, resume=True, show_progress=False)
    assert rows[0]["status"] == "error" and "other settings" in rows[0]["error"]
    rows = run(other, out, client=client, force=True, show_progress=False)
    assert rows[0]["status"] == "done" and _check_clip(out / "c0")["settings"]["fps"] == 10


@pytest.mark.slow
def test_cli_on_a_running_scheduler_reports_each_bad_clip_on_one_line(client, tmp_path, monkeypatch, capsys):
    from visemeface.cli import main

    monkeypatch.chdir(tmp_path)
    (tmp_path / "jobs.csv").write_text("clip,text,emotion\nc0,bin blue,\nc1,lay red,sadness=0.5\n"
                                       "bad,lay red,hapiness\n")
    argv = ["batch", "jobs.csv", "-o", "out", "--scheduler", client.scheduler.address, "--size", "32",
            "--fps", "15", "--msaa", "0", "--outputs", "video", "-q"]
    assert main(argv) == 1
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("visemeface: clip bad: error: jobs.csv:4: unknown emotion")
    assert sorted(p.name for p in (tmp_path / "out").iterdir()) == ["batch_report.csv", "c0", "c1"]
    assert main(argv) == 2                                # not empty: needs --resume or --force
    assert "use --resume" in capsys.readouterr().err
    (tmp_path / "scheduler.json").write_text(json.dumps({"address": client.scheduler.address}))
    argv[argv.index("--scheduler") + 1] = "scheduler.json"  # the same scheduler through its scheduler file
    assert main(argv + ["--resume"]) == 1                 # the bad row is still bad; nothing remade
    statuses = [r["status"] for r in read_report(tmp_path / "out" / REPORT)]
    assert statuses == ["skipped", "skipped", "error"]


def test_cli_refuses_a_scheduler_that_is_neither_an_address_nor_a_scheduler_file(tmp_path, monkeypatch, capsys):
    from visemeface.cli import main

    monkeypatch.chdir(tmp_path)
    (tmp_path / "jobs.csv").write_text("clip,text\nc0,bin blue\n")
    (tmp_path / "junk.json").write_text("{}")
    for target, message in (("head-node", "must be a Dask scheduler address"), ("junk.json", "not a Dask scheduler file")):
        assert main(["batch", "jobs.csv", "-o", "out", "--scheduler", target]) == 2
        err = capsys.readouterr().err
        assert err.count("\n") == 1 and message in err
    assert not (tmp_path / "out").exists()


@pytest.mark.slow
def test_a_worker_killed_mid_clip_loses_no_clip_and_leaves_no_partial_file(tmp_path):
    jobs = _jobs(tmp_path, 8)
    out = tmp_path / "out"
    c = _cluster()
    killed = {}

    def kill_a_busy_worker(row):
        if killed:
            return
        deadline, busy = time.monotonic() + 30, {}
        while time.monotonic() < deadline:
            busy = {w: keys for w, keys in c.processing().items() if keys}
            if busy:
                break
            time.sleep(0.01)
        assert busy, "no worker was busy"
        worker, keys = next(iter(busy.items()))
        pid = c.run(os.getpid, workers=[worker])[worker]
        os.kill(pid, signal.SIGKILL)
        killed.update(pid=pid, keys=list(keys))

    try:
        rows = run(jobs, out, client=c, show_progress=False, on_result=kill_a_busy_worker)
        pids = set(c.run(os.getpid).values())
    finally:
        cluster = c.cluster
        c.close()
        cluster.close()
    assert killed and killed["pid"] not in pids          # the nanny started a new worker process
    assert [r["clip"] for r in rows] == [f"c{i}" for i in range(8)]
    assert all(r["status"] == "done" for r in rows), rows
    assert not _temporaries(out)
    for i in range(8):
        _check_clip(out / f"c{i}")
    assert sorted(p.name for p in out.iterdir()) == sorted([REPORT] + [f"c{i}" for i in range(8)])


@pytest.mark.slow
def test_without_a_client_a_local_cluster_is_started_and_closed(tmp_path):
    import psutil

    before = {p.pid for p in psutil.Process().children(recursive=True)}
    rows = run(_jobs(tmp_path, 1), tmp_path / "out", workers=2, show_progress=False)
    assert [r["status"] for r in rows] == ["done"]          # one clip: one worker was started, not two
    _check_clip(tmp_path / "out" / "c0")
    left = [p for p in psutil.Process().children(recursive=True) if p.pid not in before and p.is_running()
            and p.status() != psutil.STATUS_ZOMBIE and "resource_tracker" not in " ".join(p.cmdline())]
    assert not left, [p.cmdline() for p in left]


def test_a_cluster_that_fails_is_named_in_the_report_not_called_an_interrupt(tmp_path):
    class NoWorkers:                                    # as a local cluster whose nannies never start
        def submit(self, *a, **k):
            raise RuntimeError("Nanny failed to start.\nmore lines of the scheduler")

        def cancel(self, futures):
            pass

    with pytest.raises(RuntimeError, match="Nanny"):
        run(_jobs(tmp_path, 2), tmp_path / "out", client=NoWorkers(), show_progress=False)
    errors = {r["error"] for r in read_report(tmp_path / "out" / REPORT)}
    assert errors == {"not made: the batch stopped: RuntimeError: Nanny failed to start."}


@pytest.mark.parametrize("existed", [False, True])
def test_an_interrupt_before_any_clip_leaves_no_folder_it_made(tmp_path, monkeypatch, existed):
    """An interrupted batch left its new folder with a report of clips "not made" and nothing else: a
    finished-looking output. A folder that was there before (a batch being resumed) keeps its report."""
    from visemeface.batch import runner

    def interrupted(*args, **kwargs):
        raise KeyboardInterrupt

    monkeypatch.setattr(runner, "_submit", interrupted)
    out = tmp_path / "out"
    if existed:
        out.mkdir()
    with pytest.raises(KeyboardInterrupt):
        run(_jobs(tmp_path, 2), out, show_progress=False)
    assert out.exists() == existed
    if existed:
        assert {r["status"] for r in read_report(out / REPORT)} == {"failed"}
