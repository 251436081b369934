"""Mouth-opening analysis speed: frames per second at 1080p and 512x512.

Prints one JSON line per case:

- ``detect``: :class:`OpeningDetector` on frames already in memory (the
  analysis itself; target >= 60 frames/s at 512x512 on 2 cores),
- ``decode+detect``: the whole ``analyze`` path from an MP4 (libx264)
  decoded by imageio-ffmpeg, without writing outputs (ffmpeg start-up included;
  decoding dominates at 1080p).

Run: ``PYTHONPATH=src python benchmarks/analyze.py [--frames N]``
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
from visemeface.analysis.profiles import analyze_frames
from visemeface.analysis.synthetic import merging_mouth_frames
from visemeface.analysis.video import open_frames

CASES = {
    # name: (frame height, width), mouth box (x, y, w, h)
    "1080p": ((1080, 1920), (560, 340, 800, 400)),     # seed 001's ~800 px mouth
    "512x512": ((512, 512), (106, 306, 300, 150)),
}


def bench_detect(frames, box, detector, repeat: int = 3) -> float:
    best = np.inf
    for _ in range(repeat):
        t0 = time.perf_counter()
        for f in frames:
            detector.detect(f, box)
        best = min(best, time.perf_counter() - t0)
    return len(frames) / best


def bench_video(frames, box, fps: float = 30.0) -> float:
    import imageio_ffmpeg
    h, w = frames[0].shape[:2]
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "bench.mp4"
        writer = imageio_ffmpeg.write_frames(str(path), (w, h), fps=fps, codec="libx264", quality=8,
                                             macro_block_size=8)
        writer.send(None)
        for f in frames:
            writer.send(np.ascontiguousarray(f))
        writer.close()
        t0 = time.perf_counter()
        source = open_frames(path)
        df = analyze_frames(source.frames(), box, source.fps)
        dt = time.perf_counter() - t0
    assert len(df) == len(frames)
    return len(frames) / dt


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--frames", type=int, default=60, help="frames per case (default 60)")
    args = ap.parse_args()
    n = args.frames
    for name, (size, box) in CASES.items():
        frames = list(merging_mouth_frames(n, n // 2, size, box))
        for label, det in (("default", OpeningDetector()),
                           ("hull+teeth", OpeningDetector(hull=True, teeth=True))):
            print(json.dumps({"bench": "analyze.detect", "case": name, "settings": label, "frames": n,
                              "mouth_width_px": box[2], "frames_per_s": round(bench_detect(frames, box, det), 1),
                              "cv2_threads": cv2.getNumThreads(), "cpus": os.cpu_count()}), flush=True)
        # Light noise for the video: white noise at sigma 6 makes a bitstream
        # several times larger than rendered or camera footage, and decoding it
        # would dominate.
        clean = list(merging_mouth_frames(n, n // 2, size, box, noise=2.0))
        print(json.dumps({"bench": "analyze.decode+detect", "case": name, "settings": "default", "frames": n,
                          "mouth_width_px": box[2], "frames_per_s": round(bench_video(clean, box), 1),
                          "cpus": os.cpu_count()}), flush=True)


if __name__ == "__main__":
    main()
