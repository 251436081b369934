"""The one streaming loop: a Motion's frames into a set of sinks.

::

    Motion (kinematic rig or FEM simulation) --Frame--> [render once] --> sinks (video, frames, obj, ...)

``speak``, ``say`` and ``simulate`` all end here. For each frame the face's
vertices come from the motion, the frame is rendered once if any sink needs
pixels, and every sink takes it before the next frame is made, so memory does
not grow with the length of the run. Sinks write temporaries and are committed
together only when every one of them has finished (all outputs or none).

Resuming
--------
A resumable motion (a simulation) saves its state after every
``checkpoint_every`` frames into a :class:`~visemeface.checkpoint.RunCheckpoint`
(with the vertices of the finished frames). After an interruption the run
replays the finished frames from it into the sinks (no simulation) and
continues the simulation from the saved state, so no frame is simulated twice
and the outputs equal those of an uninterrupted run. A kinematic motion needs
no checkpoint (any frame is one matrix product); its expensive part, rendering,
is kept by the frames sink (``--frames DIR``), whose finished PNGs a resumed
run reads back instead of rendering them again. A run that diverges keeps no
checkpoint: the simulation is deterministic, so resumed it diverges at the same
step again; the finished PNGs stay in the frames sink's ``.partial`` folder to
look at, and the next run (with other options) starts afresh.
"""

from __future__ import annotations

import contextlib
import contextvars
import dataclasses
from dataclasses import dataclass, field

from visemeface.errors import InputError, SimulationDiverged
from visemeface.export.sinks import RunInfo, Sink, check_distinct
from visemeface.motion import Motion
from visemeface.outputs import progress
from visemeface.runtime import landing

#: Frame sizes the renderer accepts: positive multiples of 16 (video codecs and GL alignment).
SIZE_STEP = 16
#: Multisample counts the renderer accepts.
MSAA = (0, 2, 4, 8, 16)


def check_msaa(n) -> int:
    """``n`` antialiasing samples per pixel if it is one of :data:`MSAA`; else :class:`InputError`."""
    if isinstance(n, bool) or n not in MSAA:
        raise InputError(f"--msaa must be one of {', '.join(map(str, MSAA))}, got {n}")
    return n


@dataclass
class RenderSettings:
    """How frames are rendered when a sink needs pixels."""

    size: int = 512
    view: str = "face"
    msaa: int = 4

    def check(self) -> RenderSettings:
        if not isinstance(self.size, int) or self.size < SIZE_STEP or self.size % SIZE_STEP:
            raise InputError(f"--size must be a positive multiple of {SIZE_STEP}, got {self.size}")
        from visemeface.render.renderer import MAX_SIZE, VIEWS

        if self.size > MAX_SIZE:
            raise InputError(f"--size {self.size} is larger than the renderer's {MAX_SIZE} px")
        check_msaa(self.msaa)
        if self.view not in VIEWS:
            raise InputError(f"--view must be one of {', '.join(VIEWS)}, got {self.view!r}")
        return self

    def key(self) -> str:
        return f"{self.size}/{self.view}/msaa{self.msaa}"


#: Where :func:`run` notes the :class:`RunStats` of each run while set to a list (the Python API's
#: :class:`visemeface.api.Result` reads it); None, the default, notes nothing.
RUNS: contextvars.ContextVar[list | None] = contextvars.ContextVar("visemeface_runs", default=None)


@dataclass
class RunStats:
    """What a run did: frames in all, made live (simulated or posed), replayed from a checkpoint,
    rendered, and images reused from kept frames."""

    frames: int = 0
    live: int = 0
    replayed: int = 0
    rendered: int = 0
    reused: int = 0
    written: list = field(default_factory=list)


def _image(frame, renderer, sinks, stats, model=None) -> None:
    for s in sinks:
        image = s.cached_image(frame.index)
        if image is not None:
            frame.image = image
            stats.reused += 1
            return
    frame.image = renderer.render(frame.vertices, model)
    stats.rendered += 1


def _feed(frame, renderer, sinks, stats, n_vertices: int, head=None) -> None:
    """Render ``frame`` (all its vertices: the motion's render face; turned by ``head``, (F, 4, 4) model matrices,
    where given) and write it (the face's vertices, never turned)."""
    if renderer is not None:
        _image(frame, renderer, sinks, stats, None if head is None else head[min(frame.index, len(head) - 1)])
    if len(frame.vertices) > n_vertices:
        frame = dataclasses.replace(frame, vertices=frame.vertices[:n_vertices])
    for s in sinks:
        s.write(frame)


