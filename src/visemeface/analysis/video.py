"""Frames to analyse: video files, image folders and the mouth-box sidecar.

Sources
-------
- A video file (``.mp4``, ``.avi``, ``.mov``, ``.mkv``, ``.webm``), decoded to
  RGB by the ffmpeg that ships with imageio-ffmpeg.
- A folder of ``.png`` / ``.jpg`` / ``.jpeg`` frames, taken in *natural* order
  (``f2.png`` before ``f10.png``); all frames must have the same size.

Mouth-box sidecar (the format this project's renderer writes)
-------------------------------------------------------------
``<video>.json`` beside the video (``take1.mp4.json``, or ``frames.json`` for a
folder ``frames/``), or given explicitly: see :mod:`visemeface.sidecars`.
"""

from __future__ import annotations

import json
import re
from collections.abc import Iterator
from dataclasses import dataclass, field
from pathlib import Path

import cv2
import numpy as np

from visemeface.analysis.openings import MouthBox
from visemeface.errors import InputError
from visemeface.outputs import atomic_output

#: Frames a video may fall short of the count its header's duration gives before analyze warns that it is
#: truncated: the duration is rounded to a frame, and some encoders count one frame more or less.
MISSING_FRAMES_TOLERATED = 2

VIDEO_SUFFIXES = {".mp4", ".avi", ".mov", ".mkv", ".webm", ".m4v"}
IMAGE_SUFFIXES = {".png", ".jpg", ".jpeg"}


@dataclass
class FrameSource:
    """Frames of one video or image folder.

    Attributes
    ----------
    path : Path
    fps : float
        Frame rate (from the video, the sidecar, or the caller for folders).
    size : (width, height)
    n_frames : int or None
        Number of frames if known (folders; videos: an estimate).
    """

    path: Path
    fps: float
    size: tuple[int, int]
    n_frames: int | None
    files: tuple[Path, ...] = ()
    # The decoder opened by open_frames (meta already read), used by the first
    # frames() call: starting and stopping ffmpeg twice costs seconds.
    _reader: Iterator | None = field(default=None, repr=False, compare=False)
    _warned: bool = field(default=False, repr=False, compare=False)

    def close(self) -> None:
        """Stop a decoder that was opened but not read."""
        if self._reader is not None:
            self._reader.close()
            self._reader = None

    def frames(self) -> Iterator[np.ndarray]:
        """Yield RGB uint8 frames (H, W, 3) in order (a video is decoded once per call)."""
        if self.files:
            for f in self.files:
                img = _read_image(f)
                if (img.shape[1], img.shape[0]) != self.size:
                    raise InputError(f"frame is {img.shape[1]}x{img.shape[0]}, the first frame was "
                                     f"{self.size[0]}x{self.size[1]}", f)
                yield img
            return
        import imageio_ffmpeg
        w, h = self.size
        gen, self._reader = self._reader, None
        try:
            if gen is None:
                gen = imageio_ffmpeg.read_frames(str(self.path), pix_fmt="rgb24")
                next(gen)
            count = 0
            for buf in gen:
                count += 1
                yield np.frombuffer(buf, np.uint8).reshape(h, w, 3)
            if self.n_frames and count < self.n_frames - MISSING_FRAMES_TOLERATED and not self._warned:
                import warnings

                self._warned = True
                warnings.warn(f"{self.path}: read {count} of the {self.n_frames} frames its header gives "
                              f"({self.n_frames / self.fps:.2f} s): the video is truncated or damaged, and only "
                              f"its first {count / self.fps:.2f} s are measured")
        except (OSError, RuntimeError) as exc:
            raise InputError(f"cannot decode video: {_first_line(exc)}", self.path) from None
        finally:
            gen.close()


def natural_key(name: str):
    """Sort key putting ``f2`` before ``f10``."""
    return [int(p) if p.isdigit() else p.lower() for p in re.split(r"(\d+)", name)]


def _first_line(exc: BaseException) -> str:
    lines = [ln.strip() for ln in str(exc).splitlines() if ln.strip()]
    return lines[-1] if lines else type(exc).__name__


def _read_image(path: Path) -> np.ndarray:
    data = np.fromfile(path, np.uint8)
    from cv2.utils import logging as cv_log

    level = cv_log.getLogLevel()
    cv_log.setLogLevel(cv_log.LOG_LEVEL_SILENT)   # a corrupt PNG printed OpenCV's [ WARN] and libpng's [ERROR]
    try:
        img = cv2.imdecode(data, cv2.IMREAD_COLOR) if data.size else None
    finally:
        cv_log.setLogLevel(level)
    if img is None:
        raise InputError("cannot read image", path)
    return cv2.cvtColor(img, cv2.COLOR_BGR2RGB)


def open_frames(path: str | Path, fps: float | None = None) -> FrameSource:
    """Open a video file or a folder of frames.

    Parameters
    ----------
    path : str or Path
    fps : float, optional
        Frame rate: a folder of frames has none of its own (default 30); overrides a video's.
    """
    path = Path(path)
    if fps is not None and not (np.isfinite(fps) and fps > 0):
        raise InputError(f"fps must be a positive number, got {fps}")
    if not path.exists():
        raise InputError("no such file or folder", path)
    if path.is_dir():
        files = sorted((p for p in path.iterdir() if p.suffix.lower() in IMAGE_SUFFIXES and p.is_file()),
                       key=lambda p: natural_key(p.name))
        if not files:
            raise InputError("folder has no .png/.jpg frames", path)
        first = _read_image(files[0])
        return FrameSource(path, float(fps or 30.0), (first.shape[1], first.shape[0]), len(files),
                           tuple(files))
    import imageio_ffmpeg
    gen = imageio_ffmpeg.read_frames(str(path), pix_fmt="rgb24")
    try:
        meta = next(gen)
    except (OSError, RuntimeError, StopIteration) as exc:
        gen.close()
        if "does not contain any stream" in str(exc):     # ffmpeg found no video stream to decode
            raise InputError("no video stream found (audio only?)", path) from None
        raise InputError(f"cannot read video: {_first_line(exc)}", path) from None
    size = meta.get("size")
    rate = float(fps or meta.get("fps") or 0)
    if not size or not all(size) or not rate > 0:
        gen.close()
        raise InputError("no video stream found" if not size or not all(size)
                         else "video has no frame rate; give --fps", path)
    duration = meta.get("duration")
    n = int(round(duration * float(meta.get("fps") or rate))) if duration else None
    return FrameSource(path, rate, (int(size[0]), int(size[1])), n, _reader=gen)


def parse_box(text: str) -> MouthBox:
    """Parse ``"x,y,w,h"`` (pixels) into a :class:`MouthBox`."""
    parts = [p.strip() for p in str(text).split(",")]
    if len(parts) != 4:
        raise InputError(f"--box needs 4 numbers x,y,w,h, got {text!r}")
    try:
        vals = [float(p) for p in parts]
    except ValueError:
        raise InputError(f"--box needs 4 numbers x,y,w,h, got {text!r}") from None
    return MouthBox.of(vals)


# The mouth-box sidecar has one home, visemeface.sidecars; these are its names here.
from visemeface.sidecars import Sidecar  # noqa: E402,F401
from visemeface.sidecars import find_video_sidecar as sidecar_path  # noqa: E402,F401
from visemeface.sidecars import read_video_sidecar as read_sidecar  # noqa: E402,F401
from visemeface.sidecars import write_video_sidecar as write_sidecar  # noqa: E402,F401
