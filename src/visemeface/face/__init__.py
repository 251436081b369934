"""visemeface.face: the face surface (:mod:`~visemeface.face.mesh`) and the embedded default face
(:mod:`~visemeface.face.procedural`).

>>> from visemeface.face import default_face, load_face
>>> face = default_face()              # ~4,500 vertices, metres, origin between the mouth corners
"""

from visemeface.face.mesh import FaceMesh, load_face
from visemeface.face.procedural import default_face

__all__ = ["FaceMesh", "default_face", "load_face"]
