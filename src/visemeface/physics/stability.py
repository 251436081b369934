"""The largest stable time step of the explicit face, from its highest natural frequency.

Central differences (:mod:`visemeface.physics.integrator`) are stable for

.. math:: \\Delta t < \\frac{2}{\\omega_{max}},\\qquad \\omega_{max}^2 = \\lambda_{max}(M^{-1} K),

``K`` the tangent stiffness of every force term and ``M`` the lumped masses;
mass-proportional damping does not lower the limit (Belytschko, Liu & Moran,
*Nonlinear Finite Elements*, 2000, §6.3). The tissue solver's element bound
(:attr:`~visemeface.physics.tled.TLEDSolver.stable_dt`, ``L_e / c_e`` per
element) is safe but pessimistic for the tissue (measured ×0.53 on the default
face), and it cannot see a force that couples nodes of different elements,
as the saliva film does across the lips.

:func:`max_eigenvalue` finds :math:`\\lambda_{max}` matrix-free: ``K v`` is the
central difference of the forces along ``v``, and Lanczos (``scipy``'s
``eigsh``) works on the symmetric :math:`M^{-1/2} K M^{-1/2}` over the free
degrees of freedom. Lanczos' Ritz value approaches :math:`\\lambda_{max}` from
below, so it is converged to ``tol`` relative.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from visemeface.errors import InputError

#: Relative size of the finite-difference probe: ``ε = PROBE · scale / |v|_∞`` (linear regime,
#: far above round-off for forces of order ``K · scale``).
PROBE = 1e-6


def max_eigenvalue(forces: Callable[[np.ndarray], np.ndarray], u0, mass, free=None, *, scale: float = 1e-3,
                   tol: float = 1e-4, seed: int = 0) -> float:
    """Largest eigenvalue of ``M⁻¹ K`` at ``u0`` (1/s²), ``K = dF/du`` of ``forces``.

    Parameters
    ----------
    forces : callable
        ``forces(u) -> (n, 3)``: the net restoring force at displacement ``u`` (internal force
        minus applied force); pure (it must not change any state).
    u0 : (n, 3) displacement to linearise at.
    mass : (n,) lumped masses (> 0).
    free : (n, 3) or None
        1 for the free degrees of freedom (the others are held), None: all free.
    scale : float
        A length of the model (m) for the size of the probe (default 1 mm).
    tol : float
        Relative tolerance of Lanczos.
    """
    from scipy.sparse.linalg import ArpackNoConvergence, LinearOperator, eigsh

    u0 = np.asarray(u0, dtype=np.float64)
    n = len(u0)
    mass = np.asarray(mass, dtype=np.float64)
    if mass.shape != (n,) or not (mass > 0).all():
        raise InputError("masses must be one positive number per node")
    keep = np.ones(3 * n, bool) if free is None else np.asarray(free, dtype=bool).reshape(-1)
    k = int(keep.sum())
    if k == 0:
        return 0.0
    root = 1.0 / np.sqrt(np.repeat(mass, 3))

    def apply(v):
        w = np.zeros(3 * n)
        w[keep] = v * root[keep]
        size = np.abs(w).max()
        if size == 0.0:
            return np.zeros(k)
        eps = PROBE * scale / size
        d = np.asarray(forces(u0 + eps * w.reshape(n, 3)), dtype=np.float64) \
            - np.asarray(forces(u0 - eps * w.reshape(n, 3)), dtype=np.float64)
        return (d.reshape(-1) * root / (2.0 * eps))[keep]

    start = np.random.default_rng(seed).standard_normal(k)
    op = LinearOperator((k, k), matvec=apply, dtype=np.float64)
    try:
        lam = eigsh(op, k=1, which="LA", tol=tol, v0=start, return_eigenvectors=False)[0]
    except ArpackNoConvergence as e:  # keep the best estimate: it is a lower bound, so say so
        raise InputError(f"the highest frequency did not converge ({e}); give the time step explicitly") from None
    return float(max(lam, 0.0))


def critical_step(lam: float) -> float:
    """``2 / sqrt(λ)``: the central-difference limit for the largest eigenvalue ``λ`` of ``M⁻¹K`` (inf for 0)."""
    return float("inf") if lam <= 0.0 else 2.0 / float(np.sqrt(lam))


#: The longest step (s) for a viscous film (``SalivaParams(viscosity=η)``, not the default): its Stefan
#: flow is integrated explicitly and grows as h³ (h the film's thickness), so at longer steps the film
#: reaches its breaking stretch before it has flowed (measured: 4 corner slabs flow at 1e-5 and 2e-5 s
#: and break at 4.8e-5 s on the coarse face's fast opening); it was made and checked at Leach & Maddock's (2018) 1e-5 s.
FLOW_STEP = 1e-5
#: Margin on the spectral limit: it is the tangent at rest, and the tissue stiffens as it is
#: compressed (the neo-Hookean tangent grows as J falls: ~ +20 % in ω² at J = 0.85) — so 0.9 in Δt.
SAFETY = 0.9


def film_stiffening(film) -> float:
    """The film law's stiffest tangent over its tangent at rest (both M at λ = 1): pressed it is capped
    at M / λ_c² (``FILM_STIFF_STRETCH`` λ_c), pulled St Venant–Kirchhoff's ½ M (3λ² − 1) at the
    largest breaking stretch √Z (the cohesive tail beyond it only softens)."""
    from visemeface.physics.saliva import FILM_STIFF_STRETCH

    z = float(np.max(film.breaking_points(0.0))) if film.n_elements else 1.0
    return max(1.0 / FILM_STIFF_STRETCH ** 2, 0.5 * (3.0 * z - 1.0))


def face_stable_step(mesh, tissue, film, *, hourglass_kappa: float) -> dict:
    """The stable time step of the FEM face and how it was found.

    ``element``: the element bound of each set (tissue, saliva: ``L_e / c_e``, the whole
    mesh's lumped masses); ``spectral``: :data:`SAFETY` × 2/ω_max with
    ω_max² ≤ λ(M⁻¹K_tissue) + s λ(M⁻¹K_film) (Weyl's inequality, both stiffnesses
    positive semi-definite; ``s`` = :func:`film_stiffening`), each λ by
    :func:`max_eigenvalue` at rest with every node free (holding nodes only lowers ω);
    ``dt`` the smaller of the two (and at most :data:`FLOW_STEP` for a viscous film): the single-rate
    step, and the film's substep in a multi-rate run; ``tissue_step`` the tissue's own limit (its element
    bound and :data:`SAFETY` × its spectral limit ``tissue_only``): the multi-rate run's step
    (:mod:`visemeface.physics.integrator`).

    Parameters
    ----------
    mesh : HexMesh (all elements: tissue and saliva); tissue : indices of its tissue elements;
    film : SalivaFilm on it.
    """
    from visemeface.physics.hexmesh import HexMesh
    from visemeface.physics.materials import SALIVA, SOFT_TISSUE
    from visemeface.physics.tled import TLEDSolver

    whole = TLEDSolver(mesh, [SOFT_TISSUE, SALIVA], dt=1e-12, hourglass_kappa=hourglass_kappa)
    is_tissue = np.zeros(mesh.n_elements, bool)
    is_tissue[np.asarray(tissue, dtype=np.int64)] = True
    dt_e = whole.element_dt
    element = {"tissue": float(dt_e[is_tissue].min()),
               "saliva": float(dt_e[~is_tissue].min()) if (~is_tissue).any() else float("inf")}
    tmesh = HexMesh(mesh.nodes, mesh.hexes[is_tissue], material=np.zeros(int(is_tissue.sum()), np.int64))
    solver = TLEDSolver(tmesh, SOFT_TISSUE, dt=1e-12, hourglass_kappa=hourglass_kappa)
    n, mass, zero = mesh.n_nodes, whole.mass, np.zeros((mesh.n_nodes, 3))
    lam_t = max_eigenvalue(solver.internal_forces, zero, mass, scale=1e-3)
    rest = film.initial_state()

    def film_forces(u):
        R = np.zeros((n, 3))
        film.add_forces(u, 0.0, {k: v.copy() for k, v in rest.items()}, R, 1e-12)
        return -R

    lam_f = max_eigenvalue(film_forces, zero, mass, scale=1e-3) if film.n_elements else 0.0
    s = film_stiffening(film)
    spectral = SAFETY * critical_step(lam_t + s * lam_f)
    dt = min(min(element.values()), spectral)
    if film.params.fluidity > 0.0:
        dt = min(dt, FLOW_STEP)
    tissue_only = SAFETY * critical_step(lam_t)
    return {"dt": dt, "element": element, "spectral": spectral, "tissue_only": tissue_only,
            "tissue_step": min(element["tissue"], tissue_only), "film_stiffening": s}


#: Track frames sampled at most for :func:`natural_shape_step`: every frame of a track up to 10 s at 60 fps,
#: every 6th (0.1 s, shorter than a viseme) of a minute at 60 fps. A sample costs about 5 ms on the default
#: face (the rig's field and the element geometry), so at most 3 s at the start of a run.
SHAPE_SAMPLES = 600


def natural_shape_step(solver, fields) -> float:
    """The tissue's element bound (``L_e / c_e``, as :attr:`~visemeface.physics.tled.TLEDSolver.stable_dt`)
    in the muscle field's natural shapes ``X + U`` for each ``U`` in ``fields``, with the rest masses.

    With the muscles as an active strain (:class:`~visemeface.physics.terms.ActiveTissue`) the tissue's
    reference is the natural shape: an element squeezed there is stiffer for its (unchanged) mass,
    ω² ∝ a_Y V_Y / V_X (a = Σ(∂h/∂Y)²), so dt_e = L_e(Y) √(V_X / V_Y) / c_e. Measured: the rounded /yu/
    squeezes a lip-corner element to a bound of 6.4e-5 s, against 1.8e-4 s at rest, and a run at the rest
    bound inverted it within 0.06 s.
    """
    from visemeface.physics.tled import characteristic_length, element_geometry

    X, conn = solver.mesh.nodes, solver.conn
    c = solver.characteristic_length / solver.element_dt          # each element's wave speed
    best = np.inf
    for U in fields:
        dh, vol = element_geometry(X + U, conn)
        a = np.einsum("eai,eai->e", dh, dh)
        with np.errstate(divide="ignore", invalid="ignore"):
            dt = characteristic_length(a * (vol / solver.volume), solver.kappa) / c
        best = min(best, float(np.nanmin(dt)))
    return best
