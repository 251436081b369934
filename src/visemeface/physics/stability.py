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
