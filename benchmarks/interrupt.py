"""How fast the command line refuses bad input and ends after Ctrl-C (the speeds tests no longer assert).

Prints JSON lines: ``startup`` (interpreter + ``import visemeface.cli``, the tests' baseline), ``refuse``
(a fresh process refusing a bad option: the parser's imports included), and ``interrupt`` (seconds from
SIGINT/SIGTERM to the exit of a running ``simulate`` and ``say``, and its exit status), each the median of
``--repeat`` runs.

Run: ``PYTHONPATH=src python benchmarks/interrupt.py [--repeat 3]``
"""

from __future__ import annotations

import argparse
import json
import signal
import statistics
import subprocess
import sys
import tempfile
import time

RUNS = {
    "simulate": ["simulate", "part", "--resolution", "800", "--size", "32", "--msaa", "0", "-o", "s.mp4", "-q"],
    "say": ["say", "bob moves five boats past the old mill while seven quiet sheep watch", "--rate", "60",
            "--size", "64", "--msaa", "0", "-o", "t.mp4", "-q", "--silent"],
}


def _time(argv, cwd) -> float:
    t0 = time.monotonic()
    subprocess.run(argv, cwd=cwd, capture_output=True)
    return time.monotonic() - t0


def _interrupt(argv, cwd, sig, after: float) -> tuple[float, int]:
    proc = subprocess.Popen([sys.executable, "-m", "visemeface", *argv], cwd=cwd, stdout=subprocess.DEVNULL,
                            stderr=subprocess.DEVNULL)
    time.sleep(after)
    t0 = time.monotonic()
    proc.send_signal(sig)
    proc.wait(timeout=120)
    return time.monotonic() - t0, proc.returncode


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--after", type=float, default=8.0, help="seconds after launch the signal comes (default 8)")
    a = ap.parse_args()
    with tempfile.TemporaryDirectory() as cwd:
        start = [_time([sys.executable, "-c", "import visemeface.cli"], cwd) for _ in range(a.repeat)]
        print(json.dumps({"what": "startup", "median_s": round(statistics.median(start), 3)}), flush=True)
        bad = [_time([sys.executable, "-m", "visemeface", "simulate", "part", "--dt", "1e-308"], cwd)
               for _ in range(a.repeat)]
        print(json.dumps({"what": "refuse", "argv": "simulate part --dt 1e-308",
                          "median_s": round(statistics.median(bad), 3)}), flush=True)
        for name, argv in RUNS.items():
            for sig in (signal.SIGINT, signal.SIGTERM):
                got = [_interrupt(argv, cwd, sig, a.after) for _ in range(a.repeat)]
                print(json.dumps({"what": "interrupt", "command": name, "signal": sig.name,
                                  "median_s": round(statistics.median(g[0] for g in got), 3),
                                  "status": sorted({g[1] for g in got})}), flush=True)


if __name__ == "__main__":
    main()
