"""End-to-end speed and peak memory of ``visemeface speak`` (transcript -> MP4).

Prints one JSON line per run and a summary line::

    PYTHONPATH=src python benchmarks/speak.py [--size 512] [--fps 30] [--durations 10 60] [--msaa 4]
                                              [--faces procedural ict]

Each run is a fresh Python process (``--child``) that runs the CLI in-process
and reports its own wall time and peak resident memory (``ru_maxrss`` of the
process itself; ffmpeg's, a child process with its own bounded buffers, is
reported separately). The transcript is "one five zero zero six" repeated to
the wanted length. Targets: >= 100 frames/s end to end at 512^2 and
30 fps; the 60 s run's peak memory within 10 % of the 10 s run's (frames are
streamed, so memory must not grow with the utterance).

``marginal_fps`` = (F_long - F_short) / (T_long - T_short) removes the fixed
start-up cost (imports, building the rig, the GL context) from the rate;
``marginal_cpu_ms_per_frame`` is the same for CPU time (all threads, ffmpeg
included), which is less disturbed than wall time when the machine is shared
(the 1-minute load average at the end of each run is printed too).
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import tempfile
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _runner import child, run_child, write_transcript  # noqa: E402

def run_one(seconds: float, size: int, fps: float, workdir: Path, msaa: int = 4, face: str = "procedural") -> dict:
    transcript = workdir / f"bench_{seconds:g}s.txt"
    end = write_transcript(transcript, seconds)
    out = workdir / f"bench_{face}_{seconds:g}s.mp4"
    argv = ["speak", str(transcript), "-o", str(out), "--size", str(size), "--fps", str(fps),
            "--msaa", str(msaa), "--face", face, "--force", "-q"]
    res, total = run_child(__file__, argv)
    from visemeface.export.video import read_video_info

    frames = read_video_info(out)["n_frames"]
    return {"bench": "speak", "face": face, "utterance_s": round(end, 3), "size": size, "fps": fps, "msaa": msaa,
            "frames": frames, "wall_s": round(res["wall_s"], 3),
            "process_s": round(total, 3),
            "frames_per_s": round(frames / res["wall_s"], 1),
            "peak_rss_mb": round(res["peak_rss_mb"], 1),
            "ffmpeg_peak_rss_mb": round(res["ffmpeg_peak_rss_mb"], 1),
            "cpu_s": round(res["cpu_s"], 2), "cpus": os.cpu_count(),
            "load_avg_1min_at_end": round(res["load1"], 2)}


def main() -> None:
    if len(sys.argv) == 3 and sys.argv[1] == "--child":
        child(json.loads(sys.argv[2]))
        return
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--size", type=int, default=512)
    ap.add_argument("--fps", type=float, default=30.0)
    ap.add_argument("--durations", type=float, nargs="+", default=[10.0, 60.0])
    ap.add_argument("--msaa", type=int, default=4, help="antialiasing samples (speak's --msaa)")
    ap.add_argument("--faces", nargs="+", default=["procedural"], help="built-in faces, measured in turn in one run")
    args = ap.parse_args()
    for face in args.faces:
        with tempfile.TemporaryDirectory() as tmp:
            rows = [run_one(s, args.size, args.fps, Path(tmp), args.msaa, face) for s in args.durations]
        for r in rows:
            print(json.dumps(r), flush=True)
        summary(rows, face)


def summary(rows: list[dict], face: str) -> None:
    """The marginal rate and the memory ratio of the longest run over the shortest."""
    short, long_ = rows[0], rows[-1]
    if len(rows) > 1 and long_["frames"] > short["frames"]:
        marginal = (long_["frames"] - short["frames"]) / max(long_["wall_s"] - short["wall_s"], 1e-9)
        ratio = long_["peak_rss_mb"] / short["peak_rss_mb"]
        cpu_per_frame = (long_["cpu_s"] - short["cpu_s"]) / (long_["frames"] - short["frames"])
        print(json.dumps({"bench": "speak_summary", "face": face, "marginal_fps": round(marginal, 1),
                          "marginal_cpu_ms_per_frame": round(1e3 * cpu_per_frame, 2),
                          "end_to_end_fps_long": long_["frames_per_s"],
                          "fps_target": 100, "fps_ok": long_["frames_per_s"] >= 100,
                          "peak_rss_ratio_long_short": round(ratio, 3),
                          "memory_ok": ratio <= 1.10}), flush=True)


if __name__ == "__main__":
    main()
