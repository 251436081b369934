"""The rig as morph targets: what glTF (and any blend-shape client) plays.

Muscle displacements are linear in the activation (Waters functions are
evaluated on rest positions), so muscle ``m``'s target is its basis field
:math:`B_m` = displacement at activation 1, and its morph weight is its
activation. The jaw is a rotation weighted per vertex, which is not linear in
its activation and not a single rigid joint either (linear-blend skinning of
one joint would shrink the arc: :math:`(1-w)x + wR(\\theta)x \\ne R(w\\theta)x`).
It is exported as ``jaw_samples`` *sampled morphs*: the jaw displacement at
openings :math:`a_k = k\\,u/K` (``u`` the jaw's range maximum; a negative
range, a clenching jaw, gets samples at the same spacing), played with the hat
weights of :func:`jaw_sample_weights`; this plays identically in every viewer
(Blender shape keys, three.js morph targets) and deviates from the rig only by
the chord sag of one sample interval.
"""

from __future__ import annotations

import numpy as np

#: Jaw openings exported as morph targets (fractions of the jaw's range).
JAW_SAMPLES = 8


def jaw_sample_weights(values: np.ndarray, samples: np.ndarray) -> np.ndarray:
    r"""Morph weights that play a nonlinear motion sampled at a few values.

    A motion :math:`D(a)` with :math:`D(0) = 0`, known at nonzero samples
    :math:`a_k`, is exported as one morph target :math:`D(a_k)` per sample. With
    the nodes :math:`s_0 < s_1 < \dots` = the samples and 0, a value
    :math:`a \in [s_{i-1}, s_i]` gets the piecewise-linear "hat" weights

    .. math:: w_{i-1} = \frac{s_i - a}{s_i - s_{i-1}}, \quad
              w_i = \frac{a - s_{i-1}}{s_i - s_{i-1}}, \quad w_j = 0 \text{ otherwise}

    (the weight of the node 0 is dropped: its target is zero), so
    :math:`\sum_k w_k D(a_k)` equals :math:`D(a)` exactly at the samples and
    interpolates it linearly between them (the chord of the jaw's arc).
    Values beyond the outer samples extrapolate along the outer chords.

    Parameters
    ----------
    values : (F,) array
        The motion's parameter per frame (e.g. jaw activation).
    samples : (K,) array
        Increasing, nonzero sample values (may be negative).

    Returns
    -------
    (F, K) float array
    """
    a = np.asarray(values, dtype=np.float64).reshape(-1)
    smp = np.asarray(samples, dtype=np.float64).reshape(-1)
    if len(smp) == 0 or np.any(np.diff(smp) <= 0) or np.any(smp == 0):
        raise ValueError("samples must be nonzero and increasing")
    zero = int(np.searchsorted(smp, 0.0))
    nodes = np.insert(smp, zero, 0.0)
    k = np.clip(np.searchsorted(nodes, a, side="right"), 1, len(nodes) - 1)  # a in [s[k-1], s[k]]
    frac = (a - nodes[k - 1]) / (nodes[k] - nodes[k - 1])
    w = np.zeros((len(a), len(nodes)))
    rows = np.arange(len(a))
    w[rows, k - 1] = 1.0 - frac
    w[rows, k] = frac
    return np.delete(w, zero, axis=1)


def rig_morph_targets(rig, jaw_samples: int = JAW_SAMPLES):
    """Morph targets for the rig: one per linear function, a few for the jaw (module docstring).

    Returns
    -------
    targets : (M - 1 + K, N, 3) float
    names : list of str
        Function names, then ``jaw@<opening>``.
    samples : (K,) float
        The jaw openings :math:`a_k`.
    """
    names = list(rig.names)
    j = names.index("jaw")
    if j != len(names) - 1:
        raise ValueError("the rig's last function must be the jaw")
    lo, hi = np.asarray(rig.ranges, dtype=np.float64).reshape(len(names), 2)[j]
    if not lo <= 0 < hi:
        raise ValueError(f"jaw range must contain 0 and a positive opening, got [{lo}, {hi}]")
    step = hi / jaw_samples
    n_neg = int(np.ceil(-lo / step - 1e-9)) if lo < 0 else 0  # a closing jaw (lo < 0) too
    samples = np.concatenate([lo * np.arange(n_neg, 0, -1) / max(n_neg, 1),
                              step * np.arange(1, jaw_samples + 1)])
    targets = list(np.asarray(rig.bases, dtype=np.float64)) + [
        np.asarray(rig.jaw_displacement(s), dtype=np.float64) for s in samples]
    tnames = [n for n in names if n != "jaw"] + [f"jaw@{s:.4g}" for s in samples]
    return np.stack(targets), tnames, samples


def morph_weights(a: np.ndarray, rig, samples: np.ndarray) -> np.ndarray:
    """(F, M - 1 + K) morph weights for activations ``a`` (F, M) (see :func:`rig_morph_targets`)."""
    j = list(rig.names).index("jaw")
    return np.hstack([np.delete(a, j, axis=1), jaw_sample_weights(a[:, j], samples)])