def run(motion: Motion, sinks: list[Sink], render: RenderSettings | None = None, info: dict | None = None,
        checkpoint=None, resume: bool = False, checkpoint_every: int = 1,
        show_progress: bool = True, also=(), final: bool = False) -> RunStats:
    """Stream ``motion`` into ``sinks`` (see the module docstring).

    Parameters
    ----------
    motion : Motion
    sinks : list of Sink
        Checked (distinct paths) before any work.
    render : RenderSettings, optional
        Used when a sink needs images.
    info : dict, optional
        More :class:`RunInfo` fields (``audio``, ``rig``, ``track``, ``end_time``, ``extra``).
    checkpoint : RunCheckpoint, optional
        Where a resumable motion saves its state (checked by the caller with
        :meth:`RunCheckpoint.check` before any work).
    resume : bool
        Continue from ``checkpoint`` (and reuse the frames sinks' kept images).
    checkpoint_every : int
        Frames between saved states.
    also : list of Staged
        More outputs the caller has written (a transcript), put in place with the sinks' (not aborted here).
    final : bool
        The sinks (and ``also``) are the command's last outputs (:func:`visemeface.runtime.landing`).
    """
    if not sinks:
        raise InputError("nothing to write: give an output")
    check_distinct(sinks)
    render = (render or RenderSettings()).check()
    stats = RunStats(frames=motion.n_frames)
    done, state = checkpoint.load() if (checkpoint is not None and resume) else (0, None)
    need_image = any(s.needs_image for s in sinks)
    run_info = RunInfo(face=motion.face, fps=motion.fps, n_frames=motion.n_frames, **(info or {}))
    opened = []
    try:   # an error or interrupt anywhere, the renderer's closing included, removes the temporaries
        with contextlib.ExitStack() as stack:
            renderer = head = None
            if run_info.extra.get("head") is not None:
                import numpy as np

                from visemeface.motion import digest
                from visemeface.speech.gestures import head_matrices, head_pivot

                angles = np.asarray(run_info.extra["head"], dtype=np.float64)
                head = head_matrices(angles, head_pivot(motion.face.vertices))
                run_info.extra.setdefault("render_key", f"{render.key()}/head:{digest(angles)[:16]}")
            run_info.extra.setdefault("render_key", render.key())
            if need_image:
                from visemeface.render.renderer import Renderer

                # the renderer turns the head (a model matrix per frame); a turned head shows what the still
                # triangles hid at rest (through the moving lips, between the teeth), so none is culled
                renderer = stack.enter_context(Renderer(motion.render_face, size=(render.size, render.size),
                                                        view=render.view, samples=render.msaa,
                                                        still=None if head is not None else motion.still_vertices()))
                run_info.size, run_info.mouth_box = render.size, renderer.mouth_box()
            for s in sinks:
                try:
                    s.open(run_info)
                except BaseException:       # a sink refused in its opening (a rig not found): its own
                    for staged in s.staged:  # temporaries go too, not only the others'
                        staged.abort()
                    raise
                opened.append(s)
            _stream(motion, sinks, renderer, checkpoint, done, state, checkpoint_every, stats, show_progress, head)
            for s in sinks:
                s.close()
    except BaseException as exc:
        diverged = isinstance(exc, SimulationDiverged)   # deterministic: a resumed run diverges again
        run_info.resumable = not diverged
        for s in opened:
            s.abort()
        if checkpoint is not None:
            checkpoint.remove() if diverged else checkpoint.close()
        raise
    with landing(final):             # after the renderer is closed; all the outputs or none of them
        for s in sinks:
            stats.written += s.commit()
        for s in also:
            s.commit()
        if checkpoint is not None:
            checkpoint.remove()
    noted = RUNS.get()
    if noted is not None:
        noted.append(stats)
    return stats


def _stream(motion, sinks, renderer, checkpoint, done, state, every, stats, show_progress, head=None) -> None:
    bar = progress(total=motion.n_frames, desc=motion.label, show=show_progress)
    with bar:
        for i in range(done):                 # finished before an interruption: replay, do not simulate
            _feed(checkpoint.replay(i), renderer, sinks, stats, motion.face.n_vertices, head)
            stats.replayed += 1
            bar.update(1)
        record = checkpoint is not None and motion.resumable
        if record:
            checkpoint.start(done)
        for frame in motion.frames(done, state):
            _feed(frame, renderer, sinks, stats, motion.face.n_vertices, head)
            stats.live += 1
            bar.update(1)
            if record:
                frame.image = None
                checkpoint.record(frame)
                n = frame.index + 1
                if n % every == 0 and n < motion.n_frames:
                    checkpoint.save(motion.state(), n)


def summary(stats: RunStats, fps: float) -> str:
    """One line: frames, duration, what was reused, the files written."""
    extra = []
    if stats.replayed:
        extra.append(f"{stats.replayed} replayed from the checkpoint")
    if stats.reused:
        extra.append(f"{stats.reused} kept from the previous run")
    more = f", {', '.join(extra)}" if extra else ""
    return (f"{stats.frames} frames ({stats.frames / fps:.2f} s at {fps:g} fps{more}) -> "
            + ", ".join(str(p) for p in stats.written))


def check_audio(path) -> float:
    """Duration in seconds of a recording (sound file or video track); :class:`InputError` if it cannot be
    read or holds no sound (:func:`visemeface.speech.audio.audio_duration`)."""
    from visemeface.speech.audio import audio_duration

    return audio_duration(path)
