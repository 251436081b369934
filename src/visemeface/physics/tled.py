"""Total Lagrangian explicit dynamics (TLED) of hex8 meshes: NiftySim's scheme.

Everything is measured against the rest configuration, so per-element
constants are computed once (:func:`element_geometry`,
:func:`hourglass_shape_vectors`) and each step is a fixed sequence of cheap
element and node loops, run by numba kernels (``parallel=True``, ``prange``,
no allocation in the loops) or by an equivalent plain-numpy reference.

One step (NiftySim's TLED, Miller et al. 2007; Leach & Maddock 2018, §3.2)
-----------------------------------
For element e with nodal displacements ``u`` (8 × 3), uniform shape-function
gradient ``∂h/∂x`` (8 × 3) and rest volume V:

1. deformation gradient ``X = I + uᵀ ∂h/∂x``, ``C = XᵀX``, ``J = det X``;
2. neo-Hookean ``S = μJ^{-2/3}(I − ⅓ tr C · C⁻¹) + K J (J − 1) C⁻¹``;
3. element nodal forces ``Fe = V · X S (∂h/∂x)ᵀ`` (Leach & Maddock's (2018) ``8 det J₀ ·
   X S ∂hᵀ`` with the exact volume) plus hourglass forces ``k γ γᵀ u``;
4. an optional hook may scale or replace each element's forces (breaking
   saliva elements);
5. element forces are gathered to nodes through a node → (element, local
   node) map (race-free) and the central difference with mass-proportional
   damping α advances every degree of freedom with lumped mass M:

   .. math::

      u^{n+1} = A (R^n - F^n) + B u^n + C u^{n-1},\\quad
      A = \\left(\\frac{M}{\\Delta t^2} + \\frac{\\alpha M}{2\\Delta t}\\right)^{-1},\\;
      B = \\frac{2 M A}{\\Delta t^2},\\; C = \\frac{\\alpha M A}{2\\Delta t} - \\frac{B}{2},

   which is ``M ü + α M u̇ + F(u) = R`` with centred differences;
6. fixed degrees of freedom stay zero, prescribed ones are set to their
   value at ``t^{n+1}``.

Shape-function gradients are by default Flanagan & Belytschko's (1981) uniform
gradients ``∂h/∂x = (1/V) ∫ ∂h/∂x dV`` (exact by 2 × 2 × 2 Gauss), which equal
the centre values for parallelepipeds and make the patch test exact on
distorted meshes (NiftySim's B-matrix method); ``gradient="centre"`` uses the
centre values with ``8 det J₀`` instead, as NiftySim's CPU element does.
Hourglass control (Flanagan–Belytschko, as in NiftySim):
``γ = Γ − (∂h/∂x)(xᵀ Γ)`` with Γ the 8 × 4 hourglass base vectors and
``k = κ V (λ + 2μ) Σ(∂h/∂x)² / 8``; ``γ`` is orthogonal to every affine
field, so hourglass forces vanish for rigid and homogeneous motion.

Stability
---------
Flanagan & Belytschko bound an element's highest frequency by
``ω² ≤ 8 c² Σ(∂h/∂x)²``; the hourglass springs add at most a factor (1 + κ).
The critical step ``2/ω`` gives each element the characteristic length
``L = 1 / sqrt(2 (1 + κ) Σ(∂h/∂x)²)`` (h / sqrt(3(1 + κ)) for a cube of edge h)
and the solver refuses ``dt > min_e L_e / c_e`` with
``c = sqrt((K + 4μ/3)/ρ)``.
"""

from __future__ import annotations

from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass

import numba
import numpy as np
from numba import njit, prange

from visemeface.errors import InputError, SimulationDiverged
from visemeface.physics.hexmesh import NODE_SIGNS, HexMesh
from visemeface.physics.materials import (TISSUE_LIMIT, NeoHookean, gent_factor, material_table,
                                          second_piola_kirchhoff, strain_energy_density)
from visemeface.runtime import set_threads  # noqa: F401  (re-exported: the solver's thread count)

#: Hourglass base vectors Γ (8 × 4) for NiftySim's hex8 node order (:mod:`visemeface.physics.hexmesh`): the
#: columns are the products ξη, ηζ, ζξ, ξηζ of the nodes' local coordinates.
HOURGLASS_BASE = np.array(
    [[1, 1, 1, -1], [-1, 1, -1, 1], [1, -1, -1, -1], [-1, -1, 1, 1],
     [1, -1, -1, 1], [-1, -1, 1, -1], [1, 1, 1, 1], [-1, 1, -1, -1]], dtype=np.float64)

#: Meshes with fewer elements run the numba kernels on one thread by default.
PARALLEL_MIN_ELEMENTS = 1000

#: Leach & Maddock (2018) Table 1's hourglass coefficient κ.
DEFAULT_HOURGLASS_KAPPA = 0.075

_GAUSS = NODE_SIGNS / np.sqrt(3.0)


def _gauss_shape_derivatives() -> np.ndarray:
    """∂N_a/∂ξ_k at the 2 × 2 × 2 Gauss points, (g, a, k)."""
    s = NODE_SIGNS
    out = []
    for g in _GAUSS:
        fac = 1.0 + s * g                                           # (8, 3)
        out.append(np.stack([s[:, 0] * fac[:, 1] * fac[:, 2], s[:, 1] * fac[:, 0] * fac[:, 2],
                             s[:, 2] * fac[:, 0] * fac[:, 1]], axis=1) / 8.0)
    return np.array(out)


_GAUSS_DN = _gauss_shape_derivatives()


# ---------------------------------------------------------------------------
# Precomputation (numpy, once)
# ---------------------------------------------------------------------------

