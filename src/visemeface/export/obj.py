"""OBJ sequences: one ``frame_000000.obj`` per frame in a folder, all with the same faces.

Only the ``v`` lines change between frames (µm precision, metres, +y up), so any
OBJ importer that keeps the vertex order (Blender: tick *Keep Vert Order* in the
legacy importer) gives meshes a point cache can animate.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from visemeface.export.images import FolderSequence, frame_name
from visemeface.export.sinks import Sink, register


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
    """An OBJ mesh per frame (the face's triangles, or its quads and extra triangles)."""

    name = "obj"
    metavar = "DIR"
    help = "also write an OBJ mesh per frame"
    folder = True

    def open(self, run) -> None:
        super().open(run)
        face = run.face
        faces = [face.quads, face.tris] if self.settings.get("quads") else face.triangles
        self.faces_text = obj_faces_text(faces)

    def write(self, frame) -> None:
        text = obj_text(frame.vertices, self.faces_text, header=f"visemeface frame {frame.index}")
        (self.tmp[0] / frame_name(frame.index, "obj")).write_text(text)
