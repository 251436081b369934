"""The FEM face's model and its central-difference integrator, stepping (model, state).

:class:`FaceModel` is everything constant over a run: the tissue's element
data (a tissue-only :class:`~visemeface.physics.tled.TLEDSolver`, used for its
precomputed geometry and compiled kernels), the lumped masses (tissue and
saliva), the fixed skull nodes, the jaw nodes and their prescribed motion, and
the force terms (:mod:`visemeface.physics.terms`). :class:`CentralDifference`
advances a :class:`~visemeface.physics.state.SimState` by

.. math::

   u^{n+1} = A (R^n - F^n) + B u^n + C u^{n-1},\\quad
   A = \\Big(\\frac{M}{\\Delta t^2} + \\frac{\\alpha M}{2\\Delta t}\\Big)^{-1},\\;
   B = \\frac{2 M A}{\\Delta t^2},\\; C = \\frac{\\alpha M A}{2\\Delta t} - \\frac{B}{2}

(``M ü + α M u̇ + F(u) = R`` with centred differences, DESIGN §6), fixed
degrees of freedom held at zero and the jaw nodes set to their value at
``tⁿ⁺¹``. Everything a step reads is in (model, state), so stepping a restored
state repeats a run bit for bit.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from visemeface.physics.state import SimState


@dataclass
class FaceModel:
    """Constant data of a run (see the module docstring).

    Attributes
    ----------
    tissue_solver : TLEDSolver
        On the tissue elements only (its ``_fe``/``_jac`` buffers are the step's).
    mass : (n,) lumped mass of tissue and saliva.
    free : (n, 3) 1 for free degrees of freedom, 0 for fixed and prescribed ones.
    dt, damping : float
        Time step (s) and mass-damping coefficient α (1/s).
    jaw_nodes : (k,) int; jaw : callable ``t -> (k, 3)`` prescribed displacement.
    terms : dict name -> Term, the tissue first.
    """

    tissue_solver: object
    mass: np.ndarray
    free: np.ndarray
    dt: float
    damping: float
    jaw_nodes: np.ndarray
    jaw: object
    terms: dict = field(default_factory=dict)

    @property
    def n_nodes(self) -> int:
        return len(self.mass)

    def external(self, state: SimState, t: float, R: np.ndarray) -> np.ndarray:
        """R(u, t): the sum of every enabled term but the tissue (the one place they are summed)."""
        R[:] = 0.0
        for name, term in self.terms.items():
            if name != "tissue" and term.enabled:
                term.add(state, t, R)
        return R

    def impose(self, u: np.ndarray, t: float) -> None:
        """Set the prescribed (jaw) nodes of ``u`` to their value at ``t``."""
        if len(self.jaw_nodes):
            u[self.jaw_nodes] = self.jaw(t)


class CentralDifference:
    """Explicit central-difference time stepping of a :class:`FaceModel` (module docstring)."""

    def __init__(self, model: FaceModel):
        from visemeface.physics import tled
        self.model = model
        m, dt, a = model.mass, model.dt, model.damping
        A = 1.0 / (m / dt ** 2 + a * m / (2.0 * dt))
        B = 2.0 * m * A / dt ** 2
        C = a * m * A / (2.0 * dt) - B / 2.0
        self._A, self._B, self._C = (np.ascontiguousarray(x[:, None] * model.free) for x in (A, B, C))
        s = model.tissue_solver
        self._kernel = tled._integrate_nb if s.parallel else tled._integrate_serial
        self._step = tled._step_nb if s.parallel else tled._step_serial
        self._R = np.zeros((model.n_nodes, 3))
        self._new = np.zeros((model.n_nodes, 3))

    def start(self, u0=None, saliva: dict | None = None) -> SimState:
        """The state at rest in ``u0`` (zero velocity: u_prev = u0), jaw imposed at t = 0."""
        n = self.model.n_nodes
        u = np.zeros((n, 3)) if u0 is None else np.array(u0, dtype=np.float64)
        u *= self.model.free
        self.model.impose(u, 0.0)
        return SimState(u, u.copy(), 0, self.model.dt, dict(saliva or {}))

    def step(self, state: SimState) -> None:
        """Advance ``state`` by one step in place.

        R(u, t) first (no term reads the tissue's forces), then the tissue's element forces and the
        update in one compiled call (:func:`~visemeface.physics.tled._step_nb`), then the divergence
        check on that call's smallest J and the jaw.
        """
        model, dt = self.model, self.model.dt
        t = state.step * dt
        tissue = model.terms["tissue"]
        s = model.tissue_solver
        R = model.external(state, t, self._R)
        new = self._new
        if tissue.enabled:
            ue, dhdx, vol, gamma, hgk = tissue.inputs(state.u, t, state.step)
            jmin = self._step(ue, s.conn, dhdx, vol, gamma, hgk, s.mu, s.K, s._fe, s._jac, s._fdef, s._energy,
                              False, s._ptr, s._slot, R, self._A, self._B, self._C, state.u, state.u_prev, new)
            if not jmin > 0.0:
                s._check(state.step, t)
        else:
            tissue.element_forces(state.u, t, state.step)
            s._check(state.step, t)
            self._kernel(s._fe.reshape(-1, 3), s._ptr, s._slot, R, self._A, self._B, self._C, state.u,
                         state.u_prev, new)
        model.impose(new, (state.step + 1) * dt)
        # rotate the buffers: u_prev <- u <- new, the old u_prev becomes the next scratch
        self._new = state.u_prev
        state.u_prev, state.u = state.u, new
        state.step += 1

    def advance(self, state: SimState, n_steps: int) -> None:
        for _ in range(int(n_steps)):
            self.step(state)
