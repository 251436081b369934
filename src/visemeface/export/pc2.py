"""PC2 point caches: the format of Blender's *Mesh Cache* modifier and 3ds Max::

    char[12] "POINTCACHE2\\0"; int32 version = 1; int32 num_points;
    float32 start_frame; float32 sample_rate; int32 num_samples;
    float32 xyz[num_samples][num_points][3]

(little-endian). ``sample_rate`` is the *interval* between samples in frames
(1.0 = one sample a frame); the frame rate itself is not stored. Blender: import
``frame_000000.obj`` of ``--obj`` (default importer settings; the legacy importer needs
*Keep Vert Order*), add a Mesh Cache modifier (PC2) and leave its axes at their defaults:
0.0005 mm from the OBJ frames (tests/export/test_clients.py). The header is
written first with ``num_samples = 0`` and patched when the writer closes, so
frames stream to disk.
"""

from __future__ import annotations

import struct
from pathlib import Path

import numpy as np

from visemeface.errors import InputError
from visemeface.export.sinks import Sink, register
from visemeface.outputs import atomic_output

PC2_MAGIC = b"POINTCACHE2\0"
_PC2_HEADER = struct.Struct("<12siiffi")


class Pc2Writer:
    """Stream vertex positions into a PC2 point cache (header patched on close).

    Parameters
    ----------
    path : str or Path
        Output ``.pc2``.
    num_points : int
        Vertices per sample.
    start_frame : float
        First frame (stored in the header).
    sample_rate : float
        Interval between samples in frames (1.0 = every frame).
    """

    def __init__(self, path, num_points: int, start_frame: float = 0.0,
                 sample_rate: float = 1.0, force: bool = False):
        self.path = Path(path)
        self.num_points = int(num_points)
        self.start_frame = float(start_frame)
        self.sample_rate = float(sample_rate)
        self.force = force
        self.num_samples = 0
        self._ctx = None
        self._fh = None

    def _header(self) -> bytes:
        return _PC2_HEADER.pack(PC2_MAGIC, 1, self.num_points, self.start_frame,
                                self.sample_rate, self.num_samples)

    def __enter__(self) -> Pc2Writer:
        self._ctx = atomic_output(self.path, self.force)
        tmp = self._ctx.__enter__()
        self._fh = open(tmp, "wb")
        self._fh.write(self._header())
        return self

    def write(self, vertices: np.ndarray) -> None:
        """Append one sample of (num_points, 3) positions (stored as float32)."""
        v = np.asarray(vertices)
        if v.shape != (self.num_points, 3):
            raise ValueError(f"expected ({self.num_points}, 3) positions, got {v.shape}")
        self._fh.write(v.astype("<f4", copy=False).tobytes())
        self.num_samples += 1

    def __exit__(self, *exc):
        fh, self._fh = self._fh, None
        try:
            if exc[0] is None:
                fh.seek(0)
                fh.write(self._header())
        finally:
            fh.close()
        return self._ctx.__exit__(*exc)


def write_pc2(path, frames, start_frame: float = 0.0, sample_rate: float = 1.0,
              force: bool = False) -> None:
    """Write a (S, N, 3) array (or an iterable of (N, 3) arrays) as a PC2 file."""
    frames = iter(frames)
    first = np.asarray(next(frames))
    with Pc2Writer(path, len(first), start_frame, sample_rate, force) as pc2:
        pc2.write(first)
        for f in frames:
            pc2.write(f)


def read_pc2(path) -> tuple[np.ndarray, dict]:
    """Read a PC2 point cache.

    Returns
    -------
    points : float32 array (num_samples, num_points, 3)
        Memory-mapped from the file.
    header : dict
        ``version``, ``num_points``, ``start_frame``, ``sample_rate``, ``num_samples``.

    Raises
    ------
    InputError
        Not a PC2 file, or its size disagrees with its header.
    """
    path = Path(path)
    size = path.stat().st_size
    with open(path, "rb") as fh:
        raw = fh.read(_PC2_HEADER.size)
    if len(raw) < _PC2_HEADER.size or raw[:12] != PC2_MAGIC:
        raise InputError("not a PC2 point cache (missing POINTCACHE2 header)", path)
    _, version, npts, start, rate, nsamp = _PC2_HEADER.unpack(raw)
    expected = _PC2_HEADER.size + 12 * npts * nsamp
    if npts < 0 or nsamp < 0 or size != expected:
        raise InputError(f"PC2 size {size} bytes does not match header "
                         f"({nsamp} samples x {npts} points = {expected} bytes)", path)
    header = {"version": version, "num_points": npts, "start_frame": start,
              "sample_rate": rate, "num_samples": nsamp}
    if nsamp == 0 or npts == 0:
        return np.zeros((nsamp, npts, 3), np.float32), header
    pts = np.memmap(path, dtype="<f4", mode="r", offset=_PC2_HEADER.size,
                    shape=(nsamp, npts, 3))
    return pts, header



@register
class Pc2Sink(Sink):
    """The vertices of every frame as a PC2 point cache."""

    name = "pc2"
    metavar = "FILE.pc2"
    help = "also write a PC2 point cache (Blender Mesh Cache modifier)"
    suffixes = (".pc2",)

    def open(self, run) -> None:
        super().open(run)
        self.writer = Pc2Writer(self.tmp[0], run.face.n_vertices, force=True).__enter__()

    def write(self, frame) -> None:
        self.writer.write(frame.vertices)

    def close(self) -> None:
        writer, self.writer = self.writer, None
        writer.__exit__(None, None, None)

    def abort(self) -> None:
        writer, self.writer = getattr(self, "writer", None), None
        if writer is not None:
            writer.__exit__(KeyboardInterrupt, KeyboardInterrupt(), None)
        super().abort()
