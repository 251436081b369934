"""Exports of an animation: MP4 (+ audio), PNG and OBJ sequences, PC2 point cache, glTF morphs.

Pure writers over numpy arrays: nothing here knows about phonemes or muscles.
Every writer streams (one frame in, one frame written) so that memory does
not grow with the length of the animation, and every writer produces its
file(s) under a temporary name that is renamed into place only when the
writer is closed without error (:mod:`visemeface.outputs`), so an error or
Ctrl-C never leaves half a file behind.

Formats
-------
MP4
    H.264 (libx264, yuv420p) through the ffmpeg shipped by ``imageio-ffmpeg``.
    An audio track (any format ffmpeg reads) is muxed in the same pass and
    encoded as AAC. When the number of frames ``F`` is known, the audio is
    padded with silence (``apad``) and the output is cut at ``-t F/fps``, so
    the video stream holds exactly ``F`` frames, the audio lasts exactly as
    long, and both start at ``t = 0``.
PNG / OBJ sequences
    ``frame_000000.png`` ... (6 zero-padded digits, frame index from 0 =
    the row of the activation track), written into a folder. OBJ frames share
    one topology (the same ``f`` lines in every file; only ``v`` lines change).
PC2
    The point cache read by Blender's *Mesh Cache* modifier and 3ds Max::

        char[12] "POINTCACHE2\\0"; int32 version = 1; int32 num_points;
        float32 start_frame; float32 sample_rate; int32 num_samples;
        float32 xyz[num_samples][num_points][3]

    (little-endian). ``sample_rate`` is the *interval* between samples in
    frames (1.0 = one sample a frame); the frame rate itself is not stored.
    The header is written first with ``num_samples = 0`` and patched when the
    writer closes, so frames stream to disk.
glTF binary (.glb)
    See :func:`write_morph_animation_glb`. Checked with the Khronos glTF
    validator (no errors, warnings or infos) and played with three.js's
    GLTFLoader + AnimationMixer (poses equal the rig's within 7 µm).

Using the exports
-----------------
Blender: *File > Import > glTF 2.0* gives the face with one shape key per
morph target and the speech as a shape-key action (set the scene's frame rate
to the export's). For the PC2 cache, import ``frame_000000.obj`` (the vertex
order is kept), add a *Mesh Cache* modifier (format PC2) and set its axes to
the importer's: the cache holds visemeface's raw +y-up coordinates. three.js:
``GLTFLoader`` then ``new AnimationMixer(gltf.scene).clipAction(gltf.animations[0]).play()``.
"""

from __future__ import annotations

import contextlib
import json
import os
import struct
from collections.abc import Sequence
from pathlib import Path

import numpy as np

from visemeface.errors import InputError
from visemeface.outputs import atomic_dir, atomic_output

#: Digits of the zero-padded frame number in sequence file names.
FRAME_DIGITS = 6


def frame_name(index: int, ext: str = "png") -> str:
    """File name of frame ``index`` in an image or mesh sequence.

    >>> frame_name(12)
    'frame_000012.png'
    """
    if index < 0 or index >= 10**FRAME_DIGITS:
        raise ValueError(f"frame index {index} out of range")
    return f"frame_{index:0{FRAME_DIGITS}d}.{ext}"


# --------------------------------------------------------------------------- MP4


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
        self._stack = stack
        return self

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
                with contextlib.suppress(Exception):
                    gen.close()
        except BaseException as err:
            stack.__exit__(type(err), err, err.__traceback__)
            raise
        return stack.__exit__(exc_type, exc, tb)


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
    import subprocess

    import imageio_ffmpeg

    proc = subprocess.run(
        [imageio_ffmpeg.get_ffmpeg_exe(), "-v", "error", "-i", str(path), "-vn", "-ac", "1",
         "-f", "f32le", "-acodec", "pcm_f32le", "-"], capture_output=True)
    probe = subprocess.run([imageio_ffmpeg.get_ffmpeg_exe(), "-hide_banner", "-i", str(path)],
                           capture_output=True, text=True)
    rate = 0
    for line in probe.stderr.splitlines():
        if "Audio:" in line and " Hz" in line:
            rate = int(line.split(" Hz")[0].split()[-1])
            break
    if proc.returncode != 0 or rate == 0:
        return np.zeros(0, np.float32), 0
    return np.frombuffer(proc.stdout, dtype="<f4").copy(), rate


