"""The sticky-lip FEM face driven by an ActivationTrack: settings, model assembly, frames.

:class:`StickySimulation` puts the parts together: the face model's
tissue, the muscle loads and the prescribed jaw of
:class:`~visemeface.physics.loads.FaceDrive`, the saliva film on its own fine
slabs (:class:`~visemeface.physics.film.SalivaFilm`), the force terms
(:mod:`visemeface.physics.terms`) in one :class:`~visemeface.physics.integrator.FaceModel`,
a :class:`~visemeface.physics.integrator.CentralDifference` integrator and one
:class:`~visemeface.physics.state.SimState`. The lips are free: no spring
pulls them toward the rig's posture and nothing knows where the seam is,
unless ``posture_hz`` is asked for, and then it acts on every free node alike.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import pandas as pd

from visemeface.errors import InputError, SimulationDiverged, close_matches
from visemeface.physics.film import FILM_ELEMENTS, SalivaFilm
from visemeface.physics.glue import GLUE, glue_per_element
from visemeface.physics.materials import SOFT_TISSUE
from visemeface.physics.openings import film_openings, seam_openings
from visemeface.physics.saliva import SalivaParams
from visemeface.physics.scenarios import track_values
from visemeface.physics.stability import SHAPE_SAMPLES, face_stable_step, natural_shape_step
from visemeface.physics.state import SimState


from visemeface.physics import PHYSICS  # noqa: E402,F401  (its one home)
#: Least volume ratio J of a tissue element in the drive's target (see :meth:`FaceDrive.untangle`).
MIN_JACOBIAN = 0.3
#: Force terms that can be switched off (:mod:`visemeface.physics.terms`).
TERMS = ("tissue", "muscles", "saliva", "drag", "posture")
#: How often (simulated seconds) a run without fixed threads re-times its thread counts, and how many
#: steps each timing takes: about 1 % of the run's time at 60 fps on the default face.
THREAD_CHECK_SECONDS = 0.5
THREAD_TRIAL_STEPS = 10


@dataclass(frozen=True)
class PhysicsSettings:
    """Solver and saliva settings (defaults: Leach & Maddock 2018, 2019, Table 1).

    ``glue`` is the uniform glue strength K_glue; ``glue_profile`` a profile
    string (:func:`visemeface.physics.glue.parse_glue_profile`) applied over
    it; ``glue_file`` a CSV (:func:`visemeface.physics.glue.read_glue_file`).
    ``posture_hz`` (0 = off) adds the stabiliser m (2π f)² (U(t) − u) on every
    free node alike; ``off`` names force terms to switch off (:data:`TERMS`).
    ``film_elements``: least saliva slabs across the mouth; ``film_corners``: the film runs on
    into the mouth corners, where the lips meet (:attr:`FEMFace.corner_hexes`; off, the default,
    it ends at the last seam pair and that free end, a notch tip, carries 1.2-1.3x the centre's
    stretch and lets go first; on, the centre carries the most and the ends the least). ``lip_bone``: the lips'
    deep (bone-side) layer, their orbicularis, is moved along the muscle field like
    the jaw's bone (``muscle``, default) or ``free``. Free, the upper lip follows the
    glued lower one down at the centre and the seam tears at the corners first
    (measured: scripts/sticky_figures.py --lip-bone free).
    ``muscles``: ``active`` (the muscle field is the tissue's natural shape, an active
    strain, :class:`~visemeface.physics.terms.ActiveTissue`) or ``loads`` (dead loads
    F_int(U), :class:`~visemeface.physics.terms.MuscleLoads`).
    ``min_jacobian`` bounds the target's volume ratio (:meth:`FaceDrive.untangle`);
    ``field_smoothing`` averages the rig's surface field over quad neighbours.
    ``multirate``: with ``dt`` None, the tissue takes its own stable step and the saliva film's nodes
    take substeps at the film's (:mod:`visemeface.physics.integrator`); False, a ``dt`` given, or a
    posture spring (a force of u, which the substeps would hold) runs everything at one step.
    ``threads``: numba threads for the steps; None (the default) times a few steps at numba's thread count
    and at one, at the start and every :data:`THREAD_CHECK_SECONDS` of simulated time, and runs on the
    faster (:func:`~visemeface.runtime.faster_thread_count`; the result is the same bits at any count).
    ``tissue_limit``: the tissue's limiting (isochoric) stretch (Gent; inf, the default here: Leach & Maddock's (2018)
    neo-Hookean; :meth:`speech`: :data:`~visemeface.physics.materials.TISSUE_LIMIT`).
    ``seam_elements``: where the FEM face is built here from a face (:func:`physics_face`, the speech
    commands), its lips are refined to this many tissue elements along the seam
    (:func:`~visemeface.physics.face_model.build_fem_face`); None: the face's own elements.

    These defaults are Leach & Maddock's (2018) model. The speech commands run :meth:`speech`: the same with the
    lips refined along the seam, saliva strands that thin before they snap, the film carried into
    the mouth corners and a tissue that stiffens.
    """

    dt: float | None = None
    damping: float = 80.0
    hourglass_kappa: float = 0.075
    glue: float = GLUE
    glue_profile: str | None = None
    glue_file: str | None = None
    saliva: SalivaParams = field(default_factory=SalivaParams)
    posture_hz: float = 0.0
    off: tuple = ()
    film_elements: int = FILM_ELEMENTS
    film_corners: bool = False
    lip_bone: str = "muscle"
    muscles: str = "active"
    field_smoothing: int = 0
    min_jacobian: float = MIN_JACOBIAN
    threads: int | None = None
    multirate: bool = True
    seam_elements: int | None = None
    tissue_limit: float = float("inf")

    @property
    def tissue(self):
        """The soft tissue: Leach & Maddock's (2018) neo-Hookean ``SOFT_TISSUE``, Gent where ``tissue_limit`` is finite."""
        return SOFT_TISSUE.with_limiting_stretch(self.tissue_limit)

    @classmethod
    def speech(cls, **changes) -> PhysicsSettings:
        """The sticky lips of ``speak``, ``say``, ``batch`` and ``simulate``, with ``changes``.

        The lips refined to :data:`~visemeface.face.refine.SEAM_ELEMENTS` tissue elements along
        the seam, so the 48 film slabs can part one by one, and saliva strands that thin over
        :data:`~visemeface.physics.saliva.RUPTURE_TIME` before they snap: the lips unzip from the
        centre over several frames. Without either, Leach & Maddock's (2018) brittle film lets go along the whole
        seam in one frame (measured: ``scripts/sticky_figures.py``). ``RUPTURE_TIME`` is a value
        chosen inside saliva's measured range for that zipper, not a measurement of lips. The film
        runs on into the mouth corners (``film_corners``), where the lips meet: ended at the last
        pair of lip vertices it leaves the corners unglued, and they open as dark notches while the
        rest of the seam is stuck (on /f v/ and wide vowels in speech, and beside a held centre).
        The tissue stiffens toward :data:`~visemeface.physics.materials.TISSUE_LIMIT` (Gent; Leach & Maddock's (2018)
        neo-Hookean lips stretch 7x and hold under glue 0.3 at full jaw; the limit is chosen, its reason there).
        """
        from visemeface.face.refine import SEAM_ELEMENTS
        from visemeface.physics.materials import TISSUE_LIMIT
        from visemeface.physics.saliva import RUPTURE_TIME
        base = {"seam_elements": SEAM_ELEMENTS, "saliva": SalivaParams(rupture_time=RUPTURE_TIME),
                "film_corners": True, "tissue_limit": TISSUE_LIMIT}
        return cls(**{**base, **changes})


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


