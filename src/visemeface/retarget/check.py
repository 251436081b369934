"""How the weights look on the character: lip gap and mouth width per sound class, on the rig played back.

A client plays the weights as :math:`x = X_0 + \\sum_k w_k S_k`; this module plays them the same way on a
:class:`~visemeface.retarget.rigs.ClientRig` and measures, in millimetres on the character:

- the **inner-lip gap** at the centre (upper minus lower lip seam height at the mouth's centre line; negative:
  the lower lip has gone through the upper one) and its minimum over the seam's pairs across the mouth,
- the **mouth width** (corner to corner) relative to the rest width,

per frame, and summarised per class of phone at each phone's middle frame: bilabials (/p b m/) must close,
open vowels open, rounded vowels (/uw w ow/) narrow the mouth.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

#: Sound classes the check reports (DECtalk symbols).
CLASSES = {
    "bilabial": ("p", "b", "m"),
    "open vowel": ("aa", "ae", "ah", "ao", "aw", "ay", "eh"),
    "rounded": ("uw", "w", "ow"),
}


@dataclass
class LipMeasures:
    """Per-frame measures (mm, and the width ratio) on a played-back rig."""

    gap: np.ndarray          # (F,) centre inner-lip gap
    min_gap: np.ndarray      # (F,) smallest gap over the seam's pairs
    width: np.ndarray        # (F,) mouth width / rest width


def seam_pairs(face) -> tuple[np.ndarray, np.ndarray]:
    """Upper and lower seam vertices paired by their lateral position (each upper vertex with the lower one
    nearest in x), inside the middle 80 % of the mouth."""
    up, lo = face.region("lip_seam_upper"), face.region("lip_seam_lower")
    x = face.vertices[:, 0]
    cl, cr = face.landmark_position("mouth_corner_left"), face.landmark_position("mouth_corner_right")
    half = 0.4 * abs(cl[0] - cr[0])
    centre = 0.5 * (cl[0] + cr[0])
    up = up[np.abs(x[up] - centre) <= half]
    nearest = lo[np.argmin(np.abs(x[lo][None, :] - x[up][:, None]), axis=1)]
    return up, nearest


def measure(face, displacements: np.ndarray) -> LipMeasures:
    """:class:`LipMeasures` of ``face`` moved by ``displacements`` (F, N, 3), metres in, millimetres out."""
    D = np.asarray(displacements, dtype=np.float64)
    V = face.vertices[None] + D
    um, lm = face.landmarks["upper_lip_mid"], face.landmarks["lower_lip_mid"]
    gap = (V[:, um, 1] - V[:, lm, 1]) * 1000
    up, lo = seam_pairs(face)
    min_gap = (V[:, up, 1] - V[:, lo, 1]).min(axis=1) * 1000
    cl, cr = face.landmarks["mouth_corner_left"], face.landmarks["mouth_corner_right"]
    rest = np.linalg.norm(face.vertices[cl] - face.vertices[cr])
    width = np.linalg.norm(V[:, cl] - V[:, cr], axis=1) / rest
    return LipMeasures(gap, min_gap, width)


def phone_frames(segments, fps: float, n_frames: int) -> dict[str, list[int]]:
    """Class name -> the middle frame of each phone of that class."""
    out = {c: [] for c in CLASSES}
    for start, end, ph in segments[["start", "end", "phoneme"]].itertuples(index=False):
        for c, members in CLASSES.items():
            if ph in members:
                out[c].append(min(int(round(0.5 * (start + end) * fps)), n_frames - 1))
    return out


def summary(m: LipMeasures, frames: dict[str, list[int]]) -> dict:
    """Per class: count, mean |gap| / gap / width at the phones' middles; plus the worst crossing."""
    out = {"frames": len(m.gap), "min_centre_gap_mm": float(m.gap.min()), "min_seam_gap_mm": float(m.min_gap.min())}
    for c, idx in frames.items():
        if not idx:
            continue
        idx = np.asarray(idx)
        out[c] = {"n": len(idx), "gap_mm": float(m.gap[idx].mean()), "max_abs_gap_mm": float(np.abs(m.gap[idx]).max()),
                  "width_ratio": float(m.width[idx].mean()), "max_width_ratio": float(m.width[idx].max())}
    return out
