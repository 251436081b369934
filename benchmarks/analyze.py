"""Mouth-opening analysis speed: frames per second at 1080p, 512x512 and GRID size (360x288 MPEG-1).

Prints one JSON line per case:

- ``detect``: :class:`OpeningDetector` on frames already in memory (the
  analysis itself), for the default ``mesh`` method, the colour ``lips`` method and seed 001's,
- ``decode+detect``: the whole ``analyze`` path from a video file decoded by
  imageio-ffmpeg (ffmpeg start-up included), without writing outputs,
- ``grid``: the real GRID clips of ../shared/realdata (360x288 MPEG-1, 75 frames,
  40-45 px mouths) through :func:`analyze_source`, decoding included, with a
  given box and with the automatic box (face-mesh landmarks with the ``track`` extra, every
  ``--landmark-every`` frames, else colour);
  where the clips are absent, a synthetic 360x288 MPEG-1 clip with a given box.
  Target: >= 200 frames/s on 2 cores, both ways.

Run: ``PYTHONPATH=src python benchmarks/analyze.py [--frames N] [--realdata DIR]``
"""

from __future__ import annotations

import argparse
import json
import os
import tempfile
import time
from pathlib import Path

import cv2
import numpy as np

from visemeface.analysis.openings import OpeningDetector
from visemeface.analysis.profiles import analyze_frames, analyze_source
from visemeface.analysis.synthetic import merging_mouth_frames
from visemeface.analysis.video import open_frames

CASES = {
    # name: (frame height, width), mouth box (x, y, w, h)
    "1080p": ((1080, 1920), (560, 340, 800, 400)),     # seed 001's ~800 px mouth
    "512x512": ((512, 512), (106, 306, 300, 150)),
}
GRID = ((288, 360), (160, 200, 42, 21))


def bench_detect(frames, box, detector, repeat: int = 3) -> float:
    best = np.inf
    for _ in range(repeat):
        t0 = time.perf_counter()
        for f in frames:
            detector.detect(f, box)
        best = min(best, time.perf_counter() - t0)
    return len(frames) / best


def write_video(frames, path: Path, fps: float = 30.0, codec: str = "libx264") -> None:
    import imageio_ffmpeg
    h, w = frames[0].shape[:2]
    writer = imageio_ffmpeg.write_frames(str(path), (w, h), fps=fps, codec=codec, quality=8, macro_block_size=8)
    writer.send(None)
    for f in frames:
        writer.send(np.ascontiguousarray(f))
    writer.close()


def bench_source(path: Path, box, repeat: int = 3, detector: OpeningDetector | None = None) -> tuple[float, int]:
    """Best frames/s of decode + (find the mouth) + measure over ``repeat`` runs."""
    best, n = np.inf, 0
    for _ in range(repeat):
        t0 = time.perf_counter()
        df, _ = analyze_source(open_frames(path), box, detector)
        best = min(best, time.perf_counter() - t0)
        n = len(df)
    return n / best, n


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--frames", type=int, default=60, help="frames per synthetic case (default 60)")
    ap.add_argument("--realdata", type=Path, default=Path(__file__).resolve().parents[2] / "shared" / "realdata")
    ap.add_argument("--landmark-every", type=int, default=None, metavar="K",
                    help="automatic box: run the face mesh on every K-th frame (default "
                    "visemeface.analysis.mouthbox.LANDMARK_EVERY)")
    ap.add_argument("--case", action="append", choices=[*CASES, "grid"],
                    help="run only these synthetic cases (repeatable; default all); the real clips always run")
    args = ap.parse_args()
    from visemeface.analysis import landmarks, mouthbox

    if args.landmark_every:
        mouthbox.LANDMARK_EVERY = args.landmark_every
    box_method = f"landmarks every {mouthbox.LANDMARK_EVERY}" if landmarks.available() else "colour"
    n = args.frames
    common = {"cv2_threads": cv2.getNumThreads(), "cpus": os.cpu_count()}
    for name, (size, box) in {**CASES, "grid": GRID}.items():
        if args.case and name not in args.case:
            continue
        frames = list(merging_mouth_frames(n, n // 2, size, box))
        for label, det in (("mesh", OpeningDetector()), ("lips", OpeningDetector(method="lips")),
                           ("seed", OpeningDetector(method="seed")),
                           ("seed hull+teeth", OpeningDetector(method="seed", hull=True, teeth=True))):
            print(json.dumps({"bench": "analyze.detect", "case": name, "settings": label, "frames": n,
                              "mouth_width_px": box[2], "frames_per_s": round(bench_detect(frames, box, det), 1),
                              **common}), flush=True)
        # Light noise for the video: white noise at sigma 6 makes a bitstream
        # several times larger than rendered or camera footage, and decoding it
        # would dominate.
        clean = list(merging_mouth_frames(n, n // 2, size, box, noise=2.0))
        with tempfile.TemporaryDirectory() as tmp:
            path = Path(tmp) / ("bench.mpg" if name == "grid" else "bench.mp4")
            write_video(clean, path, 25.0 if name == "grid" else 30.0, "mpeg1video" if name == "grid" else "libx264")
            fps, _ = bench_source(path, box, repeat=1 if name == "1080p" else 3)
        print(json.dumps({"bench": "analyze.decode+detect", "case": name, "settings": "mesh, given box",
                          "frames": n, "mouth_width_px": box[2], "frames_per_s": round(fps, 1), **common}), flush=True)
    clips = sorted(args.realdata.glob("*.mpg")) if args.realdata.is_dir() else []
    for clip in clips:
        from visemeface.analysis.mouthbox import track_mouth

        boxes = track_mouth(list(open_frames(clip).frames()))
        given = boxes[len(boxes) // 2]
        # the default method ("mesh") and the previous default ("lips") in the same run
        for method, label, box in (("mesh", "given box", given), ("mesh", "automatic box", None),
                                   ("lips", "automatic box", None)):
            fps, frames = bench_source(clip, box, detector=OpeningDetector(method=method))
            print(json.dumps({"bench": "analyze.grid", "case": clip.stem, "settings": f"{method}, {label}",
                              "box": box_method if box is None else "given",
                              "frames": frames, "mouth_width_px": given.mouth_width, "frames_per_s": round(fps, 1),
                              "target_frames_per_s": 200, **common}), flush=True)


if __name__ == "__main__":
    main()