def _check_settings(physics: str, settings: PhysicsSettings) -> None:
    if physics not in PHYSICS:
        raise InputError(f"unknown physics {physics!r}" + close_matches(physics, PHYSICS)
                         + f"; use one of {', '.join(PHYSICS)}")
    if settings.dt is not None and not (np.isfinite(settings.dt) and settings.dt > 0):
        raise InputError(f"time step must be > 0, got {settings.dt}")
    if not (np.isfinite(settings.posture_hz) and settings.posture_hz >= 0):
        raise InputError(f"posture spring frequency must be >= 0, got {settings.posture_hz}")
    if settings.muscles not in ("active", "loads"):
        raise InputError(f"muscles must be 'active' or 'loads', got {settings.muscles!r}")
    settings.tissue                                            # a limit that is no number > 1: InputError
    if settings.lip_bone not in ("free", "muscle"):
        raise InputError(f"lip_bone must be 'free' or 'muscle', got {settings.lip_bone!r}")
    if settings.threads is not None:
        from visemeface.runtime import check_threads
        check_threads(settings.threads)
    for name in settings.off:
        if name not in TERMS:
            raise InputError(f"unknown force term {name!r}" + close_matches(name, TERMS)
                             + f"; known: {', '.join(TERMS)}")


def steps_per_frame(fps: float, dt: float | None, limit: float) -> int:
    """Steps per frame: the fewest whose step is at most ``dt`` (None: the stable ``limit``), so frames
    fall on steps; a ``dt`` above the stable limit is an :class:`InputError` naming both."""
    if dt is not None and dt > limit * (1.0 + 1e-9):
        raise InputError(f"time step {dt:.4g} s exceeds the stable limit {limit:.4g} s of this face; "
                         f"give --dt <= {limit:.4g} or leave it out (the limit is then used)")
    return int(np.ceil(1.0 / (fps * (limit if dt is None else dt)) - 1e-9))


