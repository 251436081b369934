"""Build the compact ICT Face Model store shipped in ``data/faces/ict/`` from ICT-FaceKit's OBJs.

The ICT Face Model "Light" (Li et al., "Learning Formation of Physically-Based Face Attributes", CVPR 2020;
USC Institute for Creative Technologies, MIT licence) is a scanned head in 17 parts with 53 artist-made
expression shapes named as ARKit's. This script reads a checkout of ICT-FaceKit (its ``FaceXModel/`` folder:
``generic_neutral_mesh.obj``, the 53 expression OBJs, ``identity000.obj`` ...) and writes

- ``ict.npz``: the neutral (float32, metres, origin at the mouth corners' midpoint, +x the subject's left,
  +y up, +z forward: ICT's axes), quads and triangles, the parts' vertex ranges, the 53 expression deltas and
  ``--identities`` identity modes as float16 deltas (metres; float16 keeps 0.03 mm at 3 cm);
- ``LICENSE`` (ICT-FaceKit's MIT notice, shipped beside the data).

The eye-wetness shells (lacrimal fluid, eye blend, occlusion) and the eyelash cards are left out: they need
the transparent shaders of a game engine and only hide the eye in our renderer.

Usage::

    python scripts/build_ict.py PATH/TO/ICT-FaceKit [--identities 20] [--force]
"""

from __future__ import annotations

import argparse
import json
import shutil
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
OUT = ROOT / "data" / "faces" / "ict"

#: ICT's parts (README of ICT-FaceKit): name -> [first, last] vertex index; kept are the first nine.
PARTS = {
    "face": (0, 9408), "head_and_neck": (9409, 11247), "mouth_socket": (11248, 13293),
    "eye_socket_left": (13294, 13677), "eye_socket_right": (13678, 14061), "gums_and_tongue": (14062, 17038),
    "teeth": (17039, 21450), "eyeball_left": (21451, 23020), "eyeball_right": (23021, 24590),
}
KEPT = PARTS["eyeball_right"][1] + 1
#: ICT's Multi-PIE 68-point landmark vertices (ICT-FaceKit README), 0-indexed.
MULTI_PIE_68 = (1225, 1888, 1052, 367, 1719, 1722, 2199, 1447, 966, 3661, 4390, 3927, 3924, 2608, 3272, 4088,
                3443, 268, 493, 1914, 2044, 1401, 3615, 4240, 4114, 2734, 2509, 978, 4527, 4942, 4857, 1140, 2075,
                1147, 4269, 3360, 1507, 1542, 1537, 1528, 1518, 1511, 3742, 3751, 3756, 3721, 3725, 3732, 5708,
                5695, 2081, 0, 4275, 6200, 6213, 6346, 6461, 5518, 5957, 5841, 5702, 5711, 5533, 6216, 6207,
                6470, 5517, 5966)
CM = 0.01


def read_obj(path: Path) -> tuple[np.ndarray, list[list[int]]]:
    verts, faces = [], []
    with open(path, encoding="utf-8") as fh:
        for line in fh:
            if line.startswith("v "):
                verts.append(line.split()[1:4])
            elif line.startswith("f "):
                faces.append([int(t.split("/")[0]) - 1 for t in line.split()[1:]])
    return np.asarray(verts, dtype=np.float64), faces


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("facekit", type=Path, help="an ICT-FaceKit checkout (holding FaceXModel/)")
    ap.add_argument("--identities", type=int, default=20, help="identity modes kept (default 20 of 100)")
    ap.add_argument("--force", action="store_true")
    args = ap.parse_args(argv)
    model = args.facekit / "FaceXModel"
    target = OUT / "ict.npz"
    if target.exists() and not args.force:
        print(f"{target} exists (use --force)", file=sys.stderr)
        return 2
    neutral, faces = read_obj(model / "generic_neutral_mesh.obj")
    meta = json.loads((model / "vertex_indices.json").read_text())
    names = list(meta["expressions"])
    corners = neutral[[MULTI_PIE_68[48], MULTI_PIE_68[54]]]
    origin = corners.mean(axis=0)
    rest = (neutral[:KEPT] - origin) * CM
    kept = [f for f in faces if max(f) < KEPT]
    quads = np.array([f for f in kept if len(f) == 4], dtype=np.int32)
    tris = np.array([f for f in kept if len(f) == 3], dtype=np.int32).reshape(-1, 3)
    deltas = np.zeros((len(names), KEPT, 3), dtype=np.float16)
    for i, name in enumerate(names):
        v, _ = read_obj(model / f"{name}.obj")
        deltas[i] = ((v[:KEPT] - neutral[:KEPT]) * CM).astype(np.float16)
        print(f"{name:18s} max {np.abs(v[:KEPT] - neutral[:KEPT]).max() * 10:6.2f} mm", file=sys.stderr)
    ident = np.zeros((args.identities, KEPT, 3), dtype=np.float16)
    for i in range(args.identities):
        v, _ = read_obj(model / f"identity{i:03d}.obj")
        ident[i] = ((v[:KEPT] - neutral[:KEPT]) * CM).astype(np.float16)
    OUT.mkdir(parents=True, exist_ok=True)
    np.savez_compressed(target, vertices=rest.astype(np.float32), quads=quads, triangles=tris,
                        part_names=np.array(list(PARTS)), part_ranges=np.array(list(PARTS.values()), np.int32),
                        multi_pie_68=np.array(MULTI_PIE_68, np.int32), expression_names=np.array(names),
                        expressions=deltas, identities=ident)
    shutil.copyfile(args.facekit / "LICENSE", OUT / "LICENSE")
    print(f"wrote {target} ({target.stat().st_size / 1e6:.2f} MB): {KEPT} vertices, {len(quads)} quads, "
          f"{len(tris)} triangles, {len(names)} expressions, {args.identities} identity modes", file=sys.stderr)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
