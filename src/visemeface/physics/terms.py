"""Force terms of the FEM face, each one switchable and testable alone.

The integrator (:mod:`visemeface.physics.integrator`) solves

.. math:: M\\ddot u + \\alpha M \\dot u + F_{tissue}(u) = R(u, t),\\qquad
          R = \\sum_{\\text{terms}} r_k(u, t)

and sums the terms' contributions to ``R`` in one place
(:meth:`FaceModel.external`). Each term has a ``name`` and ``enabled`` flag and
``add(state, t, R)``; the tissue's internal force is the one term the fused
assembly-and-update kernel sums itself (:class:`Tissue`).

=========== ============================================================================
tissue      neo-Hookean soft tissue (TLED, :mod:`visemeface.physics.tled`); by default with the
            muscles as an active strain (:class:`ActiveTissue`)
muscles     or the muscles as dead loads f(a(t)) = F_tissue(U(a(t))) (:class:`MuscleLoads`)
saliva      the breaking saliva film, with its contact push (:class:`~visemeface.physics.film.SalivaFilm`)
drag        α M dU/dt: the mass damping measured relative to the moving muscle field
posture     optional spring m (2π f)² (U(t) − u) on every free node (off by default)
=========== ============================================================================

Stabilisers act on every free node alike and know nothing of the seam.
"""

from __future__ import annotations

import numpy as np


#: How often the active strain's natural shape is refreshed (s; every step when the step is longer): between
#: refreshes it lags the track by at most this, 3 % of a 60 fps frame. 5e-4 s, not the 1e-4 s (10 steps of
#: 1e-5 s) it was: a refresh costs 0.4 ms on the default face, 5 s per simulated second at 1e-4 s.
REFRESH_SECONDS = 5e-4


class Term:
    """A force term: ``add(state, t, R)`` adds its force (n, 3) to ``R`` in place."""

    name = "term"

    def __init__(self, enabled: bool = True):
        self.enabled = bool(enabled)

    def add(self, state, t: float, R: np.ndarray) -> None:  # pragma: no cover - interface
        raise NotImplementedError


class Tissue(Term):
    """The tissue's internal forces: element forces into the solver's buffer (summed by the kernel)."""

    name = "tissue"

    def __init__(self, solver, enabled: bool = True):
        super().__init__(enabled)
        self.solver = solver

    def inputs(self, u, t: float = 0.0, step: int = 0) -> tuple:
        """What the element kernel reads at this step: (the displacement the elements see, ∂h/∂x, V, γ,
        hourglass stiffness); here ``u`` and the rest geometry."""
        s = self.solver
        return u, s.dhdx, s.force_volume, s.gamma, s.hourglass_stiffness

    def segment(self, times, step: int = 0) -> tuple:
        """For substeps at ``times`` within step ``step`` (:mod:`visemeface.physics.integrator`): (a, d, w, geometry)
        with the displacement the elements see u − (a + w_j d) at ``times[j]``; here a = d = 0 and the rest geometry."""
        s = self.solver
        if getattr(self, "_zero", None) is None:
            self._zero = np.zeros(s.mesh.nodes.shape)
        return self._zero, self._zero, np.zeros(len(times)), (s.dhdx, s.force_volume, s.gamma, s.hourglass_stiffness)

    def element_forces(self, u, t: float = 0.0, step: int = 0) -> None:
        """Fill ``solver._fe`` (zeros when switched off) and ``solver._jac`` for ``u``."""
        s = self.solver
        if not self.enabled:
            s._element_forces(u, False)
            s._fe[:] = 0.0
            return
        ue, dhdx, vol, gamma, hgk = self.inputs(u, t, step)
        s._elem_kernel(ue, s.conn, dhdx, vol, gamma, hgk, s.mu, s.K, s.ijm, s._fe, s._jac, s._fdef, False,
                       s._energy, False)