# --------------------------------------------------------------------------- PNG


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


class _FolderSequence:
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


class PngSequenceWriter(_FolderSequence):
    """Write frames as ``DIR/frame_000000.png``, ``frame_000001.png``, ...

    The folder appears (atomically renamed from a temporary folder) only when
    the block ends without error.
    """

    def write(self, index: int, image: np.ndarray) -> None:
        """Write frame ``index``."""
        write_png(self._tmp / frame_name(index, "png"), image)


# --------------------------------------------------------------------------- OBJ


def obj_faces_text(faces: np.ndarray | Sequence[np.ndarray]) -> str:
    """The ``f`` lines of an OBJ for 0-based faces, (F, k) int arrays (k = 3 or 4)."""
    blocks = [faces] if isinstance(faces, np.ndarray) else list(faces)
    out = []
    for block in blocks:
        block = np.asarray(block, dtype=np.int64)
        if block.size == 0:
            continue
        k = block.shape[1]
        out.append((("f" + " %d" * k + "\n") * len(block)) % tuple((block + 1).ravel()))
    return "".join(out)


def obj_text(vertices: np.ndarray, faces_text: str, header: str = "") -> str:
    """An OBJ file's text: ``v`` lines (µm precision, metres) then the given ``f`` lines."""
    v = np.asarray(vertices, dtype=np.float64)
    head = f"# {header}\n" if header else ""
    return head + ("v %.6f %.6f %.6f\n" * len(v)) % tuple(v.ravel()) + faces_text


class ObjSequenceWriter(_FolderSequence):
    """Write one OBJ per frame into a folder, all with the same faces.

    Parameters
    ----------
    folder : str or Path
        Output folder (must not exist unless ``force``).
    faces : (F, k) int array or list of them
        0-based vertex indices, shared by every frame.
    """

    def __init__(self, folder, faces, force: bool = False):
        super().__init__(folder, force)
        self.faces_text = obj_faces_text(faces)

    def write(self, index: int, vertices: np.ndarray) -> None:
        """Write frame ``index`` with vertex positions (N, 3)."""
        text = obj_text(vertices, self.faces_text, header=f"visemeface frame {index}")
        (self._tmp / frame_name(index, "obj")).write_text(text)


# --------------------------------------------------------------------------- PC2

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


# --------------------------------------------------------------------------- glTF


def unit_normals(normals: np.ndarray) -> np.ndarray:
    """Normals made exactly unit length as glTF requires; zero rows (a vertex in no
    triangle) become ``+z``."""
    n = np.asarray(normals, dtype=np.float64).copy()
    length = np.linalg.norm(n, axis=1)
    bad = ~(length > 1e-12)
    n[bad] = (0.0, 0.0, 1.0)
    length[bad] = 1.0
    return n / length[:, None]


def vertex_normals(vertices: np.ndarray, triangles: np.ndarray) -> np.ndarray:
    """Unit area-weighted vertex normals (:func:`visemeface.face.mesh.vertex_normals`),
    ``+z`` for vertices in no triangle."""
    from visemeface.face.mesh import vertex_normals as area_weighted

    return unit_normals(area_weighted(np.asarray(vertices, dtype=np.float64),
                                      np.asarray(triangles, dtype=np.int64)))


def jaw_sample_weights(values: np.ndarray, samples: np.ndarray) -> np.ndarray:
    r"""Morph weights that play a nonlinear motion sampled at a few values.

    A motion :math:`D(a)` with :math:`D(0) = 0`, known at nonzero samples
    :math:`a_k`, is exported as one morph target :math:`D(a_k)` per sample. With
    the nodes :math:`s_0 < s_1 < \dots` = the samples and 0, a value
    :math:`a \in [s_{i-1}, s_i]` gets the piecewise-linear "hat" weights

    .. math:: w_{i-1} = \frac{s_i - a}{s_i - s_{i-1}}, \quad
              w_i = \frac{a - s_{i-1}}{s_i - s_{i-1}}, \quad w_j = 0 \text{ otherwise}

    (the weight of the node 0 is dropped: its target is zero), so
    :math:`\sum_k w_k D(a_k)` equals :math:`D(a)` exactly at the samples and
    interpolates it linearly between them (the chord of the jaw's arc).
    Values beyond the outer samples extrapolate along the outer chords.

    Parameters
    ----------
    values : (F,) array
        The motion's parameter per frame (e.g. jaw activation).
    samples : (K,) array
        Increasing, nonzero sample values (may be negative).

    Returns
    -------
    (F, K) float array
    """
    a = np.asarray(values, dtype=np.float64).reshape(-1)
    smp = np.asarray(samples, dtype=np.float64).reshape(-1)
    if len(smp) == 0 or np.any(np.diff(smp) <= 0) or np.any(smp == 0):
        raise ValueError("samples must be nonzero and increasing")
    zero = int(np.searchsorted(smp, 0.0))
    nodes = np.insert(smp, zero, 0.0)
    k = np.clip(np.searchsorted(nodes, a, side="right"), 1, len(nodes) - 1)  # a in [s[k-1], s[k]]
    frac = (a - nodes[k - 1]) / (nodes[k] - nodes[k - 1])
    w = np.zeros((len(a), len(nodes)))
    rows = np.arange(len(a))
    w[rows, k - 1] = 1.0 - frac
    w[rows, k] = frac
    return np.delete(w, zero, axis=1)


