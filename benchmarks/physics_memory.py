"""Peak memory of the physical face against the number of frames: it must not grow.

Prints one JSON line per run and a summary line per command::

    PYTHONPATH=src python benchmarks/physics_memory.py [--resolution 1500] [--size 256]

- ``speak --physics sticky`` on 1 s and 3 s of speech ("one five zero zero six" repeated);
- ``simulate part`` at 40 and 120 fps (the same 0.75 s of simulation, 3x the frames).

Each run is a fresh process (``--child``) reporting its own peak resident memory
(``ru_maxrss``). Frames stream through the run loop to the video, frames, PC2 and
CSV outputs and to the checkpoint on disk, so the peak must stay within 10 % (issue 12).
A coarse face (``--resolution``) keeps the benchmark to a few minutes; the memory that
could grow is per frame, which a coarse face shows as well as the default one.
"""

from __future__ import annotations

import argparse
import json
import sys
import tempfile
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _runner import child, run_child, write_transcript  # noqa: E402


def _outputs(tag: str, work: Path, size: int) -> list[str]:
    return ["-o", str(work / f"{tag}.mp4"), "--frames", str(work / f"{tag}_frames"), "--pc2",
            str(work / f"{tag}.pc2"), "--measures", str(work / f"{tag}.csv"), "--size", str(size),
            "--msaa", "0", "--force", "-q"]


def run(tag: str, argv: list[str], frames: int) -> dict:
    res, total = run_child(__file__, argv)
    row = {"bench": "physics_memory", "run": tag, "frames": frames, "wall_s": round(res["wall_s"], 2),
           "peak_rss_mb": round(res["peak_rss_mb"], 1)}
    print(json.dumps(row), flush=True)
    return row


def summary(name: str, short: dict, long_: dict) -> None:
    ratio = long_["peak_rss_mb"] / short["peak_rss_mb"]
    print(json.dumps({"bench": "physics_memory_summary", "command": name,
                      "frames_ratio": round(long_["frames"] / short["frames"], 2),
                      "peak_rss_ratio_long_short": round(ratio, 3), "memory_ok": ratio <= 1.10}), flush=True)


def main() -> None:
    if len(sys.argv) == 3 and sys.argv[1] == "--child":
        child(json.loads(sys.argv[2]))
        return
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--resolution", type=int, default=1500, help="face vertices (default 1500; the default "
                    "face has 4446)")
    ap.add_argument("--size", type=int, default=256)
    args = ap.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        work = Path(tmp)
        from visemeface.face.procedural import default_face

        face = work / "face.obj"
        default_face(resolution=args.resolution).save(face)
        rows = []
        for seconds in (1.0, 3.0):
            transcript = work / f"speech_{seconds:g}s.txt"
            end = write_transcript(transcript, seconds)
            argv = ["speak", str(transcript), "--physics", "sticky", "--face", str(face), "--fps", "30",
                    *_outputs(f"speak{seconds:g}", work, args.size)]
            rows.append(run(f"speak --physics sticky, {end:.2f} s", argv, round(end * 30)))
        summary("speak --physics sticky", *rows)
        rows = []
        for fps in (40, 120):
            argv = ["simulate", "part", "--resolution", str(args.resolution), "--fps", str(fps),
                    *_outputs(f"simulate{fps}", work, args.size)]
            rows.append(run(f"simulate part at {fps} fps", argv, round(0.75 * fps) + 1))
        summary("simulate", *rows)


if __name__ == "__main__":
    main()
