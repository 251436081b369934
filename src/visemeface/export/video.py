"""MP4 video (H.264 + AAC audio) and its analysis sidecar.

H.264 (libx264, yuv420p) through the ffmpeg shipped by ``imageio-ffmpeg``. An
audio track (any format ffmpeg reads) is muxed in the same pass and encoded as
AAC. When the number of frames ``F`` is known, the audio is padded with silence
(``apad``) and the output is cut at ``-t F/fps``, so the video stream holds
exactly ``F`` frames, the audio lasts exactly as long, and both start at ``t = 0``.

The video sink also writes ``<video>.json`` (:mod:`visemeface.sidecars`): the
rest mouth box and frame rate, so ``visemeface analyze out.mp4`` needs no ``--box``.
"""

from __future__ import annotations

import contextlib
from pathlib import Path

import numpy as np

from visemeface.errors import InputError
from visemeface.export.sinks import Sink, register
from visemeface.outputs import Staged, atomic_output


class VideoWriter:
    """Stream RGB frames into an MP4 file (H.264, yuv420p), optionally with audio.

    Use as a context manager; the file appears at ``path`` only when the block
    ends without error.

    Parameters
    ----------
    path : str or Path
        Output ``.mp4``.
    size : (int, int)
        Frame width and height in pixels; both must be even (yuv420p).
    fps : float
        Frame rate.
    audio : str or Path, optional
        Sound file to mux (encoded as AAC). It starts at ``t = 0``.
    n_frames : int, optional
        Number of frames that will be written. With ``audio``, the audio is
        padded with silence / cut so its length equals ``n_frames / fps``
        exactly; without ``n_frames`` ffmpeg's ``-shortest`` is used, which
        rounds the audio to whole AAC packets (about 21 ms at 48 kHz).
    force : bool
        Replace an existing file.
    crf : int
        x264 constant rate factor (lower = better; 18 is visually lossless).
    preset : str
        x264 speed preset.

    Examples
    --------
    >>> with VideoWriter("out.mp4", (128, 128), fps=30) as video:  # doctest: +SKIP
    ...     for frame in frames:
    ...         video.write(frame)
    """

    def __init__(self, path, size, fps: float, audio=None, n_frames: int | None = None,
                 force: bool = False, crf: int = 18, preset: str = "veryfast"):
        self.path = Path(path)
        self.width, self.height = int(size[0]), int(size[1])
        if self.width % 2 or self.height % 2 or self.width <= 0 or self.height <= 0:
            raise InputError(f"video size {self.width}x{self.height} must be positive and even")
        if not fps > 0:
            raise InputError(f"frame rate must be positive, got {fps}")
        self.fps = float(fps)
        self.audio = None if audio is None else Path(audio)
        self.n_frames = n_frames
        self.force = force
        self.crf = crf
        self.preset = preset
        self.frames_written = 0
        self._stack = None
        self._gen = None

    def __enter__(self) -> VideoWriter:
        import imageio_ffmpeg

        stack = contextlib.ExitStack()
        tmp = stack.enter_context(atomic_output(self.path, self.force))
        from visemeface.runtime import signals_deferred

        try:
            with signals_deferred():              # an interrupt while ffmpeg starts comes once it has started
                self._start(imageio_ffmpeg, tmp)
        except BaseException as err:
            # stopped as ffmpeg starts (Ctrl-C): end ffmpeg before its file is removed, or it would write the
            # file after the removal and leave it behind (and the unclosed writer's warning after our line)
            gen, self._gen = self._gen, None
            if gen is not None:
                _stop(gen)
            stack.__exit__(type(err), err, err.__traceback__)
            raise
        self._stack = stack
        return self

    def _start(self, imageio_ffmpeg, tmp) -> None:
        params = ["-preset", self.preset, "-crf", str(self.crf), "-movflags", "+faststart"]
        audio_kw = {}
        if self.audio is not None:
            audio_kw = dict(audio_path=str(self.audio), audio_codec="aac")
            if self.n_frames is not None:
                params += ["-af", "apad", "-t", f"{self.n_frames / self.fps:.6f}"]
            else:
                params += ["-shortest"]
        self._gen = imageio_ffmpeg.write_frames(
            str(tmp), (self.width, self.height), fps=self.fps, codec="libx264",
            pix_fmt_in="rgb24", pix_fmt_out="yuv420p", quality=None, macro_block_size=1,
            ffmpeg_log_level="error", output_params=params, **audio_kw)
        self._gen.send(None)

    def write(self, frame: np.ndarray) -> None:
        """Append one frame, uint8 of shape (height, width, 3), RGB, top row first."""
        if frame.shape != (self.height, self.width, 3) or frame.dtype != np.uint8:
            raise ValueError(f"frame must be uint8 ({self.height}, {self.width}, 3), "
                             f"got {frame.dtype} {frame.shape}")
        self._gen.send(np.ascontiguousarray(frame))
        self.frames_written += 1

    def __exit__(self, exc_type, exc, tb):
        gen, self._gen = self._gen, None
        stack, self._stack = self._stack, None
        try:
            if exc_type is None:
                gen.close()  # flushes and waits for ffmpeg to finish the file
            else:
                _stop(gen)   # stopped (an error, Ctrl-C): the file is a temporary, removed below
        except BaseException as err:
            stack.__exit__(type(err), err, err.__traceback__)
            raise
        return stack.__exit__(exc_type, exc, tb)


