"""The ICT Face Model: a scanned head with artist-made ARKit-style expression shapes, built in.

The ICT Face Model "Light" (USC Institute for Creative Technologies; Li et al., "Learning Formation of
Physically-Based Face Attributes", CVPR 2020; MIT licence, ``data/faces/ict/LICENSE``) is a head scanned in a
light stage and registered to one topology, with 53 expression shapes an artist made to ARKit's definitions
(``jawOpen``, ``mouthClose``, ``mouthSmile_L`` ...) and PCA identity modes. ``data/faces/ict/ict.npz`` holds a
compact copy (``scripts/build_ict.py`` makes it from ICT-FaceKit): the neutral's first nine parts (face, head
and neck, mouth socket, eye sockets, gums and tongue, teeth, eyeballs), the expression deltas and 20 identity
modes.

:func:`ict_face` turns it into a :class:`~visemeface.face.mesh.FaceMesh` with the project's landmarks and
regions, found from ICT's 68 Multi-PIE landmark vertices and the mesh's connectivity (no hand labels):

- the lip seams are the shortest surface paths through the inner-lip landmarks (ICT's lips touch in front
  and fold inward behind the contact line, so a height cut mislabels their inner surfaces);
- the lips are the face vertices nearer (along the surface) to one seam than to the other, within the lip's
  height at the centre;
- lids are the bands around each eye opening, above and below the eye's corners;
- gums, tongue and teeth are split by ICT's part ranges and each vertex's nearest teeth.

:func:`ict_expressions` gives the 53 shapes (ARKit's names) as a :class:`Blendshapes`.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass

import numpy as np

from visemeface.face.mesh import MESH_RIG_DEFAULTS
from visemeface.face.multipie import edge_graph, lid_regions, lip_regions, mouth_interior, named_landmarks
from visemeface.numeric import sphere_fit
from visemeface.resources import data_path

#: ICT's colours (linear 0..1): skin, lips, sclera, iris, teeth, gums and tongue, the mouth socket.
COLOURS = {"skin": (0.80, 0.60, 0.50), "lip": (0.70, 0.40, 0.40), "sclera": (0.90, 0.88, 0.85),
           "iris": (0.30, 0.20, 0.12), "pupil": (0.03, 0.02, 0.02), "teeth": (0.92, 0.90, 0.82), "gums": (0.75, 0.36, 0.38),
           "socket": (0.18, 0.05, 0.06)}


#: The rig-file values the head needs (:attr:`FaceMesh.rig_defaults`): the jaw's motion fades out over 30°
#: past the chin about the jaw axis, so the throat and the nape stay (ICT's own jawOpen moves the neck at most
#: 11.7 mm; without the fade our jaw turned the whole neck, 32 mm at jaw 1).
#: The linear muscles' pull fades in over the first 60 % of their length from the attachment: a scanned head
#: has skin (the scalp, the temples) at the attachments, which the procedural face lacks, and Waters' falloff
#: still moved it by half (four dents in the scalp on surprise).
#: The jaw opens in mouth widths as the default face's does (its lower lip's centre drops 0.421 W at jaw 1,
#: where the visemes' openings were fitted): ICT's jaw joints lie further behind the lips, so the default
#: face's 9.5 degrees dropped its lip only 0.17 W.
#: The mouth corners move as one piece (:data:`~visemeface.face.mesh.MESH_RIG_DEFAULTS`): the scan's lip rows
#: converge on each corner 0.1-0.2 mm apart, and without it 64 triangles beside the corners turned over on /aa/
#: (the upper lip's corners hooked down) and 2,426 over the visemes and the emotions blended with /aa/ and /uw/.
#: The eyeballs are spheres (radius 15.8 mm): each turns whole and exactly about its own centre (``[gaze] rigid``),
#: where the default face's flattened caps turn only their front, linearised, about a point 9.5 mm behind it.
RIG_DEFAULTS = {"jaw": {"neck_fade_deg": 30.0, "max_drop": 0.421}, "defaults": {"attachment_fade": 0.6},
                "gaze": {"rigid": True}, **MESH_RIG_DEFAULTS}


@functools.lru_cache(maxsize=1)
def _store() -> dict:
    with np.load(data_path("faces", "ict", "ict.npz")) as z:
        return {k: z[k] for k in z.files}


def parts() -> dict[str, np.ndarray]:
    """ICT's parts: name -> vertex indices (``face``, ``head_and_neck``, ``mouth_socket``, ...)."""
    s = _store()
    return {str(n): np.arange(a, b + 1) for n, (a, b) in zip(s["part_names"], s["part_ranges"])}


