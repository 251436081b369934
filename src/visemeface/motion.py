"""Motion: the frames of an animation, produced one at a time.

A :class:`Motion` is an iterator factory over :class:`Frame` objects (the
face's vertices at each frame time, plus per-frame measures) that the run loop
(:func:`visemeface.pipeline.run`) feeds to the sinks. Two kinds:

:class:`KinematicMotion`
    The rig posed along an ActivationTrack: each frame is one matrix product,
    so any frame can be made again at once (resuming needs no saved state).
:class:`SimulatedMotion`
    The FEM face (:class:`visemeface.physics.drive.StickySimulation`) driven by
    a track: each frame costs thousands of time steps, so the motion can save
    its whole state after a frame (:meth:`SimulatedMotion.state`) and continue
    from it bit-identically (``frames(state=...)``).

``key()`` is a digest of everything the vertices depend on: a checkpoint or
kept frames are only reused for the same key.
"""

from __future__ import annotations

import hashlib
import json
from collections.abc import Iterator
from dataclasses import dataclass, field

import numpy as np

from visemeface import __version__
from visemeface.track import track_fps


@dataclass
class Frame:
    """One frame of a motion.

    Attributes
    ----------
    index : int
        Frame number from 0 (the row of the activation track).
    time : float
        ``index / fps`` (s).
    vertices : (N, 3) float32
        The face's vertex positions.
    data : dict
        Per-frame measures (name -> float), e.g. the saliva state of a simulation.
    image : (H, W, 3) uint8 or None
        The rendered frame, set by the run loop when a sink needs it.
    """

    index: int
    time: float
    vertices: np.ndarray
    data: dict = field(default_factory=dict)
    image: np.ndarray | None = None


def digest(*parts) -> str:
    """SHA-256 (hex) of arrays and JSON-able values, in order."""
    h = hashlib.sha256()
    for p in parts:
        if isinstance(p, np.ndarray):
            arr = np.ascontiguousarray(p)
            h.update(str((arr.dtype.str, arr.shape)).encode())
            h.update(arr.tobytes())
        else:
            h.update(json.dumps(p, sort_keys=True, default=str).encode())
    return h.hexdigest()


def face_digest(face) -> str:
    """Digest of what a rendered face depends on besides its motion."""
    return digest(np.asarray(face.vertices, np.float64), np.asarray(face.triangles, np.int64),
                  np.asarray(face.vertex_colors(), np.float32), np.asarray(face.vertex_normals(), np.float32))


class Motion:
    """Base class: ``face``, ``fps``, ``n_frames``; :meth:`frames`; :meth:`key`.

    ``face`` is the mesh the outputs are written for. A frame's ``vertices`` may hold more rows than
    it has: the first ``face.n_vertices`` are its vertices, and the whole array is the vertices of
    :attr:`render_face`, a finer mesh of the same surface that is rendered (the FEM face's lips
    refined along the seam, :func:`visemeface.face.refine.refine_lip_seam`).
    """

    #: True when the motion has state worth saving (a simulation), False when any
    #: frame is cheap to make again.
    resumable: bool = False
    #: Progress-bar label.
    label: str = "rendering"

    face = None
    fps: float = 0.0
    n_frames: int = 0

    @property
    def render_face(self):
        """The mesh rendered and checkpointed: ``face``, or a finer one whose first vertices are ``face``'s."""
        return self.face

    def frames(self, start: int = 0, state: dict | None = None) -> Iterator[Frame]:
        """Frames ``start … n_frames-1`` (a resumable motion continues from ``state``)."""
        raise NotImplementedError

    def still_vertices(self):
        """(N,) bool: the render face's vertices every frame leaves at rest (the renderer may then leave
        out triangles hidden at rest, :mod:`visemeface.render.culling`), or None where none is known."""
        return None

    def frame(self, index: int) -> Frame:
        """Frame ``index`` alone (kinematic motions only)."""
        raise NotImplementedError

    def state(self) -> dict:
        """The state after the last frame :meth:`frames` yielded (resumable motions only)."""
        raise NotImplementedError

    def key(self) -> str:
        raise NotImplementedError

    def settings(self) -> dict:
        """The run's named settings as strings (recorded in its checkpoint, so that a checkpoint refused as
        another run's can say which differ); {} where there are none."""
        return {}


