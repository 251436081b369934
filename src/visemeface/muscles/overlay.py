"""Pictures of the rig: displacement tints and muscle vectors drawn over a render.

Used by ``visemeface pose --show-muscles`` and ``scripts/muscle_sheet.py``.
Drawing is done with OpenCV on the renderer's RGB output, projecting 3-D
points with the renderer's own camera (:meth:`Renderer.project`).
"""

from __future__ import annotations

import dataclasses

import numpy as np

__all__ = ["tinted_face", "draw_muscles", "muscle_outline"]

TINT = np.array([0.95, 0.15, 0.1])


def tinted_face(face, magnitude: np.ndarray, scale: float | None = None):
    """A copy of ``face`` whose colours blend toward red where ``magnitude`` is large.

    ``magnitude`` (N,) is normalised by ``scale`` (default its maximum); the
    blend is :math:`c = (1 - t)\\,c_0 + t\\,c_{red}` with :math:`t = 0.85 \\min(m / s, 1)`.
    """
    base = face.vertex_colors().astype(float)
    m = np.asarray(magnitude, dtype=float)
    s = float(m.max()) if scale is None else float(scale)
    t = 0.85 * np.clip(m / s, 0.0, 1.0) if s > 0 else np.zeros_like(m)
    colors = (1 - t)[:, None] * base + t[:, None] * TINT
    return dataclasses.replace(face, colors=colors)


def muscle_outline(muscle, frame, n: int = 48) -> list[np.ndarray]:
    """3-D polylines outlining a muscle's zone: cone edges (linear), the ellipse (sphincter), or the
    ellipse of a local function's radii / a turning part's radius (tongue, lips, lids, gaze)."""
    if muscle.kind in ("local", "turn"):
        t = np.linspace(0, 2 * np.pi, n)
        ex, ey = frame.axes[0], frame.axes[1]
        if muscle.kind == "local":
            rx, ry = muscle.radii[0], muscle.radii[1]
        else:
            rx = ry = muscle.inner if muscle.inner is not None else 0.1 * frame.width
        return [muscle.centre + np.outer(rx * np.cos(t), ex) + np.outer(ry * np.sin(t), ey)]
    if muscle.kind == "sphincter":
        t = np.linspace(0, 2 * np.pi, n)
        ex, ey = frame.axes[0], frame.axes[1]
        ring = muscle.centre + np.outer(muscle.semi_x * np.cos(t), ex) + np.outer(muscle.semi_y * np.sin(t), ey)
        r = muscle.shield if muscle.shield is not None else muscle.semi_y
        disc = muscle.centre + np.outer(r * np.cos(t), ex) + np.outer(r * np.sin(t), ey)
        return [ring, disc]
    a, i = muscle.attachment, muscle.insertion
    axis = (i - a) / np.linalg.norm(i - a)
    # Two cone edges in the plane of the axis and the view direction's normal (the face's z).
    side = np.cross(axis, frame.axes[2])
    if np.linalg.norm(side) < 1e-9:
        side = frame.axes[0]
    side /= np.linalg.norm(side)
    lines = []
    for sgn in (-1, 1):
        d = np.cos(muscle.zone_angle) * axis + sgn * np.sin(muscle.zone_angle) * side
        lines.append(np.stack([a, a + muscle.falloff_end * d]))
    arc_t = np.linspace(-muscle.zone_angle, muscle.zone_angle, n)
    arc = a + muscle.falloff_end * (np.outer(np.cos(arc_t), axis) + np.outer(np.sin(arc_t), side))
    lines.append(arc)
    return lines


def draw_muscles(image: np.ndarray, renderer, rig, names=None, zones: bool = True,
                 label: bool = False) -> np.ndarray:
    """Draw attachment -> insertion arrows (and zone outlines) of ``names`` over ``image``.

    Attachments are drawn as filled dots (bone), insertions as arrow heads on
    the skin, pointing from insertion to attachment (the direction skin is
    pulled). Returns a new RGB uint8 image.
    """
    import cv2

    out = np.ascontiguousarray(image.copy())
    scale = max(1, round(out.shape[0] / 256))
    names = [m.name for m in rig.muscles] if names is None else list(names)
    colours = {"upper": (80, 200, 255), "lower": (255, 190, 60), "both": (120, 255, 140)}
    for name in names:
        if name == "jaw":
            jl, jr = rig.jaw_joints
            p = renderer.project(np.stack([jl, jr]))
            for q in p:
                cv2.circle(out, tuple(int(v) for v in q), 3 * scale, (255, 255, 255), -1, cv2.LINE_AA)
            cv2.line(out, tuple(int(v) for v in p[0]), tuple(int(v) for v in p[1]), (255, 255, 255),
                     scale, cv2.LINE_AA)
            continue
        m = rig.muscle(name)
        col = colours[m.lip]
        if zones:
            for line in muscle_outline(m, rig.frame):
                pts = renderer.project(line).round().astype(np.int32)
                cv2.polylines(out, [pts], False, tuple(int(c * 0.7) for c in col), scale, cv2.LINE_AA)
        if m.kind == "linear":
            a, i = renderer.project(np.stack([m.attachment, m.insertion]))
            cv2.circle(out, (int(a[0]), int(a[1])), 3 * scale, col, -1, cv2.LINE_AA)
            cv2.arrowedLine(out, (int(i[0]), int(i[1])), (int(a[0]), int(a[1])), col, scale, cv2.LINE_AA,
                            tipLength=0.15)
            anchor = i
        else:
            c = renderer.project(m.centre[None])[0]
            cv2.circle(out, (int(c[0]), int(c[1])), 3 * scale, col, -1, cv2.LINE_AA)
            anchor = c
        if label:
            cv2.putText(out, name, (int(anchor[0]) + 4, int(anchor[1])), cv2.FONT_HERSHEY_SIMPLEX,
                        0.3 * scale, col, 1, cv2.LINE_AA)
    return out
