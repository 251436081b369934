r"""ARKit weights played on our face with ARKit's meaning.

A take of ARKit weights (a Live Link Face capture, an ``--arkit`` export, an Audio2Face file) means what the
weights do on a rig made to ARKit's definition: ``jawOpen`` 1 opens the lips about 33 mm on the ICT Face
Model, and ``mouthClose`` closes the lips of an open jaw (alone it pushes the lower lip through the upper
one). Our face's own recipe shapes (``data/retarget/arkit.csv``) are sized to our rig, not to ARKit's, and
have no corrective ``mouthClose``: a take played on them opens the mouth less and never closes it.

So a take is carried to our face through the one thing both faces share, the muscles. For each frame:

1. the weights pose the reference ARKit rig (the ICT Face Model's own shapes,
   :func:`~visemeface.retarget.rigs.reference_rig`): :math:`t = \sum_k w_k S_k`,
2. the activations :math:`\mathbf a` of our muscles, placed on that rig's neutral, that pose it closest to
   :math:`t` are found: a bounded least squares over the muscles (:func:`~visemeface.retarget.fit.box_qp`)
   for each jaw activation of a grid, refined around the best (the jaw is the rig's one nonlinear function),
3. those activations are the frame's track, posed on *our* face (or any face of the same rig file).

This is the inverse of how the ARKit weights are made (:meth:`~visemeface.retarget.rigs.ClientRig.track_weights`
poses the same rig with our activations and fits its shapes), so a take we wrote comes back as the motion
it was made from, up to what the 53 shapes cannot hold. A frame costs a few dozen solves of 25 unknowns,
all from small matrices made once (the vertices enter once, as for the forward fit).

The fitted vertices are weighted: the lips' meeting line (the ``lip_seam_*`` regions, 78 of the rig's
11,000 measured vertices) weighs as much as all the others together (:data:`SEAM_SHARE`), because whether the
lips meet is what a viewer and a lip reader read of every mouth shape. That share is chosen, not measured:
counting every vertex once, the jaw's residual over the chin and cheeks outweighs the lips, and a bilabial
written as ``jawOpen`` 0.3 + ``mouthClose`` 0.3 plays 5.5 mm open (on the reference rig it is shut).
Played back, a take we wrote follows the motion it was made from (lip-gap correlation 0.97-0.996 on four
sentences) at 60-84 % of its opening: the 53 shapes and our 25 muscles span different motions, and each
of the two fits keeps only what the other can hold.
"""

from __future__ import annotations

import functools

import numpy as np

#: Jaw activations tried before the refinement (the range in this many even steps).
JAW_GRID = 24
#: Ridge of the muscle fit, relative to the mean squared size of a muscle's field, pulling towards rest:
#: two muscles that move the same vertices alike (a left and right pair at the midline) share the work
#: evenly instead of swinging, and a muscle that moves nothing measured (the eyes' turns) stays at 0.
RIDGE = 1e-4
#: The share of the fit's weight on the lips' meeting line (module docstring): a chosen constant, not a
#: measured one. With 0 (every vertex once) jawOpen 0.3 + mouthClose 0.3 leaves our lips 5.5 mm apart, with
#: 0.25 2.7 mm, with 0.5 shut; 0.75 shrinks the round trip's rounded vowels further (slope 0.53).
SEAM_SHARE = 0.5


