"""Figures of a face's rig that the renders depend on, for the default face and the ICT head (JSON lines).

- ``lip_stretch``: the largest stretch (posed / rest edge length) of a lip triangle more than 0.1 mouth widths
  from either corner over every viseme alone and with each emotion at full weight (1: none; torn: over 3);
- ``aa_corner_flips``: triangles within 0.15 mouth widths of a corner whose normal turns over on /aa/, and how
  many of them lie in front of the mouth's lining (``_front``: centroid less than 11 mm behind the lips' front);
- ``gaze_*``: at a vertical gaze of +1 and -1 (15 degrees), how far the pupil and the upper and lower lids'
  margins over it move (mm): the upper lid follows the eye when the two agree, the lower by about 0.3.

::

    PYTHONPATH=src python benchmarks/face_figures.py
"""

from __future__ import annotations

import argparse
import json

import numpy as np


def gaze(rig) -> dict:
    from visemeface.muscles.measure import lid_margin

    face, rest = rig.face, rig.face.vertices
    pupil = face.landmarks["eye_centre_left"]
    (margin, _), (lower, _) = lid_margin(face, "left", "upper"), lid_margin(face, "left", "lower")
    out = {}
    for g in (1.0, -1.0):
        posed = rig.pose({"eye_turn_vertical_left": g, "eye_turn_vertical_right": g})
        out[f"gaze_{g:+.0f}_pupil_mm"] = round(1000 * float(posed[pupil, 1] - rest[pupil, 1]), 2)
        out[f"gaze_{g:+.0f}_lid_margin_mm"] = round(1000 * float(posed[margin, 1] - rest[margin, 1]), 2)
        out[f"gaze_{g:+.0f}_lower_lid_margin_mm"] = round(1000 * float(posed[lower, 1] - rest[lower, 1]), 2)
    return out


def main(argv=None) -> None:
    argparse.ArgumentParser(description=__doc__.splitlines()[0]).parse_args(argv)
    from visemeface.face.prepare import lip_stretch
    from visemeface.muscles.measure import corner_folds
    from visemeface.muscles.rig import rig_for
    from visemeface.postures.library import PostureLibrary

    for name in ("procedural", "ict"):
        rig = rig_for(name)
        flips, front = corner_folds(rig.face, PostureLibrary(rig).posed_vertices("aa", None))
        print(json.dumps({"benchmark": "face_figures", "face": name, "lip_stretch": round(lip_stretch(rig.face), 3),
                          "aa_corner_flips": flips, "aa_corner_flips_front": front, **gaze(rig)}), flush=True)


if __name__ == "__main__":
    main()
