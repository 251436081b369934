"""The simulation's whole state: one object that checkpoints and restores exactly.

The central-difference integrator (:mod:`visemeface.physics.integrator`) needs
``u(tⁿ)`` and ``u(tⁿ⁻¹)`` (not a velocity: rebuilding ``u(tⁿ⁻¹)`` from a
velocity by a Taylor step is off by round-off and more), the step count ``n``
(time ``tⁿ = n Δt`` from one integer, so a resumed run sees the very same
floating-point times) and the saliva film's per-slab state
(:class:`~visemeface.physics.film.SalivaFilm`). A :class:`SimState` saved after
a frame and restored continues bit for bit as if never stopped.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

#: The film's state arrays (:meth:`SalivaFilm.initial_state`) and their dtypes.
SALIVA_KEYS = {"broken": np.bool_, "dry": np.bool_, "stored": np.float64, "stretch": np.float64, "flow": np.float64,
               "damage": np.float64}


@dataclass
class SimState:
    """u, u_prev, step (t = step · dt) and the saliva film's state.

    Attributes
    ----------
    u, u_prev : (n, 3) float64
        Node displacements at steps ``step`` and ``step − 1``.
    step : int
    dt : float
    saliva : dict of arrays
        ``broken``, ``dry``, ``stored`` (E, 8, 3), ``stretch``, ``flow``, ``damage`` per film slab.
    fine_prev : (k, 3) float64 or None
        With a multi-rate step (:mod:`visemeface.physics.integrator`): the film nodes' displacement one
        substep before ``step``; None for a single-rate run.
    """

    u: np.ndarray
    u_prev: np.ndarray
    step: int
    dt: float
    saliva: dict = field(default_factory=dict)
    fine_prev: np.ndarray | None = None

    @property
    def t(self) -> float:
        return self.step * self.dt

    @property
    def velocity(self) -> np.ndarray:
        """Backward-difference velocity (u − u_prev) / dt."""
        return (self.u - self.u_prev) / self.dt

    def copy(self) -> SimState:
        return SimState(self.u.copy(), self.u_prev.copy(), int(self.step), float(self.dt),
                        {k: v.copy() for k, v in self.saliva.items()},
                        None if self.fine_prev is None else self.fine_prev.copy())

    def to_dict(self) -> dict:
        """Plain arrays and numbers (``np.savez`` without pickle keeps every bit)."""
        out = {"u": self.u.copy(), "u_prev": self.u_prev.copy(), "step": int(self.step), "dt": float(self.dt)}
        out.update({f"saliva_{k}": v.copy() for k, v in self.saliva.items()})
        if self.fine_prev is not None:
            out["fine_prev"] = self.fine_prev.copy()
        return out

    @classmethod
    def from_dict(cls, d: dict) -> SimState:
        saliva = {k: np.array(d[f"saliva_{k}"], dtype=t) for k, t in SALIVA_KEYS.items() if f"saliva_{k}" in d}
        if "stretch" in saliva and "flow" not in saliva:      # a checkpoint from before the film could flow
            saliva["flow"] = np.zeros_like(saliva["stretch"])
        if "stretch" in saliva and "damage" not in saliva:    # ... or soften by the cohesive law
            saliva["damage"] = np.zeros_like(saliva["stretch"])
        fine = np.array(d["fine_prev"], dtype=np.float64) if "fine_prev" in d else None
        return cls(np.array(d["u"], dtype=np.float64), np.array(d["u_prev"], dtype=np.float64),
                   int(d["step"]), float(d["dt"]), saliva, fine)
