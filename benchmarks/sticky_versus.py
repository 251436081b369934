"""``speak --physics sticky`` on the 3 s example: this checkout against an earlier version, in one run.

    PYTHONPATH=src python benchmarks/sticky_versus.py --rev cdbfff9      # the code before issue 16

Issue 16 asks that sticky lips v2 not cost more than 25 % over what ``speak --physics sticky`` cost
before it. This times the whole command (transcript -> simulated face -> rendered MP4, the 3 s
example ``transcripts/one_five_zero_zero_six.txt`` at 30 fps) three ways, each in a fresh process
(:func:`_runner.run_child`): the version ``--rev`` (checked out into a temporary git worktree and
run from its ``src/``), this checkout's speech default (lips refined along the seam, cohesive film
into the corners, the tissue that stiffens) and this checkout with the seed's model (``--seam-elements 0
--rupture-time 0 --no-film-corners --tissue-limit inf``). Each is run once untimed first, so numba's compiled cache is warm for all
three. One JSON line per timed run, then the ratios to the first.
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
import tempfile
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _runner import child, run_child  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
SEED = ["--seam-elements", "0", "--rupture-time", "0", "--no-film-corners", "--tissue-limit", "inf"]


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--rev", default="cdbfff9", help="the earlier version (git revision; default cdbfff9, "
                    "main just before issue 16's first commit)")
    ap.add_argument("--child", help=argparse.SUPPRESS)
    args = ap.parse_args(argv)
    if args.child:
        return child(json.loads(args.child))
    from visemeface.export.video import read_video_info
    transcript = str(ROOT / "transcripts" / "one_five_zero_zero_six.txt")
    with tempfile.TemporaryDirectory() as tmp:
        tree = Path(tmp) / "rev"
        subprocess.run(["git", "-C", str(ROOT), "worktree", "add", "-q", "--detach", str(tree), args.rev],
                       check=True)
        try:
            runs = [(f"{args.rev} (before)", tree / "src", []), ("speech default", None, []),
                    ("seed's model", None, SEED)]
            first = None
            for label, src, extra in runs:
                out = str(Path(tmp) / "out.mp4")
                cmd = ["speak", transcript, "--physics", "sticky", *extra, "-o", out, "--force", "-q"]
                run_child(__file__, cmd, src)                        # warm numba's cache
                res, _ = run_child(__file__, cmd, src)
                first = first or res["wall_s"]
                seconds = (read_video_info(out)["n_frames"] - 1) / 30.0
                print(json.dumps({"benchmark": "sticky_versus", "version": label, "extra": " ".join(extra),
                                  "wall_s": round(res["wall_s"], 1), "simulated_s": round(seconds, 3),
                                  "wall_per_simulated_s": round(res["wall_s"] / seconds, 1),
                                  "ratio_to_first": round(res["wall_s"] / first, 2), "load1": res["load1"]}),
                      flush=True)
        finally:
            subprocess.run(["git", "-C", str(ROOT), "worktree", "remove", "--force", str(tree)], check=False)


if __name__ == "__main__":
    main()
