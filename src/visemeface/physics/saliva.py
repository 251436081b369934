"""Breaking saliva elements: the sticky-lip material of seed 000 §3.4.

A single layer of hexahedra bridges the upper and lower lip seams. Each saliva
element is neo-Hookean (stiff, so it barely moves the lips while intact) and
*breaks* when it is stretched across the lips beyond a moisture-dependent
breaking point:

moisture (Herz-Knudsen, constant rate φ)
    ᵗM = max(⁰M − t·φ, 0)
breaking point
    Z = 1                         if ᵗM > M_c  (wet: no stickiness)
    Z = 1 + K_glue · ᵗM / M_c     otherwise
stretch across the lips (the element's local y axis n_y, reference frame)
    Q = C_yy = n_yᵀ C n_y = |F n_y|²,   C = FᵀF
force once broken (seed eq. 11)
    ᵗF = 0.99 · ᵗ⁻¹F             (geometric decay, one factor per time step)

Two choices the seed leaves open, made here and documented:

* **Latch and re-bond.** Once ``Q ≥ Z`` the element stays broken (the brief's
  reading of eq. 11; the literal per-step test would make a half-broken
  element snap back to full force whenever Q dips under Z). A broken element
  re-bonds when the lips come back into contact, ``Q ≤ 1`` (its y extent back
  at or under the rest gap), with the breaking point of its *current*
  moisture. This is what makes a second opening sticky again and lets
  evaporation matter over a run (later openings unzip faster).
* **Glue per element.** ``K_glue`` is an array: uniform, a profile across the
  mouth (:func:`parse_glue_profile`) or read from a file
  (:func:`read_glue_file`).

Everything here is a pure function over numpy arrays except
:class:`SalivaBreaking`, the per-step state machine used as the TLED solver's
element-force hook.
"""

from __future__ import annotations

import csv
import re
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from visemeface.errors import InputError

#: Seed 000 / 001 Table 1 (the saliva's elastic constants are ``materials.SALIVA``).
INITIAL_MOISTURE = 100.0
CRITICAL_MOISTURE = 100.0
EVAPORATION_RATE = 0.0
GLUE = 0.08
CENTRAL_GLUE = 0.18
FORCE_DECAY = 0.99

#: Hex8 natural-coordinate signs of the nodes, order (−,−,−) (+,−,−) (+,+,−) (−,+,−), then z+.
HEX_SIGNS = np.array([[-1, -1, -1], [1, -1, -1], [1, 1, -1], [-1, 1, -1],
                      [-1, -1, 1], [1, -1, 1], [1, 1, 1], [-1, 1, 1]], dtype=np.float64)


@dataclass(frozen=True)
class SalivaParams:
    """Saliva moisture and breaking parameters (seed Table 1 defaults).

    The saliva's neo-Hookean constants are :data:`visemeface.physics.materials.SALIVA`.

    Attributes
    ----------
    initial_moisture : float
        ⁰M, the same for every element (arbitrary units, seed: 100).
    critical_moisture : float
        M_c, the level under which saliva glues (seed: 100).
    evaporation : float
        φ, moisture lost per second (seed: 0).
    decay : float
        Per-step force factor of a broken element (seed: 0.99).
    """

    initial_moisture: float = INITIAL_MOISTURE
    critical_moisture: float = CRITICAL_MOISTURE
    evaporation: float = EVAPORATION_RATE
    decay: float = FORCE_DECAY

    def __post_init__(self):
        if not np.isfinite(self.critical_moisture) or self.critical_moisture <= 0:
            raise InputError(f"critical moisture must be > 0, got {self.critical_moisture}")
        if not np.isfinite(self.initial_moisture) or self.initial_moisture < 0:
            raise InputError(f"moisture must be >= 0, got {self.initial_moisture}")
        if not np.isfinite(self.evaporation) or self.evaporation < 0:
            raise InputError(f"evaporation rate must be >= 0, got {self.evaporation}")
        if not 0.0 <= self.decay < 1.0:
            raise InputError(f"force decay must be in [0, 1), got {self.decay}")


