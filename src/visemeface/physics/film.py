"""The saliva film between the lips on its own discretisation, and the one compiled rule.

:class:`SalivaFilm` carries the breaking saliva of :mod:`visemeface.physics.saliva`
on slabs finer than the face mesh: each saliva hexahedron of the face model
(node order ξ along the seam, η from the lower lip up, ζ from the bone side
out) is split into ``r`` slabs along ξ, with ``r`` chosen so that at least
:data:`FILM_ELEMENTS` slabs span the mouth. A slab node at fraction ``w``
along its hexahedron's ξ edge is

.. math:: x_v = (1 - w)\\,x_{a} + w\\,x_{b},

``a``, ``b`` the edge's two tissue nodes: the hexahedron's own trilinear field,
so the slabs tile it exactly and add no degree of freedom. A slab's nodal forces
go back to the tissue nodes with the same weights (the transpose), so the film
does virtual work on the tissue exactly as it stores energy.

The per-slab rule (stretch, breaking, decay, contact, re-bond, squeeze) is
:func:`_film_step`, written once and compiled; its plain-numpy reference is in
``tests/physics/film_reference.py``. The film's state (``broken``, ``dry``,
``stored``, ``stretch``, ``flow``: the stretch taken up by the saliva's viscous
flow, :attr:`~visemeface.physics.saliva.SalivaParams.viscosity`; ``damage``: the cohesive
law's D, :attr:`~visemeface.physics.saliva.SalivaParams.rupture_time`) lives in the simulation's
:class:`~visemeface.physics.state.SimState`, not here.

The film may run on into the mouth corners (wedges from the last seam pair to the corner
node both lips share, :attr:`~visemeface.physics.face_model.FEMFace.corner_hexes`): then it
has no free end, whose notch tip otherwise carries 1.2-1.3x the centre's stretch.
"""

from __future__ import annotations

import numpy as np

from visemeface.physics import tled as _tled  # noqa: F401  (chooses numba's cache folder first)
from visemeface.physics.saliva import (DECAY_STEP, FILM_STIFF_STRETCH, SalivaParams, breaking_point, deformation_gradient,
                                       element_frames, film_gradients, hex_centre_gradients, moisture,
                                       stretch_across)

#: Least number of film slabs across the mouth (the open span grows in steps
#: of at most 1/48 of the mouth, whatever the face mesh's resolution).
FILM_ELEMENTS = 48
#: The stretch Q of a slab folded over (J ≤ 0): larger than any real one.
FOLDED = 1e300
#: Damage at which a cohesive slab counts as snapped (its last 0.1 % of pull dropped; a
#: first-order rupture approaches 1 only asymptotically).
SNAPPED = 0.999
#: ξ-partner of each hex8 node (0-1, 3-2, 4-5, 7-6) and whether the node is on the ξ+ side.
_PARTNER = np.array([1, 0, 3, 2, 5, 4, 7, 6])
_XI_PLUS = np.array([False, True, True, False, False, True, True, False])


def refine_slabs(hexes, r: int):
    """Split hexahedra into ``r`` slabs along ξ: per slab node, (node ξ−, node ξ+, weight on ξ+).

    Returns
    -------
    n0, n1 : (E·r, 8) int
        The two tissue nodes each slab node lies between (n0 on the ξ− side).
    w : (E·r, 8) float
        Weight of ``n1``: slab ``j`` of ``r`` has its ξ− face at ``j/r``, its ξ+ face at ``(j+1)/r``.
    """
    hexes = np.asarray(hexes, dtype=np.int64)
    E = len(hexes)
    minus = np.where(_XI_PLUS, _PARTNER, np.arange(8))        # the ξ− node of each local node's edge
    plus = np.where(_XI_PLUS, np.arange(8), _PARTNER)
    j = np.arange(r)
    frac = np.where(_XI_PLUS[None, :], (j[:, None] + 1.0) / r, j[:, None] / float(r))   # (r, 8)
    n0 = np.repeat(hexes[:, minus], r, axis=0)
    n1 = np.repeat(hexes[:, plus], r, axis=0)
    w = np.tile(frac, (E, 1))
    return n0, n1, w


