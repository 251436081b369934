#!/usr/bin/env python
"""Side by side: each real GRID clip of ``../shared/realdata`` and our face saying the same sentence.

For every clip the sentence is timed as ``compare_realdata.py`` times it (forced alignment of
the text to the clip's audio, :func:`compare_realdata.timed_segments`), animated at the clip's
25 fps and rendered in the mouth view. Eight frames evenly over the audio's speech span
(:func:`visemeface.speech.audio.speech_span`, relative to the noise floor) are shown: the real
mouth (cut out around a mouth centre found by eye in each clip, :data:`CLIPS`, for the picture
only) above our render at the same time, cut to the same mouth-width fraction. The figures are
``compare_realdata.py``'s: the project's opening analysis with the same settings on both (the real
clip with the automatic mouth box, the render with the renderer's), the means, L2 distance and
Pearson r of the opening width, height and area (in mouth widths) over the speech span, the height's
best lag within +-5 frames (:func:`compare_realdata.speech_correlation`), and the fractions of each
tile that are teeth and dark cavity (:mod:`visemeface.render.mouth_pixels`), printed as JSON lines.

``--releases`` draws a release instead (``docs/images/realdata_releases.png``): per clip, 12 frames
from the start of a bilabial release (:data:`RELEASES`), the real mouth above the seed's sticky FEM model
(``PhysicsSettings()``) and the speech commands' sticky lips (``PhysicsSettings.speech()``), each render
with the openings the project's analysis finds outlined.

Usage::

    PYTHONPATH=src python scripts/realdata_sheet.py [--realdata ../shared/realdata] [-o docs/images/realdata.png]
    PYTHONPATH=src python scripts/realdata_sheet.py --releases [-o docs/images/realdata_releases.png]
"""

from __future__ import annotations

import argparse
import itertools
import json
import sys
from pathlib import Path

import cv2
import numpy as np

#: clip, sentence, mouth centre (x, y) and mouth width (px) in the 360x288 frames (by eye).
CLIPS = (
    ("swwp2s", "set white with p two soon", (176, 213), 46),
    ("bbaf2n", "bin blue at f two now", (158, 213), 44),
    ("lbax4n", "lay blue at x four now", (196, 204), 46),
)
FPS = 25.0
TILE = (192, 128)          # width, height of one tile
WIDTH_FRACTION = 0.55      # mouth width / tile width
SHOWN = 8
#: ``--releases``: per clip, the first of the 12 frames shown (25 fps): "blue", "blue", "p two".
RELEASES = {"swwp2s": 33, "bbaf2n": 33, "lbax4n": 19}


def read_clip(path: Path) -> list[np.ndarray]:
    cap = cv2.VideoCapture(str(path))
    frames = []
    while True:
        ok, f = cap.read()
        if not ok:
            break
        frames.append(cv2.cvtColor(f, cv2.COLOR_BGR2RGB))
    return frames


def crop(img: np.ndarray, centre, mouth_w: float) -> np.ndarray:
    """The tile around ``centre`` whose width holds the mouth at :data:`WIDTH_FRACTION`."""
    w = mouth_w / WIDTH_FRACTION
    h = w * TILE[1] / TILE[0]
    x0, y0 = int(round(centre[0] - w / 2)), int(round(centre[1] - h * 0.45))
    pad = int(w)
    big = cv2.copyMakeBorder(img, pad, pad, pad, pad, cv2.BORDER_REPLICATE)
    part = big[y0 + pad:y0 + pad + int(round(h)), x0 + pad:x0 + pad + int(round(w))]
    return cv2.resize(part, TILE, interpolation=cv2.INTER_CUBIC)


def our_frames(segments, n_frames: int, physics=None):
    """Our face along ``segments`` at :data:`FPS`, rendered (mouth view): frames, tile centre, width, box.
    ``physics``: PhysicsSettings of the sticky FEM face (default: the kinematic face)."""
    from visemeface.muscles.rig import default_rig
    from visemeface.postures.library import load_visemes
    from visemeface.render.renderer import Renderer
    from visemeface.speech.timeline import activation_track

    rig = default_rig()
    track = activation_track(segments, load_visemes(rig=rig), fps=FPS)
    if physics is None:
        poses, face = rig.poses(track), rig.face
    else:
        from visemeface.animate import simulated_motion
        motion = simulated_motion(rig, track, "sticky", physics)
        poses, face = [f.vertices for f in itertools.islice(motion.frames(), n_frames)], motion.render_face
    r = Renderer(face, size=(256, 256), view="mouth")
    x, y, w, h = box = r.mouth_box()
    frames = [r.render(poses[min(i, len(poses) - 1)]) for i in range(n_frames)]
    r.release()
    return frames, (x + w / 2, y + h * 0.45), w, box


def release_tiles(name, real, segments, centre, mouth_w, detector):
    """``--releases``' tiles and labels of one clip: real, the seed's sticky model, the speech default's."""
    from visemeface.analysis.openings import draw_openings
    from visemeface.physics.drive import PhysicsSettings

    shown = range(RELEASES[name], RELEASES[name] + 12)
    tiles = [crop(real[i], centre, mouth_w) for i in shown]
    labels = [f"{name} real {i / FPS:.2f}s" for i in shown]
    for who, settings in (("seed", PhysicsSettings()), ("v2", PhysicsSettings.speech())):
        ours, c, w, box = our_frames(segments, shown.stop, settings)
        tiles += [crop(draw_openings(ours[i], detector.detect(ours[i], box), box), c, w) for i in shown]
        labels += [f"{name} {who} {i / FPS:.2f}s" for i in shown]
    return tiles, labels


