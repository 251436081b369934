"""The Waters muscle rig: 25 muscles, the tongue's, lips', lids' and eyes' functions and the jaw on any face mesh.

A rig file (TOML, ``data/rig/default.toml``) places every muscle relative to
the face's landmarks, in a *mouth frame* measured on the mesh: origin the
midpoint of the mouth corners, x toward ``mouth_corner_left``, y up (chin to
nasion, made orthogonal to x), z = x × y forward, and lengths in mouth widths
``W`` (corner-to-corner distance). The same file therefore fits the default
face at any resolution and a user's mesh with landmarks.

On construction each muscle's displacement at activation 1 is computed on the
rest mesh (a basis field ``B_m``, (N, 3)) and trimmed by the lip surface; a pose
is

.. math:: X(\\mathbf a) = X_0 + \\sum_m a_m B_m + J(a_{jaw})

where the jaw term :math:`J` rotates the lower face about the jaw-joint axis
(nonlinear in its angle, evaluated per pose). Activations are clamped to each
muscle's range (Edge & Maddock 2001, §2.1.3) with a warning naming the muscles.

Rig file format
---------------
``[trim]`` (lip-trim surface), ``[defaults]`` (``exclude``: regions no muscle
moves), ``[jaw]`` (``rigid``: regions that turn with the mandible, weight 1) and one
``[[muscle]]`` table per function or left/right pair: ``kind`` "linear" or
"sphincter" (Waters), "local" (a Gaussian push on some regions: tongue, lip
shaping, lids; :func:`~visemeface.muscles.functions.local_displacement`) or "turn"
(a linearised rotation: gaze). The file is read by :mod:`visemeface.muscles.rigfile`.
A point is ``{at = "landmark", offset = [x, y, z]}`` or
``{mix = {landmark = weight, ...}, offset = [...]}`` with the offset in mouth
widths along the mouth frame. In a pair (``sides = ["left", "right"]``) the
text ``{side}`` in landmark names is replaced by the side and x offsets are
written for the left side (+x = outward); the right side mirrors them.
"""

from __future__ import annotations

import functools
import warnings
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from visemeface.errors import InputError, close_matches
from visemeface.muscles import functions as mf
from visemeface.muscles.eyeballs import eyeball_coefficients, eyeball_turns
from visemeface.muscles.posing import MovingProduct
from visemeface.resources import data_path
from visemeface.muscles.muscle import Muscle
from visemeface.muscles.rigfile import CONVENTION_REGIONS, LIP_SIDES, _RigFileReader, muscles_from  # noqa: F401

__all__ = ["MouthFrame", "MuscleRig", "default_rig", "mouth_frame", "SPEECH_FUNCTIONS"]

#: Edge & Maddock (2001) Table 1: the twelve functions used for visual speech.
SPEECH_FUNCTIONS = (
    "orbicularis_oris",
    "risorius_left", "risorius_right",
    "depressor_labii_inferioris_left", "depressor_labii_inferioris_right",
    "levator_labii_superioris_left", "levator_labii_superioris_right",
    "zygomatic_major_left", "zygomatic_major_right",
    "depressor_anguli_oris_left", "depressor_anguli_oris_right",
    "jaw",
)


@dataclass(frozen=True)
class MouthFrame:
    """Mouth frame of a rest mesh: origin, unit axes (rows of ``axes``) and mouth width."""

    origin: np.ndarray
    axes: np.ndarray  # (3, 3): ex, ey, ez
    width: float

    def to_local(self, points: np.ndarray) -> np.ndarray:
        """World points (N, 3) -> frame coordinates (m) along ex, ey, ez."""
        return (np.asarray(points, dtype=float) - self.origin) @ self.axes.T

    def to_world(self, offset_w: np.ndarray) -> np.ndarray:
        """An offset in mouth widths along the frame axes -> a world vector (m)."""
        return self.width * (np.asarray(offset_w, dtype=float) @ self.axes)


