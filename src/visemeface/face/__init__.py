"""visemeface.face: the face surface (:mod:`~visemeface.face.mesh`) and the embedded default face
(:mod:`~visemeface.face.procedural`).

>>> from visemeface.face import default_face, load_face
>>> face = default_face()              # ~5,000 vertices, metres, origin between the mouth corners

The names are loaded on first use, so importing one submodule does not build the other.
"""

__all__ = ["FaceMesh", "default_face", "load_face"]


def __getattr__(name):
    if name in ("FaceMesh", "load_face"):
        from visemeface.face import mesh

        return getattr(mesh, name)
    if name == "default_face":
        from visemeface.face.procedural import default_face

        return default_face
    raise AttributeError(f"module 'visemeface.face' has no attribute {name!r}")
