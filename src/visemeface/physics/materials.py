"""Compressible neo-Hookean materials for the TLED solver, and their analytic laws.

The strain energy per unit reference volume (NiftySim's, DESIGN §6) is

.. math::

    W(C) = \\frac{\\mu}{2}\\left(J^{-2/3} I_1 - 3\\right) + \\frac{K}{2}(J - 1)^2,
    \\qquad I_1 = \\operatorname{tr} C,\\; J = \\det X,\\; C = X^T X,

with shear modulus μ and bulk modulus K (Pa). Its second Piola–Kirchhoff
stress ``S = 2 ∂W/∂C`` is

.. math::

    S = \\mu J^{-2/3}\\left(I - \\tfrac13 I_1 C^{-1}\\right) + K J (J - 1) C^{-1}.

Small strains give Lamé λ = K − 2μ/3 and the pressure (P-) wave speed
``c = sqrt((K + 4μ/3) / ρ)`` that bounds the explicit time step.

A model's materials are a sequence of :class:`NeoHookean`; each element's
``HexMesh.material`` id indexes it (id 0 soft tissue, id 1 the saliva layer of
issue 8, …). :func:`material_table` turns the sequence into per-element arrays.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from scipy.optimize import brentq

from visemeface.errors import InputError


@dataclass(frozen=True)
class NeoHookean:
    """A compressible neo-Hookean solid.

    Parameters
    ----------
    mu : float
        Shear modulus μ (Pa).
    K : float
        Bulk modulus K (Pa).
    rho : float
        Reference density ρ (kg/m³).
    name : str
        Label used in messages.
    """

    mu: float
    K: float
    rho: float
    name: str = "material"

    def __post_init__(self):
        for key in ("mu", "K", "rho"):
            value = getattr(self, key)
            if not (np.isfinite(value) and value > 0):
                raise InputError(f"material {self.name!r}: {key} must be a positive number, got {value!r}")

    @property
    def lame_lambda(self) -> float:
        """Small-strain Lamé λ = K − 2μ/3 (Pa)."""
        return self.K - 2.0 * self.mu / 3.0

    @property
    def p_wave_modulus(self) -> float:
        """Small-strain uniaxial-strain (P-wave) modulus M = K + 4μ/3 (Pa)."""
        return self.K + 4.0 * self.mu / 3.0

    @property
    def wave_speed(self) -> float:
        """Dilatational wave speed c = sqrt(M/ρ), M = K + 4μ/3 (m/s)."""
        return float(np.sqrt(self.p_wave_modulus / self.rho))

    @property
    def shear_wave_speed(self) -> float:
        """Shear wave speed sqrt(μ/ρ) (m/s)."""
        return float(np.sqrt(self.mu / self.rho))

    @property
    def poisson_ratio(self) -> float:
        """Small-strain Poisson ratio ν = (3K − 2μ) / (2(3K + μ))."""
        return (3 * self.K - 2 * self.mu) / (2 * (3 * self.K + self.mu))


#: Soft facial tissue of seed 000 Table 1.
SOFT_TISSUE = NeoHookean(mu=800.0, K=7000.0, rho=1050.0, name="soft_tissue")
#: The stiff saliva layer between the lips of seed 000 Table 1.
SALIVA = NeoHookean(mu=7700.0, K=191000.0, rho=1050.0, name="saliva")


def material_table(materials: Sequence[NeoHookean], material_ids: np.ndarray) -> dict:
    """Per-element material arrays.

    Parameters
    ----------
    materials : sequence of NeoHookean
        Indexed by material id.
    material_ids : int array (e,)
        ``HexMesh.material``.

    Returns
    -------
    dict of float64 arrays (e,)
        ``mu``, ``K``, ``rho``, ``wave_speed``.

    Raises
    ------
    InputError
        If an element's id has no material.
    """
    if isinstance(materials, NeoHookean):
        materials = [materials]
    materials = list(materials)
    ids = np.asarray(material_ids, dtype=np.int64)
    if len(materials) == 0:
        raise InputError("no material given")
    bad = np.flatnonzero((ids < 0) | (ids >= len(materials)))
    if len(bad):
        e = int(bad[0])
        raise InputError(f"element {e} has material id {ids[e]} but only {len(materials)} "
                         f"material(s) were given")
    table = {
        "mu": np.array([m.mu for m in materials], dtype=np.float64),
        "K": np.array([m.K for m in materials], dtype=np.float64),
        "rho": np.array([m.rho for m in materials], dtype=np.float64),
        "wave_speed": np.array([m.wave_speed for m in materials], dtype=np.float64),
    }
    return {k: np.ascontiguousarray(v[ids]) for k, v in table.items()}


def second_piola_kirchhoff(F: np.ndarray, mu, K) -> np.ndarray:
    """Neo-Hookean S for deformation gradients ``F`` (..., 3, 3).

    ``S = μ J^{-2/3} (I − I₁ C⁻¹ / 3) + K J (J − 1) C⁻¹`` with C = FᵀF.
    ``mu`` and ``K`` broadcast against the leading dimensions of F.
    """
    F = np.asarray(F, dtype=np.float64)
    C = np.swapaxes(F, -1, -2) @ F
    J = np.linalg.det(F)
    Cinv = np.linalg.inv(C)
    I1 = np.trace(C, axis1=-2, axis2=-1)
    mu = np.asarray(mu, dtype=np.float64)[..., None, None]
    K = np.asarray(K, dtype=np.float64)[..., None, None]
    Jm23 = np.cbrt(J * J)[..., None, None] ** -1.0
    eye = np.eye(3)
    return mu * Jm23 * (eye - I1[..., None, None] / 3.0 * Cinv) + K * (J * (J - 1.0))[..., None, None] * Cinv


def cauchy_stress(F: np.ndarray, mu, K) -> np.ndarray:
    """Cauchy stress σ = F S Fᵀ / J for deformation gradients (..., 3, 3)."""
    F = np.asarray(F, dtype=np.float64)
    S = second_piola_kirchhoff(F, mu, K)
    J = np.linalg.det(F)[..., None, None]
    return F @ S @ np.swapaxes(F, -1, -2) / J


def strain_energy_density(F: np.ndarray, mu, K) -> np.ndarray:
    """W = μ/2 (J^{-2/3} I₁ − 3) + K/2 (J − 1)² per unit reference volume."""
    F = np.asarray(F, dtype=np.float64)
    J = np.linalg.det(F)
    I1 = np.einsum("...ij,...ij->...", F, F)
    return 0.5 * np.asarray(mu) * (I1 / np.cbrt(J * J) - 3.0) + 0.5 * np.asarray(K) * (J - 1.0) ** 2


def _lateral_residual(lt, stretch, mu, K):
    J = stretch * lt * lt
    I1 = 2.0 * lt * lt + stretch * stretch
    return mu * J ** (-5.0 / 3.0) * (lt * lt - I1 / 3.0) + K * (J - 1.0)


def uniaxial_stress(stretch, material: NeoHookean) -> tuple[np.ndarray, np.ndarray]:
    """Analytic uniaxial-stress response of the compressible neo-Hookean bar.

    For an axial stretch λ the lateral stretch λₜ makes the lateral Cauchy
    stress vanish,

    .. math:: \\mu J^{-5/3}\\left(\\lambda_t^2 - \\tfrac13 I_1\\right) + K (J - 1) = 0,
              \\quad J = \\lambda \\lambda_t^2,\\; I_1 = \\lambda^2 + 2\\lambda_t^2,

    (solved by Brent's method) and the nominal (first Piola–Kirchhoff) axial
    stress, force per reference area, is

    .. math:: P = \\lambda_t^2 \\left[\\mu J^{-5/3}\\left(\\lambda^2 - \\tfrac13 I_1\\right) + K (J - 1)\\right].

    Parameters
    ----------
    stretch : float or array
        Axial stretch λ > 0.
    material : NeoHookean

    Returns
    -------
    nominal_stress, lateral_stretch : ndarray
        Same shape as ``stretch``.

    Examples
    --------
    >>> P, lt = uniaxial_stress(1.0, SOFT_TISSUE)
    >>> float(P), float(lt)
    (0.0, 1.0)
    """
    lam = np.asarray(stretch, dtype=np.float64)
    flat = lam.ravel()
    lts = np.empty_like(flat)
    for i, s in enumerate(flat):
        if not s > 0:
            raise InputError(f"stretch must be positive, got {s}")
        if s == 1.0:
            lts[i] = 1.0
            continue
        lts[i] = brentq(_lateral_residual, 1e-6, 1e3, args=(s, material.mu, material.K),
                        xtol=1e-15, rtol=4 * np.finfo(float).eps, maxiter=200)
    lt = lts.reshape(lam.shape)
    J = lam * lt * lt
    I1 = lam * lam + 2.0 * lt * lt
    sigma = material.mu * J ** (-5.0 / 3.0) * (lam * lam - I1 / 3.0) + material.K * (J - 1.0)
    return sigma * lt * lt, lt
