"""Drive the FEM face from an ActivationTrack: muscle loads and the prescribed jaw.

The kinematic rig (:mod:`visemeface.muscles.rig`) says where every surface
vertex goes for an activation vector **a**. The FEM face is driven so that,
without saliva, its equilibrium is that posture:

1. **Muscle field.** U(**a**) on every FEM node: the rig's displacement on
   the surface nodes; on the bone side, zero for the skull and the jaw's
   rotation for the jaw nodes; linear through the tissue's depth in between.
   Under the lips (``fem.lip_weight``) the bone side is the lips' own muscle
   layer (orbicularis oris): free, its field the rig's.
2. **Jaw.** The bone-side jaw nodes are *prescribed* U(**a**): the rig's jaw
   rotation with the jaw weight of the vertex above; weight 0 (the skull) is
   fixed. The bone is moved, not pushed.
3. **Muscle loads.** The external force on the free nodes is the internal
   elastic force of the soft tissue held in that field,

   .. math:: \\mathbf f(\\mathbf a) = \\mathbf F_{int}^{tissue}\\big(U(\\mathbf a)\\big),

   the rig's Waters displacement fields turned into force fields through the
   tissue's own (nonlinear: neo-Hookean, or Gent with a limiting stretch) stiffness: with these loads and the
   jaw the static balance F_int(u) = f holds at u = U(**a**). Nothing holds the
   lips to that posture: they reach it, or not, by the FEM
   (:mod:`visemeface.physics.simulation`).

Loads and the jaw are computed at the track's frame times and linearly
interpolated in between, per time step. Track helpers live in
:mod:`visemeface.physics.scenarios`; the simulation in
:mod:`visemeface.physics.simulation`; :mod:`visemeface.physics.drive` gathers them.
"""

from __future__ import annotations

import numpy as np



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
                 min_jacobian: float = 0.0, lip_bone: str = "free"):
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
        # the rig's full field there (blended by ``fem.lip_weight``); it is free, or with
        # ``lip_bone="muscle"`` moved (prescribed) along that field like the jaw's bone.
        inner = mesh.node_sets["inner"]
        w = rig.jaw_weight[fem.surface_vertices[inner - L * S]]
        lam = fem.lip_weight if fem.lip_weight is not None else np.zeros(S)
        self._lip = lam[inner - L * S]
        under_lips = self._lip > 0
        moving = (w != 0) | under_lips
        self.fixed_nodes = inner[~moving]
        self.jaw_nodes = inner[moving & ~under_lips] if lip_bone == "free" else inner[moving]
        self._inner = inner
        self._inner_rest = mesh.nodes[inner]
        self._inner_w = w.copy()
        self._jaw_col = list(rig.names).index("jaw")
        self._cache: dict[int, tuple] = {}
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


    def keyframe(self, k: int):
        """(external force (n, 3), jaw displacement (k, 3), U) at frame ``k`` (cached)."""
        k = int(np.clip(k, 0, self.n_frames - 1))
        if k not in self._cache:
            if len(self._cache) > 4:
                self._cache.pop(min(self._cache))
            U = self.kinematic_field(self.values[k])
            self._cache[k] = (self.tissue_forces(U), U[self.jaw_nodes], U)
        return self._cache[k]

    def _interval(self, t: float):
        """Weight w of time ``t`` between frames i and i + 1; caches that segment's loads.

        Per segment: force, jaw and target at frame i, their change to frame
        i + 1, the target's velocity (constant in between) and output buffers.
        """
        f = t * self.fps
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

    def target_segment(self, t: float):
        """(U at frame i, its change to frame i + 1, weight w) at time ``t``: U(t) = U_i + w ΔU."""
        w = self._interval(t)
        a, d, _ = self._seg["target"]
        return a, d, w

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
