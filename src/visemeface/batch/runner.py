"""Run a batch of clips on a Dask cluster: a local one, or any scheduler the user points to.

Each good job is one Dask task (:func:`visemeface.batch.clip.make_clip`):

- **idempotent**: a clip's folder appears only when the clip is complete;
  with ``resume`` the clips already made with the same settings are skipped
  (checked here before any task is sent, and again by the task);
- **retried on worker loss** by Dask itself: when a worker process dies the
  scheduler reschedules its tasks (up to ``distributed.scheduler.allowed-failures``
  times, 3 by default) and the retry removes the dead worker's temporary;
- **isolated**: a bad row or a failing clip is one line of the report
  (``batch_report.csv``: clip, status, seconds, error) and the others go on.

Without a client a :class:`distributed.LocalCluster` is started on this
machine: ``workers`` processes (default: the CPU count), one thread each, on
free ports (several batches can run side by side), numba capped at one thread
per task, so the workers do not oversubscribe the cores.
"""

from __future__ import annotations

import csv
import logging
import os
import shutil
import signal
import uuid
from collections.abc import Callable, Iterable
from pathlib import Path

from visemeface.batch.clip import clip_state, make_clip, report_row
from visemeface.batch.manifest import RESERVED, BadRow, Job, read_manifest
from visemeface.errors import InputError

#: The report's file name in the output folder, and its columns.
REPORT = RESERVED[0]
REPORT_COLUMNS = ("clip", "status", "seconds", "error")


def check_outdir(outdir, resume: bool = False, force: bool = False) -> Path:
    """The output folder, refused before any work when it would be overwritten unasked."""
    outdir = Path(outdir)
    if resume and force:
        raise InputError("--resume keeps the finished clips and --force remakes them; give one")
    if outdir.exists() and not outdir.is_dir():
        raise InputError("output exists and is not a folder", outdir)
    if not outdir.parent.is_dir():
        raise InputError("output folder's parent does not exist", outdir.parent)
    if not os.access(outdir if outdir.is_dir() else outdir.parent, os.W_OK | os.X_OK):
        raise InputError("output folder is not writable", outdir)
    if outdir.is_dir() and any(outdir.iterdir()) and not (resume or force):
        raise InputError("output folder is not empty; use --resume to continue it or --force to remake "
                         "its clips", outdir)
    return outdir


def local_client(workers: int | None = None):
    """A :class:`distributed.Client` on a new local cluster: ``workers`` processes of one thread each."""
    from distributed import Client, LocalCluster

    n = workers or os.cpu_count() or 1
    # The worker processes inherit an ignored SIGINT: a terminal's Ctrl-C reaches the whole process group,
    # and each worker printed a KeyboardInterrupt traceback; this process alone stops the batch.
    previous = signal.signal(signal.SIGINT, signal.SIG_IGN) if _main_thread() else None
    before = _clusters()
    try:
        cluster = LocalCluster(n_workers=n, threads_per_worker=1, processes=True, dashboard_address=":0",
                               # a cancelled task on Ctrl-C is no warning, and a worker's heartbeat that
                               # meets the scheduler closing at the end of a batch logs a 29-line
                               # CommClosedError at ERROR (about 1 run in 25 of 1,000 rows): every clip's
                               # failure is in the report and its line, so the workers' logs say nothing new
                               silence_logs=logging.CRITICAL)
    except BaseException:
        # stopped while the cluster starts (SIGTERM, or a failure): its half-made workers cannot be closed
        # (distributed asserts they started) and Dask's own exit hook printed that assertion's traceback
        # after our one line. They are the interpreter's daemon processes and end with it.
        for half_made in _clusters() - before:
            half_made.shutdown_on_close = False
        raise
    finally:
        if previous is not None:
            signal.signal(signal.SIGINT, previous)
    return Client(cluster)


def _clusters() -> set:
    """The Dask clusters of this process."""
    from distributed.deploy.spec import SpecCluster

    return set(SpecCluster._instances)


def _main_thread() -> bool:
    import threading

    return threading.current_thread() is threading.main_thread()