def mouth_frame(face) -> MouthFrame:
    """The :class:`MouthFrame` of ``face`` from its rest landmarks."""
    cl = face.landmark_position("mouth_corner_left")
    cr = face.landmark_position("mouth_corner_right")
    width = float(np.linalg.norm(cl - cr))
    if not width > 0:
        raise InputError("mouth corners coincide: cannot place the rig")
    ex = (cl - cr) / width
    up = face.landmark_position("nasion") - face.landmark_position("chin")
    ey = up - (up @ ex) * ex
    ey /= np.linalg.norm(ey)
    ez = np.cross(ex, ey)
    return MouthFrame(origin=(cl + cr) / 2, axes=np.stack([ex, ey, ez]), width=width)


class MuscleRig:
    """Muscles and jaw placed on a face, with precomputed displacement bases.

    Build with :meth:`from_file`. Attributes: ``face``, ``muscles`` (list of
    :class:`~visemeface.muscles.muscle.Muscle`), ``names`` (muscle names then ``"jaw"``), ``ranges``
    ((M+1, 2)), ``bases`` ((M, N, 3) trimmed displacement at activation 1),
    ``upper_weight`` ((N,) lip-trim weight of upper-lip muscles), ``jaw_weight``
    ((N,)), ``frame`` (:class:`MouthFrame`), ``path`` (the rig file).
    """

    def __init__(self, face, muscles: list[Muscle], jaw: dict, trim: dict, frame: MouthFrame,
                 path: Path | None = None, modiolus: dict | None = None):
        self.face = face
        self.muscles = muscles
        self.frame, self.path = frame, path
        self.jaw, self.trim = jaw, trim
        self.names = tuple(m.name for m in muscles) + ("jaw",)
        self.index = {n: i for i, n in enumerate(self.names)}
        self.ranges = np.array([m.range for m in muscles] + [jaw["range"]], dtype=float)
        self.rest = rest = face.vertices
        local = frame.to_local(rest)
        u = local[:, 0] / (frame.width / 2)
        surface, side = self._seam_surface(face, local, u, trim), self._lip_sides(face)
        self.upper_weight = self._trim_weights(frame, local, u, surface, side, trim)
        lower = 1.0 - self.upper_weight
        bases = np.zeros((len(muscles), len(rest), 3))
        for i, m in enumerate(muscles):
            b = m.field(rest, frame)
            if m.kind == "local" and m.direction_lower is not None:
                # one function moving the two lips differently (rounding: the lips' sides meet)
                b = b * self.upper_weight[:, None] + m.field(rest, frame, m.direction_lower) * lower[:, None]
            if m.lip == "upper":
                b *= self.upper_weight[:, None]
            elif m.lip == "lower":
                b *= lower[:, None]
            for region in m.exclude:
                b[face.regions[region]] = 0.0
            bases[i] = b
        self.bases = bases
        # The jaw's own trim: its blend starts nearer the centre and its lip tag is weaker, so
        # the opening narrows smoothly into the corners (a lens, not a box with vertical ends).
        jaw_trim = dict(trim, corner_start=jaw["corner_start"], corner_end=jaw["corner_end"])
        jaw_lower = 1.0 - self._trim_weights(frame, local, u, surface, side, jaw_trim, tag=jaw["tag"])
        jw = mf.jaw_centre_weight(u, jaw["reach"]) * jaw_lower
        if jaw.get("neck_fade") is not None:
            jw = jw * mf.jaw_neck_weight(rest, face.landmark_position(jaw["joints"][0]),
                                         face.landmark_position(jaw["joints"][1]), face.landmark_position("chin"),
                                         frame.axes[2], jaw["neck_fade"])
        for region in jaw.get("rigid", ()):
            jw[face.regions[region]] = 1.0      # lower teeth, gum and tongue turn with the mandible
        for region in jaw["exclude"]:
            jw[face.regions[region]] = 0.0
        self.modiolus = modiolus
        if modiolus:
            held = np.zeros(len(rest), bool)
            for region in modiolus["exclude"]:
                held[face.regions[region]] = True
            corners = [face.landmark_position(n) for n in ("mouth_corner_left", "mouth_corner_right")]
            self.bases, jw = mf.modiolus_blend(rest, bases, jw, corners, modiolus["radius"] * frame.width,
                                               modiolus["core"], held)
        self.jaw_weight = jw
        self.jaw_joints = (face.landmark_position(jaw["joints"][0]), face.landmark_position(jaw["joints"][1]))
        self.max_jaw_angle = jaw["max_angle"]
        self._jaw_idx = np.flatnonzero(jw > 0)
        jl, jr = self.jaw_joints
        kax = (jl - jr) / np.linalg.norm(jl - jr)
        r = rest[self._jaw_idx] - jr
        self._jaw_perp = r - np.outer(r @ kax, kax)
        self._jaw_cross = np.cross(kax, r)
        self._jaw_w = jw[self._jaw_idx]
        self._build_fast_path()

    def _build_fast_path(self, tolerance: float = 1e-10):
        r"""One matrix for the whole pose: muscle bases plus Taylor series of the rotations.

        With :math:`\theta_i = \theta w_i` the jaw term is
        :math:`(\cos\theta_i - 1)\,\mathbf r_\perp + \sin\theta_i\,(\mathbf k \times \mathbf r)
        = \sum_{j \ge 1} \theta^j C_j` (:func:`~visemeface.muscles.functions.rotation_terms`), cut at the
        degree whose next term is below ``tolerance`` metres for every angle in the jaw's range. The rigid
        turns of one eyeball (``[gaze] rigid``) add the rows of :mod:`~visemeface.muscles.eyeballs`. So a pose is one
        product :math:`\mathbf c(\mathbf a) \cdot B` (exactness is checked against
        :meth:`jaw_displacement` and the rotations themselves in the tests).
        """
        n = len(self.rest)
        lo, hi = self.jaw["range"]
        theta_max = max(abs(lo), abs(hi)) * self.max_jaw_angle * (self._jaw_w.max() if len(self._jaw_w) else 0.0)
        radius = float(np.linalg.norm(np.hstack([self._jaw_perp, self._jaw_cross]), axis=1).max()) \
            if len(self._jaw_w) else 0.0
        degree = mf.series_degree(theta_max, radius, tolerance)
        self._jaw_degree = degree
        c = np.zeros((degree, n, 3))
        c[:, self._jaw_idx] = mf.rotation_terms(self._jaw_perp, self._jaw_cross, self._jaw_w, range(1, degree + 1))
        rows = [self.bases.reshape(len(self.muscles), 3 * n), c.reshape(degree, 3 * n)]
        self._eyes = eyeball_turns(self.rest, self.muscles, self.frame.axes[2])
        rows += [eye.rows.reshape(len(eye.rows), 3 * n) for eye in self._eyes]
        # float32 halves the memory traffic of the product (the pose's cost); displacements are
        # millimetres, so the rounding is below a nanometre. Positions stay float64.
        self._matrix = np.ascontiguousarray(np.vstack(rows), dtype=np.float32)
        self._rest_flat = self.rest.reshape(-1)
        self._powers = np.arange(1, degree + 1)
        self._moving = MovingProduct(self._matrix, self._rest_flat)   # the product :meth:`pose` makes

    def still_vertices(self, activations=None) -> np.ndarray:
        """(N,) bool: the vertices at rest in every :meth:`pose` (of the clamped ``activations``, (F, M+1), given)."""
        c = None if activations is None else np.abs(self._coefficients(np.atleast_2d(activations))).max(0) > 0
        return self._moving.still(c)

    def _coefficients(self, a: np.ndarray) -> np.ndarray:
        """``[a_muscles, theta, theta^2, ..., then each eyeball's pair terms]`` for activations (..., M+1)
        (an eyeball's rigid turns scaled as :func:`~visemeface.muscles.eyeballs.eyeball_coefficients` says)."""
        a = np.asarray(a, dtype=np.float64)
        theta = a[..., -1:] * self.max_jaw_angle
        muscles, pairs = eyeball_coefficients(a[..., :-1], self._eyes)
        return np.concatenate([muscles, theta ** self._powers, *pairs], axis=-1).astype(np.float32)

    # ---------------------------------------------------------------- build
    @staticmethod
    def _seam_surface(face, local, u, trim) -> np.ndarray:
        """The lip-trim surface's height (N,) over each vertex: the lips' seams and corners, smoothed."""
        seam = np.concatenate([face.region("lip_seam_upper"), face.region("lip_seam_lower")])
        corners = [face.landmarks["mouth_corner_left"], face.landmarks["mouth_corner_right"]]
        seam = np.unique(np.concatenate([seam, corners]))
        return mf.seam_height(u, u[seam], local[seam, 1], smooth=2.0 * trim["smooth"])  # W -> half-widths (u units)

    @staticmethod
    def _lip_sides(face) -> np.ndarray:
        """The lip-trim tag (N,): +1 on the upper lip, -1 on the lower, 0 elsewhere, and over the mouth's lining
        the lips' tags carried into it (see :func:`~visemeface.muscles.functions.lip_trim_weights`)."""
        side = np.zeros(face.n_vertices)
        if "upper_lip" in face.regions:
            side[face.regions["upper_lip"]] = 1.0
        if "lower_lip" in face.regions:
            side[face.regions["lower_lip"]] = -1.0
        if "cavity_wall" in face.regions:
            # the mouth's lining goes with the lip it joins, fading into the cavity (a smooth map over the
            # lining from the lips' inner edges): by height alone the lining behind a lip's corner split
            # half and half while that lip went one way, and the triangles between stretched 4.6 times
            from visemeface.face.multipie import face_edges, harmonic_extension

            lining = np.zeros(face.n_vertices, bool)
            lining[face.regions["cavity_wall"]] = True
            side = harmonic_extension(face_edges(face.quads, face.tris), side, side != 0, lining & (side == 0))
        return side

    @staticmethod
    def _trim_weights(frame, local, u, surface, side, trim, tag: float = 2.0) -> np.ndarray:
        return mf.lip_trim_weights(u, local[:, 1], surface, side, trim["inner_width"] * frame.width,
                                   trim["outer_width"] * frame.width, trim["corner_start"], trim["corner_end"],
                                   tag)

    @classmethod
    def from_file(cls, face, path: str | Path | None = None) -> MuscleRig:
        """Place the rig described by ``path`` (default ``data/rig/default.toml``) on ``face``."""
        path = Path(path) if path is not None else data_path("rig", "default.toml")
        for name in ("mouth_corner_left", "mouth_corner_right", "nasion", "chin"):
            if name not in face.landmarks:
                raise InputError(f"no landmark {name!r}; the rig places its muscles by it (add it to the face's "
                                 "landmarks)", getattr(face, "landmarks_file", None) or "the face")
        frame = mouth_frame(face)
        reader = _RigFileReader(path, face, frame)
        muscles = muscles_from(reader)
        fade = reader.table("defaults")
        for m in muscles if "attachment_fade" in fade else ():
            m.params = {**m.params, "attachment_fade": float(fade["attachment_fade"])} if m.kind == "linear" else m.params
        t = reader.data.get("trim", {})
        trim = {f: reader.get(t, "trim", f, float) for f in
                ("inner_width", "outer_width", "corner_start", "corner_end", "smooth")}
        if not 0 < trim["inner_width"] <= trim["outer_width"]:
            raise reader.error("trim", "outer_width", "need 0 < inner_width <= outer_width")
        if not 0 <= trim["corner_start"] < trim["corner_end"]:
            raise reader.error("trim", "corner_end", "need 0 <= corner_start < corner_end")
        for region in ("lip_seam_upper", "lip_seam_lower"):
            if region not in face.regions or len(face.regions[region]) == 0:
                raise InputError(f"the face has no {region!r} region, needed for lip trimming", path)
        j = reader.data.get("jaw")
        if not isinstance(j, Mapping):
            raise reader.error("jaw", "jaw", "missing [jaw] table")
        j = reader.table("jaw")
        joints = j.get("joints", ["jaw_joint_left", "jaw_joint_right"])
        if not (isinstance(joints, list) and len(joints) == 2 and all(isinstance(x, str) for x in joints)):
            raise reader.error("jaw", "joints", f"expected two landmark names, got {joints!r}")
        for n in joints:
            reader.landmark("jaw", "joints", n)
        jaw = {
            "joints": joints,
            "max_angle": np.radians(reader.get(j, "jaw", "max_angle_deg", float)),
            "reach": reader.get(j, "jaw", "reach", float),
            "range": reader.get(j, "jaw", "range", "range"),
            "exclude": reader.get(j, "jaw", "exclude", "regions", ()),
            "corner_start": reader.get(j, "jaw", "corner_start", float, trim["corner_start"]),
            "corner_end": reader.get(j, "jaw", "corner_end", float, trim["corner_end"]),
            "tag": reader.get(j, "jaw", "tag", float, 2.0),
            "neck_fade": (np.radians(reader.get(j, "jaw", "neck_fade_deg", float))
                          if "neck_fade_deg" in j else None),
        }
        if not 0 <= jaw["corner_start"] < jaw["corner_end"]:
            raise reader.error("jaw", "corner_end", "need 0 <= corner_start < corner_end")
        if "max_drop" in j:     # the same opening in mouth widths on a head whose jaw joints lie further back
            drop = reader.get(j, "jaw", "max_drop", float)
            jaw["max_angle"] = mf.jaw_angle_for_drop(*(face.landmark_position(n) for n in joints),
                                                     face.landmark_position("lower_lip_mid"), drop * frame.width)
            if not np.isfinite(jaw["max_angle"]):
                raise reader.error("jaw", "max_drop", f"must be positive and below the jaw's reach, got {drop}")
        jaw["exclude"] = reader.regions(jaw["exclude"], "jaw", "exclude")
        jaw["rigid"] = reader.regions(reader.get(j, "jaw", "rigid", "regions", ()), "jaw", "rigid")
        if jaw["reach"] <= 0:
            raise reader.error("jaw", "reach", f"must be positive, got {jaw['reach']}")
        return cls(face, muscles, jaw, trim, frame, path, modiolus=reader.modiolus())

    # -------------------------------------------------------- activations
    def muscle(self, name: str) -> Muscle:
        """The :class:`~visemeface.muscles.muscle.Muscle` called ``name`` (InputError with close matches if unknown)."""
        for m in self.muscles:
            if m.name == name:
                return m
        raise InputError(f"unknown muscle {name!r}" + close_matches(name, self.names))

    def activation_vector(self, mapping: Mapping | None = None, **kw) -> np.ndarray:
        """Activations (M+1,) in ``names`` order from ``{name: value}`` (missing = 0).

        Unknown names raise :class:`InputError` listing close matches; NaN/inf
        raise naming the muscle; values outside a muscle's range are clamped with
        one warning naming them.
        """
        items = dict(mapping or {})
        items.update(kw)
        a = np.zeros(len(self.names))
        for name, value in items.items():
            if name not in self.index:
                raise InputError(f"unknown muscle {name!r}" + close_matches(str(name), self.names))
            try:
                v = float(value)
            except (TypeError, ValueError):
                raise InputError(f"activation of {name!r} is not a number: {value!r}") from None
            if not np.isfinite(v):
                raise InputError(f"activation of {name!r} is {v} (must be finite)")
            a[self.index[name]] = v
        return self.clamp(a)

    def _vector(self, a) -> np.ndarray:
        if hasattr(a, "columns"):
            raise InputError("a pose is one posture (a mapping or a vector); for a track (a DataFrame, a row per "
                             "frame) use rig.poses(track)")
        if isinstance(a, Mapping) or hasattr(a, "items"):
            return self.activation_vector(dict(a.items()))
        a = np.asarray(a, dtype=float)
        if a.shape != (len(self.names),):
            raise InputError(f"expected {len(self.names)} activations in rig.names order, got shape {a.shape}")
        if not np.all(np.isfinite(a)):
            i = int(np.flatnonzero(~np.isfinite(a))[0])
            raise InputError(f"activation of {self.names[i]!r} is {a[i]} (must be finite)")
        return self.clamp(a)

    # ---------------------------------------------------------------- poses
    def jaw_displacement(self, jaw: float) -> np.ndarray:
        """Displacement (N, 3) of the jaw alone at activation ``jaw`` (angle = jaw · max angle)."""
        out = np.zeros_like(self.rest)
        out[self._jaw_idx] = self._jaw_term(float(jaw))
        return out

    def _jaw_term(self, jaw: float) -> np.ndarray:
        theta = (jaw * self.max_jaw_angle) * self._jaw_w
        return (np.cos(theta) - 1.0)[:, None] * self._jaw_perp + np.sin(theta)[:, None] * self._jaw_cross

    def displacement(self, a) -> np.ndarray:
        """Displacement (N, 3) from rest: :math:`\\sum_m a_m B_m + J(a_{jaw})`."""
        a = self._vector(a)
        return (self._coefficients(a) @ self._matrix).astype(np.float64).reshape(-1, 3)

    def pose(self, a) -> np.ndarray:
        """Posed vertices (N, 3): rest + :meth:`displacement`. ``a``: mapping or vector in ``names`` order."""
        # the functions in use only, on one thread (and on a large mesh its moving vertices only):
        # visemeface.muscles.posing
        return self._moving(self._coefficients(self._vector(a))).reshape(-1, 3)

    def track_matrix(self, track) -> np.ndarray:
        """An ActivationTrack (DataFrame, columns = rig functions) as (F, M+1) floats in ``names`` order.

        The one conversion every consumer of a track uses (rendering, exports, the FEM drive):
        a column that is no rig function is an error (with close matches), a rig function the
        track leaves out is 0 (rest), a non-finite value is an error naming the muscle and time.
        Values are *not* clamped here; :meth:`poses` clamps with a warning.
        """
        unknown = [c for c in track.columns if c not in self.index]
        if unknown:
            raise InputError(f"unknown muscle {unknown[0]!r} in the activation track"
                             + close_matches(str(unknown[0]), self.names))
        A = track.reindex(columns=list(self.names), fill_value=0.0).to_numpy(dtype=np.float64)
        if not np.all(np.isfinite(A)):
            f, i = np.argwhere(~np.isfinite(A))[0]
            raise InputError(f"activation of {self.names[i]!r} at t={track.index[f]:g} s is {A[f, i]} "
                             "(must be finite)")
        return A

    def clamp(self, A: np.ndarray) -> np.ndarray:
        """Activations ``A`` ((M+1,) or (F, M+1)) clamped to the functions' ranges.

        The one clamp of the project: one warning names each function clamped with
        its most extreme value, e.g. ``jaw=1.7 -> 1`` (for a track, the frame count too).
        """
        A = np.asarray(A, dtype=float)
        lo, hi = self.ranges[:, 0], self.ranges[:, 1]
        out = np.clip(A, lo, hi)
        bad = np.atleast_2d(out != A)
        if bad.any():
            rows = np.atleast_2d(A)
            parts = []
            for i in np.flatnonzero(bad.any(axis=0)):
                col = rows[bad[:, i], i]
                worst = col[np.argmax(np.abs(col - np.clip(col, lo[i], hi[i])))]
                frames = f" in {int(bad[:, i].sum())} frames" if A.ndim == 2 else ""
                parts.append(f"{self.names[i]}={worst:.4g} -> {np.clip(worst, lo[i], hi[i]):.4g}{frames}")
            warnings.warn("activations clamped to the muscles' ranges: " + ", ".join(parts), stacklevel=3)
        return out

    def poses(self, activations) -> np.ndarray:
        """Posed vertices (F, N, 3) float32 for activations (F, M+1) (or a DataFrame with rig columns)."""
        if hasattr(activations, "columns"):
            activations = self.track_matrix(activations)
        A = np.atleast_2d(np.asarray(activations, dtype=float))
        if A.ndim != 2 or A.shape[1] != len(self.names):
            raise InputError(f"expected activations of shape (frames, {len(self.names)}), got {A.shape}")
        if not np.all(np.isfinite(A)):
            f, i = np.argwhere(~np.isfinite(A))[0]
            raise InputError(f"activation of {self.names[i]!r} at frame {f} is {A[f, i]} (must be finite)")
        A = self.clamp(A)
        out = self._coefficients(A) @ self._matrix
        out += self._rest_flat.astype(np.float32)
        return out.reshape(len(A), -1, 3)

    def table(self):
        """A DataFrame describing the muscles: name, kind, side, range, lip side."""
        import pandas as pd
        rows = [(m.name, m.kind, m.side, m.range[0], m.range[1], m.lip) for m in self.muscles]
        rows.append(("jaw", "rotation", "centre", *self.jaw["range"], "lower"))
        return pd.DataFrame(rows, columns=["name", "kind", "side", "min", "max", "lip"]).set_index("name")