def moisture(t, initial_moisture, evaporation):
    """Moisture level at time ``t`` (seed 000 eq. 6).

    .. math:: {}^tM = \\max({}^0M - t\\,\\varphi,\\ 0)

    Parameters
    ----------
    t : float or array
        Time in seconds.
    initial_moisture : float or array
        ⁰M per element.
    evaporation : float or array
        φ, the constant evaporation rate (moisture per second).

    Examples
    --------
    >>> float(moisture(2.0, 100.0, 30.0)), float(moisture(5.0, 100.0, 30.0))
    (40.0, 0.0)
    """
    return np.maximum(np.asarray(initial_moisture, dtype=np.float64)
                      - np.asarray(t, dtype=np.float64) * evaporation, 0.0)


def breaking_point(moisture_level, critical_moisture, glue):
    """Breaking stretch Z of a saliva element (seed 000 eq. 7).

    .. math:: Z = 1 \\text{ if } {}^tM > M_c, \\quad
              Z = 1 + K_{glue}\\,{}^tM / M_c \\text{ otherwise}

    Wet saliva (above the critical level) breaks as soon as it is stretched
    (Z = 1); drier saliva holds up to Q = C_yy = Z. A dry lip (M = 0) does not
    glue either.

    Examples
    --------
    >>> breaking_point(np.array([150.0, 100.0, 50.0, 0.0]), 100.0, 0.08)
    array([1.  , 1.08, 1.04, 1.  ])
    """
    m = np.asarray(moisture_level, dtype=np.float64)
    glue = np.asarray(glue, dtype=np.float64)
    return np.where(m > critical_moisture, 1.0, 1.0 + glue * m / critical_moisture)


def hex_centre_gradients(X):
    """Shape-function gradients of hex8 elements at their centres.

    With natural-coordinate signs s_a, ∂N_a/∂ξ = s_a/8 at ξ = 0, the Jacobian
    J = Σ_a X_a ⊗ ∂N_a/∂ξ and ∂N_a/∂X = J⁻ᵀ ∂N_a/∂ξ.

    Parameters
    ----------
    X : (E, 8, 3) reference node positions.

    Returns
    -------
    (E, 8, 3) array: ∂N_a/∂X per element and node.
    """
    X = np.asarray(X, dtype=np.float64)
    dN = HEX_SIGNS / 8.0                                   # (8, 3) ∂N/∂ξ
    J = np.einsum("eai,aj->eij", X, dN)                   # J_ij = ∂X_i/∂ξ_j
    Jinv = np.linalg.inv(J)                               # ∂ξ/∂X
    return np.einsum("aj,eji->eai", dN, Jinv)             # ∂N/∂X_i = Σ_j ∂N/∂ξ_j ∂ξ_j/∂X_i


def deformation_gradient(u, dNdX):
    """Centre deformation gradient F = I + Σ_a u_a ⊗ ∂N_a/∂X, (E, 3, 3).

    ``u`` is (E, 8, 3) nodal displacements, ``dNdX`` from :func:`hex_centre_gradients`.
    """
    return np.eye(3) + np.einsum("eai,eaj->eij", u, dNdX)


def element_frames(X):
    """Local orthonormal frames of hex8 elements, rows (x, y, z), (E, 3, 3).

    x runs along the element's ξ edges (along the lip seam for saliva), y along
    its η edges (across the lips, lower to upper) made orthogonal to x, z = x × y.
    """
    X = np.asarray(X, dtype=np.float64)
    ex = (X[:, [1, 2, 5, 6]] - X[:, [0, 3, 4, 7]]).mean(axis=1)
    ey = (X[:, [3, 2, 7, 6]] - X[:, [0, 1, 4, 5]]).mean(axis=1)
    ex /= np.linalg.norm(ex, axis=1, keepdims=True)
    ey = ey - np.sum(ey * ex, axis=1, keepdims=True) * ex
    ey /= np.linalg.norm(ey, axis=1, keepdims=True)
    ez = np.cross(ex, ey)
    return np.stack([ex, ey, ez], axis=1)


def stretch_across(F, axis):
    """Q = C_yy in the element frame: the squared stretch along the unit ``axis``.

    .. math:: Q = n^T C n = |F n|^2, \\quad C = F^T F

    Rotation-invariant (C is); 1 at rest, > 1 stretched, < 1 compressed.

    Parameters
    ----------
    F : (E, 3, 3) deformation gradients (reference to current).
    axis : (E, 3) unit local y axes in the reference configuration.
    """
    Fn = np.einsum("eij,ej->ei", F, axis)
    return np.sum(Fn * Fn, axis=1)


# --------------------------------------------------------------------------- glue profiles

