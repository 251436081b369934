"""The face surface: vertices, quads, named regions and landmarks, and its files.

A :class:`FaceMesh` is the one geometry every stage shares. Quads (not only
triangles) are kept so that the surface can later be extruded into hexahedra;
``triangles`` splits them for rendering. Regions are sorted vertex-index
arrays; landmarks are single vertex indices.

Files
-----
The surface is written through trimesh (OBJ, PLY, GLB/glTF by suffix) with
per-vertex colours, beside a JSON sidecar ``<stem>.landmarks.json``::

    {"format": "visemeface-landmarks", "version": 1,
     "landmarks": {"nose_tip": 1234, "chin": [0.0, -0.04, 0.01], ...},
     "regions": {"upper_lip": [..], ...},
     "quads": [[a, b, c, d], ...]}          # optional

A landmark may be a vertex index or an ``[x, y, z]`` position, which is
snapped to the nearest vertex. ``quads`` lets a file that only stores
triangles give its quads back; a user's mesh without them loads with no quads.
"""

from __future__ import annotations

import io
import json
import re
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from visemeface.errors import InputError
from visemeface.outputs import atomic_output

#: Landmark names of docs/conventions.md.
LANDMARK_NAMES = (
    "mouth_corner_left", "mouth_corner_right", "upper_lip_mid", "lower_lip_mid",
    "upper_lip_top", "lower_lip_bottom", "chin", "nose_tip",
    "brow_inner_left", "brow_inner_right", "brow_outer_left", "brow_outer_right",
    "jaw_joint_left", "jaw_joint_right", "eye_centre_left", "eye_centre_right",
    "cheek_left", "cheek_right", "nasion",
)
#: Landmarks of a mouth interior (the default face has them; a user's mesh may): the
#: incisal edges' centres and the tongue's tip and highest point at rest.
INTERIOR_LANDMARKS = ("upper_incisor_edge", "lower_incisor_edge", "tongue_tip", "tongue_dorsum")

#: Linear-RGB-ish display colours (0..1) used when a mesh carries none.
SKIN = np.array([0.86, 0.66, 0.55])
LIP = np.array([0.74, 0.40, 0.40])
CAVITY = np.array([0.10, 0.025, 0.03])
EYE = np.array([0.90, 0.89, 0.86])

MESH_SUFFIXES = (".obj", ".ply", ".glb", ".gltf")


from visemeface.sidecars import landmarks_sidecar as sidecar_path  # noqa: E402  (the one rule, re-exported)
from visemeface.face.normals import NormalAccumulator, unit_rows  # noqa: E402


def split_quads(quads: np.ndarray) -> np.ndarray:
    """Split quads ``(a, b, c, d)`` into triangles ``(a, b, c)``, ``(a, c, d)``.

    Both triangles keep the quad's counter-clockwise order, so their normals
    point the same way as the quad's.
    """
    quads = np.asarray(quads, dtype=np.int64).reshape(-1, 4)
    tris = np.empty((2 * len(quads), 3), dtype=np.int64)
    tris[0::2] = quads[:, [0, 1, 2]]
    tris[1::2] = quads[:, [0, 2, 3]]
    return tris


#: The rig defaults of a face read from a mesh file (and of the ICT head): the mouth corners move as one piece
#: within 0.2 mouth widths, fully within 0.3 of that (the rig file's ``[modiolus]``,
#: :func:`visemeface.muscles.functions.modiolus_blend`). At each corner the muscles of cheek and lips insert into
#: the modiolus, a knot about 1 cm across (Standring 2016): 0.2 W of a 5 cm mouth. A scan's lip rows converge on
#: each corner a fraction of a millimetre apart, and without it they pass each other and fold (ICT's head: 64
#: triangles beside the corners turned over on /aa/; its OBJ prepared by ``face --prepare``, a lip stretched 8.2
#: times, 2.8 with it). The procedural face goes without (docs/notes/mouth_corners.md).
MESH_RIG_DEFAULTS = {"modiolus": {"radius": 0.2, "core": 0.3,
                                  "exclude": ["eyes", "eyeballs", "upper_teeth", "lower_teeth", "upper_gum",
                                              "lower_gum", "tongue"]}}