def interior_fractions(real, ours, centre, mouth_w, our_centre, our_w, span) -> dict:
    """Per frame, the fractions of the mouth tile that are teeth and dark cavity (render.mouth_pixels)."""
    from visemeface.render.mouth_pixels import teeth_pixels

    out = {}
    for key, test in (("teeth", teeth_pixels),
                      ("dark", lambda im: im.astype(np.float32) @ np.array([0.299, 0.587, 0.114]) < 40)):
        a = np.array([test(crop(f, centre, mouth_w)).mean() for f in real[span]])
        b = np.array([test(crop(f, our_centre, our_w)).mean() for f in ours[span]])
        out[key] = (a, b)
    return out


def main(argv=None) -> int:
    from visemeface.commands.sheet import compose_sheet
    from visemeface.errors import InputError
    from visemeface.outputs import atomic_output, check_new

    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--realdata", type=Path, default=Path(__file__).resolve().parents[2] / "shared" / "realdata")
    ap.add_argument("-o", "--output", type=Path, help="default: docs/images/realdata.png, with --releases "
                    "docs/images/realdata_releases.png")
    ap.add_argument("--force", action="store_true")
    ap.add_argument("--releases", action="store_true", help="a bilabial release per clip: real, the seed's sticky "
                    "model, the speech commands' sticky lips (12 frames each)")
    args = ap.parse_args(argv)
    args.output = args.output or Path("docs/images/realdata_releases.png" if args.releases else "docs/images/realdata.png")
    missing = [f"{name}.mpg" for name, *_ in CLIPS if not (args.realdata / f"{name}.mpg").is_file()]
    if missing:
        print(f"realdata_sheet: {', '.join(missing)} not in {args.realdata} (--realdata: the folder of "
              "../shared/realdata/README.md)", file=sys.stderr)
        return 2
    args.output.parent.mkdir(parents=True, exist_ok=True)
    try:
        check_new(args.output, args.force)            # before minutes of rendering, not after
    except InputError as e:
        print(f"realdata_sheet: {e}", file=sys.stderr)
        return 2
    import warnings

    from visemeface.analysis.openings import OpeningDetector
    from visemeface.analysis.profiles import analyze_frames

    sys.path.insert(0, str(Path(__file__).resolve().parent))
    from compare_realdata import real_profile, speech_correlation, timed_segments

    warnings.simplefilter("ignore")
    detector = OpeningDetector()
    tiles, labels = [], []
    for name, sentence, centre, mouth_w in CLIPS:
        path = args.realdata / f"{name}.mpg"
        real = read_clip(path)
        segments, _ = timed_segments(path, sentence, "align", len(real) / FPS)
        if args.releases:
            more = release_tiles(name, real, segments, centre, mouth_w, detector)
            tiles, labels = tiles + more[0], labels + more[1]
            continue
        pr, _, _ = real_profile(path, detector)
        ours, our_centre, our_w, our_box = our_frames(segments, len(real))
        po = analyze_frames(ours, our_box, FPS, detector, source="synthetic")
        sp = speech_correlation(pr, po, path)
        t0, t1 = sp["span_s"]
        idx = np.linspace(t0 * FPS, t1 * FPS - 1, SHOWN).round().astype(int)
        for row, (frames, c, w, who) in enumerate(((real, centre, mouth_w, "real"), (ours, our_centre, our_w, "ours"))):
            for i in idx:
                tiles.append(crop(frames[i], c, w))
                labels.append(f"{name} {who} {i / FPS:.2f}s")
        span = slice(int(np.ceil(t0 * FPS - 1e-9)), int(t1 * FPS + 1e-9) + 1)
        out = {"clip": name, "sentence": sentence, "speech_s": [t0, t1],
               "corr_height_best_lag": [sp["lag"], round(sp["r_lag"], 2)]}
        for k in ("width", "height", "area"):
            a, b = pr[k].to_numpy()[span], po[k].to_numpy()[span]
            out[f"real_{k}_mean"], out[f"ours_{k}_mean"] = round(float(a.mean()), 3), round(float(b.mean()), 3)
            out[f"l2_{k}"] = round(float(np.sqrt(np.mean((a - b) ** 2))), 3)
            out[f"corr_{k}"] = round(float(np.corrcoef(a, b)[0, 1]), 2) if a.std() > 0 and b.std() > 0 else None
        for k, (a, b) in interior_fractions(real, ours, centre, mouth_w, our_centre, our_w, span).items():
            out[f"real_{k}_mean"], out[f"ours_{k}_mean"] = round(float(a.mean()), 4), round(float(b.mean()), 4)
            out[f"corr_{k}"] = round(float(np.corrcoef(a, b)[0, 1]), 2) if a.std() > 0 and b.std() > 0 else None
        print(json.dumps(out), flush=True)
    sheet = compose_sheet(tiles, labels, columns=12 if args.releases else SHOWN)
    from PIL import Image

    with atomic_output(args.output, args.force) as tmp:
        Image.fromarray(sheet).save(tmp, format="PNG", optimize=True)
    print(f"wrote {args.output}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
