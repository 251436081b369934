#!/usr/bin/env python
"""Issue 13's mouth-shape figures on the default rig, with and without the lip-shaping functions.

Prints one JSON line per posture: the inner opening (width, height, width/height, width over
the mouth width), the protrusion, the distance from the lower lip's inner edge to the upper
incisal edge, and how far the tongue tip is in front of the lower incisors; then the same
with each posture's lip-shaping function (lip_rounding, corner_seal, lower_lip_tuck) set to 0,
to show what the tuned functions do. Targets (the issue's acceptance): /uw/ /w/ width/height
<= 2.5 with protrusion >= 4 mm; /aa/ width <= 0.8 mouth width; /f/ /v/ lip-to-incisor <= 1 mm;
/th/ /dh/ tongue tip in front of the lower incisors.

Usage::

    PYTHONPATH=src python scripts/mouth_shapes.py
"""

from __future__ import annotations

import json
import sys

import numpy as np

POSTURES = ("uw", "w", "aa", "f", "v", "th", "dh")
SHAPING = {"uw": "lip_rounding", "w": "lip_rounding", "aa": "corner_seal", "f": "lower_lip_tuck",
           "v": "lower_lip_tuck", "th": "tongue_protrusion", "dh": "tongue_protrusion"}


def figures(rig, activations) -> dict:
    from visemeface.muscles.measure import inner_opening, lip_dimensions

    p = rig.pose(activations)
    lm = rig.face.landmarks
    o = inner_opening(rig.face, p)
    d = lip_dimensions(rig.face, p)
    return {"width_mm": round(1e3 * o["width"], 1), "height_mm": round(1e3 * o["height"], 1),
            "width_over_height": round(o["aspect"], 2) if np.isfinite(o["aspect"]) else None,
            "width_over_mouth": round(o["width"] / d["mouth_width"], 2),
            "protrusion_mm": round(1e3 * d["protrusion"], 1),
            "lower_lip_to_upper_incisor_mm": round(1e3 * float(np.linalg.norm(
                p[lm["lower_lip_mid"]] - p[lm["upper_incisor_edge"]])), 1),
            "tongue_tip_ahead_of_lower_incisors_mm": round(1e3 * float(
                p[lm["tongue_tip"], 2] - p[lm["lower_incisor_edge"], 2]), 1)}


def main() -> int:
    from visemeface.muscles.rig import default_rig
    from visemeface.postures.library import blend

    rig = default_rig()
    for v in POSTURES:
        a = blend(v, {}, rig=rig)
        without = a.copy()
        without[SHAPING[v]] = 0.0
        print(json.dumps({"posture": v, **figures(rig, a),
                          "without": {"function": SHAPING[v], **figures(rig, without)}}))
    return 0


if __name__ == "__main__":
    sys.exit(main())
