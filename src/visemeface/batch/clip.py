"""One clip of a batch, made where a Dask worker runs it: ``OUTDIR/<clip>/`` written all at once.

A clip's outputs are the sinks its job names (:data:`visemeface.export.SINKS`),
each under a fixed name in the clip's folder (:func:`output_name`: ``video.mp4``,
``frames/``, ``gltf.glb``, ``track.csv`` ...), and ``clip.json``: the job's
settings, the package version and the frame count. The folder is staged
(:class:`visemeface.outputs.Staged`, ``OUTDIR/.<clip>.vf<pid>~``) and renamed
into place when every output is complete, so ``OUTDIR/<clip>/`` exists only
for a finished clip: a worker killed mid-clip leaves only a temporary, which
the retry (or any later run writing that clip) removes.

The clip is made through the same library path as ``visemeface speak`` and
``say`` (:func:`visemeface.animate.animate`, i.e. :func:`visemeface.pipeline.run`).
"""

from __future__ import annotations

import functools
import json
import time
import warnings
from pathlib import Path

from visemeface.batch.manifest import Job
from visemeface.errors import InputError, VisemefaceError

#: The record of a finished clip, in its folder.
CLIP_RECORD = "clip.json"
#: Report statuses: made now, already made (``--resume``), bad input, crashed.
STATUSES = ("done", "skipped", "error", "failed")


def output_name(sink: str) -> str:
    """File or folder name of a sink's output in a clip folder: ``video.mp4``, ``frames``, ``gltf.glb``."""
    from visemeface.export import SINKS

    cls = SINKS[sink]
    if cls.folder or not cls.suffixes:
        return sink
    return sink + cls.suffixes[0]


def clip_state(job: Job, outdir) -> str:
    """``"missing"``, ``"done"`` (made with these settings) or ``"other"`` (made with other settings)."""
    folder = Path(outdir) / job.clip
    if not folder.is_dir():
        return "missing"
    try:
        record = json.loads((folder / CLIP_RECORD).read_text())
    except (OSError, ValueError):
        return "other"
    return "done" if isinstance(record, dict) and record.get("settings") == job.settings() else "other"


@functools.lru_cache(maxsize=2)
def _rig(face: str | None, landmarks: str | None, rig: str | None, identity: str | None = None):
    """The rig of the batch's face and rig files (and a clip's ICT identity), built once per worker process."""
    from visemeface.muscles.rig import rig_for

    return rig_for(face, landmarks, rig, identity)


def _utterance(job: Job):
    if job.transcript is not None:
        from visemeface.speech.transcripts import read_utterance

        return read_utterance(job.transcript, rate_wpm=job.rate, audio=job.audio)
    from visemeface.speech.transcripts import timed_text

    return timed_text(job.text, job.rate, job.audio)


def _our_clip(folder: Path) -> bool:
    """A clip folder ``--force`` may replace: made by a batch (its record) and holding nothing else but
    sink outputs (``video.mp4``, ``video.mp4.json``, ``frames``, ...) and staged temporaries."""
    from visemeface.export import SINKS
    from visemeface.outputs import is_temporary

    return (folder / CLIP_RECORD).is_file() and all(
        p.name == CLIP_RECORD or p.name.split(".")[0] in SINKS or is_temporary(p) for p in folder.iterdir())


def _make(job: Job, folder: Path, force: bool) -> int:
    """Make the clip into ``folder`` (staged); returns its frame count."""
    from visemeface import __version__
    from visemeface.animate import animate
    from visemeface.export import SINKS
    from visemeface.outputs import Staged
    from visemeface.pipeline import RenderSettings, check_audio

    if job.audio is not None:
        check_audio(job.audio)
    render = RenderSettings(size=job.size, view=job.view, msaa=job.msaa).check()
    utterance = _utterance(job)
    rig = _rig(job.face, job.landmarks, job.rig, job.identity)
    staged = Staged(folder, force=force, folder=True, ours=_our_clip)
    tmp = staged.open()
    try:
        sinks = [SINKS[name](tmp / output_name(name)) for name in job.outputs]
        stats = animate(utterance, sinks, render, rig=rig, emotions=dict(job.emotion), interp=job.interp,
                        fps=job.fps, audio=job.audio, physics=job.physics, show_progress=False,
                        source=str(job.transcript) if job.transcript else "text")
        record = {"clip": job.clip, "visemeface": __version__, "frames": stats.frames, "settings": job.settings()}
        (tmp / CLIP_RECORD).write_text(json.dumps(record, indent=1) + "\n")
    except BaseException:
        staged.abort()
        raise
    staged.commit()
    return stats.frames


#: Mesa's software rasteriser (llvmpipe) starts a thread per core for each GL context unless told.
RASTER_THREADS = ("LP_NUM_THREADS", "1")


def _one_thread_per_worker() -> None:
    """Cap the worker's compute threads at one: numba (:func:`visemeface.runtime.configure`) and Mesa's
    llvmpipe (read when the first GL context is made), unless the user set them."""
    import os

    from visemeface.runtime import configure

    configure(threads=1)
    os.environ.setdefault(*RASTER_THREADS)


def make_clip(job: Job, outdir: str, force: bool = False) -> dict:
    """Make one clip (the task a Dask worker runs); returns its report row.

    Never raises for a bad clip: bad input is status ``error``, anything else
    ``failed``, with the reason on one line. A clip already made with the same
    settings is ``skipped`` (unless ``force``); one made with other settings is
    an error unless ``force``. The worker's threads are capped at one
    (:func:`_one_thread_per_worker`), so N workers use N cores.
    """
    t0 = time.perf_counter()
    _one_thread_per_worker()
    folder = Path(outdir) / job.clip
    status, message = "done", ""
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        try:
            state = clip_state(job, outdir)
            if state == "done" and not force:
                status = "skipped"
            elif state == "other" and not force:
                raise InputError("made earlier with other settings; remove it or use --force", folder)
            else:
                _make(job, folder, force=True)
        except VisemefaceError as e:
            status, message = "error", str(e)
        except Exception as e:  # a crash in one clip must not stop the batch: report it
            status, message = "failed", f"{type(e).__name__}: {e}"
    if status == "done" and caught:
        message = "; ".join(f"warning: {w.message}" for w in caught[:3])
    return report_row(job.clip, status, time.perf_counter() - t0, message)


def report_row(clip: str, status: str, seconds: float, error: str = "") -> dict:
    """One row of ``batch_report.csv`` (the error on one line)."""
    assert status in STATUSES
    return {"clip": clip, "status": status, "seconds": round(float(seconds), 3),
            "error": " ".join(str(error).split())}