@dataclass
class FaceMesh:
    """A face surface with named vertex regions and landmarks.

    Parameters
    ----------
    vertices : (N, 3) float64
        Rest positions in metres (+x subject's left, +y up, +z forward).
    quads : (Q, 4) int64
        Counter-clockwise seen from outside.
    tris : (T, 3) int64
        Extra triangles that are not part of a quad (e.g. an eye's pupil fan).
    regions : dict[str, ndarray]
        Name -> sorted unique int64 vertex indices.
    landmarks : dict[str, int]
        Name -> vertex index.
    colors : (N, 3) float, optional
        Display colours in 0..1; derived from the regions when absent.
    """

    vertices: np.ndarray
    quads: np.ndarray
    tris: np.ndarray = field(default_factory=lambda: np.zeros((0, 3), np.int64))
    regions: dict = field(default_factory=dict)
    landmarks: dict = field(default_factory=dict)
    colors: np.ndarray | None = None
    #: Where the landmarks came from (a ``.landmarks.json``), named in errors; None for a built face.
    landmarks_file: str | None = None
    #: A refined face (:func:`visemeface.face.refine.lip_refinement`) is shaded as the face it refines:
    #: ``(P, parent)``, its normals those of its first N vertices on ``parent``'s triangles, interpolated by
    #: the sparse (N', N) ``P`` that made its vertices (see :meth:`normal_accumulator`); None: its own.
    shading_parent: tuple | None = field(default=None, repr=False, compare=False)
    #: Rig-file values this face needs where the rig file leaves them out, ``{table: {key: value}}``: a
    #: scanned head with a neck sets ``{"jaw": {"neck_fade_deg": ...}}`` (:func:`visemeface.face.ict.ict_face`).
    rig_defaults: dict = field(default_factory=dict, repr=False, compare=False)

    def __post_init__(self):
        self.vertices = np.ascontiguousarray(self.vertices, dtype=np.float64).reshape(-1, 3)
        self.quads = np.ascontiguousarray(self.quads, dtype=np.int64).reshape(-1, 4)
        self.tris = np.ascontiguousarray(self.tris, dtype=np.int64).reshape(-1, 3)
        self.regions = {k: np.unique(np.asarray(v, dtype=np.int64)) for k, v in self.regions.items()}
        self.landmarks = {k: int(v) for k, v in self.landmarks.items()}
        if self.colors is not None:
            self.colors = np.asarray(self.colors, dtype=np.float64).reshape(-1, 3)
        n = len(self.vertices)
        for name, idx in [("quads", self.quads), ("tris", self.tris)]:
            if idx.size and (idx.min() < 0 or idx.max() >= n):
                raise ValueError(f"{name} index out of range for {n} vertices")

    @property
    def n_vertices(self) -> int:
        return len(self.vertices)

    @property
    def triangles(self) -> np.ndarray:
        """(2Q + T, 3) int64: the quads split (see :func:`split_quads`), then ``tris``."""
        return np.concatenate([split_quads(self.quads), self.tris])

    def region(self, name: str) -> np.ndarray:
        """Vertex indices of region ``name`` (InputError with a hint if unknown)."""
        from visemeface.errors import close_matches
        try:
            return self.regions[name]
        except KeyError:
            raise InputError(f"unknown region {name!r}" + close_matches(name, self.regions)) from None

    def landmark_position(self, name: str, vertices: np.ndarray | None = None) -> np.ndarray:
        """Position of landmark ``name`` in ``vertices`` (rest positions if None)."""
        from visemeface.errors import close_matches
        if name not in self.landmarks:
            raise InputError(f"unknown landmark {name!r}" + close_matches(name, self.landmarks))
        v = self.vertices if vertices is None else vertices
        return np.asarray(v[self.landmarks[name]], dtype=np.float64)

    def shading_groups(self) -> np.ndarray:
        """Per-vertex smoothing group: 1 for the mouth cavity, 0 elsewhere."""
        g = np.zeros(self.n_vertices, np.int8)
        if "mouth_cavity" in self.regions:
            g[self.regions["mouth_cavity"]] = 1
        return g

    def normal_accumulator(self):
        """The per-frame normals of this face's vertices (:class:`NormalAccumulator`, by smoothing group).

        A refined face (:attr:`shading_parent`) takes its parent's normals interpolated as its vertices
        were: at rest the same smooth shading as the unrefined face. Its own thin strips, shaded
        directly, show the creases between the parent's bilinear quads (up to 10° on the default face)
        as streaks one strip wide, which the parent's coarse interpolation hides.
        """
        if self.shading_parent is None:
            return NormalAccumulator(self.triangles, self.n_vertices, self.shading_groups())
        P, parent = self.shading_parent
        coarse, n = parent.normal_accumulator(), parent.n_vertices

        def normals(vertices, dtype=np.float64, lengths=None):
            v = np.asarray(vertices)
            own = None if lengths is None else np.empty(n)
            out = unit_rows(P @ coarse(v[:n], dtype=np.float64, lengths=own)).astype(dtype, copy=False)
            if lengths is not None:
                lengths[:] = P @ own          # the parent's, interpolated as the vertices were
            return out

        return normals

    def vertex_normals(self, vertices: np.ndarray | None = None) -> np.ndarray:
        """Unit vertex normals of ``vertices`` (rest positions if None), by smoothing group."""
        return self.normal_accumulator()(self.vertices if vertices is None else vertices)

    def vertex_colors(self) -> np.ndarray:
        """(N, 3) float32 display colours: skin, redder lips, dark mouth cavity, pale eyes.

        The mesh's own ``colors`` when it has them, otherwise derived from the
        ``upper_lip``/``lower_lip``, ``eyes`` and ``mouth_cavity`` regions.
        """
        if self.colors is not None:
            return self.colors.astype(np.float32)
        c = np.tile(SKIN, (self.n_vertices, 1))
        for name, colour in [("upper_lip", LIP), ("lower_lip", LIP), ("eyes", EYE),
                             ("mouth_cavity", CAVITY)]:
            if name in self.regions:
                c[self.regions[name]] = colour
        return c.astype(np.float32)

    def boundary_edges(self) -> np.ndarray:
        """(E, 2) vertex pairs of edges used by exactly one triangle/quad side."""
        # Quad diagonals are interior to a quad, so count quad sides and extra tris' sides only.
        q = self.quads
        edges = [q[:, [0, 1]], q[:, [1, 2]], q[:, [2, 3]], q[:, [3, 0]],
                 self.tris[:, [0, 1]], self.tris[:, [1, 2]], self.tris[:, [2, 0]]]
        e = np.concatenate(edges)
        key = np.sort(e, axis=1)
        uniq, counts = np.unique(key, axis=0, return_counts=True)
        return uniq[counts == 1]

    # ------------------------------------------------------------------ files
    def sidecar(self) -> dict:
        """The JSON-able landmarks/regions/quads record written beside the mesh."""
        return {
            "format": "visemeface-landmarks",
            "version": 1,
            "landmarks": dict(self.landmarks),
            "regions": {k: v.tolist() for k, v in self.regions.items()},
            "quads": self.quads.tolist(),
            "n_vertices": self.n_vertices,
            "rig_defaults": self.rig_defaults,
        }

    def to_trimesh(self):
        """A ``trimesh.Trimesh`` (process=False keeps vertex order) with vertex colours."""
        import trimesh
        rgba = np.concatenate([np.clip(self.vertex_colors(), 0, 1) * 255,
                               np.full((self.n_vertices, 1), 255)], axis=1).round().astype(np.uint8)
        return trimesh.Trimesh(self.vertices, self.triangles, vertex_colors=rgba, process=False)

    def save(self, path: str | Path, force: bool = False) -> tuple[Path, Path]:
        """Write the surface (format by suffix: .obj .ply .glb .gltf) and its sidecar.

        Both files go through :func:`visemeface.outputs.atomic_output`; nothing is
        overwritten unless ``force``. Returns ``(mesh_path, sidecar_path)``.
        """
        path = Path(path)
        suffix = path.suffix.lower()
        if suffix not in MESH_SUFFIXES:
            raise InputError(f"unknown mesh format {path.suffix!r} (use one of {', '.join(MESH_SUFFIXES)})",
                             path)
        side = sidecar_path(path)
        tm = self.to_trimesh()
        text = json.dumps(self.sidecar(), separators=(",", ":"))
        # The same landmarks already beside it (this face saved in another format, head.obj then head.glb):
        # kept, not a clash.
        same = side.is_file() and side.read_text(errors="replace") == text
        # Check both targets before writing either, so a refusal leaves no half pair.
        from visemeface.outputs import check_new
        check_new(path, force)
        if not same:
            check_new(side, force)
        with atomic_output(path, force) as tmp:
            if suffix == ".obj":
                data = tm.export(file_type="obj", include_color=True, include_normals=False,
                                 include_texture=False, digits=12)
                tmp.write_text(data)
            elif suffix == ".gltf":
                # A .gltf with embedded buffers keeps the pair to two files.
                data = tm.export(file_type="gltf", embed_buffers=True)
                name = next(iter(data))
                tmp.write_bytes(data[name])
            else:
                tmp.write_bytes(tm.export(file_type=suffix[1:]))
        if not same:
            with atomic_output(side, force) as tmp:
                tmp.write_text(text)
        return path, side


