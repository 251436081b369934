r"""Rigid eyeballs: each eyeball's "turn" functions as one exact rotation, in the rig's one product.

A face whose eyeballs are spheres (the ICT head; rig-file table ``[gaze] rigid = true``) turns each whole
eyeball about its own centre. Its turns (horizontal and vertical gaze) compose as Listing's law has it: one
rotation from the primary position about an axis in the frontal plane (Helmholtz 1867; Tweed & Vilis 1990),
:math:`\boldsymbol\omega = \sum_i \theta_i \hat{\mathbf e}_i` with :math:`\theta_i` each turn's activation
times its angle at 1. By Rodrigues' formula

.. math:: \Delta\mathbf r = f(\theta)\,\boldsymbol\omega \times \mathbf r
          + g(\theta)\,\boldsymbol\omega \times (\boldsymbol\omega \times \mathbf r),
   \qquad \theta = |\boldsymbol\omega|,\ f = \frac{\sin\theta}{\theta},\ g = \frac{1 - \cos\theta}{\theta^2},

so the turns' own bases (:math:`\theta_i\,\hat{\mathbf e}_i \times \mathbf r` at activation 1, the
linearised turn of :func:`~visemeface.muscles.functions.turn_displacement`) are scaled by :math:`f`, and one
row per pair :math:`i \le j`, :math:`\hat{\mathbf e}_i \times (\hat{\mathbf e}_j \times \mathbf r)`
(symmetrised for :math:`i \ne j`), is added with the coefficient :math:`\theta_i \theta_j g`. The pose stays
one product, exact on the eyeball for any gaze; a lid vertex that turns by a share :math:`w_i` of each angle
gets :math:`w_i` of the bases and :math:`w_i w_j` of the pair rows (exact to third order in the angle).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from visemeface.muscles import functions as mf


@dataclass(frozen=True)
class EyeballTurns:
    r"""One eyeball's rigid turns: their function indices, unit axes (n, 3), angles at 1 (n,), the pairs
    :math:`i \le j` (two index arrays) and the pairs' rows (pairs, N, 3)."""

    indices: np.ndarray
    axes: np.ndarray
    angles: np.ndarray
    pairs: tuple
    rows: np.ndarray


def eyeball_turns(rest: np.ndarray, muscles, view) -> list[EyeballTurns]:
    """The rigid "turn" functions of ``muscles`` grouped by eyeball (the vertices they turn), with the pair
    rows at the rest positions ``rest`` (N, 3); ``view`` is the face's forward axis (for the lids' fade)."""
    groups: dict = {}
    for i, m in enumerate(muscles):
        if m.kind == "turn" and m.rigid and m.mask.any():
            groups.setdefault(m.mask.tobytes(), []).append(i)
    out = []
    for idx in groups.values():
        ms = [muscles[i] for i in idx]
        axes = np.array([m.axis / np.linalg.norm(m.axis) for m in ms])
        w = [mf.turn_weight(rest, m.centre if m.line is None else m.line, m.mask, None, view, m.lids, m.lid_radius)
             for m in ms]
        r = rest - ms[0].centre
        pi, pj = np.triu_indices(len(idx))
        rows = []
        for a, b in zip(pi, pj):
            q = np.cross(axes[a], np.cross(axes[b], r))
            if a != b:
                q = q + np.cross(axes[b], np.cross(axes[a], r))
            rows.append((w[a] * w[b])[:, None] * q)
        out.append(EyeballTurns(np.array(idx), axes, np.array([m.k for m in ms]), (pi, pj), np.array(rows)))
    return out


def eyeball_coefficients(activations: np.ndarray, eyes: list[EyeballTurns]) -> tuple[np.ndarray, list]:
    """The functions' coefficients (..., M) with each eyeball's turns scaled by :math:`f(\theta)`, and each
    eyeball's pair coefficients (..., pairs) :math:`\theta_i \theta_j g(\theta)`."""
    a = np.asarray(activations, dtype=np.float64)
    if eyes:
        a = a.copy()                        # scaled in place below, the caller's array left as it is
    pairs = []
    for eye in eyes:
        t = a[..., eye.indices] * eye.angles
        size = np.linalg.norm(t @ eye.axes, axis=-1, keepdims=True)
        a[..., eye.indices] = a[..., eye.indices] * np.sinc(size / np.pi)              # sin(x) / x
        pairs.append(t[..., eye.pairs[0]] * t[..., eye.pairs[1]] * 0.5 * np.sinc(size / (2 * np.pi)) ** 2)
    return a, pairs
