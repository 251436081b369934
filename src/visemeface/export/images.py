"""PNG frames: ``DIR/frame_000000.png`` ... (6 zero-padded digits, frame index from 0).

The frames sink renders into ``DIR.partial/`` (each PNG written under a
temporary name and renamed, so every ``frame_NNNNNN.png`` there is complete)
and renames it to ``DIR`` when the run commits. A hidden manifest
(``.visemeface-frames.json``) records the *render key*: a digest of everything
the pixels depend on (the motion's key, frame size, view, antialiasing). After
an interruption the partial folder is kept; a run with ``--resume`` and the same
key reads those frames back instead of rendering them again (rendering is
deterministic, so a kept frame is bit-identical to a new one). A key mismatch
is refused before any work.
"""

from __future__ import annotations

import json
import os
import shutil
import warnings
from pathlib import Path

import numpy as np

from visemeface import __version__
from visemeface.errors import InputError
from visemeface.export.sinks import Sink, register
from visemeface.outputs import Staged, atomic_dir, check_new, holds_only_ours, output_path

#: Digits of the zero-padded frame number in sequence file names.
FRAME_DIGITS = 6
MANIFEST = ".visemeface-frames.json"


def frame_name(index: int, ext: str = "png") -> str:
    """File name of frame ``index`` in an image or mesh sequence.

    >>> frame_name(12)
    'frame_000012.png'
    """
    if index < 0 or index >= 10**FRAME_DIGITS:
        raise ValueError(f"frame index {index} out of range")
    return f"frame_{index:0{FRAME_DIGITS}d}.{ext}"


def encode_png(image: np.ndarray) -> bytes:
    """PNG bytes of an RGB uint8 image (deterministic: same pixels, same bytes)."""
    import cv2

    ok, buf = cv2.imencode(".png", np.ascontiguousarray(image[..., ::-1]),
                           [cv2.IMWRITE_PNG_COMPRESSION, 1])
    if not ok:  # pragma: no cover - cv2 only fails on invalid arrays
        raise ValueError("PNG encoding failed")
    return buf.tobytes()


def write_png(path, image: np.ndarray) -> None:
    """Write an RGB uint8 image as PNG, atomically (temporary name, then rename)."""
    path = Path(path)
    tmp = path.with_name(f".{path.name}.tmp")
    tmp.write_bytes(encode_png(image))
    os.replace(tmp, path)


def read_png(path) -> np.ndarray:
    """Read a PNG as RGB uint8 (H, W, 3); :class:`InputError` if unreadable."""
    import cv2

    img = cv2.imread(str(path), cv2.IMREAD_COLOR)
    if img is None:
        raise InputError("not a readable image", path)
    return np.ascontiguousarray(img[..., ::-1])


class FolderSequence:
    """A context manager filling a folder of frame files through :func:`atomic_dir`:
    the folder appears (renamed from a temporary one) only when the block ends without error."""

    def __init__(self, folder, force: bool = False):
        self.folder = Path(folder)
        self.force = force
        self._ctx = None
        self._tmp = None

    def __enter__(self):
        self._ctx = atomic_dir(self.folder, self.force)
        self._tmp = self._ctx.__enter__()
        return self

    def __exit__(self, *exc):
        return self._ctx.__exit__(*exc)


class PngSequenceWriter(FolderSequence):
    """Write frames as ``DIR/frame_000000.png``, ``frame_000001.png``, ...

    The folder appears (atomically renamed from a temporary folder) only when
    the block ends without error.
    """

    def write(self, index: int, image: np.ndarray) -> None:
        """Write frame ``index``."""
        write_png(self._tmp / frame_name(index, "png"), image)


def _manifest_key(folder: Path) -> str | None:
    try:
        return json.loads((folder / MANIFEST).read_text())["key"]
    except (OSError, ValueError, KeyError, TypeError):
        return None


