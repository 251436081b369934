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

(``M ü + α M u̇ + F(u) = R`` with centred differences, as NiftySim's TLED), fixed
degrees of freedom held at zero and the jaw nodes set to their value at
``tⁿ⁺¹``. Everything a step reads is in (model, state), so stepping a restored
state repeats a run bit for bit.

**Multi-rate.** The saliva film is far stiffer than the tissue (its
stable step on the default face is 4.8e-5 s, the tissue's 1.8e-4 s) but acts
only on the few nodes it is tied to (52 of 3,558). With ``substeps`` m > 1 the
other nodes take the step Δt and those *film nodes* take m substeps δt = Δt/m:
nodal-partition subcycling (Belytschko, Yen & Mullen 1979; Belytschko, Liu &
Moran 2000, §6.6). At substep j the film nodes' force is recomputed: the
film's, and the tissue's from the elements that hold a film node, with the
other nodes of those elements at their linear interpolation between uⁿ and
uⁿ⁺¹ (known: they stepped first); the rest of their force (muscles, drag) is
held at tⁿ, which is why a term that depends on u (the optional posture spring) must not be there: held
over the substeps it grows, so :class:`~visemeface.physics.simulation.StickySimulation` runs single-rate
with one:

.. math::

   x_{j+1} = a\\,\\big(R^n_{other} - F_{tissue}(x_j, \\tilde u(t_j)) + f_{film}(x_j, t_j)\\big)
             + b\\,x_j + c\\,x_{j-1},\\qquad t_j = t^n + jδt

(a, b, c the coefficients above at δt; the film's breaking rule advances at
δt, as in the single-rate run), and the end of the last substep is the film
nodes' uⁿ⁺¹. The film's stiffness is integrated at its own limit, the
tissue's at its own. The film nodes' last substep position is part of the
state (``SimState.fine_prev``), so a checkpoint resumes bit for bit.
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
    substeps : int
        Film substeps per step (1: single rate; see the module docstring).
    film_nodes : (k,) int
        The nodes the saliva film acts on (those it reads and loads), subcycled when ``substeps`` > 1.
    """

    tissue_solver: object
    mass: np.ndarray
    free: np.ndarray
    dt: float
    damping: float
    jaw_nodes: np.ndarray
    jaw: object
    terms: dict = field(default_factory=dict)
    substeps: int = 1
    film_nodes: np.ndarray = field(default_factory=lambda: np.zeros(0, np.int64))

    @property
    def n_nodes(self) -> int:
        return len(self.mass)

    @property
    def multirate(self) -> bool:
        """Whether the film's nodes are subcycled (more than one substep and the film switched on)."""
        film = self.terms.get("saliva")
        return self.substeps > 1 and film is not None and film.enabled and len(self.film_nodes) > 0

    def external(self, state: SimState, t: float, R: np.ndarray, skip: tuple = ()) -> np.ndarray:
        """R(u, t): the sum of every enabled term but the tissue and ``skip`` (the one place they are summed)."""
        R[:] = 0.0
        for name, term in self.terms.items():
            if name != "tissue" and name not in skip and term.enabled:
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
        m = max(1, int(model.substeps))
        fast = np.ascontiguousarray(model.film_nodes, dtype=np.int64)
        self._fast = fast
        if m > 1 and len(fast):
            h = dt / m
            mf = model.mass[fast]
            a_f = 1.0 / (mf / h ** 2 + a * mf / (2.0 * h))
            b_f = 2.0 * mf * a_f / h ** 2
            c_f = a * mf * a_f / (2.0 * h) - b_f / 2.0
            free = model.free[fast]
            # held degrees of freedom keep their value at tⁿ through the substeps (the jaw is imposed after)
            self._fine = tuple(np.ascontiguousarray(x[:, None] * free) for x in (a_f, b_f, c_f)) \
                + (np.ascontiguousarray(1.0 - free),)
            self._film_on_jaw = bool(np.isin(fast, model.jaw_nodes).any())
            conn = model.tissue_solver.conn
            touches = np.isin(conn, fast).any(axis=1)
            #: The tissue elements that hold a film node, and every node of theirs.
            self._elems = np.flatnonzero(touches).astype(np.int64)
            self._ring = np.unique(conn[self._elems]).astype(np.int64)
            self._G = np.zeros((len(fast), 3))
            self._x = np.zeros((len(fast), 3))
            self._film_u = np.zeros((model.n_nodes, 3))
            self._film_R = np.zeros((model.n_nodes, 3))
            self._ue = np.zeros((model.n_nodes, 3))
            film = model.terms["saliva"].film
            #: The film's breaking points: the buffer its rule reads, and its value at each substep.
            self._Z = film.breaking_points_at(0.0).copy()
            self._Zs = np.ascontiguousarray(np.tile(self._Z, (m, 1)))

    def start(self, u0=None, saliva: dict | None = None) -> SimState:
        """The state at rest in ``u0`` (zero velocity: u_prev = u0), jaw imposed at t = 0."""
        n = self.model.n_nodes
        u = np.zeros((n, 3)) if u0 is None else np.array(u0, dtype=np.float64)
        u *= self.model.free
        self.model.impose(u, 0.0)
        fine = u[self._fast].copy() if self.model.multirate else None
        return SimState(u, u.copy(), 0, self.model.dt, dict(saliva or {}), fine)

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
        multirate = model.multirate
        R = model.external(state, t, self._R, ("saliva",) if multirate else ())
        new = self._new
        if tissue.enabled:
            ue, dhdx, vol, gamma, hgk = tissue.inputs(state.u, t, state.step)
            jmin = self._step(ue, s.conn, dhdx, vol, gamma, hgk, s.mu, s.K, s.ijm, s._fe, s._jac, s._fdef, s._energy,
                              False, s._ptr, s._slot, R, self._A, self._B, self._C, state.u, state.u_prev, new)
            if not jmin > 0.0:
                s._check(state.step, t)
        else:
            tissue.element_forces(state.u, t, state.step)
            s._check(state.step, t)
            self._kernel(s._fe.reshape(-1, 3), s._ptr, s._slot, R, self._A, self._B, self._C, state.u,
                         state.u_prev, new)
        model.impose(new, (state.step + 1) * dt)
        if multirate:                   # after the jaw: the film nodes' neighbours interpolate to its uⁿ⁺¹
            self._substeps(state, t, R, new)
            if self._film_on_jaw:       # a film node on the jaw held its uⁿ through the substeps
                model.impose(new, (state.step + 1) * dt)
        # rotate the buffers: u_prev <- u <- new, the old u_prev becomes the next scratch
        self._new = state.u_prev
        state.u_prev, state.u = state.u, new
        state.step += 1

    def _substeps(self, state: SimState, t: float, R: np.ndarray, new: np.ndarray) -> None:
        """The film nodes' m substeps (module docstring), in one compiled call (:func:`_substep_loop`):
        ``new``'s film-node rows become their uⁿ⁺¹."""
        model, s = self.model, self.model.tissue_solver
        tissue, film = model.terms["tissue"], model.terms["saliva"].film
        m = int(model.substeps)
        h = model.dt / m
        if state.fine_prev is None:           # a state made without multi-rate: start the film nodes at rest
            state.fine_prev = state.u[self._fast].copy()
        times = [t + j * h for j in range(m)]
        Ua, Ud, w, geo = tissue.segment(times, state.step)
        if film.params.evaporation != 0.0:
            self._Zs = np.stack([film.breaking_points(tj) for tj in times])
        tis = (s.conn,) + tuple(geo) + (s.mu, s.K, s.ijm, s._fe, s._jac, s._fdef, s._energy, s._ptr, s._slot)
        jmin = _substep_loop(self._fast, self._ring, self._elems, state.u, new, self._x, state.fine_prev,
                             self._film_u, self._ue, self._film_R, self._G, R, self._fine, (Ua, Ud, w), tis,
                             film.rule_args(self._Z, state.saliva, h), self._Z, self._Zs, tissue.enabled)
        if not jmin > 0.0:
            s._check(state.step, t)

    def advance(self, state: SimState, n_steps: int) -> None:
        for _ in range(int(n_steps)):
            self.step(state)


from numba import njit  # noqa: E402

from visemeface.physics.film import _film_step  # noqa: E402
from visemeface.physics.tled import _element_force, _node_force  # noqa: E402


@njit(cache=True, boundscheck=False)
def _boundary_forces(elems, rows, ue, conn, dhdx, vol, gamma, hgk, mu, K, ijm, fe, jac, fdef, energy, ptr, slot, R,
                     G):  # pragma: no cover - compiled
    """The elements ``elems`` (every element that holds a node of ``rows``) at ``ue``, then
    G[i] = R[n] − Σ of node n's element forces, n = rows[i]; returns their smallest J."""
    jmin = np.inf
    for k in range(elems.shape[0]):
        e = elems[k]
        _element_force(e, ue, conn, dhdx, vol, gamma, hgk, mu, K, ijm, fe, jac, fdef, False, energy, False)
        if jmin > 0.0 and not jac[e] >= jmin:     # the smallest J; the first that is not > 0 (or NaN) stays
            jmin = jac[e]
    fe_flat = fe.reshape(-1, 3)
    for i in range(rows.shape[0]):
        n = rows[i]
        f = _node_force(n, fe_flat, ptr, slot)
        for d in range(3):
            G[i, d] = R[n, d] - f[d]
    return jmin


@njit(cache=True, boundscheck=False)
def _substep_loop(fast, ring, elems, u, new, x, xp, U, ue, Rf, G, R, coef, field, tis, film_args, Z, Zs,
                  tissue_on):  # pragma: no cover - compiled
    """The film nodes' m = len(w) substeps of one step (the integrator's module docstring); returns the
    smallest J of the elements that hold them (≤ 0: stopped there).

    ``u``, ``new``: every node at tⁿ and tⁿ⁺¹ (the film nodes' rows of ``new`` are overwritten with
    theirs); ``x``, ``xp``: the film nodes' positions now and a substep before (``xp`` is the state's);
    ``U``, ``ue``, ``Rf``, ``G``: work rows; ``R``: the step's force without the film, held; ``coef``: the
    substep's (a, b, c, hold); ``field``: (U_i, ΔU, w) with the elements seeing U − (U_i + w_j ΔU) at
    substep j; ``tis``: the tissue's element data; ``film_args``: the film rule's arguments after (u, R),
    whose breaking points are the array ``Z``, refilled from ``Zs[j]`` each substep.
    """
    a, b, c, hold = coef
    Ua, Ud, w = field
    conn, dhdx, vol, gamma, hgk, mu, K, ijm, fe, jac, fdef, energy, ptr, slot = tis
    m = w.shape[0]
    jmin = np.inf
    for i in range(fast.shape[0]):
        for d in range(3):
            x[i, d] = u[fast[i], d]
    for j in range(m):
        s = j / m
        for k in range(ring.shape[0]):            # the other nodes of the film nodes' elements: interpolated
            n = ring[k]
            for d in range(3):
                U[n, d] = u[n, d] + s * (new[n, d] - u[n, d])
        for i in range(fast.shape[0]):
            for d in range(3):
                U[fast[i], d] = x[i, d]
        if tissue_on:
            wj = w[j]
            for k in range(ring.shape[0]):
                n = ring[k]
                for d in range(3):
                    ue[n, d] = U[n, d] - (Ud[n, d] * wj + Ua[n, d])
            jm = _boundary_forces(elems, fast, ue, conn, dhdx, vol, gamma, hgk, mu, K, ijm, fe, jac, fdef, energy, ptr,
                                  slot, R, G)
            if not jm > 0.0:
                return jm
            jmin = min(jmin, jm)
        else:
            for i in range(fast.shape[0]):
                for d in range(3):
                    G[i, d] = R[fast[i], d]
        Z[:] = Zs[j]
        _film_step(U, Rf, *film_args)
        _fine_update(fast, G, Rf, a, b, c, hold, x, xp)
    for i in range(fast.shape[0]):
        for d in range(3):
            new[fast[i], d] = x[i, d]
    return jmin


@njit(cache=True, boundscheck=False)
def _fine_update(rows, G, Rf, a, b, c, hold, x, xp):  # pragma: no cover - compiled
    """One substep of the film nodes: x ← a (G + film force) + b x + c x_prev (held rows keep x), in place
    (xp takes the old x); the film's force rows are zeroed for the next substep."""
    for i in range(rows.shape[0]):
        n = rows[i]
        for d in range(3):
            v = a[i, d] * (G[i, d] + Rf[n, d]) + b[i, d] * x[i, d] + c[i, d] * xp[i, d] + hold[i, d] * x[i, d]
            xp[i, d] = x[i, d]
            x[i, d] = v
            Rf[n, d] = 0.0
