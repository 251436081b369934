r"""Per-frame least-squares fit of our face's motion onto a target vocabulary.

For a frame with displacement :math:`d` (the posed vertices minus rest, flattened) and the
vocabulary's shapes :math:`S_k` (rows of :math:`B`, only those the rig can make), the weights solve
the bounded problem

.. math::

    \min_{0 \le w \le 1} \; \lVert B^\top w - d \rVert^2 + \lambda \lVert w \rVert^2
        \; [+\; \mu (\mathbf 1^\top w - 1)^2 \text{ for a simplex vocabulary}]

with :math:`\lambda = \rho\,\bar g`, :math:`\mu = \sigma\,\bar g`, :math:`\bar g = \operatorname{tr}(BB^\top)/K`
(so both are relative to the shapes' mean squared size and the fit has no unit). With
:math:`H = BB^\top + \lambda I + \mu \mathbf 1 \mathbf 1^\top = R^\top R` (Cholesky) and
:math:`c = Bd + \mu \mathbf 1`, the objective is :math:`\lVert Rw - R^{-\top}c\rVert^2` + const, a
K-dimensional bounded least-squares problem (:func:`scipy.optimize.lsq_linear`, BVLS) per frame: the
vertices enter once, through :math:`Bd`.

The residual of a frame is the RMS over the vertices the rig moves of :math:`B^\top w - d`, in metres,
from :math:`\lVert B^\top w - d\rVert^2 = w^\top G w - 2 w^\top Bd + d^\top d`.
"""

from __future__ import annotations

import numpy as np
from scipy.linalg import cho_factor, solve_triangular
from scipy.optimize import lsq_linear

#: Ridge ρ, relative to the mean squared shape size. The vocabularies hold shapes that are nearly
#: collinear (mouthPressLeft + mouthPressRight = the whole presser; a dimple shares the stretcher's
#: risorius): without a ridge the Gram matrix is near-singular and the split between such twins swings
#: from frame to frame; 1e-4 picks the even split and changes a weight by ~1e-4, far below what a
#: client can see.
RIDGE = 1e-4
#: Weight σ of the partition-of-one row of a simplex vocabulary (visemes): 1e3 times the mean squared
#: shape size makes the weights add up to 1 within ~1e-3 while the fit stays one least-squares problem
#: (the rest pose ``sil`` takes what the others leave).
SUM_WEIGHT = 1e3


def moving_vertices(rig) -> np.ndarray:
    """Boolean mask (N,) of the face-surface vertices any rig function moves (where residuals are measured).

    The mouth's interior (the ``mouth_cavity`` region: teeth, gums, tongue, cavity walls) is left out: the
    clients' vocabularies describe the face's surface (ARKit's one tongue shape, tongueOut, cannot hold the
    tongue's speech positions), and fitting the tongue would bend the lip weights to explain it.
    """
    moving = (np.abs(rig.bases).sum(axis=(0, 2)) > 0) | (np.asarray(rig.jaw_weight) > 0)
    moving[rig.face.regions.get("mouth_cavity", np.empty(0, np.int64))] = False
    return moving


class ShapeFit:
    """The fit of the module docstring for one vocabulary, factored once.

    Parameters
    ----------
    vocab : :class:`~visemeface.retarget.recipes.Vocabulary`
    mask : (N,) bool, optional
        The vertices fitted and over which residuals are averaged (default: all); with
        :func:`moving_vertices` the others (which no shape moves) only cost time.
    """

    def __init__(self, vocab, mask: np.ndarray | None = None):
        self.vocab = vocab
        self.k = len(vocab.names)
        self.made = np.flatnonzero(vocab.made)
        n = vocab.shapes.shape[1]
        self.mask = np.ones(n, bool) if mask is None else np.asarray(mask, bool)
        b = vocab.shapes[self.made][:, self.mask].reshape(len(self.made), -1)
        self.B = b
        self.G = b @ b.T
        g = np.trace(self.G) / max(len(self.made), 1)
        self.lam = RIDGE * g
        self.mu = SUM_WEIGHT * g if vocab.simplex else 0.0
        ones = np.ones(len(self.made))
        H = self.G + self.lam * np.eye(len(self.made)) + self.mu * np.outer(ones, ones)
        self.R, _ = cho_factor(H, lower=False)
        self.R = np.triu(self.R)
        self.n_measured = int(np.count_nonzero(self.mask))

    def frame(self, displacement: np.ndarray) -> tuple[np.ndarray, float]:
        """Weights (K,) and residual RMS (m) of one frame's displacement (N, 3)."""
        d = np.asarray(displacement, dtype=np.float64)[self.mask].reshape(-1)
        bd = self.B @ d
        c = bd + self.mu
        rhs = solve_triangular(self.R, c, trans="T", lower=False)
        wm = lsq_linear(self.R, rhs, bounds=(0.0, 1.0), method="bvls").x if len(self.made) else np.zeros(0)
        wm = np.clip(wm, 0.0, 1.0)  # BVLS may step a rounding error past a bound
        sq = float(wm @ self.G @ wm - 2.0 * wm @ bd + d @ d)
        w = np.zeros(self.k)
        w[self.made] = wm
        return w, float(np.sqrt(max(sq, 0.0) / self.n_measured))

    def frames(self, displacements: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Weights (F, K) and residuals (F,) of displacements (F, N, 3)."""
        out = [self.frame(d) for d in displacements]
        return np.array([w for w, _ in out]).reshape(len(out), self.k), np.array([r for _, r in out])

    def play(self, weights: np.ndarray) -> np.ndarray:
        """Displacements (F, N, 3) the weights (F, K) give in a blend-shape client: :math:`\\sum_k w_k S_k`."""
        w = np.atleast_2d(weights)
        return np.einsum("fk,knc->fnc", w, self.vocab.shapes)
