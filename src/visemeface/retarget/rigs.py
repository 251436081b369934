r"""A character's own blendshape rig as the target of the ARKit weights.

ARKit's 52 blendshapes are defined by what they do on a face, not by any one mesh. To write weights that
mean on a user's character what they mean in ARKit, the motion is carried to a rig *made to that
definition* and fitted onto its shapes:

1. our muscles are placed on the rig's neutral mesh (the rig file reads landmarks, so it fits any head),
2. each frame's activations pose that mesh (the same muscles, jaw and lips as on our face),
3. the displacement is fitted onto the rig's own shapes, :class:`~visemeface.retarget.fit.ShapeFit`, with
   ``mouthClose`` held to at most ``jawOpen`` (ARKit's ``mouthClose`` closes the lips *of an open jaw*; alone it
   pushes the lower lip through the upper one),
4. the weights are written under ARKit's names (a rig's ``mouthSmile_L`` is ARKit's ``mouthSmileLeft``).

Without a rig of the user's (``--arkit-rig``) the reference is the ICT Face Model's 53 artist-made shapes
(:mod:`visemeface.face.ict`), so the default weights are sized to an ARKit rig's, not to our face's.

A rig is a ``.glb``/``.gltf`` with morph targets (Ready Player Me, VRM and Blender exports keep the target
names in ``mesh.extras.targetNames``) or a folder of OBJs of one topology, one of them the neutral
(``*neutral*.obj``, ICT-FaceKit's layout). Its landmarks come from ``<neutral>.landmarks.json`` beside it, or,
for ICT's topology, from ICT's own landmark vertices.
"""

from __future__ import annotations

import functools
import json
import re
import struct
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from visemeface.errors import InputError
from visemeface.face.ict import Blendshapes

#: ARKit's corrective pairs: the corrective's weight never exceeds its base's.
CORRECTIVES = {"mouthClose": "jawOpen"}
#: ARKit shapes that rigs often split in two halves (ICT: browInnerUp_L/_R); ARKit's weight is their mean.
SPLIT_PAIRS = ("browInnerUp", "cheekPuff")


def arkit_names() -> list[str]:
    """ARKit's 52 blendshape names in Live Link Face's order (``data/retarget/arkit.csv``)."""
    from visemeface.retarget.recipes import _rows

    return [r["name"] for r in _rows("arkit.csv")[1]]


def canonical(name: str) -> str:
    """A rig's shape name in ARKit's spelling: ``mouthSmile_L`` / ``MouthSmileLeft`` /
    ``blendShape1.mouthSmile_L`` -> ``mouthSmileLeft``; ``browInnerUp_L`` stays (a half of ``browInnerUp``)."""
    n = name.split(".")[-1].split(":")[-1].strip()
    n = re.sub(r"^(ARKit|arkit)[_-]?", "", n)
    m = re.match(r"^(.*?)[_ ]?(L|R|Left|Right|left|right)$", n)
    base, side = (m.group(1), m.group(2)) if m else (n, "")
    base = base[:1].lower() + base[1:]
    if base in SPLIT_PAIRS and side:
        return f"{base}_{side[0].upper()}"
    return base + {"L": "Left", "R": "Right", "left": "Left", "right": "Right"}.get(side, side)