def element_geometry(nodes: np.ndarray, hexes: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Uniform shape-function gradients and exact volumes of hex8 elements.

    With ``∂x/∂ξ`` the Jacobian (columns c₀, c₁, c₂), ``adj(∂x/∂ξ)`` has rows
    ``c₁×c₂, c₂×c₀, c₀×c₁``, so

    .. math:: B_a = \\int \\frac{\\partial h_a}{\\partial x} dV
              = \\int \\frac{\\partial h_a}{\\partial \\xi} \\operatorname{adj}
              \\Big(\\frac{\\partial x}{\\partial \\xi}\\Big) d\\xi,\\qquad
              V = \\int \\det \\frac{\\partial x}{\\partial \\xi} d\\xi .

    Both integrands are at most cubic in each of ξ, η, ζ, so 2 × 2 × 2 Gauss
    points integrate them exactly. Returns ``∂h/∂x = B / V``.

    Parameters
    ----------
    nodes : ndarray (n, 3)
    hexes : int ndarray (e, 8)

    Returns
    -------
    dhdx : ndarray (e, 8, 3)
        Σₐ dhdx[a] = 0 and Σₐ xₐ ⊗ dhdx[a] = I (exact for affine fields).
    volume : ndarray (e,)
    """
    x = np.asarray(nodes, dtype=np.float64)[np.asarray(hexes)]        # (e, 8, 3)
    dN = _GAUSS_DN[:, None]                                         # (g, 1, 8, 3) ∂N/∂ξ
    cols = np.matmul(dN.transpose(0, 1, 3, 2), x[None])             # (g, e, 3, 3): cols[..., k, :] = ∂x/∂ξ_k
    c0, c1, c2 = cols[:, :, 0], cols[:, :, 1], cols[:, :, 2]
    adj = np.stack([np.cross(c1, c2), np.cross(c2, c0), np.cross(c0, c1)], axis=2)   # (g, e, 3, 3) rows
    V = np.einsum("gei,gei->e", c0, adj[:, :, 0])
    B = np.matmul(dN, adj).sum(axis=0)                              # (e, 8, 3)
    with np.errstate(divide="ignore", invalid="ignore"):
        dhdx = B / V[:, None, None]
    return np.ascontiguousarray(dhdx), V


def centre_gradients(nodes: np.ndarray, hexes: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Shape-function gradients at the element centre and ``8 det J₀`` (NiftySim's CPU element).

    ``∂h/∂x = (∂h/∂ξ)(0) · J₀⁻¹`` with ``J₀ = ∂x/∂ξ`` at ξ = 0 and ``∂hₐ/∂ξ(0) = sₐ/8``.
    Equal to :func:`element_geometry` for parallelepipeds; on other shapes
    a homogeneous stress leaves residual forces at interior nodes (the patch
    test fails), which is why the solver defaults to the uniform gradient.

    Returns
    -------
    dhdx : ndarray (e, 8, 3)
    volume : ndarray (e,)
        ``8 det J₀``, the one-point estimate of the volume.
    """
    x = np.asarray(nodes, dtype=np.float64)[np.asarray(hexes)]
    dN = NODE_SIGNS / 8.0
    J0 = np.einsum("eai,ak->eik", x, dN)                           # ∂x_i/∂ξ_k
    det = np.linalg.det(J0)
    with np.errstate(divide="ignore", invalid="ignore"):
        inv = np.linalg.inv(np.where(det[:, None, None] != 0, J0, np.eye(3)))
    return np.ascontiguousarray(np.einsum("ak,eki->eai", dN, inv)), 8.0 * det


def hourglass_shape_vectors(nodes: np.ndarray, hexes: np.ndarray, dhdx: np.ndarray) -> np.ndarray:
    """Flanagan–Belytschko hourglass shape vectors ``γ = Γ − (∂h/∂x)(xᵀ Γ)``.

    Returns
    -------
    ndarray (e, 8, 4)
        γ[e] is orthogonal to constant and linear nodal fields: Σₐ γₐₖ (A xₐ + b) = 0.
    """
    x = np.asarray(nodes, dtype=np.float64)[np.asarray(hexes)]
    xg = np.einsum("ebi,bk->eik", x, HOURGLASS_BASE)               # (e, 3, 4)
    return np.ascontiguousarray(HOURGLASS_BASE[None] - np.einsum("eai,eik->eak", dhdx, xg))


def rigid_rotation(points: np.ndarray, centre, axis, angle: float) -> np.ndarray:
    """Displacements ``(R − I)(p − c)`` of a rotation by ``angle`` about an axis.

    Rodrigues: ``R v = v cos θ + (k × v) sin θ + k (k·v)(1 − cos θ)``, k the
    unit axis. A jaw opening is a rotation about the axis through both jaw
    joints (``prescribed_rotation``).
    """
    p = np.asarray(points, dtype=np.float64) - np.asarray(centre, dtype=np.float64)
    k = np.asarray(axis, dtype=np.float64)
    norm = np.linalg.norm(k)
    if not norm > 0:
        raise InputError(f"rotation axis must be non-zero, got {list(np.ravel(axis))}")
    k = k / norm
    c, s = np.cos(angle), np.sin(angle)
    rotated = p * c + np.cross(k, p) * s + np.outer(p @ k, k) * (1.0 - c)
    return rotated - p


def prescribed_rotation(mesh: HexMesh, nodes, centre, axis, angle: Callable[[float], float]):
    """A prescribed-displacement condition rotating ``nodes`` rigidly.

    Returns ``(nodes, f)`` for :class:`TLEDSolver`'s ``prescribed`` with
    ``f(t) = rigid_rotation(X[nodes], centre, axis, angle(t))``.
    """
    nodes = np.asarray(nodes, dtype=np.int64)
    rest = mesh.nodes[nodes].copy()
    return nodes, (lambda t: rigid_rotation(rest, centre, axis, angle(t)))


def characteristic_length(a, kappa: float):
    """Each element's ``L = 1 / sqrt(2 (1 + κ) a)`` from ``a = Σ(∂h/∂x)²`` (the module docstring's
    stability bound; its stable step is ``L / c``)."""
    return 1.0 / np.sqrt(2.0 * (1.0 + kappa) * np.asarray(a, dtype=np.float64))


def node_slots(conn: np.ndarray, n_nodes: int) -> tuple[np.ndarray, np.ndarray]:
    """Node → (element, local node) map as CSR over the flat slots ``e·8 + a``: node ``k``'s slots are
    ``slot[ptr[k]:ptr[k + 1]]``, in increasing slot order (the order its forces are summed in)."""
    flat = np.asarray(conn, dtype=np.int64).ravel()
    ptr = np.zeros(n_nodes + 1, dtype=np.int64)
    np.cumsum(np.bincount(flat, minlength=n_nodes), out=ptr[1:])
    return ptr, np.ascontiguousarray(np.argsort(flat, kind="stable").astype(np.int64))


# ---------------------------------------------------------------------------
# numba kernels
# ---------------------------------------------------------------------------

# Safe fast-math: contraction to FMA, reassociation, reciprocals; NaN and inf
# semantics kept (no "nnan"/"ninf") so a blow-up still shows in J.
_FASTMATH = {"contract", "reassoc", "arcp", "nsz", "afn"}
_KERNEL = dict(parallel=True, cache=True, boundscheck=False, error_model="numpy", fastmath=_FASTMATH)
_SERIAL = dict(_KERNEL, parallel=False)

# Cubic fit of J^(-1/3) on [0.5, 2] (relative error < 4e-3), refined below.
_IC0, _IC1, _IC2, _IC3 = 1.7343073149751, -1.2416945615627, 0.62614907499671, -0.12057017491707


@njit(inline="always", cache=True, error_model="numpy")
def _inv_cbrt(J):  # pragma: no cover - compiled
    """J^(-1/3) to round-off, about 3x faster than libm's cbrt near J = 1.

    For 0.5 < J < 2 a cubic start y₀ is corrected with the exact identity
    J^(-1/3) = y (1 − r)^(-1/3), r = 1 − J y³, by the binomial series: to r⁴
    (|r| < 1.2e-2 leaves < 1e-10), then to r² (leaves < 1e-19). Elsewhere
    (rare, large strain) it falls back to 1 / cbrt(J).
    """
    if J > 0.5 and J < 2.0:
        y = _IC0 + J * (_IC1 + J * (_IC2 + J * _IC3))
        r = 1.0 - J * y * y * y
        y = y * (1.0 + r * (1.0 / 3.0 + r * (2.0 / 9.0 + r * (14.0 / 81.0 + r * (35.0 / 243.0)))))
        r = 1.0 - J * y * y * y
        return y * (1.0 + r * (1.0 / 3.0 + r * (2.0 / 9.0)))
    return 1.0 / np.cbrt(J)


@njit(inline="always", error_model="numpy", fastmath=_FASTMATH)
def _element_force(e, u, conn, dhdx, vol, gamma, hgk, mu, K, ijm, fe, jac, fdef, store_f, energy, want_energy):  # pragma: no cover - compiled
    """Forces of element e into fe[e] (and J, X, energy): the body of the element loop.

    Straight-line scalar code: no array is allocated, so the parallel loop
    around it runs at full speed (allocation in a prange body costs 50–100×).
    """
    x00 = 1.0
    x01 = 0.0
    x02 = 0.0
    x10 = 0.0
    x11 = 1.0
    x12 = 0.0
    x20 = 0.0
    x21 = 0.0
    x22 = 1.0
    q00 = 0.0
    q01 = 0.0
    q02 = 0.0
    q10 = 0.0
    q11 = 0.0
    q12 = 0.0
    q20 = 0.0
    q21 = 0.0
    q22 = 0.0
    q30 = 0.0
    q31 = 0.0
    q32 = 0.0
    for a in range(8):
        n = conn[e, a]
        u0 = u[n, 0]
        u1 = u[n, 1]
        u2 = u[n, 2]
        d0 = dhdx[e, a, 0]
        d1 = dhdx[e, a, 1]
        d2 = dhdx[e, a, 2]
        x00 += u0 * d0
        x01 += u0 * d1
        x02 += u0 * d2
        x10 += u1 * d0
        x11 += u1 * d1
        x12 += u1 * d2
        x20 += u2 * d0
        x21 += u2 * d1
        x22 += u2 * d2
        g = gamma[e, a, 0]
        q00 += g * u0
        q01 += g * u1
        q02 += g * u2
        g = gamma[e, a, 1]
        q10 += g * u0
        q11 += g * u1
        q12 += g * u2
        g = gamma[e, a, 2]
        q20 += g * u0
        q21 += g * u1
        q22 += g * u2
        g = gamma[e, a, 3]
        q30 += g * u0
        q31 += g * u1
        q32 += g * u2
    # With C⁻¹ = X⁻¹X⁻ᵀ, X S = μJ^(-2/3) X + (K J (J − 1) − μJ^(-2/3) I₁/3) X⁻ᵀ and
    # X⁻ᵀ = cof(X) / J: the first Piola–Kirchhoff stress without forming C or C⁻¹.
    w00 = x11 * x22 - x12 * x21
    w01 = x12 * x20 - x10 * x22
    w02 = x10 * x21 - x11 * x20
    w10 = x02 * x21 - x01 * x22
    w11 = x00 * x22 - x02 * x20
    w12 = x01 * x20 - x00 * x21
    w20 = x01 * x12 - x02 * x11
    w21 = x02 * x10 - x00 * x12
    w22 = x00 * x11 - x01 * x10
    J = x00 * w00 + x01 * w01 + x02 * w02
    I1 = (x00 * x00 + x01 * x01 + x02 * x02 + x10 * x10 + x11 * x11 + x12 * x12
          + x20 * x20 + x21 * x21 + x22 * x22)
    y = _inv_cbrt(J)
    Jm23 = y * y
    V = vol[e]
    x = Jm23 * I1 - 3.0                       # Ī₁ − 3; Gent's μ_eff = μ / (1 − x / J_m), ijm = 1 / J_m
    gi = 1.0 - x * ijm[e]
    # at or past the limiting stretch there is no finite stress: NaN forces, and J = -inf the divergence
    # check's sign for it (selects, not a branch around a store, so the element loop still vectorises)
    jac[e] = -np.inf if (gi <= 0.0 and J > 0.0) else J
    gi = gi if gi > 0.0 else np.nan
    m = mu[e] * Jm23 / gi
    am = V * m
    bm = V * (K[e] * J * (J - 1.0) - m * I1 / 3.0) / J
    p00 = am * x00 + bm * w00
    p01 = am * x01 + bm * w01
    p02 = am * x02 + bm * w02
    p10 = am * x10 + bm * w10
    p11 = am * x11 + bm * w11
    p12 = am * x12 + bm * w12
    p20 = am * x20 + bm * w20
    p21 = am * x21 + bm * w21
    p22 = am * x22 + bm * w22
    k = hgk[e]
    r00 = k * q00
    r01 = k * q01
    r02 = k * q02
    r10 = k * q10
    r11 = k * q11
    r12 = k * q12
    r20 = k * q20
    r21 = k * q21
    r22 = k * q22
    r30 = k * q30
    r31 = k * q31
    r32 = k * q32
    for a in range(8):
        d0 = dhdx[e, a, 0]
        d1 = dhdx[e, a, 1]
        d2 = dhdx[e, a, 2]
        g0 = gamma[e, a, 0]
        g1 = gamma[e, a, 1]
        g2 = gamma[e, a, 2]
        g3 = gamma[e, a, 3]
        fe[e, a, 0] = p00 * d0 + p01 * d1 + p02 * d2 + g0 * r00 + g1 * r10 + g2 * r20 + g3 * r30
        fe[e, a, 1] = p10 * d0 + p11 * d1 + p12 * d2 + g0 * r01 + g1 * r11 + g2 * r21 + g3 * r31
        fe[e, a, 2] = p20 * d0 + p21 * d1 + p22 * d2 + g0 * r02 + g1 * r12 + g2 * r22 + g3 * r32
    if store_f:
        fdef[e, 0, 0] = x00
        fdef[e, 0, 1] = x01
        fdef[e, 0, 2] = x02
        fdef[e, 1, 0] = x10
        fdef[e, 1, 1] = x11
        fdef[e, 1, 2] = x12
        fdef[e, 2, 0] = x20
        fdef[e, 2, 1] = x21
        fdef[e, 2, 2] = x22
    if want_energy:
        hg = (q00 * q00 + q01 * q01 + q02 * q02 + q10 * q10 + q11 * q11 + q12 * q12
              + q20 * q20 + q21 * q21 + q22 * q22 + q30 * q30 + q31 * q31 + q32 * q32)
        iso = 0.5 * mu[e] * x if ijm[e] == 0.0 else -0.5 * mu[e] / ijm[e] * np.log1p(-x * ijm[e])
        energy[e] = V * (iso + 0.5 * K[e] * (J - 1.0) * (J - 1.0)) + 0.5 * k * hg


@njit(**_KERNEL)
def _element_forces_nb(u, conn, dhdx, vol, gamma, hgk, mu, K, ijm, fe, jac, fdef, store_f, energy, want_energy):  # pragma: no cover - compiled
    """Element forces, elements split over numba's threads (race-free: one writer per element)."""
    for e in prange(conn.shape[0]):
        _element_force(e, u, conn, dhdx, vol, gamma, hgk, mu, K, ijm, fe, jac, fdef, store_f, energy, want_energy)


@njit(**_SERIAL)
def _element_forces_serial(u, conn, dhdx, vol, gamma, hgk, mu, K, ijm, fe, jac, fdef, store_f, energy, want_energy):  # pragma: no cover - compiled
    """Element forces on one thread: small meshes, where thread start-up dominates."""
    for e in range(conn.shape[0]):
        _element_force(e, u, conn, dhdx, vol, gamma, hgk, mu, K, ijm, fe, jac, fdef, store_f, energy, want_energy)


@njit(inline="always", error_model="numpy", fastmath=_FASTMATH)
def _node_force(n, fe_flat, ptr, slot):  # pragma: no cover - compiled
    """Node n's assembled internal force: the sum over its (element, local node) slots, in slot order."""
    f0 = 0.0
    f1 = 0.0
    f2 = 0.0
    for p in range(ptr[n], ptr[n + 1]):
        s = slot[p]
        f0 += fe_flat[s, 0]
        f1 += fe_flat[s, 1]
        f2 += fe_flat[s, 2]
    return f0, f1, f2


@njit(inline="always", error_model="numpy", fastmath=_FASTMATH)
def _integrate_node(n, fe_flat, ptr, slot, R, A, B, C, u, uprev, unew):  # pragma: no cover - compiled
    """Gather node n's force from its (element, local node) slots, then the
    central-difference update u⁺ = A (R − F) + B u + C u⁻ of its three DOFs."""
    f0, f1, f2 = _node_force(n, fe_flat, ptr, slot)
    unew[n, 0] = A[n, 0] * (R[n, 0] - f0) + B[n, 0] * u[n, 0] + C[n, 0] * uprev[n, 0]
    unew[n, 1] = A[n, 1] * (R[n, 1] - f1) + B[n, 1] * u[n, 1] + C[n, 1] * uprev[n, 1]
    unew[n, 2] = A[n, 2] * (R[n, 2] - f2) + B[n, 2] * u[n, 2] + C[n, 2] * uprev[n, 2]


@njit(**_KERNEL)
def _integrate_nb(fe_flat, ptr, slot, R, A, B, C, u, uprev, unew):  # pragma: no cover - compiled
    """Assembly + time integration, nodes split over threads (each node written once)."""
    for n in prange(u.shape[0]):
        _integrate_node(n, fe_flat, ptr, slot, R, A, B, C, u, uprev, unew)


@njit(**_SERIAL)
def _integrate_serial(fe_flat, ptr, slot, R, A, B, C, u, uprev, unew):  # pragma: no cover - compiled
    """Assembly + time integration on one thread."""
    for n in range(u.shape[0]):
        _integrate_node(n, fe_flat, ptr, slot, R, A, B, C, u, uprev, unew)


@njit(inline="always")
def _min_jacobian(jac):  # pragma: no cover - compiled
    """The smallest J (NaN if any J is NaN): the step's one divergence check."""
    m = np.inf
    for e in range(jac.shape[0]):
        j = jac[e]
        if not j > 0.0:
            return j
        if j < m:
            m = j
    return m


@njit(**_KERNEL)
def _step_nb(ue, conn, dhdx, vol, gamma, hgk, mu, K, ijm, fe, jac, fdef, energy, want_energy, ptr, slot, R, A, B, C,
             u, uprev, unew):  # pragma: no cover - compiled
    """One whole step in one call: element forces of ``ue`` (elements over threads), then gather and
    central difference (nodes over threads); returns the smallest J.

    The same arithmetic as :func:`_element_forces_nb` then :func:`_integrate_nb`, without the return
    to Python between them: there the second thread fell asleep and had to be woken for each loop
    (measured: 2 threads were slower than 1 on the 2,172-hex face). ``ue`` is the displacement the
    elements see (``u``, or ``u`` minus the active strain's field); ``u`` is integrated.
    """
    for e in prange(conn.shape[0]):
        _element_force(e, ue, conn, dhdx, vol, gamma, hgk, mu, K, ijm, fe, jac, fdef, False, energy, want_energy)
    fe_flat = fe.reshape(-1, 3)
    for n in prange(u.shape[0]):
        _integrate_node(n, fe_flat, ptr, slot, R, A, B, C, u, uprev, unew)
    return _min_jacobian(jac)


@njit(**_SERIAL)
def _step_serial(ue, conn, dhdx, vol, gamma, hgk, mu, K, ijm, fe, jac, fdef, energy, want_energy, ptr, slot, R, A, B, C,
                 u, uprev, unew):  # pragma: no cover - compiled
    """:func:`_step_nb` on one thread."""
    for e in range(conn.shape[0]):
        _element_force(e, ue, conn, dhdx, vol, gamma, hgk, mu, K, ijm, fe, jac, fdef, False, energy, want_energy)
    fe_flat = fe.reshape(-1, 3)
    for n in range(u.shape[0]):
        _integrate_node(n, fe_flat, ptr, slot, R, A, B, C, u, uprev, unew)
    return _min_jacobian(jac)


@njit(**_KERNEL)
def _gather_nb(fe_flat, ptr, slot, out):  # pragma: no cover - compiled
    """Assembled nodal forces out[n] = Σ over n's slots of fe_flat[slot]."""
    for n in prange(out.shape[0]):
        out[n, 0], out[n, 1], out[n, 2] = _node_force(n, fe_flat, ptr, slot)


# ---------------------------------------------------------------------------
# numpy reference of the same kernels
# ---------------------------------------------------------------------------

def _element_forces_np(u, conn, dhdx, vol, gamma, hgk, mu, K, ijm, fe, jac, fdef, store_f, energy,
                       want_energy):
    """The numpy reference of :func:`_element_force`: the material law of :mod:`~visemeface.physics.materials`
    (its S and W, NaN past a Gent limit) at each element's uniform gradient, the same hourglass control; J = −inf
    marks an element at or past its limit."""
    ue = u[conn]                                                    # (e, 8, 3)
    X = np.eye(3) + np.einsum("eai,eaj->eij", ue, dhdx)
    J = np.linalg.det(X)
    P = vol[:, None, None] * (X @ second_piola_kirchhoff(X, mu, K, ijm))
    q = np.einsum("eak,eai->eki", gamma, ue)                        # (e, 4, 3)
    fe[:] = np.einsum("eij,eaj->eai", P, dhdx) + hgk[:, None, None] * np.einsum("eak,eki->eai", gamma, q)
    x = np.einsum("eij,eij->e", X, X) / np.cbrt(J * J) - 3.0       # Ī₁ − 3
    jac[:] = np.where(np.isnan(gent_factor(x, ijm)) & (J > 0.0), -np.inf, J)
    if store_f:
        fdef[:] = X
    if want_energy:
        energy[:] = vol * strain_energy_density(X, mu, K, ijm) + 0.5 * hgk * np.einsum("eki,eki->e", q, q)


def _gather_np(fe_flat, conn_flat, out):
    for i in range(3):
        out[:, i] = np.bincount(conn_flat, weights=fe_flat[:, i], minlength=len(out))


# ---------------------------------------------------------------------------
# Solver
# ---------------------------------------------------------------------------

@dataclass
class Frame:
    """One output of :meth:`TLEDSolver.run`.

    Attributes
    ----------
    step : int
    time : float
        ``step · dt`` (s).
    displacement : ndarray (n, 3)
        Node displacements u(t) (m), a copy.
    kinetic_energy : float
        ½ Σ M v² with the centred velocity (u(t+dt) − u(t−dt)) / 2dt (J).
    strain_energy : float
        Σₑ V W(X) + ½ uᵀ HG u, hourglass energy included (J).
    velocity : ndarray (n, 3) or None
        The centred velocity (u(t+dt) − u(t−dt)) / 2dt (m/s); with
        ``displacement`` it restarts a run (``initial_displacement``,
        ``initial_velocity``) where this one stood, e.g. from a checkpoint.
    """

    step: int
    time: float
    displacement: np.ndarray
    kinetic_energy: float
    strain_energy: float
    velocity: np.ndarray | None = None


ElementHook = Callable[[int, float, np.ndarray, np.ndarray], "np.ndarray | None"]


class TLEDSolver:
    """Explicit dynamics of a hex8 neo-Hookean mesh (see the module docstring).

    Parameters
    ----------
    mesh : HexMesh
    materials : NeoHookean or sequence of NeoHookean
        Indexed by ``mesh.material`` (e.g. ``[SOFT_TISSUE, SALIVA]``).
    dt : float
        Time step (s); refused if above :attr:`stable_dt`.
    damping : float
        Mass-proportional damping coefficient α (1/s); the seed uses 80.
    hourglass_kappa : float
        Hourglass coefficient κ (seed: 0.075).
    fixed : int array of node ids, or bool array (n, 3)
        Degrees of freedom held at zero displacement.
    prescribed : sequence of (node ids, f)
        ``f(t)`` returns the displacements (k, 3) (or one (3,) vector) of those
        nodes at time t; see :func:`prescribed_rotation`.
    forces : sequence of (node ids, f)
        ``f(t)`` returns external nodal forces (k, 3) or (3,) (N) at time t.
    element_hook : callable, optional
        ``hook(step, time, F, forces)`` is called every step after the element
        forces are computed and before they are assembled. ``F`` (e, 3, 3) holds
        each element's deformation gradient X (so C = FᵀF, J = det F);
        ``forces`` (e, 8, 3) the element's nodal internal forces (hourglass
        included), which the hook may change in place; or it may return an
        (e,) array of factors to scale each element's forces. Both arrays are
        reused between steps: copy what must be kept.
    backend : {"numba", "numpy"}
        The numba kernels, or the plain-numpy reference.
    gradient : {"uniform", "centre"}
        ``"uniform"`` (default): Flanagan–Belytschko mean gradients with the
        exact volume (:func:`element_geometry`; NiftySim's B-matrix method),
        which pass the patch test on any mesh. ``"centre"``: gradients at the
        element centre with ``8 det J₀`` (:func:`centre_gradients`; NiftySim's
        CPU default and NiftySim's formulation read literally). Identical for parallelepipeds.
    parallel : bool, optional
        Split the numba loops over threads (:func:`set_threads`). Default: only
        for meshes of at least ``PARALLEL_MIN_ELEMENTS`` elements, since on small
        meshes the two thread start-ups per step cost more than the work.

    Examples
    --------
    >>> from visemeface.physics.hexmesh import box_mesh
    >>> from visemeface.physics.materials import SOFT_TISSUE
    >>> mesh = box_mesh((4, 1, 1), (0.04, 0.01, 0.01))
    >>> solver = TLEDSolver(mesh, SOFT_TISSUE, dt=1e-5, damping=80.0,
    ...                     fixed=mesh.node_sets["xmin"],
    ...                     forces=[(mesh.node_sets["xmax"], lambda t: [0.01 * min(t / 0.1, 1), 0, 0])])
    >>> frames = list(solver.run(n_steps=1000, output_every=500))
    >>> [f.step for f in frames]
    [0, 500, 1000]
    """

    def __init__(self, mesh: HexMesh, materials: NeoHookean | Sequence[NeoHookean], *, dt: float,
                 damping: float = 0.0, hourglass_kappa: float = DEFAULT_HOURGLASS_KAPPA,
                 fixed=None, prescribed: Sequence = (), forces: Sequence = (),
                 element_hook: ElementHook | None = None, backend: str = "numba",
                 parallel: bool | None = None, gradient: str = "uniform"):
        if backend not in ("numba", "numpy"):
            raise InputError(f"unknown TLED backend {backend!r}; use 'numba' or 'numpy'")
        if not (np.isfinite(damping) and damping >= 0):
            raise InputError(f"damping must be a number >= 0, got {damping!r}")
        if not (np.isfinite(hourglass_kappa) and hourglass_kappa >= 0):
            raise InputError(f"hourglass_kappa must be a number >= 0, got {hourglass_kappa!r}")
        self.mesh = mesh
        self.backend = backend
        self.damping = float(damping)
        self.kappa = float(hourglass_kappa)
        self.element_hook = element_hook
        n, ne = mesh.n_nodes, mesh.n_elements
        self.parallel = ne >= PARALLEL_MIN_ELEMENTS if parallel is None else bool(parallel)
        if backend == "numba":
            self._elem_kernel = _element_forces_nb if self.parallel else _element_forces_serial
            self._int_kernel = _integrate_nb if self.parallel else _integrate_serial
            self._step_kernel = _step_nb if self.parallel else _step_serial
        else:
            self._elem_kernel = _element_forces_np
        if ne == 0:
            raise InputError("the hex mesh has no elements")

        mat = material_table(materials, mesh.material)
        self.mu, self.K, self.rho = mat["mu"], mat["K"], mat["rho"]
        #: 1 / J_m per element (Gent's limiting Ī₁ − 3; 0: neo-Hookean).
        self.ijm = mat["ijm"]
        self.conn = np.ascontiguousarray(mesh.hexes, dtype=np.int64)
        if gradient not in ("uniform", "centre"):
            raise InputError(f"unknown gradient rule {gradient!r}; use 'uniform' or 'centre'")
        self.gradient = gradient
        self.dhdx, self.volume = element_geometry(mesh.nodes, self.conn)
        # Exact volume for masses and hourglass stiffness; forces use V (uniform) or 8 det J0 (centre).
        self.force_volume = self.volume
        if gradient == "centre":
            self.dhdx, self.force_volume = centre_gradients(mesh.nodes, self.conn)
        bad = ~(self.volume > 0) | ~(self.force_volume > 0)
        if bad.any():
            e = int(np.flatnonzero(bad)[0])
            raise InputError(f"element {e} (nodes {self.conn[e].tolist()}) has volume "
                             f"{self.volume[e]:.3g} m^3 (centre estimate {self.force_volume[e]:.3g}) "
                             f"<= 0: inverted or degenerate")
        self.gamma = hourglass_shape_vectors(mesh.nodes, self.conn, self.dhdx)
        a = np.einsum("eai,eai->e", self.dhdx, self.dhdx)
        lam_2mu = self.K + 4.0 * self.mu / 3.0                     # λ + 2μ with λ = K − 2μ/3
        self.hourglass_stiffness = self.kappa * self.volume * lam_2mu * a / 8.0

        # Stability: dt_e = L_e / c_e, L_e = 1 / sqrt(2 (1 + κ) a_e).
        self.characteristic_length = characteristic_length(a, self.kappa)
        #: Each element's own stable step L_e / c_e (s).
        self.element_dt = dt_e = self.characteristic_length / mat["wave_speed"]
        self.critical_element = int(np.argmin(dt_e))
        self.stable_dt = float(dt_e[self.critical_element])
        if not (np.isfinite(dt) and dt > 0):
            raise InputError(f"time step must be a positive number, got {dt!r}")
        if dt > self.stable_dt:
            e = self.critical_element
            raise InputError(
                f"time step {dt:.4g} s exceeds the stable limit {self.stable_dt:.4g} s "
                f"(element {e}: characteristic length {self.characteristic_length[e]:.4g} m, "
                f"wave speed {mat['wave_speed'][e]:.4g} m/s); use dt <= {self.stable_dt:.4g}")
        self.dt = float(dt)

        # Lumped mass ρV/8 per element node; central-difference coefficients per DOF.
        mass = np.bincount(self.conn.ravel(), weights=np.repeat(self.rho * self.volume / 8.0, 8),
                           minlength=n)
        if not (mass > 0).all():
            orphan = int(np.flatnonzero(~(mass > 0))[0])
            raise InputError(f"node {orphan} belongs to no element (zero mass); remove unused nodes")
        self.mass = mass
        A = 1.0 / (mass / dt**2 + self.damping * mass / (2.0 * dt))
        B = 2.0 * mass * A / dt**2
        C = self.damping * mass * A / (2.0 * dt) - B / 2.0
        self.free = self._free_mask(fixed)
        self._A = np.ascontiguousarray(A[:, None] * self.free)
        self._B = np.ascontiguousarray(B[:, None] * self.free)
        self._C = np.ascontiguousarray(C[:, None] * self.free)

        self.prescribed = [(self._node_ids(ids, f"prescribed[{i}]"), f) for i, (ids, f) in enumerate(prescribed)]
        self.forces = [(self._node_ids(ids, f"forces[{i}]", unique=True), f) for i, (ids, f) in enumerate(forces)]
        self._force_nodes = (np.unique(np.concatenate([ids for ids, _ in self.forces]))
                             if self.forces else np.zeros(0, dtype=np.int64))
        self._all_nodes_force = (len(self.forces) == 1 and len(self.forces[0][0]) == n
                                 and bool((self.forces[0][0] == np.arange(n)).all()))

        self._ptr, self._slot = node_slots(self.conn, n)
        self._conn_flat = self.conn.ravel()

        # Work buffers, allocated once.
        self._fe = np.zeros((ne, 8, 3))
        self._jac = np.zeros(ne)
        self._fdef = np.zeros((ne, 3, 3) if element_hook is not None else (1, 3, 3))
        self._energy = np.zeros(ne)

    # -- set-up helpers -----------------------------------------------------

    def _node_ids(self, ids, what: str, unique: bool = False) -> np.ndarray:
        ids = np.asarray(ids)
        if ids.dtype == bool:
            if ids.shape != (self.mesh.n_nodes,):
                raise InputError(f"{what}: boolean node mask must have shape ({self.mesh.n_nodes},), got {ids.shape}")
            ids = np.flatnonzero(ids)
        ids = np.asarray(ids, dtype=np.int64).ravel()
        if ids.size and (ids.min() < 0 or ids.max() >= self.mesh.n_nodes):
            raise InputError(f"{what}: node ids must lie in 0..{self.mesh.n_nodes - 1}, "
                             f"got {ids.min()}..{ids.max()}")
        if unique and len(np.unique(ids)) != len(ids):
            raise InputError(f"{what}: node ids repeat; give each node once (sum its forces)")
        return ids

    def _free_mask(self, fixed) -> np.ndarray:
        free = np.ones((self.mesh.n_nodes, 3))
        if fixed is None:
            return free
        fixed = np.asarray(fixed)
        if fixed.dtype == bool and fixed.shape == (self.mesh.n_nodes, 3):
            free[fixed] = 0.0
        else:
            free[self._node_ids(fixed, "fixed")] = 0.0
        return free

    @staticmethod
    def _values(f, t, k: int, what: str) -> np.ndarray:
        v = np.asarray(f(t), dtype=np.float64)
        if v.shape == (k, 3) or v.shape == (3,):     # (3,): numpy's assignment broadcasts it (no copy made)
            return v
        try:
            v = np.broadcast_to(v, (k, 3))
        except ValueError:
            raise InputError(f"{what} at t = {t:.6g} s returned shape {v.shape}; expected ({k}, 3) or (3,)") from None
        return v

    # -- kernels ------------------------------------------------------------

    def _element_forces(self, u: np.ndarray, want_energy: bool, conn=None) -> None:
        self._elem_kernel(u, self.conn if conn is None else conn, self.dhdx, self.force_volume, self.gamma, self.hourglass_stiffness,
                          self.mu, self.K, self.ijm, self._fe, self._jac, self._fdef, self.element_hook is not None,
                          self._energy, want_energy)

    def internal_forces(self, u: np.ndarray) -> np.ndarray:
        """Assembled internal nodal forces F(u) (n, 3) (N), hook not applied.

        Raises
        ------
        InputError
            If ``u`` takes an element to or past its material's limiting stretch (no finite force).
        """
        u = np.ascontiguousarray(u, dtype=np.float64)
        self._element_forces(u, False)
        past = np.flatnonzero(self._jac == -np.inf)
        if len(past):
            raise InputError(f"element {int(past[0])} (and {len(past) - 1} more) is at or past the tissue's "
                             f"limiting stretch in this displacement: no finite force")
        out = np.zeros((self.mesh.n_nodes, 3))
        if self.backend == "numba":
            _gather_nb(self._fe.reshape(-1, 3), self._ptr, self._slot, out)
        else:
            _gather_np(self._fe.reshape(-1, 3), self._conn_flat, out)
        return out

    def element_stress(self, u: np.ndarray) -> dict:
        """Per-element deformation gradient, J and stresses for displacements u.

        Returns
        -------
        dict of ndarray
            ``F`` (e, 3, 3), ``J`` (e,), ``S`` (second Piola–Kirchhoff) and
            ``cauchy`` (σ = F S Fᵀ / J), evaluated at the element centre with the
            uniform gradient (numpy).
        """
        ue = np.asarray(u, dtype=np.float64)[self.conn]
        F = np.eye(3) + np.einsum("eai,eaj->eij", ue, self.dhdx)
        S = second_piola_kirchhoff(F, self.mu, self.K, self.ijm)
        J = np.linalg.det(F)
        return {"F": F, "J": J, "S": S, "cauchy": F @ S @ np.swapaxes(F, 1, 2) / J[:, None, None]}

    def _check(self, step: int, t: float) -> None:
        # NaN propagates through min(); an infinite displacement makes the
        # next step's J NaN, so one reduction a step catches every blow-up.
        if self._jac.min() > 0.0:
            return
        bad = np.flatnonzero(~(self._jac > 0) | ~np.isfinite(self._jac))
        e = int(bad[0])
        J = self._jac[e]
        limit = J == -np.inf
        what = ("reached the tissue's limiting stretch" if limit
                else "a non-finite deformation (NaN/inf displacement)" if not np.isfinite(J)
                else f"J = {J:.4g} <= 0 (inverted)")
        advice = ("This motion stretches the tissue further than its limit allows: raise the limit (--tissue-limit; "
                  f"the default, {TISSUE_LIMIT:g}, holds on the default face at glue 0.3 and full jaw; inf: Leach & Maddock's (2018) "
                  "neo-Hookean tissue, which never stiffens) or lower the glue (a smaller dt does not help)"
                  if limit else f"Reduce dt (now {self.dt:.4g} s, stable limit {self.stable_dt:.4g} s), loads or "
                  f"prescribed motion, or raise damping")
        raise SimulationDiverged(
            f"simulation diverged at step {step} (t = {t:.6g} s): element {e} "
            f"(nodes {self.conn[e].tolist()}) has {what}; {len(bad)} element(s) affected. {advice}", step, t, e)

    def _apply_hook(self, step: int, t: float) -> None:
        scale = self.element_hook(step, t, self._fdef, self._fe)
        if scale is not None:
            scale = np.asarray(scale, dtype=np.float64)
            if scale.shape != (self.mesh.n_elements,):
                raise InputError(f"element_hook returned shape {scale.shape}; expected "
                                 f"({self.mesh.n_elements},) scale factors or None")
            self._fe *= scale[:, None, None]

    def _external(self, t: float, run) -> np.ndarray:
        """R(t) of the loads in the run's node numbering (``run``: :meth:`_run_numbering`)."""
        forces, R = run.forces, run.R
        if self._all_nodes_force:         # one load on every node: (3,) broadcasts, (n, 3) is in the mesh's order
            v = self._values(forces[0][1], t, len(R), "forces[0]")
            if v.ndim == 1:
                np.copyto(R, v)
            else:
                R[run.rank] = v
        elif len(forces) == 1:            # unique ids: only they are ever non-zero
            ids, f = forces[0]
            R[ids] = self._values(f, t, len(ids), "forces[0]")
        elif forces:
            R[run.force_nodes] = 0.0
            for i, (ids, f) in enumerate(forces):
                R[ids] += self._values(f, t, len(ids), f"forces[{i}]")
        return R

    def _impose(self, u: np.ndarray, t: float, run) -> None:
        """Set the prescribed nodes of ``u`` (in the run's numbering) to their values at ``t``."""
        for i, (ids, f) in enumerate(run.prescribed):
            u[ids] = self._values(f, t, len(ids), f"prescribed[{i}]")

    def _run_numbering(self):
        """The arrays :meth:`run` steps, with the nodes numbered in the order the elements first touch
        them (:func:`~visemeface.physics.hexmesh.first_touch_order`; cached). Elements keep their order,
        and each node's forces are summed in the same order, so the run gives the same bits in any
        numbering; the frames are given back in the mesh's."""
        if getattr(self, "_run", None) is None:
            from types import SimpleNamespace

            from visemeface.physics.hexmesh import first_touch_order
            n = self.mesh.n_nodes
            order = first_touch_order(self.conn, n)
            rank = np.empty(n, dtype=np.int64)
            rank[order] = np.arange(n)
            conn = np.ascontiguousarray(rank[self.conn])
            ptr, slot = node_slots(conn, n)
            self._run = SimpleNamespace(
                order=order, rank=rank, conn=conn, flat=conn.ravel(), ptr=ptr, slot=slot,
                A=np.ascontiguousarray(self._A[order]), B=np.ascontiguousarray(self._B[order]),
                C=np.ascontiguousarray(self._C[order]), free=self.free[order], mass=self.mass[order],
                forces=[(rank[ids], f) for ids, f in self.forces], force_nodes=rank[self._force_nodes],
                prescribed=[(rank[ids], f) for ids, f in self.prescribed], R=np.zeros((n, 3)))
        return self._run

    # -- time stepping ------------------------------------------------------

    def run(self, n_steps: int, output_every: int = 1, initial_displacement=None,
            initial_velocity=None) -> Iterator[Frame]:
        """Advance ``n_steps`` steps, yielding a :class:`Frame` every ``output_every``.

        Frames are produced at steps 0, N, 2N, … ≤ n_steps. The start is
        ``u(0) = u₀`` (with prescribed values imposed) and, by Taylor expansion,
        ``u(−dt) = u₀ − dt v₀ + ½ dt² M⁻¹(R(0) − F(u₀))``.

        Raises
        ------
        SimulationDiverged
            When an element inverts (J ≤ 0) or a value turns NaN/inf, naming the
            step, time and element.
        """
        n_steps, output_every = int(n_steps), int(output_every)
        if n_steps < 0 or output_every < 1:
            raise InputError(f"need n_steps >= 0 and output_every >= 1, got {n_steps}, {output_every}")
        n, dt = self.mesh.n_nodes, self.dt
        o = self._run_numbering()                     # the run's node numbering; frames in the mesh's
        u = np.zeros((n, 3)) if initial_displacement is None else \
            np.array(np.broadcast_to(np.asarray(initial_displacement, dtype=np.float64), (n, 3))[o.order])
        u *= o.free
        self._impose(u, 0.0, o)
        v0 = np.zeros((n, 3)) if initial_velocity is None else \
            np.broadcast_to(np.asarray(initial_velocity, dtype=np.float64), (n, 3))[o.order]
        self._element_forces(u, False, o.conn)
        self._check(0, 0.0)
        if self.element_hook is not None:
            self._apply_hook(0, 0.0)
        force0 = np.zeros((n, 3))
        _gather_np(self._fe.reshape(-1, 3), o.flat, force0)
        accel = (self._external(0.0, o) - force0) / o.mass[:, None]
        u_prev = np.ascontiguousarray((u - dt * v0 + 0.5 * dt * dt * accel) * o.free)
        self._impose(u_prev, 0.0, o)
        u_new = np.zeros((n, 3))
        fe_flat = self._fe.reshape(-1, 3)
        numba_backend = self.backend == "numba"
        fused = numba_backend and self.element_hook is None
        for step in range(n_steps + 1):
            t = step * dt
            output = step % output_every == 0
            if fused:                          # the whole step in one compiled call (see _step_nb)
                R = self._external(t, o)
                jmin = self._step_kernel(u, o.conn, self.dhdx, self.force_volume, self.gamma,
                                         self.hourglass_stiffness, self.mu, self.K, self.ijm, self._fe, self._jac,
                                         self._fdef, self._energy, output, o.ptr, o.slot, R, o.A, o.B, o.C,
                                         u, u_prev, u_new)
                if not jmin > 0.0:
                    self._check(step, t)
            else:
                self._element_forces(u, output, o.conn)
                self._check(step, t)
                if self.element_hook is not None:
                    self._apply_hook(step, t)
                R = self._external(t, o)
                if numba_backend:
                    self._int_kernel(fe_flat, o.ptr, o.slot, R, o.A, o.B, o.C, u, u_prev, u_new)
                else:
                    _gather_np(fe_flat, o.flat, force0)
                    np.multiply(o.A, R - force0, out=u_new)
                    u_new += o.B * u + o.C * u_prev
            self._impose(u_new, t + dt, o)
            if output:
                v = (u_new - u_prev) / (2.0 * dt)
                yield Frame(step, t, u[o.rank], float(0.5 * np.einsum("n,ni,ni->", o.mass, v, v)),
                            float(self._energy.sum()), v[o.rank])
            u_prev, u, u_new = u, u_new, u_prev
