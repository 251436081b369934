"""Shared by the benchmarks: a timed test utterance and a CLI run in a fresh process.

A benchmark runs ``python benchmarks/<name>.py --child '<argv as JSON>'`` (:func:`run_child`),
which runs the CLI in-process (:func:`child`) and prints its own wall time and peak
resident memory (``ru_maxrss`` of the process; its children's, e.g. ffmpeg, separately).
"""

from __future__ import annotations

import json
import os
import resource
import subprocess
import sys
import time
from pathlib import Path

# "one five zero zero six" in DECtalk symbols with durations (s); "_" = pause.
WORDS = [
    [("w", 0.08), ("ah", 0.14), ("n", 0.09)],
    [("f", 0.10), ("ay", 0.18), ("v", 0.08)],
    [("z", 0.09), ("ir", 0.12), ("ow", 0.15)],
    [("z", 0.09), ("ir", 0.12), ("ow", 0.15)],
    [("s", 0.11), ("ih", 0.09), ("k", 0.07), ("s", 0.12)],
]


def write_transcript(path: Path, seconds: float) -> float:
    """Timed ``start end phone`` lines repeating the digits until ``seconds``; returns the end."""
    t, lines = 0.0, ["# benchmark: 'one five zero zero six' repeated"]
    while True:
        for word in WORDS:
            for phone, dur in word + [("_", 0.06)]:
                if t + dur > seconds:
                    path.write_text("\n".join(lines) + "\n")
                    return t
                lines.append(f"{t:.3f} {t + dur:.3f} {phone}")
                t += dur


def child(argv: list[str]) -> None:
    """Run the CLI with ``argv`` in this process and print its wall time and peak memory as JSON."""
    from visemeface.cli import main

    t0 = time.perf_counter()
    code = main(argv)
    wall = time.perf_counter() - t0
    me = resource.getrusage(resource.RUSAGE_SELF)
    kids = resource.getrusage(resource.RUSAGE_CHILDREN)
    print(json.dumps({"code": code, "wall_s": wall, "peak_rss_mb": me.ru_maxrss / 1024,
                      "ffmpeg_peak_rss_mb": kids.ru_maxrss / 1024,
                      "cpu_s": me.ru_utime + me.ru_stime + kids.ru_utime + kids.ru_stime,
                      "load1": os.getloadavg()[0]}))


def run_child(script: str, argv: list[str], src: str | Path | None = None) -> tuple[dict, float]:
    """Run ``script --child argv`` in a fresh Python with ``src`` (default: this checkout's src/) first on
    its path, so another version's package can be timed; (its JSON line, wall seconds)."""
    env = dict(os.environ)
    src = str(src or Path(__file__).resolve().parents[1] / "src")
    env["PYTHONPATH"] = src + os.pathsep + env.get("PYTHONPATH", "")
    t0 = time.perf_counter()
    proc = subprocess.run([sys.executable, script, "--child", json.dumps(argv)], capture_output=True, text=True,
                          env=env)
    total = time.perf_counter() - t0
    if proc.returncode != 0:
        raise SystemExit(f"{argv[0]} failed:\n{proc.stderr}")
    res = json.loads(proc.stdout.strip().splitlines()[-1])
    if res["code"] != 0:
        raise SystemExit(f"{argv[0]} exited {res['code']}:\n{proc.stderr}")
    return res, total