def _regions_and_landmarks(V, quads, tris, lm68) -> tuple[dict, dict]:
    p = parts()
    n = len(V)
    face_part = np.zeros(n, bool)
    face_part[p["face"]] = True
    graph = edge_graph(V, quads, tris, face_part)
    regions = lip_regions(V, graph, face_part, lm68)
    width = float(np.linalg.norm(V[lm68[54]] - V[lm68[48]]))
    # eyes: the eyeballs; the lids: face vertices within a band of each eye opening, split at its corners
    eyeballs = np.concatenate([p["eyeball_left"], p["eyeball_right"]])
    regions["eyeballs"] = eyeballs
    regions["eyes"] = eyeballs
    # the iris shells inside the outer shells (the iris is painted on the outer one): no camera sees them
    regions["enclosed"] = np.concatenate([p[f"eyeball_{s}"][_OUTER_SHELL:] for s in ("left", "right")])
    regions.update(lid_regions(V, face_part, lm68))
    # the mouth interior
    teeth = p["teeth"]
    upper_teeth = teeth[teeth < 19247]
    lower_teeth = teeth[teeth >= 19247]
    gt = p["gums_and_tongue"]
    interior, interior_landmarks = mouth_interior(V, upper_teeth, lower_teeth, gt, width)
    regions.update(interior)
    regions.update({"cavity_wall": p["mouth_socket"], "mouth_cavity": np.concatenate([p["mouth_socket"], gt, teeth])})
    # the skull that no facial muscle moves: the back of the head and the neck
    regions["scalp"] = p["head_and_neck"]
    landmarks = named_landmarks(V, p["face"], lm68)
    for side, ball in (("left", p["eyeball_left"]), ("right", p["eyeball_right"])):
        iris_front = ball[np.argmax(V[ball, 2])]
        landmarks[f"eye_centre_{side}"] = int(iris_front)
    landmarks.update(interior_landmarks)
    return regions, landmarks


#: An adult's iris is 11.8 mm across (horizontal visible iris diameter; Rüfer et al. 2005) and its pupil
#: about 4 mm in room light; both are painted on ICT's eye shells as discs about the cornea's axis.
IRIS_RADIUS = 0.0059
PUPIL_RADIUS = 0.0020
_EDGE = 0.0008
#: Each ICT eyeball part is two shells: the outer one (the sclera with the cornea's bulge in front, its first
#: 770 vertices) and the inner iris shell behind it.
_OUTER_SHELL = 770


def _eye_axis_distance(P: np.ndarray, shell: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Each point's distance from the eye's optical axis and whether it lies in front of the eye's centre.

    The centre is the sphere fitted to the outer shell; the axis runs from it through the cornea's apex (the
    shell's farthest point from the centre: the cornea bulges about 1 mm past the sclera's sphere). Painted by
    this distance, the iris and pupil are round and centred under the cornea, as they are in a real eye."""
    centre, axis = _eye_axis(shell)
    r = P - centre
    along = r @ axis
    rho = np.linalg.norm(r - np.outer(along, axis), axis=1)
    return rho, along > 0.0


def _eye_axis(shell: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """An eyeball's centre (the sphere fitted to its outer ``shell``) and optical axis (unit, to the cornea's apex,
    the shell's farthest point from the centre)."""
    centre, _ = sphere_fit(shell)
    d = shell - centre
    axis = d[np.argmax(np.einsum("ij,ij->i", d, d))]
    return centre, axis / np.linalg.norm(axis)


def _aim_eyes(V: np.ndarray, reference: np.ndarray) -> np.ndarray:
    """``V`` with each eyeball turned about its centre so that it looks where ``reference``'s does.

    ICT's identity modes turn the eyeballs as well as shaping them (at 1 sigma a few degrees each way, one eye
    differently from the other: `--identity 3` looked outward by 11.0 against 8.4 degrees); where a person
    looks is not who they are, so a speaker drawn from the modes keeps the generic neutral's primary gaze
    (each optical axis about 8 degrees outward of straight ahead, as the anatomical axis is of the visual)."""
    out = np.array(V, dtype=np.float64)
    for side in ("left", "right"):
        ball = parts()[f"eyeball_{side}"]
        centre, a = _eye_axis(out[ball[:_OUTER_SHELL]])
        _, b = _eye_axis(reference[ball[:_OUTER_SHELL]])
        v, c = np.cross(a, b), float(a @ b)
        K = np.array([[0.0, -v[2], v[1]], [v[2], 0.0, -v[0]], [-v[1], v[0], 0.0]])
        R = np.eye(3) + K + K @ K / (1.0 + c)              # the least rotation taking a to b
        out[ball] = (out[ball] - centre) @ R.T + centre
    return out