_ITEM = re.compile(r"^\s*([A-Za-z_]+|[-+]?\d*\.?\d+\s*\.\.\s*[-+]?\d*\.?\d+)\s*=\s*([^=]+?)\s*$")
_NAMED = ("centre", "center", "left", "right", "corners", "all")


def _positive_glue(text: str, spec: str) -> float:
    try:
        v = float(text)
    except ValueError:
        raise InputError(f"glue profile {spec!r}: {text!r} is not a number") from None
    if not np.isfinite(v) or v < 0:
        raise InputError(f"glue profile {spec!r}: glue must be >= 0, got {v}")
    return v


def parse_glue_profile(spec: str, s, base: float = GLUE) -> np.ndarray:
    """Glue strength per saliva element from a profile across the mouth.

    Parameters
    ----------
    spec : str
        Comma-separated ``WHERE=VALUE`` items applied left to right over
        ``base``. WHERE is ``all``; ``centre`` (the element(s) nearest the
        mouth centre, ties included: seed 001's "central element");
        ``left`` / ``right`` (the subject's left, s > 0 / right, s < 0);
        ``corners`` (|s| ≥ 0.7); or a range ``a..b`` of s. A bare number sets
        ``all``. Example: ``"centre=0.18"``, ``"left=0.2,-0.1..0.1=0"``.
    s : (E,) array
        Element-centre positions across the mouth, −1 at the right corner,
        0 at the centre, +1 at the left corner.
    base : float
        Glue of elements no item names.

    Raises
    ------
    InputError
        Unparseable item, negative value, or an item naming no element.

    Examples
    --------
    >>> parse_glue_profile("centre=0.18", np.array([-0.5, -0.1, 0.2, 0.6]))
    array([0.08, 0.18, 0.08, 0.08])
    """
    s = np.asarray(s, dtype=np.float64)
    glue = np.full(len(s), float(base))
    spec = str(spec).strip()
    if not spec:
        raise InputError("empty glue profile")
    for item in spec.split(","):
        try:
            glue[:] = _positive_glue(item, spec)
            continue
        except InputError:
            pass
        m = _ITEM.match(item)
        if not m:
            raise InputError(f"glue profile {spec!r}: cannot read {item.strip()!r} "
                             "(expected WHERE=VALUE, WHERE one of centre, left, right, corners, all, a..b)")
        where, value = m.group(1).strip().lower(), _positive_glue(m.group(2), spec)
        if ".." in where:
            a, b = sorted(float(x) for x in where.split(".."))
            sel = (s >= a) & (s <= b)
        elif where in ("centre", "center"):
            d = np.abs(s)
            sel = d <= d.min() + 1e-9 if len(s) else np.zeros(0, bool)
        elif where == "left":
            sel = s > 0
        elif where == "right":
            sel = s < 0
        elif where == "corners":
            sel = np.abs(s) >= 0.7
        elif where == "all":
            sel = np.ones(len(s), bool)
        else:
            from visemeface.errors import close_matches
            raise InputError(f"glue profile {spec!r}: unknown place {where!r}" + close_matches(where, _NAMED))
        if not sel.any():
            raise InputError(f"glue profile {spec!r}: {item.strip()!r} names no saliva element "
                             f"(elements span s = {s.min():.2f}..{s.max():.2f})")
        glue[sel] = value
    return glue