def _stop(gen) -> None:
    """End a frame writer whose file will be discarded: ffmpeg is killed and reaped, not left to encode the
    frames it holds (under load that took seconds after Ctrl-C), and imageio-ffmpeg's warning that the file
    is invalid, a second line after ours, is not printed."""
    frame = gen.gi_frame
    proc = frame.f_locals.get("p") if frame is not None else None    # imageio-ffmpeg's ffmpeg process
    with contextlib.suppress(BaseException), _quiet("imageio_ffmpeg"):
        gen.throw(KeyboardInterrupt)     # its policy for an interrupt: kill ffmpeg, do not wait for the file
    if proc is not None:
        with contextlib.suppress(Exception):
            proc.kill()
            proc.wait(timeout=10)


@contextlib.contextmanager
def _quiet(logger: str):
    """``logger``'s warnings held back for the block."""
    import logging

    log = logging.getLogger(logger)
    level = log.level
    log.setLevel(logging.ERROR)
    try:
        yield
    finally:
        log.setLevel(level)


def read_video_info(path) -> dict:
    """Frame count, frame rate and size of a video, decoding every frame (for checks).

    Returns
    -------
    dict
        ``n_frames``, ``fps``, ``size`` (w, h), ``duration`` (container, s),
        ``audio_samples`` and ``audio_rate`` (0 when there is no audio).
    """
    import imageio_ffmpeg

    gen = imageio_ffmpeg.read_frames(str(path))
    meta = next(gen)
    n = sum(1 for _ in gen)
    samples, rate = read_video_audio(path)
    return {"n_frames": n, "fps": meta["fps"], "size": tuple(meta["size"]),
            "duration": meta["duration"], "audio_samples": len(samples), "audio_rate": rate}


def read_video_audio(path) -> tuple[np.ndarray, int]:
    """Decode the first audio stream of a media file to float32 mono (empty if none)."""
    from visemeface.speech.audio import read_audio

    try:
        samples, rate = read_audio(path)
    except InputError:
        return np.zeros(0, np.float32), 0
    return samples.astype(np.float32), rate


@register
class VideoSink(Sink):
    """The rendered frames as an MP4 (with the run's audio), and its mouth-box sidecar."""

    name = "video"
    option = "--output"
    metavar = "OUT.mp4"
    help = "video file to write"
    suffixes = (".mp4",)
    needs_image = True

    def __init__(self, path, force: bool = False, **settings):
        super().__init__(path, force, **settings)
        from visemeface.sidecars import video_sidecar

        self.staged.append(Staged(video_sidecar(self.path), force))

    def open(self, run) -> None:
        super().open(run)
        self._ctx = contextlib.ExitStack()
        self.writer = self._ctx.enter_context(
            VideoWriter(self.tmp[0], (run.size, run.size), run.fps, audio=run.audio, n_frames=run.n_frames,
                        force=True))

    def write(self, frame) -> None:
        self.writer.write(frame.image)

    def close(self) -> None:
        ctx, self._ctx = self._ctx, None
        ctx.close()
        from visemeface.sidecars import write_video_sidecar

        run = self.run
        if not write_video_sidecar(self.tmp[1], run.mouth_box, fps=run.fps, size=(run.size, run.size), force=True):
            self.staged.pop().abort()     # thumbnails too small to measure a mouth in: no sidecar

    def abort(self) -> None:
        ctx, self._ctx = getattr(self, "_ctx", None), None
        if ctx is not None:
            with contextlib.suppress(Exception):
                ctx.__exit__(KeyboardInterrupt, KeyboardInterrupt(), None)
        super().abort()
