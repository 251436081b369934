"""The figures of ``face --prepare`` in docs/notes/ict_head.md: landmarks found on ICT's head against ICT's own
Multi-PIE vertices (mm), the prepared regions against the built-in head's, and the lips' stretch when posed.

Usage::

    python scripts/prepare_figures.py PATH/TO/generic_neutral_mesh.obj [--stretch]

The OBJ is ICT-FaceKit's neutral as it ships (centimetres; its first 24,591 vertices are the built-in head's).
"""

from __future__ import annotations

import argparse

import numpy as np


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("obj", help="ICT-FaceKit's generic_neutral_mesh.obj")
    ap.add_argument("--stretch", action="store_true", help="also pose every viseme and emotion (slow)")
    args = ap.parse_args(argv)
    from visemeface.face.ict import _store, ict_face
    from visemeface.face.prepare import lip_stretch, prepare

    face, lm = prepare(args.obj)
    known = _store()["multi_pie_68"].astype(np.int64)
    mm = np.linalg.norm(face.vertices[lm] - face.vertices[known], axis=1) * 1000
    print(f"landmarks vs ICT's (mm): median {np.median(mm):.1f}, mouth 48-67 mean {mm[48:68].mean():.1f}, "
          f"inner lips 60-67 {mm[60:68].mean():.1f}, eyes 36-47 {mm[36:48].mean():.1f}, brows and nose 17-35 "
          f"{mm[17:36].mean():.1f}, jaw contour 0-16 {mm[:17].mean():.1f} (max {mm[:17].max():.1f})")
    ref = ict_face()
    for name, r in ref.landmarks.items():
        if name in face.landmarks and r < len(face.vertices):
            d = np.linalg.norm(face.vertices[face.landmarks[name]] - face.vertices[r]) * 1000
            print(f"  {name:20s} {d:5.1f} mm")
    for name in ("upper_lip", "lower_lip", "lip_seam_upper", "lip_seam_lower", "upper_lids", "lower_lids", "eyeballs",
                 "upper_teeth", "lower_teeth", "upper_gum", "lower_gum", "tongue"):
        a, b = set(face.regions.get(name, np.zeros(0, int)).tolist()), set(ref.regions[name].tolist())
        print(f"  {name:15s} {len(a):5d} vertices (built-in {len(b):5d}), overlap {len(a & b) / len(a | b):.2f}")
    if args.stretch:
        print(f"lip stretch: prepared {lip_stretch(face):.2f}, built-in {lip_stretch(ref):.2f}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