@dataclass
class ClientRig:
    """A blendshape rig our motion is fitted onto.

    Attributes
    ----------
    name : str
    face : FaceMesh
        Its neutral mesh with our landmarks and regions (metres, our axes).
    shapes : Blendshapes
        Its shapes (its own names), displacements from the neutral in metres.
    scale : float
        Metres per unit of the rig's file (0.01 for ICT's centimetres).
    """

    name: str
    face: object
    shapes: Blendshapes
    scale: float = 1.0
    _cache: dict = field(default_factory=dict, repr=False)

    def rig(self, rig_file=None):
        """Our muscles placed on the neutral (the run's rig file; default ``data/rig/default.toml``)."""
        from visemeface.muscles.rig import MuscleRig

        key = ("rig", str(rig_file))
        if key not in self._cache:
            self._cache[key] = MuscleRig.from_file(self.face, rig_file)
        return self._cache[key]

    def mask(self) -> np.ndarray:
        """The vertices fitted: those a shape moves, less the mouth's interior (teeth, gums, tongue, socket)."""
        moving = np.abs(self.shapes.deltas).max(axis=(0, 2)) > 1e-5
        moving[self.face.regions.get("mouth_cavity", np.empty(0, np.int64))] = False
        moving[self.face.regions.get("scalp", np.empty(0, np.int64))] = False
        return moving

    def vocabulary(self):
        from visemeface.retarget.recipes import Vocabulary

        k = len(self.shapes.names)
        return Vocabulary(self.name, list(self.shapes.names), self.shapes.deltas, np.zeros((k, 0)),
                          np.ones(k, bool), False, ["" for _ in range(k)])

    def fit(self):
        """The :class:`~visemeface.retarget.fit.ShapeFit` onto its shapes (factored once)."""
        from visemeface.retarget.fit import ShapeFit

        if "fit" not in self._cache:
            names = [canonical(n) for n in self.shapes.names]
            corr = {self.shapes.names[names.index(c)]: self.shapes.names[names.index(b)]
                    for c, b in CORRECTIVES.items() if c in names and b in names}
            self._cache["fit"] = ShapeFit(self.vocabulary(), self.mask(), corr)
        return self._cache["fit"]

    def track_weights(self, activations: np.ndarray, rig_file=None) -> tuple[np.ndarray, np.ndarray]:
        r"""Weights (F, K) on the rig's shapes and residuals (F,) (m) of our muscles posing its neutral with
        ``activations`` (F, M+1) (the run rig's ``names`` order, clamped).

        The pose is linear in the rig's coefficients :math:`\mathbf c(\mathbf a)` (muscles, then powers of
        the jaw angle): :math:`d = M^\top \mathbf c`, so :math:`Bd = (BM^\top)\mathbf c` and
        :math:`d^\top d = \mathbf c^\top (MM^\top) \mathbf c` come from two small matrices made once, and a
        frame costs a few thousand multiplications however many vertices the rig has.
        """
        rig, fit = self.rig(rig_file), self.fit()
        key = ("projection", str(rig_file))
        if key not in self._cache:
            cols = np.flatnonzero(np.repeat(fit.mask, 3))
            M = rig._matrix[:, cols].astype(np.float64)          # (rows, 3 * measured)
            self._cache[key] = (M @ fit.B.T, M @ M.T)
        P, Q = self._cache[key]
        A = np.atleast_2d(np.asarray(activations, dtype=np.float64))
        C = rig._coefficients(np.clip(A, rig.ranges[:, 0], rig.ranges[:, 1])).astype(np.float64)
        W, R = np.zeros((len(A), len(self.shapes.names))), np.zeros(len(A))
        for f, c in enumerate(C):
            W[f], R[f] = fit.solve(c @ P, float(c @ Q @ c))
        return W, R

    def arkit_map(self) -> tuple[list[str], np.ndarray, list[str]]:
        """``(names, M, missing)``: ARKit's 52 names, the (52, K) matrix taking the rig's weights to them
        (a split pair averaged) and the ARKit names the rig has no shape for."""
        names = arkit_names()
        own = [canonical(n) for n in self.shapes.names]
        M = np.zeros((len(names), len(own)))
        missing = []
        for i, a in enumerate(names):
            hits = [j for j, o in enumerate(own) if o == a]
            if not hits and a in SPLIT_PAIRS:
                hits = [j for j, o in enumerate(own) if o in (f"{a}_L", f"{a}_R")]
            if hits:
                M[i, hits] = 1.0 / len(hits)
            else:
                missing.append(a)
        return names, M, missing

    def extra_shapes(self) -> list[int]:
        """The rig's shapes with no ARKit name (written under their own names beside ARKit's)."""
        known = set(arkit_names()) | {f"{a}_{s}" for a in SPLIT_PAIRS for s in "LR"}
        return [j for j, n in enumerate(self.shapes.names) if canonical(n) not in known]