def build_model(fem, drive, film, settings: PhysicsSettings, dt: float, substeps: int = 1):
    """The :class:`FaceModel` of a run: tissue solver, masses, boundary conditions, terms."""
    from visemeface.physics import terms as T
    from visemeface.physics.hexmesh import HexMesh
    from visemeface.physics.integrator import FaceModel
    from visemeface.physics.materials import SALIVA
    from visemeface.physics.tled import TLEDSolver

    mesh = fem.mesh
    tissue_law = settings.tissue
    # The whole mesh (tissue and the saliva hexahedra the film refines) once, for the lumped
    # masses (the saliva hexahedra are no TLED elements: the film's stable step is in
    # StickySimulation.stability); the tissue alone for the step's forces.
    whole = TLEDSolver(mesh, [tissue_law, SALIVA], dt=1e-12, damping=settings.damping,
                       hourglass_kappa=settings.hourglass_kappa)
    tissue_mesh = HexMesh(mesh.nodes, mesh.hexes[fem.tissue], material=np.zeros(len(fem.tissue), np.int64))
    tissue = TLEDSolver(tissue_mesh, tissue_law, dt=dt, damping=settings.damping,
                        hourglass_kappa=settings.hourglass_kappa)
    free = np.ones((mesh.n_nodes, 3))
    free[drive.fixed_nodes] = 0.0
    free[drive.jaw_nodes] = 0.0
    mass = whole.mass
    active = settings.muscles == "active"
    refresh = max(1, int(round(T.REFRESH_SECONDS / dt)))
    terms = {"tissue": T.ActiveTissue(tissue, drive, dt, refresh) if active else T.Tissue(tissue),
             "muscles": T.MuscleLoads(drive, enabled=not active), "saliva": T.Saliva(film),
             "drag": T.Drag(drive, (settings.damping * mass)[:, None] * free)}
    if settings.posture_hz > 0:
        k = (mass * (2.0 * np.pi * settings.posture_hz) ** 2)[:, None] * free
        terms["posture"] = T.PostureSpring(drive, k)
    for name in settings.off:
        if name in terms:
            terms[name].enabled = False
    film_nodes = np.unique(np.concatenate([film.n0.ravel(), film.n1.ravel()]))
    return FaceModel(tissue, mass, free, dt, settings.damping, drive.jaw_nodes, drive.jaw, terms, substeps,
                     film_nodes)


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
    (``1 / (fps · ceil(1 / (fps · dt)))``), so frames fall exactly on steps; ``settings.dt``
    None (the default) takes the face's stable limits (:func:`~visemeface.physics.stability.face_stable_step`,
    in :attr:`stability`): the tissue's, with the film's nodes in :attr:`substeps` at the film's
    (``settings.multirate``); a ``settings.dt`` above the film's limit is refused.
    Everything is checked (dt against the stable limit, glue, moisture) when
    the object is made, before any simulation time is spent.
    """

    def __init__(self, fem, rig, track: pd.DataFrame, physics: str = "sticky",
                 settings: PhysicsSettings | None = None):
        from visemeface.physics.loads import FaceDrive
        from visemeface.physics.integrator import CentralDifference

        settings = settings or PhysicsSettings()
        _check_settings(physics, settings)
        self.fem, self.rig, self.physics, self.settings = fem, rig, physics, settings
        self.values, self.fps = track_values(track, rig)
        if physics == "elastic":
            def glue(s):
                return np.zeros(len(s))
        else:
            def glue(s):
                return glue_per_element(s, settings.glue, settings.glue_profile, settings.glue_file)
        mesh = fem.mesh
        per_layer = len(fem.seam_pairs) - 1
        hexes, ends = mesh.hexes[fem.saliva], fem.seam_s[fem.saliva_pairs]
        if settings.film_corners and fem.corner_hexes is not None and len(fem.corner_hexes):
            hexes, ends = np.concatenate([hexes, fem.corner_hexes]), np.concatenate([ends, fem.corner_s])
            per_layer += len(fem.corner_hexes) // max(len(fem.saliva) // max(per_layer, 1), 1)
        self.film = SalivaFilm(mesh.nodes, hexes, ends, glue, settings.saliva, across=per_layer,
                               min_elements=settings.film_elements)
        #: The film's slabs along the seam (its wedges into the corners, where the lips meet, come after).
        self.seam_slabs = slice(0, len(fem.saliva) * self.film.refine)
        self.stability = face_stable_step(mesh, fem.tissue, self.film, hourglass_kappa=settings.hourglass_kappa)
        film_dt = self.stability["dt"]
        from visemeface.physics.hexmesh import HexMesh
        from visemeface.physics.tled import TLEDSolver
        # dead loads F_int(U), from rest: used by muscles="loads" only (a Gent law has no force in a wide-open U)
        loads = TLEDSolver(HexMesh(mesh.nodes, mesh.hexes[fem.tissue], material=np.zeros(len(fem.tissue), np.int64)),
                           settings.tissue if settings.muscles == "loads" else SOFT_TISSUE, dt=film_dt,
                           hourglass_kappa=settings.hourglass_kappa)
        self.drive = FaceDrive(fem, rig, self.values, self.fps, loads.internal_forces,
                               field_smoothing=settings.field_smoothing, min_jacobian=settings.min_jacobian,
                               lip_bone=settings.lip_bone)
        # The substeps hold every force but the film's and the tissue's at tⁿ: a posture spring (a force of u)
        # held over them grows (measured: it diverged above ~170 Hz), so with one the run is single-rate.
        posture = settings.posture_hz > 0 and "posture" not in settings.off
        multirate = settings.multirate and settings.dt is None and "saliva" not in settings.off and not posture
        if multirate and settings.muscles == "active":      # the tissue's bound in the track's natural shapes
            k = max(1, int(np.ceil(self.n_frames / SHAPE_SAMPLES)))
            shape = natural_shape_step(loads, (self.drive.kinematic_field(v) for v in self.values[::k]))
            self.stability["natural_shape"] = shape
            self.stability["tissue_step"] = min(self.stability["tissue_step"], shape)
        self.steps_per_frame = steps_per_frame(self.fps, settings.dt,
                                               self.stability["tissue_step"] if multirate else film_dt)
        self.dt = 1.0 / (self.fps * self.steps_per_frame)
        #: Film substeps per step (1: single rate).
        self.substeps = int(np.ceil(self.dt / film_dt - 1e-9)) if multirate else 1
        self.model = build_model(fem, self.drive, self.film, settings, self.dt, self.substeps)
        self.integrator = CentralDifference(self.model)
        self.state: SimState | None = None
        self.rest_gaps = fem.rest_gaps
        import numba
        self._most_threads = numba.get_num_threads()
        #: Whether the thread count is timed during the run (no fixed count, more than one thread to try).
        self._timed = settings.threads is None and self._most_threads > 1
        #: numba threads the steps run on (see PhysicsSettings.threads).
        self.threads = settings.threads if settings.threads is not None else self._most_threads
        #: Frames whose multi-rate step diverged and that ran at one rate instead (:meth:`_advance_frame`).
        self.single_rate_frames: list[int] = []
        self._fine = None

    @property
    def n_frames(self) -> int:
        return len(self.values)

    @property
    def duration(self) -> float:
        return (self.n_frames - 1) / self.fps

    @property
    def broken(self) -> np.ndarray:
        """Broken flags of the film's slabs now."""
        return self.state.saliva["broken"]

    def saliva_state(self, vertices, u) -> dict:
        """Per-frame saliva measures: broken fraction (of the film along the seam: the wedges into the
        corners are left out), openings along the seam (mesh) and the film."""
        op = seam_openings(self.fem, vertices, self.rest_gaps)
        film = film_openings(self.film, u, self.fem.mouth_width)
        sal = self.state.saliva
        return {"broken_fraction": float(sal["broken"][self.seam_slabs].mean()), "open_count": op["count"],
                "open_span": op["span"], "open_fraction": op["open_fraction"], "centre_gap": op["centre_gap"],
                "max_stretch": float(np.minimum(sal["stretch"], 1e9).max()),
                "film_open_count": film["count"], "film_open_span": film["span"]}

    def initial_state(self) -> SimState:
        """At rest in the first frame's posture (its equilibrium without glue): a track may start mid-gesture.
        Where that posture presses the lips together the film starts squeezed out (:meth:`SalivaFilm.initial_state`)."""
        u0 = self.drive.keyframe(0)[2] if np.any(self.values[0]) else None
        state = self.integrator.start(u0)
        state.saliva = self.film.initial_state(u0)
        return state

    def frames(self, start: dict | None = None):
        """Simulate, yielding a :class:`SimFrame` per track frame.

        Parameters
        ----------
        start : dict, optional
            A checkpoint from :meth:`checkpoint`: continue after its frame.
        """
        spf = self.steps_per_frame
        if start is None:
            self.state, first = self.initial_state(), 0
        else:
            self.state = SimState.from_dict(start)
            first = int(start["frame"]) + 1
            if self.state.step != (first - 1) * spf or self.state.dt != self.dt:
                raise InputError("the checkpoint's step does not match its frame")
        # Steps on a copy compile (or load) every kernel before the first frame, so an interrupt never
        # lands in numba's compiler, and choose the thread count; the step's caches are pure functions of time.
        self._pick_threads()
        check = max(1, int(round(THREAD_CHECK_SECONDS * self.fps)))
        if start is not None:
            self._advance_frame(first)
        for k in range(first, self.n_frames):
            if k > first:
                if self._timed and (k - first) % check == 0:
                    self._pick_threads()
                self._advance_frame(k)
            yield self._frame(k)

    def _advance_frame(self, k: int) -> None:
        """Step the state to frame ``k``. A multi-rate frame that diverges is run again from its start at one
        rate, every node at the film's substep (:meth:`_single_rate_frame`; the frame goes in
        :attr:`single_rate_frames`); one that diverges single-rate too raises."""
        if self.substeps == 1:
            self.integrator.advance(self.state, self.steps_per_frame)
            return
        start = self.state.copy()
        try:
            self.integrator.advance(self.state, self.steps_per_frame)
        except SimulationDiverged:
            self.state = start
            self._single_rate_frame()
            self.single_rate_frames.append(k)

    def _single_rate_frame(self) -> None:
        """One frame of ``substeps`` × the steps at the film's substep h = dt / substeps, from and back to the
        multi-rate state: u_prev is the position h (then dt) before u, the film's nodes' from their last
        substep (exact), the others' linearly from the velocity (u − u_prev) / dt (central differences'
        change of step)."""
        from visemeface.physics.integrator import CentralDifference
        m, st = self.substeps, self.state
        if self._fine is None:
            self._fine = CentralDifference(build_model(self.fem, self.drive, self.film, self.settings, self.dt / m, 1))
        fast = self.integrator._fast
        st.u_prev = st.u - (st.u - st.u_prev) / m
        if st.fine_prev is not None:
            st.u_prev[fast] = st.fine_prev
        st.step, st.dt = st.step * m, self.dt / m
        self._fine.advance(st, self.steps_per_frame * m)
        st.fine_prev = st.u_prev[fast].copy()
        st.u_prev = st.u - (st.u - st.u_prev) * m
        st.step, st.dt = st.step // m, self.dt
        self.state = st.copy()          # no array of the state is the fine integrator's scratch

    def _pick_threads(self) -> None:
        """Run on ``settings.threads``, or time :data:`THREAD_TRIAL_STEPS` steps on a copy of the state at
        numba's thread count and at one and keep the faster."""
        from visemeface.runtime import faster_thread_count, set_threads

        if not self._timed:
            set_threads(self.threads)
            try:
                self.integrator.step(self.state.copy())      # compiles every kernel before the first frame
            except SimulationDiverged:      # that frame runs single-rate (_advance_frame)
                pass
            return
        def trial():
            try:
                self.integrator.advance(self.state.copy(), THREAD_TRIAL_STEPS)
            except SimulationDiverged:      # the next frame runs single-rate (_advance_frame): time what ran
                pass
        self.threads = faster_thread_count(trial, self._most_threads)

    def _frame(self, k: int) -> SimFrame:
        st = self.state
        base = self.rig.pose(self.values[k])
        verts = self.fem.surface(st.u, base)
        return SimFrame(k, k / self.fps, verts, self.fem.display_vertices(verts, self.rest_gaps), st.u.copy(),
                        st.velocity, self.saliva_state(verts, st.u))

    def checkpoint(self, frame: SimFrame) -> dict:
        """Everything :meth:`frames` needs to continue after ``frame`` (the state as the frame was made)."""
        if self.state is None or self.state.step != frame.index * self.steps_per_frame:
            raise ValueError("checkpoint() takes the frame the simulation has just produced")
        return {"frame": frame.index, **self.state.to_dict(), "fingerprint": self.fingerprint()}

    def fingerprint(self) -> str:
        """A digest of the model, track and settings: a checkpoint only resumes the same run."""
        import hashlib
        h = hashlib.sha256()
        for arr in (self.fem.mesh.nodes, self.fem.mesh.hexes, self.values, self.film.glue):
            h.update(np.ascontiguousarray(arr).tobytes())
        s = self.settings
        h.update(repr((self.physics, self.fps, self.dt, self.substeps, s.damping, s.hourglass_kappa, s.saliva, s.posture_hz,
                       tuple(s.off), s.film_elements, s.film_corners, s.lip_bone, s.muscles, s.field_smoothing, s.min_jacobian)
                      + ((s.tissue_limit,) if np.isfinite(s.tissue_limit) else ())).encode())
        return h.hexdigest()[:16]


