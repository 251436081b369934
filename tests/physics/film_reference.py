"""Plain-numpy reference of the saliva film's compiled rule (:func:`visemeface.physics.film._film_step`).

Only the tests use it: the simulation runs the compiled rule alone.
"""

from __future__ import annotations

import numpy as np

from visemeface.physics import saliva as sv
from visemeface.physics.film import SNAPPED


def reference_step(film, u, t: float, state: dict, dt: float = 1e-5) -> np.ndarray:
    """One step of every slab of ``film`` at node displacements ``u``: the nodal forces (n, 3).

    Updates ``state`` (``broken``, ``dry``, ``stored``, ``stretch``) like the compiled rule.
    """
    p = film.params
    ue = film.slab_displacement(u)
    F = sv.deformation_gradient(ue, film.cgrads)
    Q = sv.stretch_across(F, film.axis)
    flow = state["flow"]
    lq = np.sqrt(Q)
    flow[state["broken"] | state["dry"]] = 0.0
    pull, push, _ = sv.film_forces(ue, film.axis, film.grads, film.volumes, film.modulus, flow)
    state["stretch"][:] = Q
    x = lq - flow
    if p.fluidity > 0:                                          # Stefan flow of the intact film
        go = ~state["broken"] & ~state["dry"]
        h = p.film_thickness + flow * film.thickness
        sig = sv._film_stress(x, film.modulus)
        f = flow + dt * sig * h ** 3 * p.fluidity / (4 * film.band ** 2 * film.thickness)
        f = np.where(sig > 0, np.minimum(f, lq - 1.0), np.maximum(np.maximum(f, lq - 1.0), 0.0))
        flow[go] = f[go]
    Qe = np.where(flow == 0.0, Q, x * x)
    Q = np.where(np.linalg.det(F) > 0.0, Q, 1e300)
    C = np.swapaxes(F, 1, 2) @ F
    strain = np.abs(C - np.eye(3)).max(axis=(1, 2))
    Z = film.breaking_points(t)
    broken, dry, stored = state["broken"], state["dry"], state["stored"]
    back = dry & (Q >= 1.0) & (Q < 1e300)
    dry &= ~back
    broken &= ~back
    squeezed = (Q < p.squeeze) | dry
    rebond = broken & (Q <= 1.0) & (strain <= p.rebond_strain) & ~squeezed
    broken &= ~rebond
    damage = state["damage"]
    damage[squeezed | rebond] = 0.0
    cohesive = np.zeros(len(Q), bool)
    if p.strand > 0 or p.rupture_time > 0:
        cohesive = ~broken & ~squeezed & (Q < 1e300) & ((Qe >= Z) | (damage > 0))
        contact = cohesive & (Q <= 1.0)
        damage[contact] = 0.0
        xp = np.sqrt(Z)
        dp, dl = (xp - 1.0) * film.thickness, (x - 1.0) * film.thickness
        sp, se = sv._film_stress(xp, film.modulus), sv._film_stress(x, film.modulus)
        with np.errstate(divide="ignore", invalid="ignore"):
            d = np.where(se > 0, 1.0 - sp * (dp + p.strand - dl) / (p.strand * se), 1.0)
        d = np.where(dl <= dp, damage, np.where(dl >= dp + p.strand, 1.0, np.minimum(np.maximum(d, damage), 1.0)))
        if p.rupture_time > 0:
            d = damage + (1.0 - np.exp(-dt / p.rupture_time)) * (d - damage)
            with np.errstate(divide="ignore", invalid="ignore"):
                d = np.where(se > sp, np.maximum(d, 1.0 - sp / se), d)
        upd = cohesive & ~contact
        damage[upd] = d[upd]
        pull[cohesive] *= (1.0 - damage[cohesive])[:, None, None]
    snapped = cohesive & (damage >= SNAPPED)
    newly = ~broken & ~cohesive & ((Qe >= Z) | (Q >= 1e300)) & ~squeezed
    stored[newly] = pull[newly]
    stored[snapped] = 0.0
    if p.soften > 0:                                   # cohesive softening with the stretch
        fac = np.clip(1.0 - (np.sqrt(np.minimum(Q, 1e30)) - np.sqrt(Z)) / p.soften, 0.0, 1.0)
    else:
        stored[broken & ~squeezed] *= p.decay
        fac = np.ones(len(Q))
    out = pull + push
    out[broken] = stored[broken] * fac[broken, None, None] + push[broken]
    broken |= newly | squeezed | snapped
    dry |= squeezed
    stored[squeezed] = 0.0
    out[squeezed] = 0.0
    nodal = np.zeros((len(u), 3))
    w = film.w[..., None]
    np.add.at(nodal, film.n0, (1.0 - w) * out)
    np.add.at(nodal, film.n1, w * out)
    return nodal