# ---------------------------------------------------------------------------------------------- readers
def _units(face_vertices: np.ndarray, left: int, right: int, path) -> float:
    """Metres per file unit, from the mouth's width (3-8 cm at rest): 1, 0.01 (cm) or 0.001 (mm)."""
    w = float(np.linalg.norm(face_vertices[left] - face_vertices[right]))
    for scale in (1.0, 0.01, 0.001):
        if 0.03 <= w * scale <= 0.08:
            return scale
    raise InputError(f"the mouth is {w:.4g} file units wide, not 3-8 cm in metres, centimetres or millimetres: "
                     "check the landmarks' mouth corners and the mesh's units", path)


def _finite(a: np.ndarray, what: str, path) -> np.ndarray:
    if not np.all(np.isfinite(a)):
        raise InputError(f"{what} holds non-finite coordinates", path)
    return a


def _read_obj_positions(path: Path, colours: bool = False):
    """``(vertices, faces)`` of an OBJ as written (no vertex split at texture seams); with ``colours`` also
    its vertex colours (``v x y z r g b``, 0..1 or 0..255), or None when not every vertex has them."""
    verts, faces, rgb = [], [], []
    try:
        with open(path, encoding="utf-8", errors="replace") as fh:
            for line in fh:
                if line.startswith("v "):
                    parts = line.split()
                    verts.append(parts[1:4])
                    if colours and len(parts) >= 7:
                        rgb.append(parts[4:7])
                elif line.startswith("f "):
                    faces.append([int(t.split("/")[0]) - 1 for t in line.split()[1:]])
        v = np.asarray(verts, dtype=np.float64).reshape(-1, 3)
        c = np.asarray(rgb, dtype=np.float64).reshape(-1, 3) if rgb and len(rgb) == len(verts) else None
    except (ValueError, OSError) as exc:
        raise InputError(f"not a readable OBJ ({exc})", path) from None
    v = _finite(v, "the mesh", path)
    if not colours:
        return v, faces
    if c is not None and (not np.all(np.isfinite(c)) or c.min() < 0):
        c = None
    elif c is not None and c.max() > 1.0:
        c = np.clip(c / 255.0, 0.0, 1.0)
    return v, faces, c


_COMPONENTS = {5120: np.int8, 5121: np.uint8, 5122: np.int16, 5123: np.uint16, 5125: np.uint32, 5126: np.float32}
_WIDTH = {"SCALAR": 1, "VEC2": 2, "VEC3": 3, "VEC4": 4}


def _gltf(path: Path) -> tuple[dict, bytes]:
    data = path.read_bytes()
    if path.suffix.lower() == ".glb":
        if len(data) < 20 or data[:4] != b"glTF":
            raise InputError("not a binary glTF (no 'glTF' header)", path)
        off, doc, binary = 12, None, b""
        while off + 8 <= len(data):
            length, kind = struct.unpack_from("<II", data, off)
            chunk = data[off + 8: off + 8 + length]
            if kind == 0x4E4F534A:
                doc = json.loads(chunk.decode("utf-8"))
            elif kind == 0x004E4942:
                binary = chunk
            off += 8 + length
        if doc is None:
            raise InputError("binary glTF without its JSON chunk", path)
        return doc, binary
    doc = json.loads(data.decode("utf-8"))
    uri = (doc.get("buffers") or [{}])[0].get("uri", "")
    if uri.startswith("data:"):
        import base64

        return doc, base64.b64decode(uri.split(",", 1)[1])
    return doc, (path.parent / uri).read_bytes() if uri else b""


