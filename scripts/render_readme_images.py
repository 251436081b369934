"""Render the README pictures of the default face: docs/images/face_front.png and
docs/images/face_three_quarter.png (512x512, perspective), overwriting them. Run::

    PYTHONPATH=src python scripts/render_readme_images.py
"""

from __future__ import annotations

from pathlib import Path

from visemeface.face.procedural import default_face
from visemeface.render.renderer import Renderer, save_png

OUT = Path(__file__).resolve().parent.parent / "docs" / "images"


def main() -> None:
    OUT.mkdir(parents=True, exist_ok=True)
    face = default_face()
    for view, name in (("face", "face_front.png"), ("three-quarter", "face_three_quarter.png")):
        with Renderer(face, size=512, view=view) as r:
            path = save_png(OUT / name, r.render(), force=True)
        print(f"wrote {path}")


if __name__ == "__main__":
    main()