class SalivaFilm:
    """The saliva film on :data:`FILM_ELEMENTS`-or-finer slabs tied to the lip tissue.

    Parameters
    ----------
    nodes : (n, 3) reference node positions of the face model.
    hexes : (E, 8) the face model's saliva hexahedra.
    s_ends : (E, 2) position across the mouth (−1 right corner .. +1 left) of each
        hexahedron's ξ− and ξ+ faces.
    glue : callable
        ``glue(s) -> (E·r,)`` K_glue per slab from the slab centres ``s``.
    params : SalivaParams
    across : int
        Hexahedra across the mouth (per saliva layer); ``r = ceil(FILM_ELEMENTS / across)``.
    min_elements : int
    """

    def __init__(self, nodes, hexes, s_ends, glue, params: SalivaParams = SalivaParams(), across=None,
                 min_elements: int = FILM_ELEMENTS):
        from visemeface.physics.materials import SALIVA
        hexes = np.asarray(hexes, dtype=np.int64)
        across = len(hexes) if across is None else int(across)
        self.refine = max(1, int(np.ceil(min_elements / max(across, 1))))
        self.n0, self.n1, self.w = refine_slabs(hexes, self.refine)
        nodes = np.asarray(nodes, dtype=np.float64)
        self.X = (1.0 - self.w[..., None]) * nodes[self.n0] + self.w[..., None] * nodes[self.n1]
        s_ends = np.asarray(s_ends, dtype=np.float64)
        j = (np.tile(np.arange(self.refine), len(hexes)) + 0.5) / self.refine
        se = np.repeat(s_ends, self.refine, axis=0)
        #: Slab centres across the mouth.
        self.s = se[:, 0] + j * (se[:, 1] - se[:, 0])
        self.params = params
        self.glue = np.ascontiguousarray(np.broadcast_to(np.asarray(glue(self.s), dtype=np.float64),
                                                         (len(self.s),)))
        self.axis = np.ascontiguousarray(element_frames(self.X)[:, 1])
        self.cgrads = np.ascontiguousarray(hex_centre_gradients(self.X))
        grads, vols = film_gradients(self.X)
        self.grads, self.volumes = np.ascontiguousarray(grads), np.ascontiguousarray(vols)
        self.modulus = SALIVA.p_wave_modulus
        #: Each slab's thickness across the lips (its η extent) and half its band through them (ζ extent / 2):
        #: the lengths of the Stefan flow (:attr:`SalivaParams.viscosity`).
        X = self.X
        self.thickness = np.linalg.norm(X[:, [3, 2, 7, 6]].mean(1) - X[:, [0, 1, 4, 5]].mean(1), axis=1)
        self.band = 0.5 * np.linalg.norm(X[:, [4, 5, 6, 7]].mean(1) - X[:, [0, 1, 2, 3]].mean(1), axis=1)
        self._Z0 = self.breaking_points(0.0)
        self.rest_gap = self.front_gaps(np.zeros((len(nodes), 3)))
        self._compile()

    def _compile(self) -> None:
        """Compile (or load) the rule now, on zero slabs: not inside the first step, where an
        interrupt would land in numba's compiler."""
        st = {k: v[:0] for k, v in self.initial_state().items()}
        z = np.zeros((1, 3))
        p = self.params
        _film_step(z, z.copy(), self.n0[:0], self.n1[:0], self.w[:0], self.cgrads[:0], self.grads[:0],
                   self.volumes[:0], self.axis[:0], self._Z0[:0], st["broken"], st["dry"], st["stored"],
                   st["stretch"], p.decay, p.rebond_strain, p.squeeze, self.modulus, FILM_STIFF_STRETCH, p.soften,
                   st["flow"], self.thickness[:0], self.band[:0], p.film_thickness, p.fluidity, 1e-5,
                   st["damage"], p.strand, p.rupture_time)

    @property
    def n_elements(self) -> int:
        return len(self.s)

    def breaking_points(self, t: float) -> np.ndarray:
        """Z per slab at time ``t`` (seed eq. 6-7)."""
        p = self.params
        return breaking_point(moisture(t, p.initial_moisture, p.evaporation), p.critical_moisture, self.glue)

    def slab_displacement(self, u) -> np.ndarray:
        """(E·r, 8, 3) displacements of the slab nodes from the tissue nodes' ``u``."""
        u = np.asarray(u, dtype=np.float64)
        return (1.0 - self.w[..., None]) * u[self.n0] + self.w[..., None] * u[self.n1]

    def stretch(self, u) -> np.ndarray:
        """Q = C_yy at each slab's centre; :data:`FOLDED` where a slab is folded over (J ≤ 0)."""
        F = deformation_gradient(self.slab_displacement(u), self.cgrads)
        return np.where(np.linalg.det(F) > 0.0, stretch_across(F, self.axis), FOLDED)

    def front_gaps(self, u) -> np.ndarray:
        """Distance (m) between the lips at each slab's skin-side centre (nodes 6, 7 up; 4, 5 down)."""
        x = self.X + self.slab_displacement(u)
        return np.linalg.norm(x[:, [6, 7]].mean(axis=1) - x[:, [4, 5]].mean(axis=1), axis=1)

    def initial_state(self, u=None, t: float = 0.0) -> dict:
        """The film's state at ``u`` (default rest): slabs already stretched past Z start parted, slabs pressed
        (Q < 1) or folded over (the lips crossed, J ≤ 0) start squeezed out (``dry``: no force until the lips
        part to the film's thickness). Pressed lips in a rounded first posture (Q = 0.09 on the 3 s example's
        silence) otherwise met the film's full push at once, which inverted a lip element within 0.3 ms at any
        step; so did the outer half of the seam, crossed in the rounding that leads into "you" (within 0.8 ms)."""
        E = self.n_elements
        state = {"broken": np.zeros(E, dtype=np.bool_), "dry": np.zeros(E, dtype=np.bool_),
                 "stored": np.zeros((E, 8, 3)), "stretch": np.ones(E), "flow": np.zeros(E),
                 "damage": np.zeros(E)}
        if u is not None:
            Q = self.stretch(u)
            state["stretch"][:] = np.minimum(Q, FOLDED)
            state["broken"][:] = Q >= self.breaking_points(t)
            pressed = (Q < 1.0) | (Q >= FOLDED)      # squeezed out between lips pressed or crossed at the start
            state["dry"][pressed] = True      # until they part to the film's thickness and it re-forms
            state["broken"][pressed] = True
        return state

    def add_forces(self, u, t: float, state: dict, R, dt: float = 1e-5) -> None:
        """Advance the film's ``state`` one step (``dt``) at time ``t`` and subtract its nodal forces from ``R``."""
        _film_step(u, R, *self.rule_args(self.breaking_points_at(t), state, dt))

    def breaking_points_at(self, t: float) -> np.ndarray:
        """Z per slab at ``t``: the rest values when the film does not evaporate (no work a step)."""
        return self._Z0 if self.params.evaporation == 0.0 else self.breaking_points(t)

    def rule_args(self, Z, state: dict, dt: float) -> tuple:
        """The compiled rule's (:func:`_film_step`) arguments after ``(u, R)``, for a step ``dt`` at
        breaking points ``Z`` (an array the caller may refill between calls)."""
        p = self.params
        return (self.n0, self.n1, self.w, self.cgrads, self.grads, self.volumes, self.axis, Z,
                state["broken"], state["dry"], state["stored"], state["stretch"], p.decay ** (dt / DECAY_STEP),
                p.rebond_strain, p.squeeze, self.modulus, FILM_STIFF_STRETCH, p.soften, state["flow"],
                self.thickness, self.band, p.film_thickness, p.fluidity, dt, state["damage"], p.strand,
                p.rupture_time)