def _accessor(doc: dict, binary: bytes, i: int) -> np.ndarray:
    acc = doc["accessors"][i]
    dtype, width, count = _COMPONENTS[acc["componentType"]], _WIDTH[acc["type"]], acc["count"]
    out = np.zeros((count, width), dtype=np.float64)
    if "bufferView" in acc:
        view = doc["bufferViews"][acc["bufferView"]]
        start = view.get("byteOffset", 0) + acc.get("byteOffset", 0)
        item = np.dtype(dtype).itemsize * width
        stride = view.get("byteStride", item)
        raw = np.frombuffer(binary, dtype=np.uint8, count=stride * (count - 1) + item, offset=start)
        rows = np.lib.stride_tricks.as_strided(raw, shape=(count, item), strides=(stride, 1))
        out = np.frombuffer(rows.tobytes(), dtype=dtype).reshape(count, width).astype(np.float64)
    sparse = acc.get("sparse")
    if sparse:
        iv, vv = sparse["indices"], sparse["values"]
        n = sparse["count"]
        view = doc["bufferViews"][iv["bufferView"]]
        idx = np.frombuffer(binary, dtype=_COMPONENTS[iv["componentType"]], count=n,
                            offset=view.get("byteOffset", 0) + iv.get("byteOffset", 0))
        view = doc["bufferViews"][vv["bufferView"]]
        val = np.frombuffer(binary, dtype=dtype, count=n * width,
                            offset=view.get("byteOffset", 0) + vv.get("byteOffset", 0)).reshape(n, width)
        out[idx.astype(np.int64)] = val
    return out


def read_gltf_morphs(path) -> tuple[np.ndarray, np.ndarray, list[str], np.ndarray]:
    """``(vertices (N, 3), triangles (T, 3), target names, targets (K, N, 3))`` of the first mesh with morph
    targets in a ``.glb``/``.gltf`` (its primitives' vertices concatenated in order; node transforms ignored)."""
    path = Path(path)
    try:
        doc, binary = _gltf(path)
        meshes = [m for m in doc.get("meshes", []) if any(p.get("targets") for p in m.get("primitives", []))]
        if not meshes:
            raise InputError("the glTF has no mesh with morph targets (blendshapes)", path)
        mesh = meshes[0]
        names = list((mesh.get("extras") or {}).get("targetNames") or [])
        verts, tris, targets, base = [], [], None, 0
        for prim in mesh["primitives"]:
            v = _accessor(doc, binary, prim["attributes"]["POSITION"])
            ts = prim.get("targets") or []
            if targets is None:
                targets = [[] for _ in ts]
                names = names or [f"target{i}" for i in range(len(ts))]
            if len(ts) != len(targets):
                raise InputError("the mesh's primitives have different numbers of morph targets", path)
            for k, t in enumerate(ts):
                targets[k].append(_accessor(doc, binary, t["POSITION"]) if "POSITION" in t else np.zeros_like(v))
            idx = (_accessor(doc, binary, prim["indices"]).astype(np.int64).reshape(-1, 3) if "indices" in prim
                   else np.arange(len(v)).reshape(-1, 3))
            verts.append(v)
            tris.append(idx + base)
            base += len(v)
    except (KeyError, IndexError, ValueError, TypeError, UnicodeDecodeError, struct.error) as exc:
        raise InputError(f"not a readable glTF mesh ({type(exc).__name__}: {exc})", path) from None
    V = _finite(np.concatenate(verts), "the mesh", path)
    T = np.stack([np.concatenate(t) for t in targets])
    _finite(T, "a morph target", path)
    if len(names) != len(T):
        raise InputError(f"{len(names)} target names for {len(T)} morph targets", path)
    return V, np.concatenate(tris), names, T


def _ict_topology_face(vertices: np.ndarray, path) -> tuple[object, float]:
    """A FaceMesh of a mesh in ICT's topology (its first 24,591 vertices), with ICT's landmarks found on it."""
    from visemeface.face import ict

    s = ict._store()
    lm = s["multi_pie_68"].astype(np.int64)
    scale = _units(vertices, lm[54], lm[48], path)
    V = vertices[: len(s["vertices"])] * scale
    return ict.face_on(V - V[[lm[48], lm[54]]].mean(axis=0)), scale


