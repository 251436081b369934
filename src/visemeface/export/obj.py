"""OBJ sequences: one ``frame_000000.obj`` per frame in a folder, all with the same faces.

Only the ``v`` and ``vn`` lines change between frames (µm precision, metres, +y up), so any
OBJ importer that keeps the vertex order (Blender: the default importer of 3.3+, or tick
*Keep Vert Order* in the legacy one) gives meshes a point cache can animate. The sink also writes
per-vertex normals of each frame and ``face.mtl`` beside the frames: the face's colour palette
(skin, lips, eyes, mouth cavity) as materials, each face using the palette colour nearest its
vertices' mean colour. ``Kd`` holds *linear* values (as Blender's importer and exporter treat it).
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from visemeface.export.images import FolderSequence, frame_name
from visemeface.export.sinks import Sink, register

#: The material library written beside the frames.
MTL_NAME = "face.mtl"


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


def obj_text(vertices: np.ndarray, faces_text: str, header: str = "", normals: np.ndarray | None = None,
             mtllib: str = "") -> str:
    """An OBJ file's text: ``v`` lines (µm precision, metres), ``vn`` lines if ``normals``, then the given
    ``f`` lines (which must use ``v//vn`` when normals are given)."""
    v = np.asarray(vertices, dtype=np.float64)
    head = (f"# {header}\n" if header else "") + (f"mtllib {mtllib}\n" if mtllib else "")
    vn = "" if normals is None else ("vn %.5f %.5f %.5f\n" * len(normals)) % tuple(np.asarray(normals).ravel())
    return head + ("v %.6f %.6f %.6f\n" * len(v)) % tuple(v.ravel()) + vn + faces_text


def palette_of(face) -> tuple[list[str], np.ndarray]:
    """The face's named display colours (skin, lip, eye, cavity) as (names, (P, 3) array)."""
    from visemeface.face.mesh import CAVITY, EYE, LIP, SKIN

    return ["skin", "lip", "eye", "cavity"], np.array([SKIN, LIP, EYE, CAVITY], dtype=np.float64)


def mtl_text(names, colours: np.ndarray) -> str:
    """A material library: one diffuse material a palette colour (``Kd`` linear, from display values)."""
    from visemeface.export.gltf import srgb_to_linear

    lin = srgb_to_linear(colours)
    return "".join(f"newmtl {n}\nKd {c[0]:.5f} {c[1]:.5f} {c[2]:.5f}\nKa 0 0 0\nKs 0.04 0.04 0.04\n"
                   "Ns 30\nd 1\nillum 2\n\n" for n, c in zip(names, lin))


def material_faces_text(triangles: np.ndarray, colours: np.ndarray, names, palette: np.ndarray) -> str:
    """``f v//vn`` lines in one ``usemtl`` block a material (palette order; the triangles' order kept
    within a block): each triangle takes the palette colour nearest the mean colour of its vertices.
    Vertex order is untouched (what a point cache needs); readers that split a mesh by material
    (trimesh) make one piece a block."""
    tri = np.asarray(triangles, dtype=np.int64)
    mean = np.asarray(colours, dtype=np.float64)[tri].mean(axis=1)
    which = np.argmin(((mean[:, None, :] - palette[None]) ** 2).sum(axis=2), axis=1)
    out = []
    for m, name in enumerate(names):
        block = tri[which == m] + 1
        if len(block):
            out.append(f"usemtl {name}\n")
            out.append(("f %d//%d %d//%d %d//%d\n" * len(block)) % tuple(np.repeat(block, 2, axis=1).ravel()))
    return "".join(out)


class ObjSequenceWriter(FolderSequence):
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


@register
class ObjSink(Sink):
    """An OBJ mesh per frame: the face's triangles with per-vertex normals and face.mtl's materials."""

    name = "obj"
    metavar = "DIR"
    help = "also write an OBJ mesh per frame (with normals and face.mtl)"
    folder = True

    def open(self, run) -> None:
        super().open(run)
        face = run.face
        names, palette = palette_of(face)
        self.faces_text = material_faces_text(face.triangles, face.vertex_colors(), names, palette)
        (self.tmp[0] / MTL_NAME).write_text(mtl_text(names, palette))

    def write(self, frame) -> None:
        from visemeface.face.normals import vertex_normals
        from visemeface.export.gltf import unit_normals

        v = np.asarray(frame.vertices, dtype=np.float64)
        n = unit_normals(vertex_normals(v, self.run.face.triangles))
        text = obj_text(v, self.faces_text, header=f"visemeface frame {frame.index}", normals=n, mtllib=MTL_NAME)
        (self.tmp[0] / frame_name(frame.index, "obj")).write_text(text)