def _obj_text(path: Path) -> str:
    """An OBJ's text: UTF-8, else Latin-1 (comments in old files); refuses what is no OBJ at all.

    Decoded here because trimesh guesses an unknown encoding with an optional package.
    """
    raw = path.read_bytes()
    if b"\0" in raw[:4096]:
        raise InputError("not a valid OBJ (binary data)", path)
    try:
        text = raw.decode("utf-8-sig")
    except UnicodeDecodeError:
        text = raw.decode("latin-1")
    if not re.search(r"^\s*v\s", text, re.M):
        raise InputError("not a valid OBJ (no vertex lines 'v x y z')", path)
    return text


#: Largest vertex coordinate a face mesh may have, in its own unit: a face in metres, millimetres or even
#: micrometres is far below it, and squared distances of such coordinates stay finite (1e308 overflowed them).
MAX_COORDINATE = 1e9


def _read_surface(path: Path):
    """(vertices, triangles, colours or None) from a mesh file via trimesh."""
    import trimesh
    if not path.exists():
        raise InputError("mesh file not found", path)
    if path.suffix.lower() not in MESH_SUFFIXES:
        raise InputError(f"unknown mesh format {path.suffix!r} (use one of {', '.join(MESH_SUFFIXES)})",
                         path)
    source = _obj_text(path) if path.suffix.lower() == ".obj" else None
    try:
        if source is not None:
            loaded = trimesh.load(io.StringIO(source), file_type="obj", process=False, maintain_order=True,
                                  skip_materials=True)
        else:
            loaded = trimesh.load(path, process=False, maintain_order=True, skip_materials=True)
        if isinstance(loaded, trimesh.Scene):
            if not any(isinstance(g, trimesh.Trimesh) for g in loaded.geometry.values()):
                raise ValueError("no triangle mesh in the scene")
            # the scene's node transforms applied, all meshes in one (vertex order kept)
            loaded = loaded.to_geometry() if hasattr(loaded, "to_geometry") else loaded.dump(concatenate=True)
    except InputError:
        raise
    except Exception as exc:  # trimesh raises many types for broken files
        msg = str(exc).splitlines()[0] if str(exc) else type(exc).__name__
        raise InputError(f"cannot read mesh: {msg}", path) from None
    if not isinstance(loaded, trimesh.Trimesh) or len(loaded.vertices) == 0 or len(loaded.faces) == 0:
        raise InputError("cannot read mesh: no vertices or faces", path)
    vertices = np.asarray(loaded.vertices, dtype=np.float64)
    if not np.all(np.isfinite(vertices)) or np.abs(vertices).max() > MAX_COORDINATE:
        bad = int(np.argmax(~np.isfinite(vertices).all(axis=1) | (np.abs(vertices) > MAX_COORDINATE).any(axis=1)))
        raise InputError(f"vertex {bad}: coordinates must be finite and at most {MAX_COORDINATE:g} in size, got "
                         f"{vertices[bad].tolist()}", path)
    colours = None
    try:
        if loaded.visual.kind == "vertex":
            colours = np.asarray(loaded.visual.vertex_colors, dtype=np.float64)[:, :3] / 255.0
    except Exception:
        colours = None
    return vertices, np.asarray(loaded.faces, dtype=np.int64), colours


