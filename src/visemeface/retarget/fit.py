r"""Per-frame least-squares fit of our face's motion onto a target vocabulary.

For a frame with displacement :math:`d` (the posed vertices minus rest, flattened) and the
vocabulary's shapes :math:`S_k` (rows of :math:`B`, only those the rig can make), the weights solve
the bounded problem

.. math::

    \min_{0 \le w \le 1} \; \lVert B^\top w - d \rVert^2 + \lambda \lVert w \rVert^2
        \; [+\; \mu (\mathbf 1^\top w - 1)^2 \text{ for a simplex vocabulary}]

with :math:`\lambda = \rho\,\bar g`, :math:`\mu = \sigma\,\bar g`, :math:`\bar g = \operatorname{tr}(BB^\top)/K`
(so both are relative to the shapes' mean squared size and the fit has no unit). With
:math:`H = BB^\top + \lambda I + \mu \mathbf 1 \mathbf 1^\top` and
:math:`c = Bd + \mu \mathbf 1`, the objective is :math:`w^\top H w - 2 c^\top w` + const, a
K-dimensional box-bounded quadratic problem (:func:`box_qp`, an active-set solve) per frame: the
vertices enter once, through :math:`Bd`.

The residual of a frame is the RMS over the vertices the rig moves of :math:`B^\top w - d`, in metres,
from :math:`\lVert B^\top w - d\rVert^2 = w^\top G w - 2 w^\top Bd + d^\top d`.
"""

from __future__ import annotations

import numpy as np

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


def box_qp(H: np.ndarray, c: np.ndarray, start: np.ndarray | None = None, lo: float = 0.0, hi: float = 1.0,
           max_iter: int = 500) -> np.ndarray:
    r"""The minimiser of :math:`\tfrac12 w^\top H w - c^\top w` over :math:`lo \le w \le hi` (``H`` positive
    definite), by a primal active-set method.

    Each step solves the free variables exactly with the others held at their bounds (a Cholesky solve of
    at most K x K); a step that would leave the box stops at the first bound it meets and holds that
    variable there; at a feasible stationary point a held variable whose gradient pulls it inside is freed.
    For a strictly convex problem the solution and its active set are unique, so ``start`` (e.g. the
    previous frame's weights) only changes how many steps it takes, not the answer. K = 53 takes a few
    tenths of a millisecond where BVLS over the K x K factor took several.
    """
    from scipy.linalg import cho_factor, cho_solve

    k = len(c)
    w = np.clip(np.zeros(k) if start is None or len(start) != k else np.asarray(start, float), lo, hi)
    state = np.where(w <= lo, -1, np.where(w >= hi, 1, 0))
    tol = 1e-12 * max(1.0, float(np.abs(np.diag(H)).max()))
    for _ in range(max_iter):
        free = state == 0
        held = ~free
        w[state == -1], w[state == 1] = lo, hi
        if free.any():
            rhs = c[free] - H[np.ix_(free, held)] @ w[held]
            x = cho_solve(cho_factor(H[np.ix_(free, free)]), rhs)
            cur = w[free]
            step = x - cur
            out = (x < lo) | (x > hi)
            if out.any():
                with np.errstate(divide="ignore", invalid="ignore"):
                    alpha = np.where(step < 0, (lo - cur) / step, np.where(step > 0, (hi - cur) / step, np.inf))
                j = int(np.argmin(np.where(out | (alpha < 1), alpha, np.inf)))
                a = float(np.clip(alpha[j], 0.0, 1.0))
                w[free] = cur + a * step
                fi = np.flatnonzero(free)[j]
                state[fi] = -1 if step[j] < 0 else 1
                continue
            w[free] = x
        g = H @ w - c
        bad = np.where(state == -1, -g, np.where(state == 1, g, 0.0))
        j = int(np.argmax(bad))
        if bad[j] <= tol:
            return w
        state[j] = 0
    return w


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
    r"""The fit of the module docstring for one vocabulary, factored once.

    Parameters
    ----------
    vocab : :class:`~visemeface.retarget.recipes.Vocabulary`
    mask : (N,) bool, optional
        The vertices fitted and over which residuals are averaged (default: all); with
        :func:`moving_vertices` the others (which no shape moves) only cost time.
    correctives : dict, optional
        ``{corrective: base}`` shape names: the corrective's weight never exceeds its base's, as ARKit's
        ``mouthClose`` (which closes the lips of an open jaw) is used only with ``jawOpen``. The fit's
        unknowns are then :math:`p = w_{base} - w_{corr} \ge 0` and :math:`q = w_{corr} \ge 0` with the
        shapes :math:`S_{base}` and :math:`S_{base} + S_{corr}` (the jaw opened with the lips kept shut),
        so the bound holds by construction and the problem stays a box-bounded least squares.
    """

    def __init__(self, vocab, mask: np.ndarray | None = None, correctives: dict | None = None):
        self.vocab = vocab
        self.k = len(vocab.names)
        self.made = np.flatnonzero(vocab.made)
        n = vocab.shapes.shape[1]
        self.mask = np.ones(n, bool) if mask is None else np.asarray(mask, bool)
        b = vocab.shapes[self.made][:, self.mask].reshape(len(self.made), -1).astype(np.float64)
        # corrective pairs, as positions among the fitted (made) shapes
        pos = {int(k): i for i, k in enumerate(self.made)}
        self.pairs = []
        for corr, base in (correctives or {}).items():
            c, bi = vocab.names.index(corr), vocab.names.index(base)
            if c in pos and bi in pos:
                self.pairs.append((pos[c], pos[bi]))
                b[pos[c]] = b[pos[c]] + b[pos[bi]]
        self.B = b
        self.G = b @ b.T
        g = np.trace(self.G) / max(len(self.made), 1)
        self.lam = RIDGE * g
        self.mu = SUM_WEIGHT * g if vocab.simplex else 0.0
        ones = np.ones(len(self.made))
        self.H = self.G + self.lam * np.eye(len(self.made)) + self.mu * np.outer(ones, ones)
        self._last = None
        self.n_measured = int(np.count_nonzero(self.mask))

    def frame(self, displacement: np.ndarray) -> tuple[np.ndarray, float]:
        """Weights (K,) and residual RMS (m) of one frame's displacement (N, 3)."""
        d = np.asarray(displacement, dtype=np.float64)[self.mask].reshape(-1)
        return self.solve(self.B @ d, float(d @ d))

    def solve(self, bd: np.ndarray, dd: float) -> tuple[np.ndarray, float]:
        """Weights (K,) and residual RMS (m) from :math:`Bd` and :math:`d^\top d` alone (a caller that poses
        the frame from activations forms both without the vertices: :meth:`ClientRig.track_weights`)."""
        if len(self.made):
            wm = box_qp(self.H, bd + self.mu, self._last)
            self._last = wm
        else:
            wm = np.zeros(0)
        sq = float(wm @ self.G @ wm - 2.0 * wm @ bd + dd)
        for c, base in self.pairs:          # back from (p, q) to the shapes' weights: w_base = p + q
            wm[base] = min(wm[base] + wm[c], 1.0)
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
        return np.einsum("fk,knc->fnc", w, self.vocab.shapes.astype(np.float64))