from numba import njit  # noqa: E402


@njit(inline="always", cache=True)
def _film_stress(x, modulus, lc):  # pragma: no cover - compiled
    """dW/dλ of the film at elastic stretch ``x``: St Venant–Kirchhoff pulled, a log barrier pressed,
    linear below ``lc`` (the stiffness cap that keeps the step stable)."""
    if x >= 1.0:
        return 0.5 * modulus * (x * x - 1.0) * x
    if x >= lc:
        return modulus * (1.0 - 1.0 / x)
    return modulus * (1.0 - 1.0 / lc) + modulus / (lc * lc) * (x - lc)


@njit(inline="always", cache=True)
def _pull_push(k, uv, n, grads, volumes, modulus, lc, flow, pull, push):  # pragma: no cover - compiled
    """Slab k's film forces at its two points into ``pull`` (λ ≥ 1) and ``push`` (λ < 1) (see film_forces);
    its elastic stretch is λ − ``flow`` (what viscous flow has not taken up)."""
    for gp in range(2):
        f0, f1, f2 = n[0], n[1], n[2]
        for a in range(8):
            gn = grads[k, gp, a, 0] * n[0] + grads[k, gp, a, 1] * n[1] + grads[k, gp, a, 2] * n[2]
            f0 += uv[a, 0] * gn
            f1 += uv[a, 1] * gn
            f2 += uv[a, 2] * gn
        lam = np.sqrt(f0 * f0 + f1 * f1 + f2 * f2)
        x = lam - flow                         # the elastic stretch
        dw = _film_stress(x, modulus, lc)
        c = dw / max(lam, 1e-12) * volumes[k, gp]
        for a in range(8):
            gn = (grads[k, gp, a, 0] * n[0] + grads[k, gp, a, 1] * n[1] + grads[k, gp, a, 2] * n[2]) * c
            if x >= 1.0:
                pull[a, 0] += gn * f0
                pull[a, 1] += gn * f1
                pull[a, 2] += gn * f2
            else:
                push[a, 0] += gn * f0
                push[a, 1] += gn * f1
                push[a, 2] += gn * f2