_FLOAT, _UINT16, _UINT32 = 5126, 5123, 5125
_ARRAY_BUFFER, _ELEMENT_ARRAY_BUFFER = 34962, 34963


class _GlbBuffer:
    """Accumulates binary data, buffer views and accessors of a single-buffer glTF."""

    def __init__(self):
        self.chunks: list[bytes] = []
        self.offset = 0
        self.views: list[dict] = []
        self.accessors: list[dict] = []

    def add(self, array: np.ndarray, type_: str, target: int | None = None,
            normalized: bool = False) -> int:
        array = np.ascontiguousarray(array)
        ctype = {np.dtype("<f4"): _FLOAT, np.dtype("<u2"): _UINT16,
                 np.dtype("<u4"): _UINT32}[array.dtype.newbyteorder("<")]
        data = array.astype(array.dtype.newbyteorder("<"), copy=False).tobytes()
        view = {"buffer": 0, "byteOffset": self.offset, "byteLength": len(data)}
        if target is not None:
            view["target"] = target
        self.views.append(view)
        pad = (-len(data)) % 4  # every view starts 4-byte aligned
        self.chunks.append(data + b"\0" * pad)
        self.offset += len(data) + pad
        ncomp = {"SCALAR": 1, "VEC3": 3, "VEC4": 4}[type_]
        flat = array.reshape(-1, ncomp)
        acc = {"bufferView": len(self.views) - 1, "componentType": ctype,
               "count": len(flat), "type": type_}
        if normalized:
            acc["normalized"] = True
        if len(flat):
            lo, hi = flat.min(axis=0), flat.max(axis=0)
            cast = float if ctype == _FLOAT else int
            acc["min"] = [cast(x) for x in lo]
            acc["max"] = [cast(x) for x in hi]
        self.accessors.append(acc)
        return len(self.accessors) - 1

    def blob(self) -> bytes:
        return b"".join(self.chunks)


def glb_bytes(gltf: dict, binary: bytes) -> bytes:
    """Pack a glTF JSON dict and its binary buffer into a GLB container (spec §4.4)."""
    js = json.dumps(gltf, separators=(",", ":")).encode("utf-8")
    js += b" " * ((-len(js)) % 4)
    binary += b"\0" * ((-len(binary)) % 4)
    total = 12 + 8 + len(js) + 8 + len(binary)
    return (struct.pack("<4sII", b"glTF", 2, total)
            + struct.pack("<I4s", len(js), b"JSON") + js
            + struct.pack("<I4s", len(binary), b"BIN\0") + binary)


