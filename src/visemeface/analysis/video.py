"""Frames to analyse: video files, image folders and the mouth-box sidecar.

Sources
-------
- A video file (``.mp4``, ``.avi``, ``.mov``, ``.mkv``, ``.webm``), decoded to
  RGB by the ffmpeg that ships with imageio-ffmpeg.
- A folder of ``.png`` / ``.jpg`` / ``.jpeg`` frames, taken in *natural* order
  (``f2.png`` before ``f10.png``); all frames must have the same size.

Mouth-box sidecar (the format this project's renderer writes)
-------------------------------------------------------------
A JSON object next to the video, found as ``<video>.json`` (e.g.
``take1.mp4.json``, or ``frames.json`` for a folder ``frames/``), else
``<video stem>.json`` (``take1.json``), or given explicitly::

    {"mouth_box": [x, y, w, h],   # pixels, origin top-left, x right, y down;
                                  # x and x + w on the mouth corners at rest
     "fps": 30.0,                 # frame rate (used for image folders)
     "size": [width, height]}     # frame size in pixels, checked against the video

Only ``mouth_box`` is required. ``w`` is the natural mouth width that
normalises every metric.
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
            for buf in gen:
                yield np.frombuffer(buf, np.uint8).reshape(h, w, 3)
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
    img = cv2.imdecode(data, cv2.IMREAD_COLOR) if data.size else None
    if img is None:
        raise InputError("cannot read image", path)
    return cv2.cvtColor(img, cv2.COLOR_BGR2RGB)


def open_frames(path: str | Path, fps: float | None = None) -> FrameSource:
    """Open a video file or a folder of frames.

    Parameters
    ----------
    path : str or Path
    fps : float, optional
        Frame rate; required meaning for folders (default 30), overrides a video's.
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


def sidecar_path(video: str | Path) -> Path | None:
    """The sidecar JSON of a video or folder if one exists (see module docstring)."""
    video = Path(video)
    for cand in (video.parent / (video.name + ".json"), video.with_suffix(".json")):
        if cand.is_file() and cand != video:
            return cand
    return None


@dataclass(frozen=True)
class Sidecar:
    """Contents of a mouth-box sidecar."""

    mouth_box: MouthBox
    fps: float | None = None
    size: tuple[int, int] | None = None


def read_sidecar(path: str | Path) -> Sidecar:
    """Read a mouth-box sidecar JSON: ``{"mouth_box": [x, y, w, h], "fps": .., "size": [w, h]}``."""
    path = Path(path)
    try:
        data = json.loads(path.read_text(encoding="utf-8"))
    except FileNotFoundError:
        raise InputError("no such file", path) from None
    except (OSError, UnicodeDecodeError) as exc:
        raise InputError(f"cannot read: {exc}", path) from None
    except json.JSONDecodeError as exc:
        raise InputError(f"not valid JSON: {exc.msg}", path, exc.lineno) from None
    if not isinstance(data, dict) or "mouth_box" not in data:
        raise InputError('expected a JSON object with "mouth_box": [x, y, w, h]', path)
    try:
        box = MouthBox.of(data["mouth_box"])
    except InputError as exc:
        raise InputError(exc.reason, path) from None
    fps = data.get("fps")
    if fps is not None:
        if not isinstance(fps, (int, float)) or not fps > 0:
            raise InputError(f'"fps" must be a positive number, got {fps!r}', path)
        fps = float(fps)
    size = data.get("size")
    if size is not None:
        if (not isinstance(size, list) or len(size) != 2
                or not all(isinstance(v, int) and v > 0 for v in size)):
            raise InputError(f'"size" must be [width, height] in pixels, got {size!r}', path)
        size = (size[0], size[1])
    return Sidecar(box, fps, size)


def write_sidecar(path: str | Path, mouth_box, fps: float | None = None, size=None,
                  force: bool = False) -> None:
    """Write a mouth-box sidecar (for renderers and tests); see :func:`read_sidecar`."""
    box = MouthBox.of(mouth_box)
    data = {"mouth_box": [box.x, box.y, box.w, box.h]}
    if fps is not None:
        data["fps"] = float(fps)
    if size is not None:
        data["size"] = [int(size[0]), int(size[1])]
    with atomic_output(path, force) as tmp:
        tmp.write_text(json.dumps(data) + "\n", encoding="utf-8")