class ActiveTissue(Tissue):
    """The tissue with the muscles as an *active strain*: its natural shape is the muscle field's.

    Each element's deformation splits as F = F_e F_a, F_a = ∂(X + U(a))/∂X the
    muscle field's own deformation (the rig's posture at activation **a**), and
    the tissue stores W(F_e) per unit volume of that natural shape (Nardinocchi &
    Teresi's active strain). That is TLED with the reference geometry
    Y = X + U(a(t)) and displacement u − U: the same kernel, per-element
    gradients, volumes and hourglass vectors of Y. At u = U every element is
    stress-free and the energy is at its minimum, so the posture is a *stable*
    equilibrium at the tissue's own stiffness (the dead loads F_int(U) of
    :class:`MuscleLoads` make it unstable on rounded visemes, which the old 1 kHz
    posture spring hid). It rotates with the tissue (no dead load), acts alike on
    every element, and knows nothing of the seam.

    Y's geometry is computed at the track's frames and interpolated linearly,
    refreshed every ``refresh`` steps (:data:`REFRESH_SECONDS`); the steps at which it is refreshed are multiples of ``refresh``,
    so a resumed run sees the same values.
    """

    name = "tissue"

    def __init__(self, solver, drive, dt: float, refresh: int = 10, enabled: bool = True):
        super().__init__(solver, enabled)
        self.drive, self.dt, self.refresh = drive, float(dt), int(refresh)
        self._geo: dict[int, tuple] = {}
        s = solver
        self._nodes = s.mesh.nodes
        self._lam2mu = s.K + 4.0 * s.mu / 3.0
        self._cur = None
        self._uY = np.zeros(s.mesh.nodes.shape)

    def geometry(self, k: int):
        """(∂h/∂Y, V_Y, γ_Y, hourglass stiffness) of the muscle field's shape at track frame ``k``."""
        from visemeface.physics.tled import element_geometry, hourglass_shape_vectors
        k = int(np.clip(k, 0, self.drive.n_frames - 1))
        if k not in self._geo:
            if len(self._geo) > 3:
                self._geo.pop(min(self._geo))
            Y = self._nodes + self.drive.keyframe(k)[2]
            conn = self.solver.conn
            dhdx, vol = element_geometry(Y, conn)
            gamma = hourglass_shape_vectors(Y, conn, dhdx)
            a = np.einsum("eai,eai->e", dhdx, dhdx)
            hgk = self.solver.kappa * vol * self._lam2mu * a / 8.0
            self._geo[k] = tuple(np.ascontiguousarray(x) for x in (dhdx, vol, gamma, hgk))
        return self._geo[k]

    def _refresh(self, step: int, t: float) -> None:
        s0 = step - step % self.refresh
        if self._cur is not None and self._cur[0] == s0:
            return
        f = s0 * self.dt * self.drive.fps
        i = int(f + 1e-9)
        w = min(max(f - i, 0.0), 1.0)
        a, b = self.geometry(i), self.geometry(i + 1)
        if self._cur is None:
            self._buf = tuple(np.empty(x.shape) for x in a)   # C order: reshape(-1) below is a view
        for out, x, y in zip(self._buf, a, b):      # out = x + w (y - x), in place: no allocation a refresh
            _lerp_into(x.ravel(), y.ravel(), w, out.reshape(-1))
        self._cur = (s0, self._buf)

    def inputs(self, u, t: float = 0.0, step: int = 0) -> tuple:
        """u − U(t) and the natural shape's geometry (see the class docstring)."""
        self._refresh(step, t)
        a, d, w = self.drive.target_segment(t)
        _minus_lerp(u.ravel(), a.ravel(), d.ravel(), w, self._uY.reshape(-1))
        return (self._uY,) + self._cur[1]


    def segment(self, times, step: int = 0) -> tuple:
        """(U_i, ΔU, w_j, geometry): the field U(times[j]) = U_i + w_j ΔU and the natural shape's geometry (as
        refreshed at ``step``); the times lie within one track segment (a step divides a frame)."""
        self._refresh(step, times[0])
        segments = [self.drive.target_segment(t) for t in times]
        a, d, _ = segments[0]
        if segments[-1][0] is not a:
            raise ValueError("substeps cross a track frame: the step must divide a frame")
        return a, d, np.array([w for _, _, w in segments]), self._cur[1]


class MuscleLoads(Term):
    """The muscles' loads on the free nodes at time ``t`` (linear between track frames)."""

    name = "muscles"

    def __init__(self, drive, enabled: bool = True):
        super().__init__(enabled)
        self.drive = drive

    def add(self, state, t, R):
        R += self.drive.force(t)


class Saliva(Term):
    """The saliva film: its breaking rule advances one step and its forces are subtracted."""

    name = "saliva"

    def __init__(self, film, enabled: bool = True):
        super().__init__(enabled)
        self.film = film

    def add(self, state, t, R):
        self.film.add_forces(state.u, t, state.saliva, R, state.dt)


class Drag(Term):
    """+α m_i dU_i/dt on every free node: with the integrator's −α m u̇, the damping α m (u̇ − U̇).

    The seed's mass damping measured relative to the muscle field's own motion,
    so a fast gesture is not held back by the damping; at rest it is the seed's.
    """

    name = "drag"

    def __init__(self, drive, alpha_m, enabled: bool = True):
        super().__init__(enabled)
        self.drive, self.alpha_m = drive, np.asarray(alpha_m, dtype=np.float64)
        self._buf = np.zeros((len(self.alpha_m), 3))
        self._v = None

    def add(self, state, t, R):
        v = self.drive.target_velocity(t)
        if v is not self._v:                      # constant over a track segment: multiplied once
            np.multiply(self.alpha_m, v, out=self._buf)
            self._v = v
        R += self._buf


class PostureSpring(Term):
    """m_i (2π f)² (U_i(t) − u_i) on every free node alike (a stabiliser; off unless asked for)."""

    name = "posture"

    def __init__(self, drive, k, enabled: bool = True):
        super().__init__(enabled)
        self.drive, self.k = drive, np.asarray(k, dtype=np.float64)
        self._buf = np.zeros((len(self.k), 3))

    def add(self, state, t, R):
        np.subtract(self.drive.target(t), state.u, out=self._buf)
        self._buf *= self.k
        R += self._buf


from numba import njit  # noqa: E402


@njit(cache=True, boundscheck=False)
def _lerp_into(x, y, w, out):  # pragma: no cover - compiled
    """out = (y − x) w + x over flat arrays, one pass (numpy took three)."""
    for i in range(out.shape[0]):
        out[i] = (y[i] - x[i]) * w + x[i]


@njit(cache=True, boundscheck=False)
def _minus_lerp(u, a, d, w, out):  # pragma: no cover - compiled
    """out = u − (d w + a) over flat arrays: the displacement from the field U(t) = a + w d, one pass."""
    for i in range(out.shape[0]):
        out[i] = u[i] - (d[i] * w + a[i])