@njit(inline="always", cache=True)
def _cohesive_damage(x, Z, d_old, thick, strand, sp, se):  # pragma: no cover - compiled
    """Damage D of a slab on the film's softening branch (a bilinear cohesive law).

    In the separation δ = (x − 1)·h across the lips (h the slab's rest thickness, x the
    elastic stretch): elastic up to the breaking point δ_p = (√Z − 1) h, where the film
    pulls σ_p = σ(√Z); then the traction falls linearly to zero at δ_p + ``strand``,
    T(δ) = σ_p (δ_p + strand − δ) / strand. The pull is (1 − D) σ(x) with
    D = max(D_old, 1 − T(δ)/σ(x)) (irreversible: unloading goes back toward zero
    along the damaged stiffness). The energy to part the film is
    G_c = ½ σ_p (δ_p + strand) per unit area, whatever the slab's size. ``sp`` and ``se`` are
    σ(√Z) and σ(x) (:func:`_film_stress`).
    """
    xp = np.sqrt(Z)
    dp = (xp - 1.0) * thick
    dlt = (x - 1.0) * thick
    if dlt <= dp:
        return d_old
    if dlt >= dp + strand:
        return 1.0                                # (strand 0: a brittle break, D_s = 1 past the peak)
    d = 1.0 - sp * (dp + strand - dlt) / (strand * se) if se > 0.0 else 1.0
    return min(max(d, d_old), 1.0)


@njit(inline="always", cache=True)
def _damage_step(Q, x, Z, d_old, thick, strand, rupture, dt, modulus, lc):  # pragma: no cover - compiled
    """A cohesive slab's damage after this step: 0 back in contact (Q ≤ 1: the film is whole
    again); else the law's value (:func:`_cohesive_damage`), reached over the ``rupture`` time
    (a strand thins before it snaps) but never pulling harder than at the breaking point."""
    if Q <= 1.0:
        return 0.0
    sp = _film_stress(np.sqrt(Z), modulus, lc)
    se = _film_stress(x, modulus, lc)
    d = _cohesive_damage(x, Z, d_old, thick, strand, sp, se)
    if rupture > 0.0:
        d = d_old + (1.0 - np.exp(-dt / rupture)) * (d - d_old)
        if se > sp:
            d = max(d, 1.0 - sp / se)
    return d