def _read_sidecar(path: Path, vertices: np.ndarray) -> tuple[dict, dict, np.ndarray | None, dict]:
    """Parse and validate a landmarks sidecar against ``vertices``: landmarks, regions, quads and the rig
    defaults (a sidecar without them, one written by hand: :data:`MESH_RIG_DEFAULTS`)."""
    if not path.exists():
        raise InputError("landmarks file not found", path)
    try:
        text = path.read_text(encoding="utf-8", errors="replace")
    except OSError as exc:
        raise InputError(f"cannot read: {exc.strerror}", path) from None
    from visemeface.textfile import parse_json

    data = parse_json(text, path)
    if not isinstance(data, dict) or "landmarks" not in data:
        raise InputError("expected a JSON object with a 'landmarks' entry", path)
    n = len(vertices)
    lms_in = data["landmarks"]
    if not isinstance(lms_in, dict):
        raise InputError("'landmarks' must map names to vertex indices or [x, y, z]", path)
    landmarks = {}
    for name, value in lms_in.items():
        if isinstance(value, bool):
            raise InputError(f"landmark {name!r}: expected a vertex index or [x, y, z], got {value!r}", path)
        if isinstance(value, int):
            if not 0 <= value < n:
                raise InputError(f"landmark {name!r}: vertex index {value} out of range (mesh has {n} vertices)",
                                 path)
            landmarks[name] = value
        elif (isinstance(value, list) and len(value) == 3
              and all(isinstance(c, (int, float)) and not isinstance(c, bool) for c in value)
              and np.all(np.isfinite(np.asarray(value, float)))):
            point = np.asarray(value, float)
            low, high = vertices.min(axis=0), vertices.max(axis=0)
            reach = high - low                   # a point beyond the mesh's box by more than its size is no landmark
            if np.any(point < low - reach) or np.any(point > high + reach):
                raise InputError(f"landmark {name!r}: {value} lies far outside the mesh (which spans "
                                 f"{', '.join(f'{a:.4g}..{b:.4g}' for a, b in zip(low, high))})", path)
            landmarks[name] = int(np.argmin(np.sum((vertices - point) ** 2, axis=1)))
        else:
            raise InputError(f"landmark {name!r}: expected a vertex index or [x, y, z], got {value!r}", path)
    regions = {}
    regions_in = data.get("regions", {})
    if not isinstance(regions_in, dict):
        raise InputError("'regions' must map names to lists of vertex indices", path)
    for name, idx in regions_in.items():
        try:
            arr = np.asarray(idx, dtype=np.int64).reshape(-1)
        except OverflowError:
            raise InputError(f"region {name!r}: vertex index out of range (mesh has {n} vertices)", path) from None
        except (TypeError, ValueError):
            raise InputError(f"region {name!r}: expected a list of vertex indices", path) from None
        if arr.size and (arr.min() < 0 or arr.max() >= n):
            raise InputError(f"region {name!r}: vertex index out of range (mesh has {n} vertices)", path)
        regions[name] = arr
    quads = None
    if "quads" in data:
        try:
            quads = np.asarray(data["quads"], dtype=np.int64).reshape(-1, 4)
        except OverflowError:
            raise InputError(f"'quads': vertex index out of range (mesh has {n} vertices)", path) from None
        except (TypeError, ValueError):
            raise InputError("'quads' must be a list of [a, b, c, d] vertex indices", path) from None
        if quads.size and (quads.min() < 0 or quads.max() >= n):
            raise InputError(f"'quads': vertex index out of range (mesh has {n} vertices)", path)
    if "n_vertices" in data and data["n_vertices"] != n:
        raise InputError(f"written for a mesh of {data['n_vertices']} vertices, the mesh has {n}", path)
    rig = data.get("rig_defaults", MESH_RIG_DEFAULTS)
    if not isinstance(rig, dict) or not all(isinstance(v, dict) for v in rig.values()):
        raise InputError("'rig_defaults' must map rig-file tables to their values, e.g. {\"modiolus\": {...}}",
                         path)
    return landmarks, regions, quads, rig