def read_glue_file(path, s) -> np.ndarray:
    """Glue per saliva element from a CSV file.

    Two layouts (header line required):

    * ``element,glue``: one row per element index (0-based, along the seam
      from the subject's right corner); every element must be given.
    * ``s,glue``: a profile across the mouth (s from −1, right corner, to +1,
      left corner), linearly interpolated at the element centres ``s``.
    """
    path = Path(path)
    s = np.asarray(s, dtype=np.float64)
    try:
        with open(path, newline="") as fh:
            rows = list(csv.reader(fh))
    except OSError as e:
        raise InputError(f"cannot read glue file: {e.strerror}", path) from None
    rows = [r for r in rows if r and any(c.strip() for c in r)]
    if not rows:
        raise InputError("empty glue file", path)
    header = [c.strip().lower() for c in rows[0]]
    if header not in (["element", "glue"], ["s", "glue"]):
        raise InputError(f"header must be 'element,glue' or 's,glue', got {','.join(rows[0])!r}", path, 1)
    keys, vals = [], []
    for i, row in enumerate(rows[1:], start=2):
        if len(row) != 2:
            raise InputError(f"expected 2 columns, got {len(row)}", path, i)
        try:
            k, v = float(row[0]), float(row[1])
        except ValueError:
            raise InputError(f"not a number in {','.join(row)!r}", path, i) from None
        if not np.isfinite(v) or v < 0:
            raise InputError(f"glue must be >= 0, got {row[1].strip()}", path, i)
        keys.append(k)
        vals.append(v)
    if not keys:
        raise InputError("no glue values", path)
    keys, vals = np.array(keys), np.array(vals)
    if header[0] == "element":
        idx = keys.astype(np.int64)
        bad = (idx != keys) | (idx < 0) | (idx >= len(s))
        if bad.any():
            raise InputError(f"element {keys[bad][0]:g} names no saliva element (0..{len(s) - 1})", path)
        glue = np.full(len(s), np.nan)
        glue[idx] = vals
        if np.isnan(glue).any():
            raise InputError(f"missing elements {np.flatnonzero(np.isnan(glue))[:5].tolist()}", path)
        return glue
    order = np.argsort(keys)
    return np.interp(s, keys[order], vals[order])


def glue_per_element(s, glue: float = GLUE, profile: str | None = None,
                     path: str | Path | None = None) -> np.ndarray:
    """Combine the three ways of giving glue: uniform ``glue``, then a ``profile``, or a file."""
    s = np.asarray(s, dtype=np.float64)
    if not np.isfinite(glue) or glue < 0:
        raise InputError(f"glue must be >= 0, got {glue}")
    if path is not None:
        return read_glue_file(path, s)
    if profile:
        return parse_glue_profile(profile, s, base=glue)
    return np.full(len(s), float(glue))


# --------------------------------------------------------------------------- the breaking state

class SalivaBreaking:
    """Per-step state of the saliva layer, used as the solver's element-force hook.

    Call :meth:`update` once per step with the current saliva-element node
    displacements and their freshly computed (unmodified) element forces; it
    returns the forces to assemble: the elastic forces of intact elements and
    the geometrically decaying stored forces of broken ones. Vectorised over
    elements.

    Parameters
    ----------
    X : (E, 8, 3) reference node positions of the saliva elements.
    glue : (E,) glue strength K_glue per element.
    params : SalivaParams
    """

    def __init__(self, X, glue, params: SalivaParams = SalivaParams()):
        X = np.asarray(X, dtype=np.float64)
        self.params = params
        self.glue = np.broadcast_to(np.asarray(glue, dtype=np.float64), (len(X),)).copy()
        self.dNdX = hex_centre_gradients(X)
        self.axis = element_frames(X)[:, 1]
        self.broken = np.zeros(len(X), dtype=bool)
        self.stored = np.zeros((len(X), 8, 3))
        self.stretch = np.ones(len(X))
        self.breaking = np.full(len(X), 1.0)

    def breaking_points(self, t: float) -> np.ndarray:
        """Z per element at time ``t``."""
        p = self.params
        return breaking_point(moisture(t, p.initial_moisture, p.evaporation), p.critical_moisture, self.glue)

    def update(self, t: float, u, forces):
        """Advance the state to time ``t`` and return the forces to assemble.

        Parameters
        ----------
        t : float
            Simulated time (s).
        u : (E, 8, 3) current node displacements of the saliva elements.
        forces : (E, 8, 3) unmodified internal element forces at ``u``.

        Returns
        -------
        (E, 8, 3) modified forces (a new array).
        """
        Q = stretch_across(deformation_gradient(u, self.dNdX), self.axis)
        Z = self.breaking_points(t)
        self.stretch, self.breaking = Q, Z
        # Re-bond where the lips are back in contact.
        self.broken &= Q > 1.0
        newly = (~self.broken) & (Q >= Z)
        out = np.array(forces, dtype=np.float64, copy=True)
        self.stored[newly] = out[newly]
        self.stored[self.broken] *= self.params.decay
        self.broken |= newly
        out[self.broken] = self.stored[self.broken]
        return out

    def state(self) -> dict:
        """Arrays needed to resume: broken flags and stored forces."""
        return {"broken": self.broken.copy(), "stored": self.stored.copy()}

    def set_state(self, state: dict) -> None:
        self.broken = np.asarray(state["broken"], dtype=bool).copy()
        self.stored = np.asarray(state["stored"], dtype=np.float64).copy()