def _colours(V: np.ndarray, regions: dict) -> np.ndarray:
    p = parts()
    c = np.tile(COLOURS["skin"], (len(V), 1))
    for name, col in (("upper_lip", "lip"), ("lower_lip", "lip")):
        c[regions[name]] = COLOURS[col]
    c[p["mouth_socket"]] = COLOURS["socket"]
    c[p["gums_and_tongue"]] = COLOURS["gums"]
    c[p["teeth"]] = COLOURS["teeth"]
    for side in ("left", "right"):
        ball = p[f"eyeball_{side}"]
        rho, front = _eye_axis_distance(V[ball], V[ball[:_OUTER_SHELL]])
        rho = np.where(front, rho, np.inf)
        # blended over about one ring of the shell's polar grid (0.8 mm), so neither edge follows the rings'
        # unevenness: a hard cut made the pupil a star and notched the iris
        iris = np.clip((IRIS_RADIUS - rho) / _EDGE + 0.5, 0.0, 1.0)[:, None]
        pupil = np.clip((PUPIL_RADIUS - rho) / _EDGE + 0.5, 0.0, 1.0)[:, None]
        sclera, brown, black = (np.asarray(COLOURS[k]) for k in ("sclera", "iris", "pupil"))
        c[ball] = sclera + iris * (brown - sclera) + pupil * (black - brown)
    return c


@functools.lru_cache(maxsize=8)
def _ict_face_cached(identity: tuple):
    s = _store()
    V = s["vertices"].astype(np.float64)
    if identity:
        modes = s["identities"].astype(np.float64)
        V = _aim_eyes(V + np.tensordot(np.asarray(identity, float), modes[: len(identity)], axes=1), V)
    return face_on(V)


def face_on(V: np.ndarray):
    """A :class:`~visemeface.face.mesh.FaceMesh` of ICT's topology with vertices ``V`` (metres, our axes; its
    first 24,591 vertices): the landmarks, regions, colours and rig defaults found on it."""
    from visemeface.face.mesh import FaceMesh

    s = _store()
    quads, tris = s["quads"].astype(np.int64), s["triangles"].astype(np.int64)
    regions, landmarks = _regions_and_landmarks(V, quads, tris, s["multi_pie_68"].astype(np.int64))
    return FaceMesh(V, quads, tris, regions, landmarks, _colours(V, regions), rig_defaults=RIG_DEFAULTS)


#: Identity modes shipped (ICT's first 20 PCA modes, each scaled to one standard deviation).
N_IDENTITY_MODES = 20
#: Largest identity weight (standard deviations): past 3 sigma the PCA model makes no real face.
IDENTITY_LIMIT = 3.0


def identity_weights(spec) -> tuple[float, ...]:
    """``--identity``: an integer seed (a speaker drawn from ICT's identity space, N(0, 1) per mode clipped to
    +-3 sigma, deterministic) or weights of the first modes separated by ``,`` ``;`` or spaces (each within +-3)."""
    from visemeface.errors import InputError

    import re

    text = str(spec).strip()
    if text.lstrip("-").isdigit():
        seed = int(text)
        if seed < 0:
            raise InputError(f"--identity seed must be a non-negative integer, got {seed}")
        w = np.random.default_rng(seed).normal(size=N_IDENTITY_MODES)
        return tuple(float(x) for x in np.clip(w, -IDENTITY_LIMIT, IDENTITY_LIMIT))
    try:
        w = [float(x) for x in re.split(r"[,;\s]+", text) if x]
    except ValueError:
        raise InputError(f"--identity is a seed or comma-separated weights, got {text!r}") from None
    if not w or len(w) > N_IDENTITY_MODES:
        raise InputError(f"--identity takes 1 to {N_IDENTITY_MODES} weights, got {len(w)}")
    bad = [x for x in w if not (np.isfinite(x) and abs(x) <= IDENTITY_LIMIT)]
    if bad:
        raise InputError(f"--identity weight {bad[0]:g} is outside +-{IDENTITY_LIMIT:g} standard deviations")
    return tuple(w)


def ict_face(identity=()) -> "FaceMesh":  # noqa: F821
    """The ICT head as a :class:`~visemeface.face.mesh.FaceMesh` (metres, our axes, origin between the mouth
    corners of the generic neutral); ``identity``: weights of its first PCA identity modes (ICT's units)."""
    import copy

    return copy.deepcopy(_ict_face_cached(tuple(float(x) for x in identity)))


@dataclass
class Blendshapes:
    """A rig's expression shapes on its neutral mesh.

    Attributes
    ----------
    names : list of str
        Shape names (the rig's own).
    deltas : (K, N, 3) float32
        Each shape's displacement from the neutral (m) at weight 1.
    """

    names: list
    deltas: np.ndarray


def ict_expressions() -> Blendshapes:
    """ICT's 53 expression shapes (names as ICT writes them: ``mouthSmile_L``, ``browInnerUp_R`` ...)."""
    s = _store()
    return Blendshapes([str(n) for n in s["expression_names"]], s["expressions"].astype(np.float32))
