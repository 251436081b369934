"""Find muscle activations that produce target lip dimensions (bounded least squares).

This is how postures are authored from measurable lip shapes rather than
guessed numbers: give the lip dimensions of a viseme (as in
``data/visemes/targets.csv``) and get the activations of the speech functions
(Edge & Maddock 2001, Table 1) that produce them on the rig.

With :math:`\\mathbf x` the free activations (left/right pairs tied when
``symmetric``), :math:`m_j(\\mathbf x)` the measured dimensions
(:class:`visemeface.muscles.measure.LipGauge`) and :math:`t_j` the targets,

.. math::
    \\min_{\\ell \\le \\mathbf x \\le \\mathbf u}\\;
    \\sum_j w_j^2 \\left(m_j(\\mathbf x) - t_j\\right)^2 + \\lambda \\lVert \\mathbf x \\rVert^2

solved by :func:`scipy.optimize.least_squares` (trust-region reflective,
bounds = the muscles' ranges). The measures are linear in the muscle
activations except through the jaw rotation and the mouth-width norm, so a few
iterations converge. The small ridge term :math:`\\lambda` picks the least
effort among activations that fit equally well.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence

import numpy as np
import pandas as pd
from scipy.optimize import least_squares

from visemeface.errors import InputError, close_matches
from visemeface.muscles import functions as mf
from visemeface.muscles.measure import LipGauge
from visemeface.muscles.rig import SPEECH_FUNCTIONS

__all__ = ["fit_activations", "SPEECH_FUNCTIONS", "FIT_DIMENSIONS"]

#: Dimensions a target may name (relative units: change from rest / rest mouth width).
FIT_DIMENSIONS = ("mouth_width", "opening_height", "protrusion", "upper_lip_raise", "lower_lip_drop",
                  "corner_height", "corner_height_left", "corner_height_right", "corner_depth", "chin_drop")


class _SubsetPoser:
    """Poses only the vertices a :class:`LipGauge` reads (fast inner loop of the fit)."""

    def __init__(self, rig, indices):
        self.rest = rig.rest[indices]
        self.bases = rig.bases[:, indices].reshape(len(rig.muscles), -1)
        self.jaw_w = rig.jaw_weight[indices]
        self.joints = rig.jaw_joints
        self.max_angle = rig.max_jaw_angle

    def __call__(self, a: np.ndarray) -> np.ndarray:
        p = self.rest + (a[:-1] @ self.bases).reshape(-1, 3)
        if a[-1] != 0.0:
            p = p + mf.jaw_rotation_displacement(self.rest, *self.joints, a[-1] * self.max_angle, self.jaw_w)
        return p


def _groups(rig, functions: Sequence[str], symmetric: bool) -> list[list[int]]:
    for f in functions:
        if f not in rig.index:
            raise InputError(f"unknown muscle {f!r}" + close_matches(f, rig.names))
    groups: dict[str, list[int]] = {}
    for f in functions:
        key = f
        if symmetric and (f.endswith("_left") or f.endswith("_right")):
            key = f.rsplit("_", 1)[0]
        groups.setdefault(key, []).append(rig.index[f])
    return list(groups.values())


def fit_activations(rig, targets: Mapping[str, float], functions: Sequence[str] = SPEECH_FUNCTIONS,
                    symmetric: bool = True, weights: Mapping[str, float] | None = None,
                    regularization: float = 1e-4, base: Mapping[str, float] | None = None,
                    units: str = "relative") -> pd.Series:
    """Activations of ``functions`` whose pose best matches ``targets``.

    Parameters
    ----------
    rig : MuscleRig
    targets : mapping
        Dimension name (:data:`FIT_DIMENSIONS`) -> target value. With
        ``units="relative"`` (the viseme table's units) a value is the change
        from rest in fractions of the rest mouth width; with ``units="metres"``
        ``mouth_width`` and ``opening_height`` are absolute and the rest are
        changes from rest, as :func:`~visemeface.muscles.measure.lip_dimensions`
        reports them.
    functions : sequence of str
        Rig functions free to vary (default: Edge & Maddock's (2001) twelve speech functions).
    symmetric : bool
        Tie each ``_left``/``_right`` pair to one value.
    weights : mapping, optional
        Per-dimension weight (default 1).
    regularization : float
        Ridge :math:`\\lambda` on the free activations.
    base : mapping, optional
        Fixed activations of the other functions (e.g. an emotion) held during the fit.

    Returns
    -------
    pandas.Series
        One value per ``rig.names`` (free functions fitted, others from ``base``
        or 0). ``attrs["achieved"]`` holds the dimensions reached (same units as
        ``targets``), ``attrs["cost"]`` the final objective, ``attrs["success"]``.

    Examples
    --------
    >>> from visemeface.muscles.rig import default_rig
    >>> a = fit_activations(default_rig(), {"opening_height": 0.2, "mouth_width": 0.0})
    >>> abs(a.attrs["achieved"]["opening_height"] - 0.2) < 0.01
    True
    """
    if units not in ("relative", "metres"):
        raise InputError(f"units must be 'relative' or 'metres', got {units!r}")
    targets = dict(targets)
    if not targets:
        raise InputError("no target dimensions given")
    for name, value in targets.items():
        if name not in FIT_DIMENSIONS:
            raise InputError(f"unknown lip dimension {name!r}" + close_matches(name, FIT_DIMENSIONS))
        if not np.isfinite(float(value)):
            raise InputError(f"target {name!r} is {value} (must be finite)")
    weights = dict(weights or {})
    for name in weights:
        if name not in targets:
            raise InputError(f"weight given for {name!r}, which is not a target" + close_matches(name, targets))
    gauge = LipGauge(rig.face)
    poser = _SubsetPoser(rig, gauge.indices)
    groups = _groups(rig, functions, symmetric)
    a0 = rig.activation_vector(base or {})
    lo = np.array([max(rig.ranges[g, 0].max(), -np.inf) for g in groups])
    hi = np.array([rig.ranges[g, 1].min() for g in groups])
    names = list(targets)
    t = np.array([float(targets[n]) for n in names])
    w = np.array([float(weights.get(n, 1.0)) for n in names])
    W = gauge.frame.width
    scale = 1.0 if units == "relative" else W

    def measure(x):
        a = a0.copy()
        for g, v in zip(groups, x):
            a[g] = v
        p = poser(a)
        dims = gauge.changes_subset(p) if units == "relative" else gauge.measure_subset(p)
        return a, np.array([dims[n] for n in names])

    def residual(x):
        _, m = measure(x)
        return np.concatenate([w * (m - t) / scale, np.sqrt(regularization) * x])

    x0 = np.clip(np.zeros(len(groups)), lo, hi)
    x0 = np.where(x0 == lo, lo + 1e-3 * (hi - lo), x0)
    sol = least_squares(residual, x0, bounds=(lo, hi), method="trf", x_scale=1.0, xtol=1e-12,
                        ftol=1e-12, gtol=1e-12, max_nfev=200 * (len(groups) + 1))
    a, m = measure(sol.x)
    out = pd.Series(a, index=list(rig.names), name="activation")
    out.attrs["achieved"] = dict(zip(names, m.tolist()))
    out.attrs["cost"] = float(sol.cost)
    out.attrs["success"] = bool(sol.success)
    return out