def _freeze(obj) -> None:
    """Make every numpy array held by ``obj`` (and its dict/list members) read-only."""
    for value in vars(obj).values():
        items = value.values() if isinstance(value, dict) else value if isinstance(value, (list, tuple)) else [value]
        for v in items:
            if isinstance(v, np.ndarray):
                v.flags.writeable = False


@functools.lru_cache(maxsize=4)
def _default_rig(resolution):
    from visemeface.face.procedural import default_face
    face = default_face() if resolution is None else default_face(resolution=resolution)
    rig = MuscleRig.from_file(face)
    # Shared by every caller: its arrays are read-only, so no caller can change the others' rig.
    _freeze(face)
    _freeze(rig)
    return rig


def default_rig(resolution: int | None = None) -> MuscleRig:
    """The default rig file placed on the default face.

    Built once per resolution and shared; its arrays are read-only (a write raises
    ``ValueError``). Build your own with ``MuscleRig.from_file(default_face())`` to modify one.
    """
    return _default_rig(resolution)


def rig_for(face: str | None = None, landmarks=None, rig=None, identity=None, skin=None) -> MuscleRig:
    """The rig of a command's ``--face``/``--landmarks``/``--rig``/``--identity``/``--skin`` (a batch's
    same fields; :func:`visemeface.face.chosen_face`): the default rig on the embedded face when all are
    None."""
    from visemeface.errors import InputError
    from visemeface.face import chosen_face

    if skin and face not in (None, "procedural"):
        raise InputError(f"--skin colours the embedded procedural face, not --face {face}")
    plain = face == "procedural" and not identity and not landmarks
    mesh = None if plain else chosen_face(face, identity, landmarks)
    if mesh is not None:
        return MuscleRig.from_file(mesh, rig)
    if rig or skin:
        from visemeface.face.procedural import default_face
        return MuscleRig.from_file(default_face(skin=skin), rig)
    return default_rig()
