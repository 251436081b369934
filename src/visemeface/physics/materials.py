"""Compressible neo-Hookean and Gent materials for the TLED solver, and their analytic laws.

The strain energy per unit reference volume (NiftySim's TLED, Miller et al. 2007) is

.. math::

    W(C) = \\frac{\\mu}{2}\\left(J^{-2/3} I_1 - 3\\right) + \\frac{K}{2}(J - 1)^2,
    \\qquad I_1 = \\operatorname{tr} C,\\; J = \\det X,\\; C = X^T X,

with shear modulus μ and bulk modulus K (Pa). Its second Piola–Kirchhoff
stress ``S = 2 ∂W/∂C`` is

.. math::

    S = \\mu J^{-2/3}\\left(I - \\tfrac13 I_1 C^{-1}\\right) + K J (J - 1) C^{-1}.

Gent's material (A. N. Gent, *Rubber Chem. Technol.* 69, 1996) replaces the first term by
:math:`-\\frac{\\mu J_m}{2}\\ln\\left(1 - \\frac{\\bar I_1 - 3}{J_m}\\right)`,
:math:`\\bar I_1 = J^{-2/3} I_1`: neo-Hookean at small strain, it stiffens without bound as
:math:`\\bar I_1 - 3` nears :math:`J_m` (the network's limiting extensibility). Its stress is the
neo-Hookean one with μ scaled by :math:`1 / (1 - (\\bar I_1 - 3)/J_m)`; ``jm = inf`` is neo-Hookean.

Small strains give Lamé λ = K − 2μ/3 and the pressure (P-) wave speed
``c = sqrt((K + 4μ/3) / ρ)`` that bounds the explicit time step.

A model's materials are a sequence of :class:`NeoHookean`; each element's
``HexMesh.material`` id indexes it (id 0 soft tissue, id 1 the saliva layer between
the lips, …). :func:`material_table` turns the sequence into per-element arrays.
"""

from __future__ import annotations