def run(jobs, outdir, client=None, workers: int | None = None, resume: bool = False, force: bool = False,
        show_progress: bool = True, on_result: Callable[[dict], None] | None = None) -> list[dict]:
    """Make every clip of ``jobs`` under ``outdir``; returns the report rows (also written to ``batch_report.csv``).

    Parameters
    ----------
    jobs : path or iterable of Job / BadRow
        A manifest (:func:`~visemeface.batch.manifest.read_manifest`) or its rows.
    outdir : path
        The output folder (made if absent; its parent must exist). Each clip goes to ``outdir/<clip>/``.
    client : distributed.Client, optional
        Where to run; default: a local cluster of ``workers`` processes (closed at the end).
    workers : int, optional
        Processes of the local cluster (default: the CPU count). Not used with ``client``.
    resume : bool
        Skip the clips already made with the same settings (continue an interrupted batch).
    force : bool
        Remake clips that exist.
    on_result : callable, optional
        Called with each report row as it arrives (in completion order).

    Returns
    -------
    list of dict
        One row per manifest row, in manifest order: ``clip``, ``status`` (done, skipped, error,
        failed), ``seconds``, ``error``.
    """
    outdir = check_outdir(outdir, resume, force)
    if isinstance(jobs, (str, Path)):
        jobs = read_manifest(jobs)
    jobs = list(jobs)
    if not jobs:
        raise InputError("no clips to make")
    created = not outdir.exists()
    outdir.mkdir(exist_ok=True)
    rows: dict[int, dict] = {}
    todo: list[tuple[int, Job]] = []
    for i, job in enumerate(jobs):
        if isinstance(job, BadRow):
            rows[i] = report_row(job.clip, "error", 0.0, job.error)
        elif resume and clip_state(job, outdir) == "done":
            rows[i] = report_row(job.clip, "skipped", 0.0)
        else:
            todo.append((i, job))
    for row in rows.values():
        if on_result is not None:
            on_result(row)

    def report(why: str = "the batch was interrupted") -> None:
        write_report(outdir / REPORT, [rows.get(i) or _unfinished(j, outdir, why) for i, j in enumerate(jobs)])

    try:
        if todo:
            _submit(todo, outdir, client, workers, force, show_progress, rows, on_result)
    except Exception as e:                      # not an interrupt: the cluster failed (e.g. workers never started)
        report(f"the batch stopped: {type(e).__name__}: {e}".splitlines()[0])
        raise
    except BaseException:                       # interrupted: a folder this run made, with no clip, is not left
        if created and not any(clip_state(j, outdir) == "done" for _, j in todo):
            shutil.rmtree(outdir, ignore_errors=True)
        else:
            report()
        raise
    report()
    return [rows[i] for i in range(len(jobs))]


def _unfinished(job: Job, outdir: Path, why: str) -> dict:
    """The report row of a clip whose result never came back (the batch stopped: ``why``)."""
    if clip_state(job, outdir) == "done":       # finished while the batch was being stopped
        return report_row(job.clip, "done", 0.0)
    return report_row(job.clip, "failed", 0.0, f"not made: {why}")


def _submit(todo, outdir: Path, client, workers, force, show_progress, rows, on_result) -> None:
    """Send the clips to the cluster and collect their rows as they finish (progress bar with ETA)."""
    from distributed import as_completed

    from visemeface.outputs import progress

    own = client is None
    if own:
        client = local_client(min(workers or os.cpu_count() or 1, len(todo)))
    run_id = uuid.uuid4().hex[:8]
    try:
        index = {}
        futures = []
        for i, job in todo:
            fut = client.submit(make_clip, job, str(outdir.resolve()), force, pure=False,
                                key=f"visemeface-clip-{job.clip}-{run_id}")
            index[fut.key] = (i, job)
            futures.append(fut)
        with progress(total=len(futures), desc="batch", unit="clip", show=show_progress) as bar:
            for fut in as_completed(futures):
                i, job = index[fut.key]
                try:
                    row = fut.result()
                except Exception as e:  # the task's worker died too often (KilledWorker), or the cluster went
                    row = report_row(job.clip, "failed", 0.0, f"{type(e).__name__}: {e}")
                if row["status"] == "skipped":  # a retry after a worker died holding the result:
                    row = report_row(job.clip, "done", row["seconds"])  # this run made the clip
                rows[i] = row
                bar.update(1)
                if on_result is not None:
                    on_result(row)
    except BaseException as e:
        if own and not isinstance(e, Exception):     # interrupted: our one line says so; the scheduler's
            _quiet_dask()                           # "couldn't gather keys" for the cancelled clips is noise
        client.cancel(futures)
        raise
    finally:
        if own:
            cluster = client.cluster
            client.close()
            cluster.close()
    _remove_stale(outdir, [job for _, job in todo])


def _quiet_dask() -> None:
    """Silence this process's Dask loggers (the scheduler of a local cluster runs here)."""
    for name in list(logging.root.manager.loggerDict):
        if name == "distributed" or name.startswith("distributed."):
            logging.getLogger(name).setLevel(logging.CRITICAL + 1)


def _remove_stale(outdir: Path, jobs: Iterable[Job]) -> None:
    """Remove any temporary of these clips left by a dead process (a worker killed mid-clip)."""
    from visemeface.outputs import remove_stale

    for job in jobs:
        remove_stale(outdir / job.clip)


def write_report(path, rows: list[dict]) -> Path:
    """``batch_report.csv``: one line per clip (clip, status, seconds, error), written atomically."""
    from visemeface.outputs import atomic_output

    with atomic_output(path, force=True) as tmp, open(tmp, "w", newline="", encoding="utf-8") as fh:
        w = csv.DictWriter(fh, fieldnames=REPORT_COLUMNS, lineterminator="\n")
        w.writeheader()
        w.writerows(rows)
    return Path(path)


def read_report(path) -> list[dict]:
    """The rows of a ``batch_report.csv``."""
    with open(path, newline="", encoding="utf-8") as fh:
        return list(csv.DictReader(fh))