def physics_face(face, rig=None, fem=None, seam_elements: int | None = None):
    """(fem, rig) for a face: the FEM model (built if not given, its lips refined to ``seam_elements``
    along the seam if given) and a rig on ``face`` as the FEM refines it (``rig``'s own file placed
    again on :func:`~visemeface.face.refine.refine_lip_seam`'s face, whose first vertices are ``face``'s).
    """
    from visemeface.face.refine import refine_lip_seam
    from visemeface.muscles.rig import MuscleRig
    from visemeface.physics.face_model import build_fem_face

    if fem is None:
        fem = build_fem_face(face, seam_elements=seam_elements)
    if rig is None or rig.face.n_vertices != fem.face.n_vertices:
        fine = face
        if fine.n_vertices != fem.face.n_vertices and seam_elements is not None:
            fine = refine_lip_seam(face, seam_elements)
        if fine.n_vertices != fem.face.n_vertices:
            raise ValueError(f"the FEM face has {fem.face.n_vertices} vertices, the face refined to "
                             f"{seam_elements} seam elements {fine.n_vertices}")
        rig = MuscleRig.from_file(fine, None if rig is None else rig.path)
    return fem, rig


def face_simulation(face, rig, track: pd.DataFrame, physics: str = "sticky",
                    settings: PhysicsSettings | None = None, fem=None) -> StickySimulation:
    """The FEM face of ``face`` driven by ``track`` (every input checked before any step): ``settings``
    default to :meth:`PhysicsSettings.speech`, the FEM and the rig come from :func:`physics_face` (the lips
    refined to ``settings.seam_elements``; the refined face's first vertices are ``face``'s)."""
    settings = settings or PhysicsSettings.speech()
    fem, rig = physics_face(face, rig, fem, settings.seam_elements)
    return StickySimulation(fem, rig, track, physics=physics, settings=settings)


def simulate_track(face, rig, track: pd.DataFrame, physics: str = "sticky",
                   settings: PhysicsSettings | None = None, fem=None, states: list | None = None):
    """Animate ``track`` on the FEM face: an iterator of float32 (N, 3) display vertices of ``face`` per track row.

    The kinematic path's drop-in for ``--physics sticky|elastic`` (lips' rest gap
    drawn closed, :meth:`FEMFace.display_vertices`; the simulation is :func:`face_simulation`'s). All input
    checks run before the first frame. ``states``, if given, collects each frame's saliva measures.
    """
    sim = face_simulation(face, rig, track, physics, settings, fem)
    n = face.n_vertices

    def frames():
        for fr in sim.frames():
            if states is not None:
                states.append({"frame": fr.index, "time": fr.time, **fr.saliva})
            yield fr.display[:n].astype(np.float32)

    return frames()