@njit(cache=True)
def _film_step(u, R, n0, n1, w, cgrads, grads, volumes, axis, Z, broken, dry, stored, stretch, decay, rebond, squeeze,
               modulus, lc, soften, flow, thick, band, h0, fluidity, dt, damage, strand, rupture):  # pragma: no cover
    """One step of every slab: the film's force law and breaking rule; R -= its nodal forces.

    Per slab (nodes interpolated from the tissue, see the module docstring):
    centre deformation gradient F, Q = |F n|², J = det F (Q := ∞ when folded);
    the film's pull (λ ≥ 1) and push (λ < 1) at its two points
    (:func:`visemeface.physics.saliva.film_forces`); then the rule of
    :mod:`visemeface.physics.saliva`: squeezed out below ``squeeze`` (no force
    until back at Q ≥ 1), re-bond on contact (Q ≤ 1, strain ≤ ``rebond``),
    break at Q ≥ Z keeping this step's pull, then decay it by ``decay`` a step (the caller passes decay^(dt / 1e-5)); or, with a
    ``strand`` or ``rupture`` > 0, past Z the pull × (1 − D) (:func:`_damage_step`), broken at D = 1.
    """
    uv = np.empty((8, 3))
    pull = np.empty((8, 3))
    push = np.empty((8, 3))
    F = np.empty((3, 3))
    for k in range(n0.shape[0]):
        for a in range(8):
            wa = w[k, a]
            for i in range(3):
                uv[a, i] = (1.0 - wa) * u[n0[k, a], i] + wa * u[n1[k, a], i]
                pull[a, i] = 0.0
                push[a, i] = 0.0
        for i in range(3):
            for j in range(3):
                acc = 1.0 if i == j else 0.0
                for a in range(8):
                    acc += uv[a, i] * cgrads[k, a, j]
                F[i, j] = acc
        n = axis[k]
        Q = 0.0
        for i in range(3):
            fi = F[i, 0] * n[0] + F[i, 1] * n[1] + F[i, 2] * n[2]
            Q += fi * fi
        lq = np.sqrt(Q)
        if broken[k] or dry[k]:
            flow[k] = 0.0                          # no liquid layer to flow: a re-formed film starts afresh
        _pull_push(k, uv, n, grads, volumes, modulus, lc, flow[k], pull, push)
        stretch[k] = Q
        x = lq - flow[k]                           # the film's elastic stretch at its centre
        if fluidity > 0.0 and not broken[k] and not dry[k]:
            # Stefan flow: the film thickens (σ > 0) or is squeezed (σ < 0) at dh/dt = σ h³ / (4 η b²),
            # b half its band across the lips; it relaxes toward x = 1 and never past it
            h = h0 + flow[k] * thick[k]
            sig = _film_stress(x, modulus, lc)
            f = flow[k] + dt * sig * h * h * h * fluidity / (4.0 * band[k] * band[k] * thick[k])
            flow[k] = min(f, lq - 1.0) if sig > 0.0 else max(f, lq - 1.0, 0.0)
        Qe = Q if flow[k] == 0.0 else x * x
        J = (F[0, 0] * (F[1, 1] * F[2, 2] - F[1, 2] * F[2, 1]) - F[0, 1] * (F[1, 0] * F[2, 2] - F[1, 2] * F[2, 0])
             + F[0, 2] * (F[1, 0] * F[2, 1] - F[1, 1] * F[2, 0]))
        if J <= 0.0:
            Q = FOLDED                              # folded over: a broken film cannot push
        if dry[k] and Q >= 1.0 and Q < FOLDED:      # lips apart to the film's thickness: it re-forms
            dry[k] = False
            broken[k] = False
        if dry[k] or Q < squeeze:                  # squeezed out between pressed lips: no force
            dry[k] = True
            broken[k] = True
            damage[k] = 0.0
            stored[k] = 0.0
            continue
        if broken[k] and Q <= 1.0:
            strain = 0.0
            for i in range(3):
                for j in range(3):
                    cij = F[0, i] * F[0, j] + F[1, i] * F[1, j] + F[2, i] * F[2, j]
                    if i == j:
                        cij -= 1.0
                    strain = max(strain, abs(cij))
            if strain <= rebond:
                broken[k] = False                  # lips back together: re-bond
                damage[k] = 0.0
        if broken[k]:
            fac = 1.0
            if soften > 0.0:                       # cohesive softening with the film's stretch
                fac = min(max(1.0 - (np.sqrt(min(Q, 1e30)) - np.sqrt(Z[k])) / soften, 0.0), 1.0)
            for a in range(8):
                for i in range(3):
                    if soften <= 0.0:
                        stored[k, a, i] *= decay
                    pull[a, i] = stored[k, a, i] * fac   # the decaying pull, and contact
        elif (strand > 0.0 or rupture > 0.0) and Q < FOLDED and (Qe >= Z[k] or damage[k] > 0.0):
            damage[k] = _damage_step(Q, x, Z[k], damage[k], thick[k], strand, rupture, dt, modulus, lc)
            if damage[k] >= SNAPPED:
                broken[k] = True                   # the strand has snapped: no pull from the next step
                stored[k] = 0.0
            pull *= 1.0 - damage[k]
        elif Qe >= Z[k] or Q >= FOLDED:
            broken[k] = True                       # keep this step's pull, decay from the next
            for a in range(8):
                for i in range(3):
                    stored[k, a, i] = pull[a, i]
        for a in range(8):
            wa = w[k, a]
            for i in range(3):
                f = pull[a, i] + push[a, i]
                R[n0[k, a], i] -= (1.0 - wa) * f
                R[n1[k, a], i] -= wa * f