@register
class FramesSink(Sink):
    """A PNG per frame, resumable (see the module docstring)."""

    name = "frames"
    metavar = "DIR"
    help = "also write a PNG per frame (frame_000000.png, ...); resumable with --resume"
    folder = True
    needs_image = True

    def __init__(self, path, force: bool = False, resume: bool = False, **settings):
        self.path = output_path(path)
        self.partial = self.path.with_name(self.path.name + ".partial")
        self.force, self.resume, self.settings = force, resume, settings
        self.kept = 0
        self._source: Path | None = None
        self._check()
        from visemeface.sidecars import video_sidecar

        # The folder's mouth-box sidecar (frames.json), so `visemeface analyze DIR` needs no --box.
        self.staged = [Staged(video_sidecar(self.path), force or resume)]

    def _check(self) -> None:
        for cand in (self.partial, self.path):
            if cand.exists() and not cand.is_dir():
                raise InputError("exists and is not a folder", cand)
        if self.resume:
            found = [c for c in (self.partial, self.path) if c.is_dir()]
            for cand in found:
                if _manifest_key(cand) is None:
                    raise InputError("cannot resume: no visemeface frame manifest here", cand)
                if not holds_only_ours(cand):      # resuming prunes the folder to its frames: never a user's file
                    raise InputError("cannot resume: the folder holds files visemeface did not write; move them",
                                     cand)
            self._source = found[0] if found else None
        else:
            check_new(self.path, self.force, folder=True)
            if self.partial.exists() and _manifest_key(self.partial) is None:
                raise InputError("exists and was not made by visemeface; move it away", self.partial)
        check_new(self.partial, force=True, folder=True, ours=lambda p: _manifest_key(p) is not None)

    def targets(self) -> list[Path]:
        return [self.path] + [s.path for s in self.staged]

    def open(self, run) -> None:
        super().open(run)
        key = f"{run.extra.get('motion_key', '')}/{run.extra.get('render_key', '')}/{__version__}"
        if self._source is not None and _manifest_key(self._source) != key:
            raise InputError("cannot resume: these frames were rendered from another input or other settings "
                             "(remove the folder or drop --resume)", self._source)
        if self._source is None and self.partial.exists():
            shutil.rmtree(self.partial)     # a stale partial run of ours, not resumed: start afresh
        if self._source == self.path:
            self.path.rename(self.partial)  # resume from a finished run: work on it in place
        self.partial.mkdir(exist_ok=True)
        (self.partial / MANIFEST).write_text(json.dumps({"key": key, "version": __version__}))

    def cached_image(self, index: int) -> np.ndarray | None:
        if not self.resume:
            return None
        path = self.partial / frame_name(index)
        if not path.is_file():
            return None
        try:
            image = read_png(path)
        except InputError:
            return None
        if image.shape != (self.run.size, self.run.size, 3):
            return None
        self.kept += 1
        return image

    def write(self, frame) -> None:
        path = self.partial / frame_name(frame.index)
        if not (self.resume and path.is_file()):
            write_png(path, frame.image)

    def commit(self) -> list[Path]:
        n = self.run.n_frames
        for p in self.partial.iterdir():
            stem = p.name.removeprefix("frame_").removesuffix(".png")
            if p.name != MANIFEST and not (p.name.startswith("frame_") and stem.isdigit() and int(stem) < n):
                p.unlink()
        if self.path.exists():
            shutil.rmtree(self.path)
        self.partial.rename(self.path)
        return [self.path] + super().commit()

    def close(self) -> None:
        from visemeface.sidecars import write_video_sidecar

        run = self.run
        if not write_video_sidecar(self.tmp[0], run.mouth_box, fps=run.fps, size=(run.size, run.size), force=True):
            self.staged.pop().abort()     # thumbnails too small to measure a mouth in: no sidecar

    def abort(self) -> None:
        super().abort()
        if self.partial.exists():
            n = sum(1 for _ in self.partial.glob("frame_*.png"))
            then = ("rerun with --resume to continue" if getattr(self.run, "resumable", True) else
                    "to look at (a diverged run stops there again on --resume; the next run starts afresh)")
            warnings.warn(f"{n} finished frame(s) kept in {self.partial}; {then}", stacklevel=2)
