#!/usr/bin/env python
"""Side by side: each real GRID clip of ``../shared/realdata`` and our face saying the same sentence.

For every clip the sentence is timed by ``text_to_utterance(sentence)`` and stretched
linearly onto the clip's speech span: the word alignment's first and last word where the
clip has one (``swwp2s.align``), else the span where the real mouth moves (frame-to-frame
change of the mouth cut-out above a third of its largest, smoothed over 5 frames; the
audio's own speech span, ``say --audio``, is thrown by the clips' noise: 0.0-2.97 s).
It is animated at the clip's 25 fps and rendered in the mouth view. Eight frames evenly over
the speech span are shown: the real mouth (cut out around a mouth centre found by eye in
each clip, :data:`CLIPS`) above our render at the same time, cut to the same mouth-width
fraction. The project's own opening analysis (:func:`visemeface.analysis.profiles.analyze_frames`,
Otsu threshold with teeth counted as opening) runs on both, and the L2 distance of the
per-frame opening width and height profiles (in mouth widths) is printed as JSON lines,
with the fractions of each tile that are teeth and dark cavity (:mod:`visemeface.render.mouth_pixels`).

Usage::

    PYTHONPATH=src python scripts/realdata_sheet.py [--realdata ../shared/realdata] [-o docs/images/realdata.png]
"""

from __future__ import annotations

import argparse
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


def speech_span(path: Path, frames, centre, mouth_w) -> tuple[float, float]:
    """The clip's speech span (s): its word alignment, else where the mouth moves (see the docstring)."""
    align = path.with_suffix(".align")
    if align.exists():
        rows = [line.split() for line in align.read_text().splitlines() if line.strip()]
        words = [(int(a) / 25000, int(b) / 25000) for a, b, w in rows if w != "sil"]
        return words[0][0], words[-1][1]
    grey = [cv2.cvtColor(crop(f, centre, mouth_w), cv2.COLOR_RGB2GRAY).astype(np.float32) for f in frames]
    energy = np.array([0.0] + [np.abs(b - a).mean() for a, b in zip(grey, grey[1:])])
    energy = np.convolve(energy, np.ones(5) / 5, mode="same")
    moving = np.flatnonzero(energy > energy.max() / 3)
    return moving[0] / FPS, (moving[-1] + 1) / FPS


def stretched(utt, t0: float, t1: float):
    """The utterance's segments with the speech moved linearly onto [t0, t1]."""
    seg = utt.segments.copy()
    speech = seg[seg.phoneme != "_"]
    s0, s1 = float(speech.start.min()), float(speech.end.max())
    f = lambda t: np.clip(t0 + (np.asarray(t, float) - s0) * (t1 - t0) / (s1 - s0), 0.0, None)  # noqa: E731
    seg["start"], seg["end"] = f(seg["start"]), f(seg["end"])
    seg.loc[seg.index[0], "start"] = 0.0
    seg.loc[seg.index[-1], "end"] = max(float(seg["end"].iloc[-1]), 3.0)
    return seg


def our_frames(sentence: str, span, n_frames: int):
    from visemeface.muscles.rig import default_rig
    from visemeface.postures.library import load_visemes
    from visemeface.render.renderer import Renderer
    from visemeface.speech.g2p import text_to_utterance
    from visemeface.speech.timeline import activation_track

    rig = default_rig()
    utt = text_to_utterance(sentence, warn=False)
    track = activation_track(stretched(utt, *span), load_visemes(rig=rig), fps=FPS)
    poses = rig.poses(track)
    r = Renderer(rig.face, size=(256, 256), view="mouth")
    x, y, w, h = r.mouth_box()
    frames = [r.render(poses[min(i, len(poses) - 1)]) for i in range(n_frames)]
    r.release()
    return frames, (x + w / 2, y + h * 0.45), w


def opening_profile(frames, centre, mouth_w):
    from visemeface.analysis.openings import OpeningDetector
    from visemeface.analysis.profiles import analyze_frames

    box = (int(centre[0] - mouth_w / 2), int(centre[1] - 0.6 * mouth_w), int(mouth_w), int(1.2 * mouth_w))
    return analyze_frames(frames, box, FPS, detector=OpeningDetector(teeth=True))


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
    from visemeface.outputs import atomic_output

    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--realdata", type=Path, default=Path(__file__).resolve().parents[2] / "shared" / "realdata")
    ap.add_argument("-o", "--output", type=Path, default=Path("docs/images/realdata.png"))
    ap.add_argument("--force", action="store_true")
    args = ap.parse_args(argv)
    tiles, labels = [], []
    for name, sentence, centre, mouth_w in CLIPS:
        real = read_clip(args.realdata / f"{name}.mpg")
        t0, t1 = speech_span(args.realdata / f"{name}.mpg", real, centre, mouth_w)
        ours, our_centre, our_w = our_frames(sentence, (t0, t1), len(real))
        idx = np.linspace(t0 * FPS, t1 * FPS - 1, SHOWN).round().astype(int)
        for row, (frames, c, w, who) in enumerate(((real, centre, mouth_w, "real"), (ours, our_centre, our_w, "ours"))):
            for i in idx:
                tiles.append(crop(frames[i], c, w))
                labels.append(f"{name} {who} {i / FPS:.2f}s")
        pr, po = opening_profile(real, centre, mouth_w), opening_profile(ours, our_centre, our_w)
        span = slice(int(t0 * FPS), int(t1 * FPS))
        out = {"clip": name, "sentence": sentence, "speech_s": [round(t0, 2), round(t1, 2)]}
        for k in ("width", "height", "area"):
            a, b = pr[k].to_numpy()[span], po[k].to_numpy()[span]
            out[f"real_{k}_mean"], out[f"ours_{k}_mean"] = round(float(a.mean()), 3), round(float(b.mean()), 3)
            out[f"l2_{k}"] = round(float(np.sqrt(np.mean((a - b) ** 2))), 3)
            out[f"corr_{k}"] = round(float(np.corrcoef(a, b)[0, 1]), 2) if a.std() > 0 and b.std() > 0 else None
        for k, (a, b) in interior_fractions(real, ours, centre, mouth_w, our_centre, our_w, span).items():
            out[f"real_{k}_mean"], out[f"ours_{k}_mean"] = round(float(a.mean()), 4), round(float(b.mean()), 4)
            out[f"corr_{k}"] = round(float(np.corrcoef(a, b)[0, 1]), 2) if a.std() > 0 and b.std() > 0 else None
        print(json.dumps(out), flush=True)
    sheet = compose_sheet(tiles, labels, columns=SHOWN)
    from PIL import Image

    args.output.parent.mkdir(parents=True, exist_ok=True)
    with atomic_output(args.output, args.force) as tmp:
        Image.fromarray(sheet).save(tmp, format="PNG", optimize=True)
    print(f"wrote {args.output}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
