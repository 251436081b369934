"""glTF 2.0 binary (.glb): a mesh with morph targets and a morph-weight animation.

Checked with the Khronos glTF validator (no errors, warnings or infos) and played
with three.js's GLTFLoader + AnimationMixer (poses equal the rig's within 7 µm).
Vertex colours are written linear (``COLOR_0``, as glTF defines them), the material
non-metallic; ``asset.extras`` holds the frame rate, frame count and source.
Blender: set the scene's frame rate to ``asset.extras.fps`` first, then *File > Import >
glTF 2.0* gives the face with one shape key per morph target and the speech as a
shape-key action, one key a frame plus the held last pose. three.js: ``GLTFLoader`` then
``new AnimationMixer(gltf.scene).clipAction(gltf.animations[0]).play()``.
"""

from __future__ import annotations

import json
import struct
from collections.abc import Sequence

import numpy as np

from visemeface.errors import InputError
from visemeface.export.sinks import Sink, register
from visemeface.face.normals import vertex_normals
from visemeface.muscles.morphs import JAW_SAMPLES, jaw_sample_weights, morph_weights, rig_morph_targets  # noqa: F401
from visemeface.outputs import atomic_output


def srgb_to_linear(c: np.ndarray) -> np.ndarray:
    r"""Display (sRGB-encoded) colour values in 0..1 -> linear ones, as glTF's ``COLOR_0`` holds them
    (IEC 61966-2-1): :math:`c/12.92` for :math:`c \le 0.04045`, else :math:`((c + 0.055)/1.055)^{2.4}`.
    Alpha is not encoded: give RGB only."""
    c = np.clip(np.asarray(c, dtype=np.float64), 0.0, 1.0)
    return np.where(c <= 0.04045, c / 12.92, ((c + 0.055) / 1.055) ** 2.4)


def unit_normals(normals: np.ndarray) -> np.ndarray:
    """Normals made exactly unit length as glTF requires; zero rows (a vertex in no
    triangle) become ``+z``."""
    n = np.asarray(normals, dtype=np.float64).copy()
    length = np.linalg.norm(n, axis=1)
    bad = ~(length > 1e-12)
    n[bad] = (0.0, 0.0, 1.0)
    length[bad] = 1.0
    return n / length[:, None]


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


def linear_colours(colors) -> np.ndarray:
    """Display colours (floats in 0..1 or uint8; RGB or RGBA) -> glTF's linear floats (alpha kept)."""
    c = np.asarray(colors)
    c = c / 255.0 if np.issubdtype(c.dtype, np.integer) else c
    c = np.clip(c.astype(np.float64), 0.0, 1.0)
    c[:, :3] = srgb_to_linear(c[:, :3])
    return c


def _check_animation(n: int, tg: np.ndarray, target_names, t: np.ndarray, w: np.ndarray) -> None:
    k = len(tg)
    if k == 0 or tg.shape != (k, n, 3) or len(target_names) != k:
        raise ValueError(f"targets must be (K >= 1, {n}, 3) with K names")
    if w.shape != (len(t), k):
        raise ValueError(f"weights must be ({len(t)}, {k}), got {w.shape}")
    if len(t) == 0 or np.any(np.diff(t) <= 0) or not np.all(np.isfinite(t)):
        raise ValueError("keyframe times must be finite and increasing")
    if not (np.all(np.isfinite(w)) and np.all(np.isfinite(tg))):
        raise ValueError("morph targets and weights must be finite")


def _animated_nodes(buf, name, t_in, w_out, n_keys: int, head):
    """The nodes, animation channels and samplers: the mesh's morph weights and, with ``head`` (pivot, (F, 3)
    degrees), a ``head`` node at the pivot, parent of the mesh, whose rotation is animated."""
    nodes = [{"mesh": 0, "name": name}]
    channels = [{"sampler": 0, "target": {"node": 0, "path": "weights"}}]
    samplers = [{"input": t_in, "output": w_out, "interpolation": "LINEAR"}]
    if head is None:
        return nodes, channels, samplers
    from visemeface.speech.gestures import head_quaternions

    pivot, angles = head
    angles = np.asarray(angles, dtype=np.float64).reshape(-1, 3)
    if len(angles) != n_keys:
        raise InputError(f"{len(angles)} head rotations for {n_keys} keyframes")
    pivot = [float(c) for c in pivot]
    nodes[0]["translation"] = [-c for c in pivot]
    nodes.append({"name": "head", "translation": pivot, "children": [0]})
    q_out = buf.add(head_quaternions(angles).astype("<f4"), "VEC4")
    channels.append({"sampler": 1, "target": {"node": 1, "path": "rotation"}})
    samplers.append({"input": t_in, "output": q_out, "interpolation": "LINEAR"})
    return nodes, channels, samplers