def write_morph_animation_glb(path, vertices: np.ndarray, triangles: np.ndarray,
                              targets: np.ndarray, target_names: Sequence[str],
                              times: np.ndarray, weights: np.ndarray,
                              colors: np.ndarray | None = None, normals: np.ndarray | None = None,
                              name: str = "face",
                              force: bool = False) -> None:
    r"""Write a mesh with morph targets and a morph-weight animation as binary glTF 2.0.

    The animated positions are

    .. math:: x(t) = X + \sum_k w_k(t)\, T_k

    with :math:`X` the rest ``vertices``, :math:`T_k` the ``targets``
    (displacements) and :math:`w_k(t)` interpolated LINEARly between the
    keyframes ``times``. glTF's axes and units are visemeface's (metres, +y up,
    +z toward the viewer), so no conversion is applied. Target names are stored
    in ``mesh.extras.targetNames``, where Blender's importer and three.js's
    GLTFLoader read them (shape keys / ``morphTargetDictionary``).

    Parameters
    ----------
    path : str or Path
        Output ``.glb``.
    vertices : (N, 3) float
        Rest positions.
    triangles : (T, 3) int
        Counter-clockwise triangles (outward normals).
    targets : (K, N, 3) float
        Morph-target displacements.
    target_names : sequence of K str
    times : (F,) float
        Keyframe times in seconds, increasing.
    weights : (F, K) float
        Morph weights per keyframe.
    colors : (N, 3) or (N, 4), optional
        Vertex colours (floats in 0..1 or uint8), exported as ``COLOR_0``.
    normals : (N, 3), optional
        Rest vertex normals (default: area-weighted, :func:`vertex_normals`).
        Morph targets carry no normal deltas: viewers shade the moving face
        with the rest normals (a small shading error, no geometric one).
    force : bool
        Replace an existing file.
    """
    x = np.asarray(vertices, dtype=np.float64)
    tri = np.asarray(triangles, dtype=np.int64)
    tg = np.asarray(targets, dtype=np.float64)
    t = np.asarray(times, dtype=np.float64)
    w = np.asarray(weights, dtype=np.float64)
    n, k = len(x), len(tg)
    if k == 0 or tg.shape != (k, n, 3) or len(target_names) != k:
        raise ValueError(f"targets must be (K >= 1, {n}, 3) with K names")
    if w.shape != (len(t), k):
        raise ValueError(f"weights must be ({len(t)}, {k}), got {w.shape}")
    if len(t) == 0 or np.any(np.diff(t) <= 0) or not np.all(np.isfinite(t)):
        raise ValueError("keyframe times must be finite and increasing")
    if not (np.all(np.isfinite(w)) and np.all(np.isfinite(tg))):
        raise ValueError("morph targets and weights must be finite")

    buf = _GlbBuffer()
    attrs = {
        "POSITION": buf.add(x.astype("<f4"), "VEC3", _ARRAY_BUFFER),
        "NORMAL": buf.add(unit_normals(vertex_normals(x, tri) if normals is None else normals)
                          .astype("<f4"), "VEC3", _ARRAY_BUFFER),
    }
    if colors is not None:
        c = np.asarray(colors)
        c = c / 255.0 if np.issubdtype(c.dtype, np.integer) else c
        c = np.clip(c.astype(np.float64), 0.0, 1.0)
        attrs["COLOR_0"] = buf.add(c.astype("<f4"), "VEC4" if c.shape[1] == 4 else "VEC3",
                                   _ARRAY_BUFFER)
    idx_dtype = "<u2" if n <= 65535 else "<u4"
    indices = buf.add(tri.ravel().astype(idx_dtype), "SCALAR", _ELEMENT_ARRAY_BUFFER)
    target_refs = [{"POSITION": buf.add(tg[i].astype("<f4"), "VEC3", _ARRAY_BUFFER)}
                   for i in range(k)]
    t_in = buf.add(t.astype("<f4"), "SCALAR")
    w_out = buf.add(w.astype("<f4").ravel(), "SCALAR")

    gltf = {
        "asset": {"version": "2.0", "generator": "visemeface"},
        "scene": 0,
        "scenes": [{"nodes": [0]}],
        "nodes": [{"mesh": 0, "name": name}],
        "materials": [{"name": "skin", "pbrMetallicRoughness": {
            "baseColorFactor": [1.0, 1.0, 1.0, 1.0], "metallicFactor": 0.0,
            "roughnessFactor": 0.7}}],
        "meshes": [{"name": name, "primitives": [{
            "attributes": attrs, "indices": indices, "material": 0, "mode": 4,
            "targets": target_refs}],
            "weights": [0.0] * k, "extras": {"targetNames": list(map(str, target_names))}}],
        "animations": [{"name": "speech", "channels": [
            {"sampler": 0, "target": {"node": 0, "path": "weights"}}],
            "samplers": [{"input": t_in, "output": w_out, "interpolation": "LINEAR"}]}],
        "buffers": [{"byteLength": buf.offset}],
        "bufferViews": buf.views,
        "accessors": buf.accessors,
    }
    data = glb_bytes(gltf, buf.blob())
    with atomic_output(path, force) as tmp:
        tmp.write_bytes(data)
