"""Drive the FEM face from an ActivationTrack: muscle forces, jaw rotation, scenarios.

The kinematic rig (:mod:`visemeface.muscles.rig`) says where every surface
vertex goes for an activation vector **a**. The FEM face is driven so that,
without saliva, its equilibrium *is* that posture:

1. **Kinematic field.** U(**a**) on every FEM node: the rig's displacement on
   the surface nodes; on the bone side, zero for the skull and the jaw's
   rotation for the jaw nodes; linear through the tissue's depth in between.
2. **Jaw.** The bone-side nodes are *prescribed* U(**a**): the rig's jaw
   rotation with the jaw weight of the vertex above; nodes of weight 0 (the
   skull) are fixed. The bone is moved, not pushed. Under the lips
   (``fem.lip_weight``) the bone side is the lips' own muscle layer
   (orbicularis oris): free, like the tissue above it.
3. **Muscle forces.** The external force on the free nodes is the internal
   elastic force of the soft tissue held in that field,

   .. math:: \\mathbf f(\\mathbf a) = \\mathbf F_{int}^{tissue}\\big(U(\\mathbf a)\\big),

   i.e. the rig's Waters displacement fields turned into force fields through
   the tissue's own (nonlinear, neo-Hookean) stiffness. With these loads and
   boundary values the static balance F_int(u) = f holds at u = U(**a**), so
   with no glue the damped dynamics settle on the kinematic posture; the
   saliva (excluded from the calibration) only changes how the lips get there.

4. **Tracking spring.** Dead loads on tissue this soft (μ 800 Pa) have
   unstable equilibria (lips snap 10-20 mm away on rounded visemes and
   closures), so every free node also feels m (2π f)² (U(t) − u), f = 1 kHz,
   which vanishes at the posture. Across the lips (y) the spring lets go in a
   band around the seam (:func:`release_weight`), so there the glue, not the
   rig, decides when the lips part: narrow at the centre, wide toward the
   corners, held at the corners themselves. This is what makes the seam
   unzip from the centre over several frames.
5. **Drag relative to the posture.** The seed's mass damping α m v is taken
   relative to the moving posture, α m (v − dU/dt), so the free lips do not
   lag behind a fast gesture; at rest it is the seed's damping.

Forces and prescribed displacements are computed at the track's frame times
and linearly interpolated in between, per time step.

Scenarios (:func:`scenario_track`) are small activation tracks for the seed's
experiments (jaw lowered and raised, the mouth opened and closed twice).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import pandas as pd

from visemeface.errors import InputError, close_matches
from visemeface.physics.face_model import seam_openings
from visemeface.physics.saliva import GLUE, SalivaBreaking, SalivaParams, glue_per_element

#: Seed 000/001 scenarios as (time s, value) keyframes of the jaw (and, for the
#: one-sided variants, the lower-lip depressor of one side), eased with a smoothstep.
SCENARIOS = {
    # the mouth opened and closed twice (seed 001 Fig. 18: "closed and reopened twice")
    "open": [(0.0, 0.0), (0.05, 0.0), (0.40, 1.0), (0.60, 1.0), (0.85, 0.0), (0.95, 0.0),
             (1.30, 1.0), (1.50, 1.0), (1.75, 0.0), (1.80, 0.0)],
    # a single opening held open (equilibrium with and without glue, seed 000 Fig. 8)
    "open-once": [(0.0, 0.0), (0.05, 0.0), (0.40, 1.0), (0.75, 1.0)],
    # a slight opening: sticky lips stay joined toward the corners (seed 000 Fig. 7)
    "part": [(0.0, 0.0), (0.05, 0.0), (0.40, 0.45), (0.75, 0.45)],
}
SIDES = ("both", "left", "right")


def smoothstep_keyframes(t, keys) -> np.ndarray:
    """Value of keyframes ``[(t0, v0), (t1, v1), ...]`` at times ``t``.

    Between keys the value eases with s = 3x² − 2x³ (zero slope at each key,
    so the drive never jerks); it is held constant outside the keys.

    Examples
    --------
    >>> smoothstep_keyframes([0.0, 0.5, 1.0, 2.0], [(0.0, 0.0), (1.0, 2.0)])
    array([0., 1., 2., 2.])
    """
    k = np.asarray(keys, dtype=np.float64)
    t = np.asarray(t, dtype=np.float64)
    i = np.clip(np.searchsorted(k[:, 0], t, side="right") - 1, 0, len(k) - 2)
    t0, t1 = k[i, 0], k[i + 1, 0]
    x = np.clip((t - t0) / np.where(t1 > t0, t1 - t0, 1.0), 0.0, 1.0)
    s = x * x * (3.0 - 2.0 * x)
    return k[i, 1] + s * (k[i + 1, 1] - k[i, 1])


def make_track(times, values: dict, names, fps: float) -> pd.DataFrame:
    """An ActivationTrack (docs/conventions.md) with the given columns, zeros elsewhere."""
    df = pd.DataFrame(0.0, index=pd.Index(np.asarray(times, float), name="time"), columns=list(names))
    for k, v in values.items():
        df[k] = v
    df.attrs["fps"] = float(fps)
    return df


def ramp_track(names, fps: float, start: float, ramp: float, hold: float, jaw: float = 0.35,
               extra: dict | None = None) -> pd.DataFrame:
    """A single jaw opening: rest until ``start``, eased up over ``ramp`` s, held ``hold`` s.

    ``jaw`` is the jaw activation at the top, ``extra`` more columns ramped the
    same way ({name: activation at the top}).
    """
    keys = [(0.0, 0.0), (start, 0.0), (start + ramp, 1.0), (start + ramp + hold, 1.0)]
    t = np.arange(int(round(keys[-1][0] * fps)) + 1) / fps
    v = smoothstep_keyframes(t, keys)
    cols = {"jaw": jaw * v, **{k: a * v for k, a in (extra or {}).items()}}
    return make_track(t, cols, names, fps)


def scenario_track(name: str, names, fps: float = 60.0, jaw: float = 0.35, side: str = "both",
                   lip: float = 0.3) -> pd.DataFrame:
    """The activation track of a named scenario.

    Parameters
    ----------
    name : str
        One of :data:`SCENARIOS`.
    names : sequence of str
        Rig column names (``rig.names``); must include ``"jaw"``.
    fps : float
        Frame rate of the track.
    jaw : float
        Jaw activation at the keyframes' value 1.
    side : {"both", "left", "right"}
        ``left``/``right``: also pull the lower lip down on that side only
        (``depressor_labii_inferioris_<side>`` at ``lip`` × the keyframe
        value), an asymmetric opening (seed 000 Fig. 10).
    lip : float
        Activation of that one-sided depressor at value 1.
    """
    if name not in SCENARIOS:
        raise InputError(f"unknown scenario {name!r}" + close_matches(name, SCENARIOS)
                         + f"; known: {', '.join(SCENARIOS)}")
    if side not in SIDES:
        raise InputError(f"side must be one of {', '.join(SIDES)}, got {side!r}")
    if fps <= 0:
        raise InputError(f"fps must be > 0, got {fps}")
    keys = SCENARIOS[name]
    n = int(np.floor(keys[-1][0] * fps + 1e-9)) + 1
    t = np.arange(n) / fps
    v = smoothstep_keyframes(t, keys)
    cols = {"jaw": jaw * v}
    if side != "both":
        cols[f"depressor_labii_inferioris_{side}"] = lip * v
    for c in cols:
        if c not in names:
            raise InputError(f"the rig has no {c!r} column" + close_matches(c, names))
    return make_track(t, cols, names, fps)


def activation_at(values: np.ndarray, fps: float, t: float) -> np.ndarray:
    """Linearly interpolated activation row of a (frames, M) track array at time ``t``."""
    f = t * fps
    i = int(np.clip(np.floor(f), 0, len(values) - 1))
    j = min(i + 1, len(values) - 1)
    w = float(np.clip(f - i, 0.0, 1.0))
    return (1.0 - w) * values[i] + w * values[j]


# --------------------------------------------------------------------------- kinematic field -> loads

class FaceDrive:
    """Loads on the FEM face for an activation track (see the module docstring).

    Parameters
    ----------
    fem : FEMFace
    rig : MuscleRig
        On ``fem.face`` (its ``names`` are the track's columns).
    values : (frames, M) array
        Activations per frame, columns in ``rig.names`` order.
    fps : float
        Frame rate of ``values``.
    tissue_forces : callable
        ``u (n, 3) -> (n, 3)`` internal forces of the tissue elements alone.
    """

    def __init__(self, fem, rig, values, fps: float, tissue_forces, field_smoothing: int = 0,
                 min_jacobian: float = 0.0, free_lips: bool = False):
        self.fem, self.rig = fem, rig
        self.min_jacobian = float(min_jacobian)
        self.field_smoothing = int(field_smoothing)
        self.values = np.asarray(values, dtype=np.float64)
        self.fps = float(fps)
        self.tissue_forces = tissue_forces
        mesh = fem.mesh
        S, L = fem.n_surface, fem.layers
        # Every bone-side node turns with the jaw by the rig's jaw weight of the
        # vertex above it, so bone and skin follow one smooth weight and the jaw
        # line tears no element: nodes of weight 0 (the skull) are fixed, the
        # others prescribed.
        # Under the lips the bone side is the lips' own muscle layer: its target is
        # the rig's full field there (blended by ``fem.lip_weight``); it is
        # prescribed that field, or with ``free_lips`` left free.
        inner = mesh.node_sets["inner"]
        w = rig.jaw_weight[fem.surface_vertices[inner - L * S]]
        lam = fem.lip_weight if fem.lip_weight is not None else np.zeros(S)
        self._lip = lam[inner - L * S]
        under_lips = self._lip > 0
        moving = (w != 0) | under_lips
        self.fixed_nodes = inner[~moving]
        self.jaw_nodes = inner[moving & ~under_lips] if free_lips else inner[moving]
        self._inner = inner
        self._inner_rest = mesh.nodes[inner]
        self._inner_w = w.copy()
        self._jaw_col = list(rig.names).index("jaw")
        self._cache: dict[int, tuple] = {}
        #: Track time of the solver's t = 0 (non-zero when resuming).
        self.offset = 0.0
        self._i = None

    @property
    def n_frames(self) -> int:
        return len(self.values)

    def bone_displacement(self, jaw: float) -> np.ndarray:
        """Displacement (S, 3) of the bone-side nodes at jaw activation ``jaw``.

        The rig's jaw rotation (about the joint axis, angle = jaw · max angle ·
        the rig's jaw weight of the vertex above each node) applied to each
        node's own rest position; zero on the skull (fixed nodes).
        """
        from visemeface.muscles.functions import jaw_rotation_displacement
        jl, jr = self.rig.jaw_joints
        return jaw_rotation_displacement(self._inner_rest, jl, jr, jaw * self.rig.max_jaw_angle, self._inner_w)

    def kinematic_field(self, a) -> np.ndarray:
        """U(a) (n, 3): the rig's surface displacement, bone values, linear through the depth."""
        fem = self.fem
        surf = self.rig.displacement(a)[fem.surface_vertices]
        if self.field_smoothing:
            surf = self._smooth(surf)
        bone = self.bone_displacement(float(np.asarray(a)[self._jaw_col]))
        lam = self._lip[:, None]
        bone = (1.0 - lam) * bone + lam * surf
        U = np.concatenate([(1.0 - w[:, None]) * surf + w[:, None] * bone for w in fem.depth_fraction])
        return self.untangle(U) if self.min_jacobian > 0 else U

    def untangle(self, U, iterations: int = 200) -> np.ndarray:
        """Relax a target field where it crushes or inverts tissue elements.

        At wide openings the rig's surface field folds the lower lip over itself at
        the mouth corners (neighbouring vertices cross, J ≤ 0): no simulation can
        reach that target, and the loads F_int(U) of a crushed element are huge and
        unstable. Each pass moves the nodes of the elements with
        J = det(I + ∇U) < ``min_jacobian`` (element centre) halfway to the mean of
        their neighbours' displacement (Laplacian smoothing of the field), the
        skull fixed; it stops when every element reaches the bound. Elsewhere
        the field is the rig's exactly.
        """
        if not hasattr(self, "_adj"):
            import scipy.sparse as sp

            from visemeface.physics.saliva import hex_centre_gradients
            hx = self.fem.mesh.hexes[self.fem.tissue]
            self._hx = hx
            self._G = hex_centre_gradients(self.fem.mesh.nodes[hx])
            n = self.fem.mesh.n_nodes
            r = np.repeat(hx, 8, axis=1).ravel()
            c = np.tile(hx, (1, 8)).ravel()
            A = sp.csr_matrix((np.ones(len(r)), (r, c)), shape=(n, n))
            A.setdiag(0)
            A.eliminate_zeros()
            A.data[:] = 1.0
            self._adj = A
            self._deg = np.asarray(A.sum(axis=1)).ravel()
            self._movable = np.ones(n, dtype=bool)
            self._movable[self.fixed_nodes] = False
        from visemeface.physics.saliva import deformation_gradient
        U = np.array(U, dtype=np.float64)
        for _ in range(iterations):
            J = np.linalg.det(deformation_gradient(U[self._hx], self._G))
            bad = J < self.min_jacobian
            if not bad.any():
                break
            move = np.unique(self._hx[bad])
            move = move[self._movable[move]]
            U[move] = 0.5 * (U[move] + (self._adj[move] @ U) / self._deg[move, None])
        return U

    def _smooth(self, field):
        """Average the surface field with its quad neighbours (``field_smoothing`` passes).

        The rig's field turns steeply at the mouth corners (lip trim, jaw
        weight); held as an FEM equilibrium it crushes the corner elements
        (J < 0.3 at jaw 0.35) and they buckle. A few passes spread it over a
        couple of elements; the lips' own shape barely changes (the
        calibration figure measures it).
        """
        from visemeface.physics.face_model import _smooth_on_quads
        if not hasattr(self, "_surf_quads"):
            node_of = np.full(self.fem.face.n_vertices, -1, dtype=np.int64)
            node_of[self.fem.surface_vertices] = np.arange(self.fem.n_surface)
            q = node_of[self.fem.face.quads]
            self._surf_quads = q[(q >= 0).all(axis=1)]
        out = np.empty_like(field)
        for i in range(3):
            out[:, i] = _smooth_on_quads(field[:, i], self._surf_quads, self.field_smoothing)
        return out

    def _bone_part(self, U):
        return U[self.jaw_nodes]


    def keyframe(self, k: int):
        """(external force (n, 3), jaw displacement (k, 3), U) at frame ``k`` (cached)."""
        k = int(np.clip(k, 0, self.n_frames - 1))
        if k not in self._cache:
            if len(self._cache) > 4:
                self._cache.pop(min(self._cache))
            U = self.kinematic_field(self.values[k])
            self._cache[k] = (self.tissue_forces(U), self._bone_part(U), U)
        return self._cache[k]

    def _interval(self, t: float):
        """Weight w of time ``t`` between frames i and i + 1; caches that segment's loads.

        Per segment: force, jaw and target at frame i, their change to frame
        i + 1, the target's velocity (constant in between) and output buffers.
        """
        f = (t + self.offset) * self.fps
        i = int(f + 1e-9)
        if i != self._i:
            fa, ja, ua = self.keyframe(i)
            fb, jb, ub = self.keyframe(i + 1)
            self._i = i
            du = ub - ua
            self._seg = {"force": (fa, fb - fa, np.empty_like(fa)), "jaw": (ja, jb - ja, np.empty_like(ja)),
                         "target": (ua, du, np.empty_like(ua))}
            self._velocity = du * self.fps
        return min(max(f - i, 0.0), 1.0)

    def _lerp(self, name: str, t: float) -> np.ndarray:
        """``name`` (force, jaw or target) at time ``t``, linear between frames, in its buffer."""
        w = self._interval(t)
        a, d, buf = self._seg[name]
        np.multiply(d, w, out=buf)
        buf += a
        return buf

    def force(self, t: float) -> np.ndarray:
        """External nodal forces at time ``t``, linear between frames."""
        return self._lerp("force", t)

    def target(self, t: float) -> np.ndarray:
        """The kinematic field U (n, 3) at time ``t``, linear between frames."""
        return self._lerp("target", t)

    def target_velocity(self, t: float) -> np.ndarray:
        """dU/dt (n, 3) at time ``t``: constant between frames (the field is linear there)."""
        self._interval(t)
        return self._velocity

    def jaw(self, t: float) -> np.ndarray:
        """Prescribed jaw-node displacements at time ``t``, linear between frames."""
        return self._lerp("jaw", t)


# --------------------------------------------------------------------------- the simulation

PHYSICS = ("sticky", "elastic")
#: Frequency (Hz) of the mass-proportional spring that holds each free node
#: toward its kinematic position (module docstring, item 4).
TRACKING_HZ = 1000.0
#: Radii (m) of the lips' released band (no tracking spring across the lips) at the
#: centre and at the corners (:func:`release_weight`).
RELEASE_CENTRE = 0.004
RELEASE_CORNER = 0.05
#: Radius (m) around each mouth corner where the lips stay held (:func:`release_weight`).
CORNER_HOLD = 0.006
#: Least volume ratio J of a tissue element in the drive's target (see :meth:`FaceDrive.untangle`).
MIN_JACOBIAN = 0.3


@dataclass(frozen=True)
class PhysicsSettings:
    """Solver and saliva settings (seed 000/001 Table 1 defaults).

    ``glue`` is the uniform glue strength K_glue; ``glue_profile`` a profile
    string (:func:`visemeface.physics.saliva.parse_glue_profile`) applied over
    it; ``glue_file`` a CSV (:func:`visemeface.physics.saliva.read_glue_file`).
    ``tracking`` (Hz, 0 = off) adds to every free node i the force
    m_i (2π f)² (U_i(t) − u_i) toward its kinematic position (equilibrium
    unchanged, unstable modes held). ``lip_release`` (centre radius, corner
    radius, corner hold; m) is where it lets go across the lips
    (:func:`release_weight`; None: only at the saliva's nodes).
    ``min_jacobian`` bounds the target's volume ratio (:meth:`FaceDrive.untangle`);
    ``field_smoothing`` averages the rig's surface field over quad neighbours.
    """

    dt: float = 1e-5
    damping: float = 80.0
    hourglass_kappa: float = 0.075
    glue: float = GLUE
    glue_profile: str | None = None
    glue_file: str | None = None
    saliva: SalivaParams = field(default_factory=SalivaParams)
    tracking: float = TRACKING_HZ
    lip_release: tuple[float, float, float] | None = (RELEASE_CENTRE, RELEASE_CORNER, CORNER_HOLD)
    field_smoothing: int = 0
    min_jacobian: float = MIN_JACOBIAN


@dataclass
class SimFrame:
    """One output frame of :class:`StickySimulation`.

    ``vertices`` are the face's vertices (FEM surface + kinematic rest of the
    face), ``display`` the same with the rest gap drawn closed (to render),
    ``displacement``/``velocity`` the FEM node state, ``saliva`` a dict of
    per-frame saliva measures (see :meth:`StickySimulation.saliva_state`).
    """

    index: int
    time: float
    vertices: np.ndarray
    display: np.ndarray
    displacement: np.ndarray
    velocity: np.ndarray
    saliva: dict


class StickySimulation:
    """The FEM face with sticky (or elastic) lips driven by an ActivationTrack.

    Parameters
    ----------
    fem : FEMFace
    rig : MuscleRig
        The rig on ``fem.face``.
    track : DataFrame
        ActivationTrack (docs/conventions.md): columns ``rig.names`` (missing
        muscles count as 0), ``attrs["fps"]``.
    physics : {"sticky", "elastic"}
        ``elastic`` is the same FEM with no glue (K_glue = 0: saliva parts as
        soon as it is stretched, still resists compression).
    settings : PhysicsSettings

    Notes
    -----
    The time step is the largest ``dt' ≤ settings.dt`` that divides a frame
    (``1 / (fps · ceil(1 / (fps · dt)))``), so frames fall exactly on steps.
    Everything is checked (dt against the stable limit, glue, moisture) when
    the object is made, before any simulation time is spent.
    """

    def __init__(self, fem, rig, track: pd.DataFrame, physics: str = "sticky",
                 settings: PhysicsSettings | None = None):
        from visemeface.physics.hexmesh import HexMesh
        from visemeface.physics.materials import SALIVA, SOFT_TISSUE
        from visemeface.physics.tled import TLEDSolver

        settings = settings or PhysicsSettings()
        if physics not in PHYSICS:
            raise InputError(f"unknown physics {physics!r}" + close_matches(physics, PHYSICS)
                             + f"; use one of {', '.join(PHYSICS)}")
        self.fem, self.rig, self.physics, self.settings = fem, rig, physics, settings
        self.values, self.fps = track_values(track, rig)
        if not (np.isfinite(settings.dt) and settings.dt > 0):
            raise InputError(f"time step must be > 0, got {settings.dt}")
        self.steps_per_frame = int(np.ceil(1.0 / (self.fps * settings.dt) - 1e-9))
        self.dt = 1.0 / (self.fps * self.steps_per_frame)
        if physics == "elastic":
            glue = np.zeros(len(fem.saliva))
        else:
            glue = glue_per_element(fem.saliva_s, settings.glue, settings.glue_profile, settings.glue_file)
        mesh = fem.mesh
        X = mesh.nodes[mesh.hexes[fem.saliva]]
        self.saliva = SalivaBreaking(X, glue, settings.saliva)
        tissue_mesh = HexMesh(mesh.nodes, mesh.hexes[fem.tissue], material=np.zeros(len(fem.tissue), np.int64))
        self._tissue = TLEDSolver(tissue_mesh, SOFT_TISSUE, dt=min(self.dt, settings.dt),
                                  damping=settings.damping, hourglass_kappa=settings.hourglass_kappa)
        self.drive = FaceDrive(fem, rig, self.values, self.fps, self._tissue.internal_forces,
                               field_smoothing=settings.field_smoothing, min_jacobian=settings.min_jacobian,
                               free_lips=settings.lip_release is not None)
        self.solver = _FaceSolver(
            mesh, [SOFT_TISSUE, SALIVA], dt=self.dt, damping=settings.damping,
            hourglass_kappa=settings.hourglass_kappa, fixed=self.drive.fixed_nodes,
            prescribed=[(self.drive.jaw_nodes, self.drive.jaw)],
            forces=[(np.arange(mesh.n_nodes), self.drive.force)],
            element_hook=self.saliva.hook(fem.saliva, mesh.hexes[fem.saliva]), unchecked=fem.saliva,
            tracking=(settings.tracking, self.drive.target, self.drive.target_velocity))
        self.saliva.node_displacement = lambda: self.solver._u_now
        if self.solver._track_k is not None:
            # Across the lips (y) the spring lets go of the lips near the seam, so the
            # glue, not the rig, decides when they part; along and out of the seam
            # (x, z) it keeps holding them (the free lips would otherwise lag and
            # buckle at the mouth corners).
            k = np.repeat(self.solver._track_k, 3, axis=1)
            seam = np.unique(mesh.hexes[fem.saliva])
            if settings.lip_release is None:
                w = np.ones(mesh.n_nodes)
                w[seam] = 0.0
            else:
                w = release_weight(fem, *settings.lip_release, seam_nodes=seam)
            k[:, 1] *= w
            self.solver._track_k = k
        self.rest_gaps = fem.rest_gaps

    @property
    def n_frames(self) -> int:
        return len(self.values)

    @property
    def duration(self) -> float:
        return (self.n_frames - 1) / self.fps

    def saliva_state(self, vertices) -> dict:
        """Per-frame saliva measures: broken fraction and openings along the seam (mesh)."""
        op = seam_openings(self.fem, vertices, self.rest_gaps)
        return {"broken_fraction": float(self.saliva.broken.mean()) if len(self.saliva.broken) else 0.0,
                "open_count": op["count"], "open_span": op["span"], "open_fraction": op["open_fraction"],
                "centre_gap": op["centre_gap"], "max_stretch": float(self.saliva.stretch.max())}

    def frames(self, start: dict | None = None):
        """Simulate, yielding a :class:`SimFrame` per track frame.

        Parameters
        ----------
        start : dict, optional
            A checkpoint from :meth:`checkpoint`: continue after its frame.
        """
        first = 0
        # Start at rest in the first frame's posture (its static equilibrium without
        # glue), not at the rest face: a track may begin mid-gesture.
        u0 = self.drive.keyframe(0)[2] if np.any(self.values[0]) else None
        v0 = None
        if u0 is not None and start is None:
            from visemeface.physics.saliva import deformation_gradient, hex_centre_gradients
            X = self.fem.mesh.nodes[self.fem.mesh.hexes[self.fem.saliva]]
            self.saliva.prime(deformation_gradient(u0[self.fem.mesh.hexes[self.fem.saliva]],
                                                   hex_centre_gradients(X)))
        if start is not None:
            first = int(start["frame"])
            u0, v0 = start["displacement"], start["velocity"]
            self.saliva.set_state(start)
        remaining = self.n_frames - 1 - first
        if remaining < 0:
            return
        t0 = first / self.fps
        spf = self.steps_per_frame
        # The solver's clock starts at 0; shift the loads so its t = 0 is frame `first`.
        self.drive.offset = t0
        self.drive._i = None
        for fr in self.solver.run(remaining * spf, output_every=spf, initial_displacement=u0,
                                  initial_velocity=v0):
            k = first + fr.step // spf
            if start is not None and k == first:
                continue
            base = self.rig.pose(self.values[k])
            verts = self.fem.surface(fr.displacement, base)
            yield SimFrame(k, k / self.fps, verts, self.fem.display_vertices(verts, self.rest_gaps),
                           fr.displacement, fr.velocity, self.saliva_state(verts))

    def checkpoint(self, frame: SimFrame) -> dict:
        """Everything :meth:`frames` needs to continue after ``frame``."""
        return {"frame": frame.index, "displacement": frame.displacement, "velocity": frame.velocity,
                **self.saliva.state(), "fingerprint": self.fingerprint()}

    def fingerprint(self) -> str:
        """A digest of the model, track and settings: a checkpoint only resumes the same run."""
        import hashlib
        h = hashlib.sha256()
        for arr in (self.fem.mesh.nodes, self.fem.mesh.hexes, self.values, self.saliva.glue):
            h.update(np.ascontiguousarray(arr).tobytes())
        h.update(repr((self.physics, self.fps, self.dt, self.settings.damping, self.settings.hourglass_kappa,
                       self.settings.saliva)).encode())
        return h.hexdigest()[:16]


class _FaceSolver:
    """Factory of :class:`~visemeface.physics.tled.TLEDSolver` that leaves given elements unchecked."""

    def __new__(cls, *args, unchecked=(), tracking=(0.0, None), **kwargs):
        from visemeface.physics.tled import TLEDSolver

        class FaceSolver(TLEDSolver):
            """A TLEDSolver whose inversion check skips the saliva elements.

            A broken saliva film may fold over as the lips slide (its forces
            are the decaying stored ones then, see ``saliva``); only tissue
            inverting means the simulation diverged.
            """

            def _check(self, step, t):
                jac = self._jac
                if jac[self._checked].min() > 0.0:     # a slice view when the saliva comes last
                    return
                masked = jac.copy()
                masked[self._unchecked] = 1.0
                self._jac = masked
                try:
                    super()._check(step, t)
                finally:
                    self._jac = jac

            def _element_forces(self, u, want_energy):
                self._u_now = u
                super()._element_forces(u, want_energy)

            def _external(self, t):
                R = super()._external(t)
                buf = self._buf
                if self._track_k is not None:
                    # R was copied fresh from the drive's buffer: add k (U(t) - u).
                    np.subtract(self._track_target(t), self._u_now, out=buf)
                    buf *= self._track_k
                    R += buf
                if self._drag is not None:
                    # Damping relative to the moving posture: + α m dU/dt.
                    np.multiply(self._drag, self._target_velocity(t), out=buf)
                    R += buf
                return R

        solver = FaceSolver(*args, **kwargs)
        hz, target = tracking[:2]
        velocity = tracking[2] if len(tracking) > 2 else None
        solver._drag = None
        solver._buf = np.zeros((solver.mesh.n_nodes, 3))
        if velocity is not None and solver.damping > 0:
            solver._drag = (solver.damping * solver.mass)[:, None] * solver.free.reshape(len(solver.mass), -1)[:, :1]
            solver._target_velocity = velocity
        solver._track_k = None
        if hz and hz > 0:
            k = solver.mass * (2.0 * np.pi * float(hz)) ** 2
            solver._track_k = k[:, None] * solver.free.reshape(len(k), -1)[:, :1]
            solver._track_target = target
        solver._unchecked = np.asarray(unchecked, dtype=np.int64)
        checked = np.setdiff1d(np.arange(solver.mesh.n_elements), solver._unchecked)
        contiguous = len(checked) and checked[-1] - checked[0] + 1 == len(checked)
        solver._checked = slice(int(checked[0]), int(checked[-1]) + 1) if contiguous else checked
        return solver


def release_weight(fem, centre: float = RELEASE_CENTRE, corner: float = RELEASE_CORNER,
                   hold: float = CORNER_HOLD, seam_nodes=None) -> np.ndarray:
    """Per FEM node, the weight of the tracking spring across the lips (y): 0 near the seam, 1 away.

    A node whose column (the surface vertex above it) lies ``d`` from the
    nearest seam vertex, at position ``s`` across the mouth, gets

    .. math:: w = \\mathrm{smoothstep}\\big((d - R/2) / (R/2)\\big),\\qquad
              R(s) = R_c + (R_e - R_c)\\,\\min(1, s^2)

    (``R_c`` = ``centre``, ``R_e`` = ``corner``): free within R/2 of the seam,
    held beyond R. The released band is narrow at the centre (the lips there
    are held close to the rig, i.e. to the jaw and teeth) and widens toward the
    corners (the lips there are free to follow the glue),
    so the jaw loads the saliva hardest at the centre and the seam unzips from
    the centre out (seed 000 §3.4.5: "the forces at the centre of the lips are
    often greater"). The mouth corners themselves, where the lips join, stay
    held within ``hold`` of the corner landmarks (w rises to 1 there): released,
    the corner's distorted elements let the lips flap by several mm in speech.
    """
    from scipy.spatial import cKDTree
    if not (0 < centre <= corner) or not hold >= 0:
        raise InputError(f"lip release radii must satisfy 0 < centre <= corner and hold >= 0, "
                         f"got {centre}, {corner}, {hold}")
    seam_v = fem.seam_pairs.ravel()
    s_v = np.repeat(fem.seam_s, 2)
    surface = fem.mesh.nodes[:fem.n_surface]
    d, j = cKDTree(fem.face.vertices[seam_v]).query(surface)
    R = centre + (corner - centre) * np.minimum(1.0, s_v[j] ** 2)
    w = np.tile(_smoothstep((d - 0.5 * R) / (0.5 * R)), fem.layers + 1)
    if seam_nodes is not None:
        w[seam_nodes] = 0.0
    if hold > 0:
        corners = np.stack([fem.face.landmark_position("mouth_corner_left"),
                            fem.face.landmark_position("mouth_corner_right")])
        dc, _ = cKDTree(corners).query(surface)
        w = np.maximum(w, np.tile(1.0 - _smoothstep(dc / hold), fem.layers + 1))
    return w


def _smoothstep(x):
    x = np.clip(x, 0.0, 1.0)
    return x * x * (3.0 - 2.0 * x)


def track_values(track: pd.DataFrame, rig) -> tuple[np.ndarray, float]:
    """(frames, M) activations in ``rig.names`` order (:meth:`MuscleRig.track_matrix`) and the
    frame rate of an ActivationTrack."""
    if not isinstance(track, pd.DataFrame) or len(track) == 0:
        raise InputError("the activation track is empty")
    values = rig.track_matrix(track)
    fps = track.attrs.get("fps")
    if fps is None and len(track) > 1:
        fps = 1.0 / float(np.median(np.diff(track.index.to_numpy(dtype=float))))
    if fps is None or not np.isfinite(fps) or fps <= 0:
        raise InputError(f"activation track needs attrs['fps'] > 0, got {fps!r}")
    return values, float(fps)


def physics_face(face, rig=None, fem=None):
    """(fem, rig) for a face: the FEM model and a rig on the same face (built if not given)."""
    from visemeface.muscles.rig import MuscleRig
    from visemeface.physics.face_model import build_fem_face

    if fem is None:
        fem = build_fem_face(face)
    if rig is None:
        rig = MuscleRig.from_file(face)
    return fem, rig


def simulate_track(face, rig, track: pd.DataFrame, physics: str = "sticky",
                   settings: PhysicsSettings | None = None, fem=None, states: list | None = None):
    """Animate ``track`` on the FEM face: an iterator of vertex arrays at the track's fps.

    The kinematic path's drop-in for ``--physics sticky|elastic``: yields one
    float32 (N, 3) array per track row, the face's vertices (FEM lower face,
    kinematic brows and eyes) with the lips' rest gap drawn closed
    (:meth:`FEMFace.display_vertices`), ready for ``Renderer(face).render``.
    All input checks (time step, glue, moisture) run before the first frame.

    Parameters
    ----------
    face : FaceMesh
        The face to animate (lips may touch at rest; the model opens a 1 mm
        saliva gap and draws it closed).
    rig : MuscleRig or None
        The rig on ``face`` (``MuscleRig.from_file(face)`` if None).
    track : DataFrame
        ActivationTrack.
    physics : {"sticky", "elastic"}
    settings : PhysicsSettings, optional
    fem : FEMFace, optional
        A prebuilt model of ``face`` (:func:`~visemeface.physics.face_model.build_fem_face`).
    states : list, optional
        If given, each frame's saliva measures (dict) are appended to it.
    """
    fem, rig = physics_face(face, rig, fem)
    sim = StickySimulation(fem, rig, track, physics=physics, settings=settings)

    def frames():
        for fr in sim.frames():
            if states is not None:
                states.append({"frame": fr.index, "time": fr.time, **fr.saliva})
            yield fr.display.astype(np.float32)

    return frames()