class ReferenceFit:
    """The per-frame fit of the module docstring, for one rig file, its small matrices made once."""

    def __init__(self, rig_file=None):
        from visemeface.retarget.rigs import reference_rig

        ref = reference_rig()
        rig = ref.rig(rig_file)
        self.names, to_arkit, _ = ref.arkit_map()
        self.rig_names = list(rig.names)
        mask = ref.mask()                                   # the vertices the forward fit measures
        seam = np.zeros(len(mask), bool)
        seam[np.concatenate([ref.face.region("lip_seam_upper"), ref.face.region("lip_seam_lower")])] = True
        seam &= mask
        share = SEAM_SHARE / (1 - SEAM_SHARE) * (mask.sum() - seam.sum()) / max(seam.sum(), 1)
        cols = np.flatnonzero(np.repeat(mask, 3))
        w = np.repeat(np.sqrt(np.where(seam, share, 1.0)), 3)[cols]
        deltas = ref.shapes.deltas.reshape(len(ref.shapes.names), -1)[:, cols].astype(np.float64)
        D = (to_arkit > 0).astype(np.float64) @ deltas * w      # a split pair: both halves at ARKit's weight
        matrix = rig._matrix[:, cols].astype(np.float64) * w
        m = len(rig.names) - 1
        self.lo, hi = rig.ranges[:m, 0], rig.ranges[:m, 1]
        self.span = hi - self.lo
        S, J = matrix[:m] * self.span[:, None], matrix[m:m + len(rig._powers)]   # the jaw's series, not the eyes'
        base = self.lo @ matrix[:m]
        self.G = S @ S.T
        self.lam = RIDGE * np.trace(self.G) / m
        self.H = self.G + self.lam * np.eye(m)
        self.rest = -self.lo / self.span
        self.SD, self.SJ, self.Sb = S @ D.T, S @ J.T, S @ base
        self.DD, self.DJ, self.Db = D @ D.T, D @ J.T, D @ base
        self.JJ, self.Jb, self.bb = J @ J.T, J @ base, float(base @ base)
        self.powers, self.max_angle = rig._powers, float(rig.max_jaw_angle)
        self.jaw_range = tuple(float(x) for x in rig.ranges[m])
        self.norm = float(w @ w) / 3                              # the weighted number of vertices
        self._played: dict = {}

    def _solve(self, wk: np.ndarray, jaw: float, start=None) -> tuple[float, np.ndarray]:
        from visemeface.retarget.fit import box_qp

        p = (jaw * self.max_angle) ** self.powers
        sr = self.SD @ wk - self.Sb - self.SJ @ p
        rr = (wk @ self.DD @ wk - 2 * wk @ self.Db - 2 * wk @ self.DJ @ p + self.bb + 2 * p @ self.Jb
              + p @ self.JJ @ p)
        x = box_qp(self.H, sr + self.lam * self.rest, start)
        return float(x @ self.G @ x - 2 * x @ sr + rr), x

    def frame(self, weights: np.ndarray) -> tuple[np.ndarray, float]:
        """Activations (M+1,) in the rig's ``names`` order and the RMS residual (m) over the vertices of one frame's
        ARKit weights (52,) in :func:`~visemeface.retarget.rigs.arkit_names` order."""
        from scipy.optimize import minimize_scalar

        wk = np.asarray(weights, dtype=np.float64)
        # rest (jaw 0) is tried too: a frame at rest is posed at rest exactly, not the refinement's tolerance off it
        grid = np.linspace(*self.jaw_range, JAW_GRID + 1)
        grid = np.union1d(grid, [0.0]) if self.jaw_range[0] <= 0.0 <= self.jaw_range[1] else grid
        last = [None]                           # each solve starts from the last one's active set

        def error(jaw):
            e, last[0] = self._solve(wk, jaw, last[0])
            return e

        errors = [error(j) for j in grid]
        i = int(np.argmin(errors))
        a, b = grid[max(i - 1, 0)], grid[min(i + 1, len(grid) - 1)]
        best = minimize_scalar(error, bounds=(a, b), method="bounded", options={"xatol": 1e-4})
        jaw = float(best.x) if best.fun < errors[i] else float(grid[i])
        err, x = self._solve(wk, jaw, last[0])
        return np.append(self.lo + self.span * x, jaw), float(np.sqrt(max(err, 0.0) / self.norm))

    def frames(self, names, weights: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Activations (F, M+1) and residuals (F,) of weights (F, len(names)) under ARKit ``names``."""
        W = np.zeros((len(weights), len(self.names)))
        W[:, [self.names.index(n) for n in names]] = weights
        key = W.tobytes()
        if key not in self._played:             # a take converted into several outputs is fitted once
            out = [self.frame(w) for w in W]
            self._played = {key: (np.array([a for a, _ in out]).reshape(len(W), -1), np.array([r for _, r in out]))}
        A, R = self._played[key]
        return A.copy(), R.copy()


@functools.lru_cache(maxsize=2)
def reference_fit(rig_file=None) -> ReferenceFit:
    """The :class:`ReferenceFit` of ``rig_file``'s muscles (default the built-in rig), made once."""
    return ReferenceFit(rig_file)


def arkit_activations(rig, names, weights: np.ndarray) -> tuple[np.ndarray, np.ndarray] | None:
    """Activations (F, M+1) of ``rig`` and residuals (F,) (m) playing ARKit weights (F, len(names)) with ARKit's
    meaning (module docstring); ``None`` when ``rig`` is not of the built-in rig file's muscles."""
    fit = reference_fit()
    if list(rig.names) != fit.rig_names:
        return None
    return fit.frames(list(names), np.asarray(weights, dtype=np.float64))