def _with_landmarks(vertices: np.ndarray, triangles: np.ndarray, sidecar: Path, path) -> tuple[object, float]:
    from visemeface.face.mesh import FaceMesh, _read_sidecar

    landmarks, regions, quads, rig = _read_sidecar(sidecar, vertices)
    for need in ("mouth_corner_left", "mouth_corner_right"):
        if need not in landmarks:
            raise InputError(f"the landmarks file has no {need!r}", sidecar)
    scale = _units(vertices, landmarks["mouth_corner_left"], landmarks["mouth_corner_right"], sidecar)
    V = vertices * scale
    return FaceMesh(V, np.zeros((0, 4), np.int64), triangles, regions, landmarks,
                    landmarks_file=str(sidecar), rig_defaults=rig), scale


def load_client_rig(path) -> ClientRig:
    """Read a character's blendshape rig (see the module docstring); :class:`InputError` on bad input."""
    from visemeface.sidecars import landmarks_sidecar

    path = Path(path)
    if not path.exists():
        raise InputError("rig not found", path)
    if path.is_dir():
        objs = sorted(p for p in path.glob("*.obj") if not p.stem.startswith("identity"))
        neutral = [p for p in objs if "neutral" in p.stem.lower()]
        if len(neutral) != 1:
            raise InputError("a rig folder needs exactly one neutral mesh (an OBJ named *neutral*.obj); found "
                             + (", ".join(p.name for p in neutral) or "none"), path)
        V, faces = _read_obj_positions(neutral[0])
        shapes, names = [], []
        for p in objs:
            if p == neutral[0]:
                continue
            v, _ = _read_obj_positions(p)
            if v.shape != V.shape:
                raise InputError(f"{len(v)} vertices where the neutral has {len(V)}: every shape needs the "
                                 "neutral's topology", p)
            shapes.append(v - V)
            names.append(p.stem)
        if not shapes:
            raise InputError("the rig folder has a neutral but no shapes", path)
        T = np.stack(shapes)
        tris = np.array([[f[0], f[i], f[i + 1]] for f in faces for i in range(1, len(f) - 1)],
                        dtype=np.int64).reshape(-1, 3)
        sidecar = landmarks_sidecar(neutral[0])
        name = path.name
    elif path.suffix.lower() in (".glb", ".gltf"):
        V, tris, names, T = read_gltf_morphs(path)
        sidecar = landmarks_sidecar(path)
        name = path.stem
    else:
        raise InputError("a rig is a .glb/.gltf with morph targets or a folder of OBJ shapes", path)
    if tris.size and (tris.min() < 0 or tris.max() >= len(V)):
        raise InputError("face indices out of range", path)
    from visemeface.face.ict import _store

    if sidecar.exists():
        face, scale = _with_landmarks(V, tris, sidecar, path)
        T = T * scale
    elif len(V) >= len(_store()["vertices"]) and _is_ict_topology(V):
        face, scale = _ict_topology_face(V, path)
        T = T[:, : face.n_vertices] * scale
    else:
        raise InputError(f"no landmarks for the rig: put {sidecar.name} beside it (the mouth corners, nasion, "
                         "chin ... as vertex indices; see the face command's --landmarks)", path)
    return ClientRig(name, face, Blendshapes(list(names), T.astype(np.float32)), scale)


def _is_ict_topology(vertices: np.ndarray) -> bool:
    """Whether a mesh is in ICT's topology: its Multi-PIE landmarks fall where ICT's lie (up to a scale)."""
    from visemeface.face.ict import _store

    s = _store()
    lm = s["multi_pie_68"].astype(np.int64)
    if len(vertices) < len(s["vertices"]):
        return False
    a, b = s["vertices"][lm].astype(np.float64), vertices[lm]
    a, b = a - a.mean(0), b - b.mean(0)
    na, nb = np.linalg.norm(a), np.linalg.norm(b)
    return nb > 0 and float(np.linalg.norm(a / na - b / nb)) < 0.1


@functools.lru_cache(maxsize=1)
def _reference() -> ClientRig:
    from visemeface.face.ict import ict_expressions, ict_face

    return ClientRig("ict", ict_face(), ict_expressions(), 0.01)


def reference_rig() -> ClientRig:
    """The ICT Face Model's 53 shapes: the reference ARKit rig of the default weights (built once)."""
    return _reference()