import numbers
from collections.abc import Sequence
from dataclasses import dataclass, replace

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
    jm : float
        Gent's limiting value of :math:`\\bar I_1 - 3` (module docstring); ``inf`` (the default):
        neo-Hookean, which never stiffens.
    """

    mu: float
    K: float
    rho: float
    name: str = "material"
    jm: float = float("inf")

    def __post_init__(self):
        for key in ("mu", "K", "rho"):
            value = getattr(self, key)
            if not (np.isfinite(value) and value > 0):
                raise InputError(f"material {self.name!r}: {key} must be a positive number, got {value!r}")
        if not (self.jm > 0):
            raise InputError(f"material {self.name!r}: jm must be a positive number or inf, got {self.jm!r}")

    @property
    def ijm(self) -> float:
        """1 / J_m (0 for neo-Hookean): what the kernels take."""
        return 0.0 if np.isinf(self.jm) else 1.0 / self.jm

    @property
    def limiting_stretch(self) -> float:
        """The isochoric uniaxial stretch at which Ī₁ − 3 reaches J_m: λ² + 2/λ − 3 = J_m (inf if none)."""
        if np.isinf(self.jm):
            return float("inf")
        return float(brentq(lambda s: s * s + 2.0 / s - 3.0 - self.jm, 1.0, np.sqrt(self.jm + 3.0) + 1.0))

    def with_limiting_stretch(self, stretch: float) -> NeoHookean:
        """This material made Gent: J_m such that it locks at isochoric uniaxial stretch ``stretch``
        (J_m = λ² + 2/λ − 3 for λ = the stretch with the volume change taken out, J^(-1/3) λ_axial: an
        incompressible bar's own stretch; a compressible bar swells and stiffens without locking, e.g. the
        soft tissue with 2.5 carries 2.9x the neo-Hookean stress at stretch 2.5, 6.5x at 3; inf: neo-Hookean)."""
        if isinstance(stretch, bool) or not isinstance(stretch, numbers.Real) or not stretch > 1.0:
            raise InputError(f"material {self.name!r}: limiting stretch must be a number > 1 (inf: none), "
                             f"got {stretch!r}")
        stretch = float(stretch)
        jm = float("inf") if np.isinf(stretch) else stretch * stretch + 2.0 / stretch - 3.0
        return replace(self, jm=jm)

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


#: Soft facial tissue of Leach & Maddock (2018) Table 1.
SOFT_TISSUE = NeoHookean(mu=800.0, K=7000.0, rho=1050.0, name="soft_tissue")
#: The stiff saliva layer between the lips of Leach & Maddock (2018) Table 1.
SALIVA = NeoHookean(mu=7700.0, K=191000.0, rho=1050.0, name="saliva")
#: The speech lips' limiting (isochoric, uniaxial) stretch for the soft tissue (Gent; ``PhysicsSettings.speech``;
#: Leach & Maddock's (2018) model, ``PhysicsSettings()``, stays neo-Hookean). The cause is physical: soft tissue stiffens
#: as it is stretched, and Leach & Maddock's (2018) neo-Hookean tissue never does, so under glue 0.3 at full jaw its lip
#: tissue beside the film stretches 7.4x (99th percentile 6.85, against 1.94 without glue) and the film, 10x
#: stiffer in shear, never breaks; at Leach & Maddock's (2018) jaw 0.35 central glue 0.18 never lets go. The
#: value is not a measurement of lips; it is chosen, said plainly, inside the window where the issue's
#: figures hold (``scripts/sticky_figures.py --tissue-limit L``): at 2.6-2.9 the first /b/ of "Bob moves
#: five boats" takes 3 frames at 60 fps (2.5: 2) and glue 0.3 at full jaw breaks every seam slab (3.0: 46 of
#: the 50); 2.7 opens that sentence's second /b/ and /m/ as three openings at once, 2.8 and 2.9 as one. Below
#: 2.5 a lip-corner element reaches its limit before a glue-0.3 film lets go, at a step of 1e-5 s as at the
#: stable one (the jaw prescribed, the lips glued). With the muscles as an active strain the tissue's
#: reference is the muscle field's natural shape, so without glue (F_e near I) the Gent tissue is the
#: neo-Hookean one. What it costs: Leach & Maddock's (2019) double opening on a jaw eased to full over 1 s lasts 7
#: frames (neo-Hookean 10; README's table).
TISSUE_LIMIT = 2.8


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
        ``mu``, ``K``, ``rho``, ``wave_speed``, ``ijm`` (1 / J_m, 0 for neo-Hookean).

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
        "ijm": np.array([m.ijm for m in materials], dtype=np.float64),
    }
    return {k: np.ascontiguousarray(v[ids]) for k, v in table.items()}


def gent_factor(x, ijm) -> np.ndarray:
    """Gent's stiffening 1 / (1 − x / J_m) of the shear modulus at x = Ī₁ − 3 (``ijm`` = 1 / J_m;
    1 for neo-Hookean); NaN at or past the limit."""
    gi = 1.0 - np.asarray(x, dtype=np.float64) * np.asarray(ijm, dtype=np.float64)
    with np.errstate(divide="ignore"):
        return np.where(gi > 0.0, 1.0 / gi, np.nan)


def second_piola_kirchhoff(F: np.ndarray, mu, K, ijm=0.0) -> np.ndarray:
    """Neo-Hookean (``ijm`` 0) or Gent (``ijm`` = 1 / J_m) S for deformation gradients ``F`` (..., 3, 3).

    ``S = g μ J^{-2/3} (I − I₁ C⁻¹ / 3) + K J (J − 1) C⁻¹`` with C = FᵀF and g :func:`gent_factor`.
    ``mu``, ``K`` and ``ijm`` broadcast against the leading dimensions of F.
    """
    F = np.asarray(F, dtype=np.float64)
    C = np.swapaxes(F, -1, -2) @ F
    J = np.linalg.det(F)
    Cinv = np.linalg.inv(C)
    I1 = np.trace(C, axis1=-2, axis2=-1)
    Jm23 = 1.0 / np.cbrt(J * J)
    m = (np.asarray(mu, dtype=np.float64) * gent_factor(Jm23 * I1 - 3.0, ijm) * Jm23)[..., None, None]
    K = np.asarray(K, dtype=np.float64)[..., None, None]
    eye = np.eye(3)
    return m * (eye - I1[..., None, None] / 3.0 * Cinv) + K * (J * (J - 1.0))[..., None, None] * Cinv


def cauchy_stress(F: np.ndarray, mu, K, ijm=0.0) -> np.ndarray:
    """Cauchy stress σ = F S Fᵀ / J for deformation gradients (..., 3, 3)."""
    F = np.asarray(F, dtype=np.float64)
    S = second_piola_kirchhoff(F, mu, K, ijm)
    J = np.linalg.det(F)[..., None, None]
    return F @ S @ np.swapaxes(F, -1, -2) / J


def strain_energy_density(F: np.ndarray, mu, K, ijm=0.0) -> np.ndarray:
    """W = μ/2 (Ī₁ − 3) + K/2 (J − 1)² per unit reference volume, Ī₁ = J^{-2/3} I₁; with ``ijm`` = 1 / J_m > 0
    Gent's −μ J_m/2 ln(1 − (Ī₁ − 3)/J_m) in place of the first term."""
    F = np.asarray(F, dtype=np.float64)
    J = np.linalg.det(F)
    x = np.einsum("...ij,...ij->...", F, F) / np.cbrt(J * J) - 3.0
    ijm = np.asarray(ijm, dtype=np.float64)
    with np.errstate(divide="ignore", invalid="ignore"):
        iso = np.where(ijm == 0.0, 0.5 * x, -0.5 / ijm * np.log1p(-x * ijm))
    return np.asarray(mu) * iso + 0.5 * np.asarray(K) * (J - 1.0) ** 2