def write_morph_animation_glb(path, vertices: np.ndarray, triangles: np.ndarray,
                              targets: np.ndarray, target_names: Sequence[str],
                              times: np.ndarray, weights: np.ndarray,
                              colors: np.ndarray | None = None, normals: np.ndarray | None = None,
                              name: str = "face", extras: dict | None = None,
                              force: bool = False, head=None) -> None:
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
        Display (sRGB) vertex colours (floats in 0..1 or uint8), exported as ``COLOR_0`` in the linear
        values glTF defines (:func:`srgb_to_linear`; alpha kept).
    normals : (N, 3), optional
        Rest vertex normals (default: area-weighted, :func:`visemeface.face.normals.vertex_normals`).
        Morph targets carry no normal deltas: viewers shade the moving face
        with the rest normals (a small shading error, no geometric one).
    extras : dict, optional
        JSON-able facts about the animation (frame rate, source), stored in ``asset.extras`` and the
        scene's and animation's ``extras`` (Blender keeps the scene's as custom properties).
    force : bool
        Replace an existing file.
    head : (pivot, (F, 3) degrees), optional
        The head's rotation per keyframe (yaw, pitch, roll, :mod:`visemeface.speech.gestures`): the mesh
        node is then the child of a ``head`` node at ``pivot`` whose rotation is animated.
    """
    x = np.asarray(vertices, dtype=np.float64)
    tri = np.asarray(triangles, dtype=np.int64)
    tg = np.asarray(targets, dtype=np.float64)
    t = np.asarray(times, dtype=np.float64)
    w = np.asarray(weights, dtype=np.float64)
    n, k = len(x), len(tg)
    _check_animation(n, tg, target_names, t, w)

    buf = _GlbBuffer()
    attrs = {
        "POSITION": buf.add(x.astype("<f4"), "VEC3", _ARRAY_BUFFER),
        "NORMAL": buf.add(unit_normals(vertex_normals(x, tri) if normals is None else normals)
                          .astype("<f4"), "VEC3", _ARRAY_BUFFER),
    }
    if colors is not None:
        c = linear_colours(colors)
        attrs["COLOR_0"] = buf.add(c.astype("<f4"), "VEC4" if c.shape[1] == 4 else "VEC3", _ARRAY_BUFFER)
    idx_dtype = "<u2" if n <= 65535 else "<u4"
    indices = buf.add(tri.ravel().astype(idx_dtype), "SCALAR", _ELEMENT_ARRAY_BUFFER)
    target_refs = [{"POSITION": buf.add(tg[i].astype("<f4"), "VEC3", _ARRAY_BUFFER)}
                   for i in range(k)]
    t_in = buf.add(t.astype("<f4"), "SCALAR")
    w_out = buf.add(w.astype("<f4").ravel(), "SCALAR")

    from visemeface import __version__

    extras = dict(extras or {})
    nodes, channels, samplers = _animated_nodes(buf, name, t_in, w_out, len(t), head)
    gltf = {
        "asset": {"version": "2.0", "generator": f"visemeface {__version__}", **({"extras": extras} if extras else {})},
        "scene": 0,
        "scenes": [{"nodes": [len(nodes) - 1], **({"extras": extras} if extras else {})}],
        "nodes": nodes,
        "materials": [{"name": "skin", "pbrMetallicRoughness": {
            "baseColorFactor": [1.0, 1.0, 1.0, 1.0], "metallicFactor": 0.0,
            "roughnessFactor": 0.7}}],
        "meshes": [{"name": name, "primitives": [{
            "attributes": attrs, "indices": indices, "material": 0, "mode": 4,
            "targets": target_refs}],
            "weights": [0.0] * k, "extras": {"targetNames": list(map(str, target_names))}}],
        "animations": [{"name": "speech", **({"extras": extras} if extras else {}), "channels": channels,
                        "samplers": samplers}],
        "buffers": [{"byteLength": buf.offset}],
        "bufferViews": buf.views,
        "accessors": buf.accessors,
    }
    data = glb_bytes(gltf, buf.blob())
    with atomic_output(path, force) as tmp:
        tmp.write_bytes(data)


def write_rig_animation(path, rig, activations: np.ndarray, times: np.ndarray, force: bool = False,
                        jaw_samples: int = JAW_SAMPLES, extras: dict | None = None, head=None) -> None:
    """Write the rig's face with its morph targets and activations (F, M) at ``times`` as a .glb."""
    targets, names, samples = rig_morph_targets(rig, jaw_samples)
    face = rig.face
    write_morph_animation_glb(path, face.vertices, face.triangles, targets, names, times,
                              morph_weights(activations, rig, samples), colors=face.vertex_colors(),
                              normals=face.vertex_normals(), extras=extras, force=force, head=head)


#: ``--gltf-shapes`` choices: the rig's own functions, or a retargeting vocabulary fitted per frame.
SHAPE_SETS = ("muscles", "arkit", "vrm", "oculus")


@register
class GltfSink(Sink):
    """The rig's face with morph targets and the motion as a morph-weight animation.

    ``--gltf-shapes muscles`` (default): one morph target per muscle and sampled jaw targets, weights
    from the activation track (exact up to the jaw's chord sag). ``arkit`` (or ``vrm``, ``oculus``): the
    vocabulary's shapes named as the client expects (``jawOpen``, ...), weights fitted to each frame
    (:mod:`visemeface.retarget`). Keyframes are the frames (one a frame, LINEAR between them); the last
    frame lies up to one frame before the end of the utterance, so a final keyframe holding the last
    pose is added at ``end_time`` (``extras.heldLastKey``). ``asset.extras`` (and the scene's and the
    animation's) hold ``fps``, ``frames``, ``source``: set a client's scene to ``fps`` before importing.
    """

    name = "gltf"
    metavar = "FILE.glb"
    help = ("also write binary glTF: the face with morph targets (muscles and sampled jaw, or --gltf-shapes) "
            "and the motion as a morph-weight animation")
    suffixes = (".glb",)
    arguments = ((("--gltf-shapes",), dict(dest="gltf_shapes", choices=SHAPE_SETS, default="muscles",
                                           help="morph targets of --gltf: the rig's muscles (default) or "
                                           "ARKit/VRM/Oculus shapes with per-frame fitted weights")),)

    @property
    def shapes(self) -> str:
        return self.settings.get("gltf_shapes") or "muscles"

    def open(self, run) -> None:
        super().open(run)
        self.times, self.weights = [], []
        if self.shapes != "muscles":
            from visemeface.retarget import ShapeFit, moving_vertices, vocabulary

            self.vocab = vocabulary(self.shapes, run.rig)
            self.fit = ShapeFit(self.vocab, moving_vertices(run.rig))
            self.rest = np.asarray(run.face.vertices, dtype=np.float64)

    def write(self, frame) -> None:
        if self.shapes != "muscles":
            self.times.append(frame.time)
            self.weights.append(self.fit.frame(np.asarray(frame.vertices, dtype=np.float64) - self.rest)[0])

    def close(self) -> None:
        fitted = None
        if self.shapes != "muscles":
            fitted = (self.vocab, np.array(self.times, dtype=np.float64),
                      np.array(self.weights).reshape(len(self.weights), len(self.vocab.names)))
        write_run_glb(self.tmp[0], self.run, self.shapes, fitted)


def write_run_glb(path, run, shapes: str = "muscles", fitted=None) -> None:
    """A run's (:class:`~visemeface.export.sinks.RunInfo`) animation as a .glb, with a held last key at
    ``run.end_time`` and the run's facts in the extras (:class:`GltfSink`).

    ``fitted``: (vocabulary, frame times, (F, K) weights) for ``shapes`` other than ``muscles``.
    """
    if shapes == "muscles":
        w = run.rig.clamp(run.rig.track_matrix(run.track))
        times = run.track.index.to_numpy(dtype=np.float64)
    else:
        vocab, times, w = fitted
    held = run.end_time is not None and run.end_time > times[-1] + 1e-6
    head = run.extra.get("head")
    if head is not None:
        from visemeface.speech.gestures import head_pivot

        angles = np.asarray(head, dtype=np.float64).reshape(-1, 3)
        angles = np.vstack([angles, np.repeat(angles[-1:], max(0, len(times) - len(angles)), axis=0)])[:len(times)]
    if held:
        times = np.append(times, run.end_time)
        w = np.vstack([w, w[-1:]])
        if head is not None:
            angles = np.vstack([angles, angles[-1:]])
    head = None if head is None else (head_pivot(run.face.vertices), angles)
    extras = {"fps": run.fps, "frames": run.n_frames, "keyframes": len(times), "heldLastKey": bool(held),
              "shapes": shapes, "source": str(run.extra.get("source", "")), "interp": str(run.extra.get("interp", ""))}
    if shapes == "muscles":
        write_rig_animation(path, run.rig, w, times, force=True, extras=extras, head=head)
        return
    face = run.face
    write_morph_animation_glb(path, face.vertices, face.triangles, vocab.shapes, vocab.names, times, w,
                              colors=face.vertex_colors(), normals=face.vertex_normals(), extras=extras, force=True,
                              head=head)