class KinematicMotion(Motion):
    """The rig posed along an ActivationTrack (activations clamped to the rig's ranges).

    Parameters
    ----------
    rig : MuscleRig
    track : DataFrame
        ActivationTrack (its frame rate by :func:`visemeface.track.track_fps`).
    """

    def __init__(self, rig, track):
        self.rig, self.track = rig, track
        self.face = rig.face
        self.fps = track_fps(track)
        self.activations = rig.clamp(rig.track_matrix(track))
        self.n_frames = len(self.activations)

    def still_vertices(self):
        return self.rig.still_vertices(self.activations)

    def frame(self, index: int) -> Frame:
        v = np.asarray(self.rig.pose(self.activations[index]), dtype=np.float32)
        return Frame(index, index / self.fps, v)

    def frames(self, start: int = 0, state: dict | None = None) -> Iterator[Frame]:
        for i in range(start, self.n_frames):
            yield self.frame(i)

    def key(self) -> str:
        rig = self.rig
        jaw = [np.asarray(rig.jaw_displacement(s), np.float64) for s in (0.25, 0.5, 1.0)]
        return digest(__version__, list(rig.names), face_digest(self.face), np.asarray(rig.bases, np.float64),
                      *jaw, np.asarray(self.activations, np.float64), self.fps)


class SimulatedMotion(Motion):
    """The FEM face driven along a track (:class:`~visemeface.physics.drive.StickySimulation`).

    Each frame's ``data`` holds the track's jaw activation and the saliva
    measures of :meth:`StickySimulation.saliva_state`. ``face`` (default: the FEM's face) is the mesh
    the outputs are written for; the FEM's face, rendered, may refine it (its first vertices are
    ``face``'s, :attr:`Motion.render_face`).
    """

    resumable = True
    label = "simulating"

    def __init__(self, sim, face=None):
        self.sim = sim
        self._render_face = sim.fem.face
        self.face = sim.fem.face if face is None else face
        n = self.face.n_vertices
        if n > self._render_face.n_vertices:
            raise ValueError(f"the FEM's face has {self._render_face.n_vertices} vertices, fewer than the face's {n}")
        self.fps = float(sim.fps)
        self.n_frames = int(sim.n_frames)
        self._jaw = sim.values[:, list(sim.rig.names).index("jaw")]
        self._last = None

    def frames(self, start: int = 0, state: dict | None = None) -> Iterator[Frame]:
        if (state is None) != (start == 0):
            raise ValueError("a simulation starts at frame 0 or continues from a saved state")
        for fr in self.sim.frames(start=state):
            self._last = fr
            data = {"jaw": float(self._jaw[fr.index]), **fr.saliva}
            yield Frame(fr.index, fr.time, np.asarray(fr.display, dtype=np.float32), data)

    @property
    def render_face(self):
        return self._render_face

    def state(self) -> dict:
        return self.sim.checkpoint(self._last)

    def key(self) -> str:
        return digest(__version__, face_digest(self.face), face_digest(self._render_face), self.sim.fingerprint())

    def settings(self) -> dict:
        """The physics, frame rate and every :class:`~visemeface.physics.drive.PhysicsSettings` field but
        ``threads`` (which changes no result)."""
        import dataclasses

        s = self.sim.settings
        named = {f.name: repr(getattr(s, f.name)) for f in dataclasses.fields(s) if f.name != "threads"}
        return {"physics": self.sim.physics, "fps": f"{self.fps:g}", **named}