def _bar_cauchy(stretch, lt, mu, K, ijm=0.0):
    """(axial, lateral) Cauchy stress of a bar stretched ``stretch`` along and ``lt`` across (NaN past a Gent
    limit): g μ J^{-5/3} (λᵢ² − I₁/3) + K (J − 1), J = λ λₜ², I₁ = λ² + 2λₜ²."""
    J = stretch * lt * lt
    I1 = stretch * stretch + 2.0 * lt * lt
    m = gent_factor(I1 / np.cbrt(J * J) - 3.0, ijm) * mu * J ** (-5.0 / 3.0)
    p = K * (J - 1.0)
    return m * (stretch * stretch - I1 / 3.0) + p, m * (lt * lt - I1 / 3.0) + p


def _lateral_residual(lt, stretch, mu, K, ijm=0.0):
    lateral = _bar_cauchy(stretch, lt, mu, K, ijm)[1]
    if np.isnan(lateral):        # past Gent's limit the stress tends to ±∞, the sign of λₜ² − I₁/3, of λₜ − λ
        return float(np.copysign(1e300, lt - stretch))
    return lateral


def uniaxial_stress(stretch, material: NeoHookean) -> tuple[np.ndarray, np.ndarray]:
    """Analytic uniaxial-stress response of the compressible neo-Hookean (or Gent) bar.

    For an axial stretch λ the lateral stretch λₜ makes the lateral Cauchy
    stress vanish,

    .. math:: \\mu J^{-5/3}\\left(\\lambda_t^2 - \\tfrac13 I_1\\right) + K (J - 1) = 0,
              \\quad J = \\lambda \\lambda_t^2,\\; I_1 = \\lambda^2 + 2\\lambda_t^2,

    (solved by Brent's method; μ times :func:`gent_factor` for a Gent material) and the
    nominal (first Piola–Kirchhoff) axial stress, force per reference area, is

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
        lts[i] = brentq(_lateral_residual, 1e-6, 1e3, args=(s, material.mu, material.K, material.ijm),
                        xtol=1e-15, rtol=4 * np.finfo(float).eps, maxiter=200)
    lt = lts.reshape(lam.shape)
    sigma = _bar_cauchy(lam, lt, material.mu, material.K, material.ijm)[0]
    return sigma * lt * lt, lt
