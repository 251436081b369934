"""Contact sheet of the rig: one labelled tile per muscle (and the jaw) at full activation.

Each tile renders the default face posed with one function at its maximum
(the jaw at 1), tinted red by the displacement magnitude, with the muscle's
attachment -> insertion vector and zone outline drawn over it.

Usage::

    PYTHONPATH=src python scripts/muscle_sheet.py [-o docs/images/muscles.png] [--view face] [--force]
"""

from __future__ import annotations

import argparse
import sys

import numpy as np


def build_sheet(rig, view: str = "face", tile: int = 320, columns: int = 6) -> np.ndarray:
    import cv2

    from visemeface.muscles.overlay import draw_muscles, tinted_face
    from visemeface.render.renderer import Renderer

    tiles = []
    for i, name in enumerate(rig.names):
        a = np.zeros(len(rig.names))
        a[i] = rig.ranges[i, 1]
        d = rig.displacement(a)
        mag = np.linalg.norm(d, axis=1)
        # One renderer per tile: the tint is part of the face's colours.
        with Renderer(tinted_face(rig.face, mag), size=(tile, tile), view=view) as renderer:
            img = draw_muscles(renderer.render(rig.rest + d), renderer, rig, [name])
        cv2.putText(img, f"{name} = {a[i]:g}", (6, 18), cv2.FONT_HERSHEY_SIMPLEX, 0.42, (255, 255, 255), 1,
                    cv2.LINE_AA)
        cv2.putText(img, f"max {1000 * mag.max():.1f} mm", (6, tile - 8), cv2.FONT_HERSHEY_SIMPLEX, 0.4,
                    (220, 220, 220), 1, cv2.LINE_AA)
        tiles.append(img)
    # Last tile: rest face with every muscle drawn.
    with Renderer(rig.face, size=(tile, tile), view=view) as renderer:
        img = draw_muscles(renderer.render(), renderer, rig, zones=False)
    cv2.putText(img, "rest, all muscles", (6, 18), cv2.FONT_HERSHEY_SIMPLEX, 0.42, (255, 255, 255), 1,
                cv2.LINE_AA)
    tiles.append(img)
    rows = -(-len(tiles) // columns)
    sheet = np.zeros((rows * tile, columns * tile, 3), np.uint8)
    for k, t in enumerate(tiles):
        r, c = divmod(k, columns)
        sheet[r * tile:(r + 1) * tile, c * tile:(c + 1) * tile] = t
    return sheet


def main(argv=None) -> int:
    from visemeface.muscles.rig import default_rig
    from visemeface.render.renderer import save_png

    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("-o", "--output", default="docs/images/muscles.png")
    p.add_argument("--view", default="face", choices=["face", "mouth", "three-quarter"])
    p.add_argument("--tile", type=int, default=320, help="tile size in pixels (multiple of 16)")
    p.add_argument("--force", action="store_true", help="overwrite the output")
    args = p.parse_args(argv)
    sheet = build_sheet(default_rig(), view=args.view, tile=args.tile)
    save_png(args.output, sheet, force=args.force)
    print(args.output)
    return 0


if __name__ == "__main__":
    sys.exit(main())
