"""One muscle placed on a face: its kind, its landmarks' positions and its displacement field.

:func:`visemeface.muscles.rigfile.muscles_from` places the muscles of a rig file;
:class:`visemeface.muscles.rig.MuscleRig` samples their fields on the face's vertices.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from visemeface.muscles import functions as mf
from visemeface.muscles.sheet import parallel_muscle_displacement


@dataclass
class Muscle:
    """One muscle placed on a face (positions in metres, angles in radians)."""

    name: str
    kind: str  # "linear" | "sphincter" | "local" | "turn"
    side: str  # "left" | "right" | "centre"
    lip: str  # "upper" | "lower" | "both"
    range: tuple
    attachment: np.ndarray | None = None
    insertion: np.ndarray | None = None
    zone_angle: float = 0.0
    falloff_start: float = 0.0
    falloff_end: float = 0.0
    centre: np.ndarray | None = None
    semi_x: float = 0.0
    semi_y: float = 0.0
    k: float = 0.0
    protrusion: float = 0.0
    depth: float | None = None
    shield: float | None = None
    exclude: tuple = ()
    description: str = ""
    params: dict = field(default_factory=dict)
    radii: np.ndarray | None = None        # "local": Gaussian radii (m) per axis
    direction: np.ndarray | None = None    # "local": displacement (m) at the centre at activation 1
    mask: np.ndarray | None = None         # "local": (N,) bool, the vertices it may move
    symmetric: bool = False                # "local": plus its mirror image about the mouth's mid-plane
    direction_lower: np.ndarray | None = None   # "local": the lower lip's direction (lip-trimmed), if any
    inner: float | None = None             # "local": a lateral band from this distance (m) instead of a Gaussian
    close_to: np.ndarray | None = None     # "local": indices of the lid its margin closes onto (sized per column)
    overlap: float = 0.0                   # "local": how far past ``close_to``'s margin it closes (m)
    axis: np.ndarray | None = None         # "turn": rotation axis (world), angle in ``k`` (radians at 1);
    #                                        ``inner`` is then the radius of the part that turns (m)
    lids: np.ndarray | None = None         # "turn": (N,) each lid vertex's share of the turn (0: none)
    lid_radius: float | None = None        # "turn": how far from the forward line the lids follow (m)
    rigid: bool = False                    # "turn": the whole region turns, exactly (muscles/eyeballs.py)
    line: np.ndarray | None = None         # "turn": a point of the forward line (default ``centre``)

    def field(self, points: np.ndarray, frame: MouthFrame, direction: np.ndarray | None = None) -> np.ndarray:
        """Untrimmed displacement (N, 3) at activation 1 (a local function's ``direction`` may be replaced)."""
        if self.kind == "turn":
            return mf.turn_displacement(points, self.centre, self.axis, self.k, self.mask, self.inner,
                                        frame.axes[2], self.lids, self.lid_radius, self.line)
        if self.kind == "local":
            if self.mask is None or not self.mask.any():
                return np.zeros_like(np.asarray(points, dtype=float))
            d = self.direction if direction is None else direction
            out = mf.local_displacement(points, self.centre, self.radii, d, self.mask, frame.axes, self.inner)
            if self.symmetric:
                ex = frame.axes[0]
                c = self.centre - 2 * ((self.centre - frame.origin) @ ex) * ex
                out = out + mf.local_displacement(points, c, self.radii, d - 2 * (d @ ex) * ex, self.mask,
                                                  frame.axes)
            if self.close_to is not None and len(self.close_to):
                out = out * mf.closing_scale(points, out, self.close_to, frame.axes, self.overlap)[:, None]
            return out
        if self.kind == "linear" and self.params.get("fibres") == "parallel":
            # a sheet (the frontalis): the skin shortens evenly from the attachment, so no attachment fade
            return parallel_muscle_displacement(points, self.attachment, self.insertion, self.zone_angle,
                                                self.falloff_end, self.k)
        if self.kind == "linear":
            d = mf.linear_muscle_displacement(points, self.attachment, self.insertion, self.zone_angle,
                                              self.falloff_start, self.falloff_end, self.k)
            fade = self.params.get("attachment_fade")
            if fade:
                # skin over the muscle's fixed end stays: the pull fades in over ``fade`` of the muscle's length
                # from the attachment (a head with a scalp; Waters' falloff keeps 54 % there)
                r = np.linalg.norm(np.asarray(points, float) - self.attachment, axis=1)
                d = d * mf.smoothstep(0.0, fade * float(np.linalg.norm(self.insertion - self.attachment)), r)[:, None]
            return d
        return mf.sphincter_displacement(points, self.centre, frame.axes[0], frame.axes[1], self.semi_x,
                                         self.semi_y, self.k, self.protrusion, self.depth, self.shield)