def load_face(path: str | Path, landmarks_path: str | Path | None = None) -> FaceMesh:
    """Read a face surface and its landmarks sidecar.

    Parameters
    ----------
    path : str or Path
        OBJ, PLY, GLB or glTF file (read with trimesh, vertex order kept).
    landmarks_path : str or Path, optional
        The JSON sidecar; default ``<stem>.landmarks.json`` beside ``path``.

    Returns
    -------
    FaceMesh
        With the sidecar's quads when the file's triangles are exactly those
        quads split (then any further triangles become ``tris``); otherwise all
        triangles are ``tris`` and there are no quads.

    Raises
    ------
    InputError
        Missing or unreadable mesh or sidecar, or indices out of range; the
        message names the file.
    """
    path = Path(path)
    vertices, faces, colours = _read_surface(path)
    side = sidecar_path(path) if landmarks_path is None else Path(landmarks_path)
    if landmarks_path is None and not side.exists():
        raise InputError(f"landmarks file not found (expected {side.name} beside the mesh; "
                         "give one with --landmarks)", side)
    landmarks, regions, quads, rig = _read_sidecar(side, vertices)
    tris = faces
    if quads is not None and len(quads):
        split = split_quads(quads)
        if len(faces) >= len(split) and np.array_equal(_canon(faces[:len(split)]), _canon(split)):
            tris = faces[len(split):]
        else:
            quads = None
    if quads is None:
        quads = np.zeros((0, 4), np.int64)
    return FaceMesh(vertices, quads, tris, regions, landmarks, colours, landmarks_file=str(side),
                    rig_defaults=rig)


def _canon(tris: np.ndarray) -> np.ndarray:
    """Rotate each triangle so its smallest index comes first (same orientation)."""
    k = np.argmin(tris, axis=1)
    idx = (k[:, None] + np.arange(3)[None, :]) % 3
    return np.take_along_axis(tris, idx, axis=1)
