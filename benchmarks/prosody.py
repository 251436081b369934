"""What the recording's analysis (JA/LI articulation and the prosodic gestures) adds to ``speak rec.wav --no-video``.

For each GRID clip (default ``../shared/realdata``), ``visemeface speak CLIP --text WORDS --no-video --track
OUT.csv`` runs in fresh processes with ``--articulation 0 --no-gestures`` (no analysis) and with the defaults,
alternately, ``--repeat`` times each; prints one JSON line per clip with the median wall and CPU seconds of
both and the added share (target: at most 20 %), and the analysis alone (level, YIN pitch, LPC formants,
articulation factors and gestures) timed in this process.

Run: ``PYTHONPATH=src python benchmarks/prosody.py [--realdata DIR] [--repeat 3]``
"""

from __future__ import annotations

import argparse
import json
import statistics
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _runner import child, run_child  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
TEXTS = {"swwp2s": "set white with p two soon", "bbaf2n": "bin blue at f two now",
         "lbax4n": "lay blue at x four now"}


def analysis_seconds(path: Path, text: str, folder: str) -> float:
    """Seconds of the analysis alone, as ``speak`` runs it: its sound track's WAV read once more and analysed."""
    from visemeface.animate import jali_factors, recording_acoustics
    from visemeface.speech.align import utterance_from_audio
    from visemeface.speech.audio import media_wav
    from visemeface.speech.gestures import speech_gestures

    wav = media_wav(path, folder)
    utt = utterance_from_audio(wav, text)
    t0 = time.perf_counter()
    ac = recording_acoustics(wav)
    jali_factors(utt, ac)
    speech_gestures(utt, int(utt.end * 30) + 1, 30.0, ac)
    return time.perf_counter() - t0


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--child")
    ap.add_argument("--realdata", type=Path, default=ROOT.parent / "shared" / "realdata")
    ap.add_argument("--repeat", type=int, default=3)
    args = ap.parse_args()
    if args.child:
        child(json.loads(args.child))
        return 0
    import warnings

    warnings.simplefilter("ignore")
    clips = [p for p in sorted(args.realdata.glob("*.mpg")) if p.stem in TEXTS]
    if not clips:
        print(f"prosody benchmark: no GRID clip in {args.realdata}", file=sys.stderr)
        return 2
    with tempfile.TemporaryDirectory() as tmp:
        for clip in clips:
            runs: dict[str, list[dict]] = {"off": [], "on": []}
            for _ in range(args.repeat):
                for mode, extra in (("off", ["--articulation", "0", "--no-gestures"]), ("on", [])):
                    argv = ["speak", str(clip), "--text", TEXTS[clip.stem], "--no-video", "--track",
                            str(Path(tmp) / f"{clip.stem}_{mode}.csv"), "--force", "-q", *extra]
                    res, _ = run_child(__file__, argv)
                    runs[mode].append(res)
            wall = {m: statistics.median(r["wall_s"] for r in rs) for m, rs in runs.items()}
            cpu = {m: statistics.median(r["cpu_s"] for r in rs) for m, rs in runs.items()}
            print(json.dumps({"bench": "prosody", "clip": clip.stem, "repeat": args.repeat,
                              "wall_s_without": round(wall["off"], 3), "wall_s_with": round(wall["on"], 3),
                              "cpu_s_without": round(cpu["off"], 3), "cpu_s_with": round(cpu["on"], 3),
                              "added_wall_pct": round(100 * (wall["on"] / wall["off"] - 1), 1),
                              "added_cpu_pct": round(100 * (cpu["on"] / cpu["off"] - 1), 1),
                              "analysis_alone_s": round(analysis_seconds(clip, TEXTS[clip.stem], tmp), 3)}), flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
