"""visemeface.face: the face surface (:mod:`~visemeface.face.mesh`) and the embedded default face
(:mod:`~visemeface.face.procedural`).

>>> from visemeface.face import default_face, load_face
>>> face = default_face()              # ~5,000 vertices, metres, origin between the mouth corners

The names are loaded on first use, so importing one submodule does not build the other.
"""

__all__ = ["BUILTIN_FACES", "FaceMesh", "builtin_face", "chosen_face", "default_face", "load_face"]

#: The faces ``--face NAME`` names: the embedded procedural face and the scanned ICT head.
BUILTIN_FACES = ("procedural", "ict")


def builtin_face(name: str, identity=None):
    """The built-in face ``name`` (:data:`BUILTIN_FACES`); ``identity`` (ICT only): a seed or weights
    (:func:`visemeface.face.ict.identity_weights`)."""
    from visemeface.errors import InputError

    if name == "ict":
        from visemeface.face.ict import ict_face, identity_weights

        return ict_face(identity_weights(identity) if identity is not None else ())
    if identity is not None:
        raise InputError(f"--identity draws a speaker of the ICT head (--face ict), not of --face {name}")
    if name == "procedural":
        from visemeface.face.procedural import default_face

        return default_face()
    raise InputError(f"no built-in face {name!r} (built in: {', '.join(BUILTIN_FACES)})")


def chosen_face(face: str | None = None, identity=None, landmarks=None):
    """The face a command's ``--face``/``--identity``/``--landmarks`` (a batch's same fields) name: a
    built-in one by name (:data:`BUILTIN_FACES`) or a mesh file with its landmarks; None for the default
    (the embedded procedural face)."""
    from pathlib import Path

    from visemeface.errors import InputError, close_matches

    if face and face not in BUILTIN_FACES and not Path(face).exists():
        if face.strip().lower() in BUILTIN_FACES:
            face = face.strip().lower()
        else:
            raise InputError(f"--face {face}: no such mesh file, and no built-in face of that name"
                             f"{close_matches(face.lower(), BUILTIN_FACES)} (built in: {', '.join(BUILTIN_FACES)})")
    if landmarks and not face:
        raise InputError("--landmarks needs --face")
    if face in BUILTIN_FACES:
        if landmarks:
            raise InputError(f"--landmarks is for a mesh of your own; the built-in --face {face} has its own")
        return builtin_face(face, identity)
    if identity is not None:
        raise InputError("--identity needs --face ict")
    if face:
        from visemeface.face.mesh import load_face

        return load_face(face, landmarks)
    return None


def __getattr__(name):
    if name in ("FaceMesh", "load_face"):
        from visemeface.face import mesh

        return getattr(mesh, name)
    if name == "default_face":
        from visemeface.face.procedural import default_face

        return default_face
    raise AttributeError(f"module 'visemeface.face' has no attribute {name!r}")
