"""Right text against wrong text: the alignment's word margins on the GRID clips, clean and degraded.

For each clip and degradation (:data:`visemeface.speech.degrade.KINDS`) and each text (the clip's
own, the other two clips' texts, four other GRID sentences, and a near miss with one word changed),
prints one JSON line: the verdict (``accepted``, ``refused``, or ``unaligned``: no path found, refused
too), each word's margin (forced alignment's score minus the free phone loop's on the same frames, per
10 ms frame; :mod:`visemeface.speech.align`) and ``statistic``, the margin of the word that decides:
the (allowed + 1)-th lowest, which must reach ``DOUBTFUL_MARGIN`` for the text to pass. Then one
``summary`` line per group (``tuning``: the cases the threshold was chosen on; ``held_out``: the
rest): the lowest statistic of a right text, the highest of a wrong one, their gap, and how many right
texts were refused and wrong ones accepted.

Run: ``PYTHONPATH=src python benchmarks/align_margin.py [--realdata ../shared/realdata] [--kinds clean,reverb]``
(about 10 minutes for every kind on one free core).
"""

from __future__ import annotations

import argparse
import json
import math
import sys
import time
import warnings
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
TEXTS = {"swwp2s": "set white with p two soon", "bbaf2n": "bin blue at f two now",
         "lbax4n": "lay blue at x four now"}
OTHERS = ["place green by a one again", "set red in g nine please", "bin white with z zero soon",
          "lay green by q seven again"]
NEAR = {"swwp2s": "set white with t two soon", "bbaf2n": "bin blue at f three now",
        "lbax4n": "lay red at x four now"}
#: The cases DOUBTFUL_MARGIN was chosen on (docs/notes/alignment_margin.md); every other one is held out.
TUNING_CLIPS = ("swwp2s", "bbaf2n")
TUNING_KINDS = ("clean", "quiet30", "white15", "speed0.85")


def judge(pcm, reference, text):
    """(verdict, word margins, statistic) of ``text`` against the audio (16 kHz PCM) and its phone loop's
    per-frame reference (:func:`visemeface.speech.align._loop_reference`, computed once per recording)."""
    import numpy as np

    from visemeface.errors import InputError
    from visemeface.speech import align

    words = text.split()
    try:
        aligned = align._force_align(pcm, words, None)
    except InputError:
        return "unaligned", [], None
    margins = align.word_margins(aligned, reference)
    try:
        align._check_match(words, margins, None)
        verdict = "accepted"
    except InputError:
        verdict = "refused"
    allowed = math.floor(max(align.DOUBTFUL_FRACTION * len(words), min(1, len(words) - 1)))
    ordered = np.sort(margins[np.isfinite(margins)])
    statistic = float(ordered[min(allowed, ordered.size - 1)]) if ordered.size else None
    return verdict, [round(float(m), 1) for m in margins], statistic


def main() -> int:
    from visemeface.speech.align import DOUBTFUL_MARGIN, _loop_reference, model_pcm
    from visemeface.speech.audio import read_audio
    from visemeface.speech.degrade import KINDS, degrade

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--realdata", type=Path, default=ROOT.parent / "shared" / "realdata")
    ap.add_argument("--kinds", default=",".join(KINDS), help="comma-separated degradations (default: all)")
    args = ap.parse_args()
    kinds = args.kinds.split(",")
    clips = [c for c in TEXTS if (args.realdata / f"{c}.mpg").is_file()]
    if not clips:
        print(f"no GRID clips in {args.realdata}", file=sys.stderr)
        return 1
    warnings.simplefilter("ignore")                        # the telephone copy's 8 kHz warning
    groups = {"tuning": {"right": [], "wrong": [], "bad_right": 0, "bad_wrong": 0},
              "held_out": {"right": [], "wrong": [], "bad_right": 0, "bad_wrong": 0}}
    for clip in clips:
        original, rate0 = read_audio(args.realdata / f"{clip}.mpg")
        cases = ([("right", TEXTS[clip]), ("near", NEAR[clip])] + [("swap", t) for c, t in TEXTS.items() if c != clip]
                 + [("other", t) for t in OTHERS])
        for kind in kinds:
            samples, rate = degrade(original, rate0, kind)
            pcm = model_pcm(samples, rate)
            reference = _loop_reference(pcm)
            group = groups["tuning" if clip in TUNING_CLIPS and kind in TUNING_KINDS else "held_out"]
            for case, text in cases:
                t0 = time.perf_counter()
                verdict, margins, statistic = judge(pcm, reference, text)
                print(json.dumps({"benchmark": "align_margin", "clip": clip, "kind": kind, "case": case, "text": text,
                                  "verdict": verdict, "statistic": None if statistic is None else round(statistic, 1),
                                  "word_margins": margins, "seconds": round(time.perf_counter() - t0, 2)}), flush=True)
                if case == "right":
                    group["right"].append(statistic if statistic is not None else -math.inf)
                    group["bad_right"] += verdict != "accepted"
                elif case != "near":
                    group["wrong"].append(statistic if statistic is not None else -math.inf)
                    group["bad_wrong"] += verdict == "accepted"
    for name, g in groups.items():
        if not g["right"]:
            continue
        low, high = min(g["right"]), max(g["wrong"])
        print(json.dumps({"benchmark": "align_margin", "summary": name, "doubtful_margin": DOUBTFUL_MARGIN,
                          "right_texts": len(g["right"]), "wrong_texts": len(g["wrong"]),
                          "lowest_right_statistic": round(low, 1),
                          "highest_wrong_statistic": None if math.isinf(high) else round(high, 1),
                          "gap": None if math.isinf(high) or math.isinf(low) else round(low - high, 1),
                          "right_refused": g["bad_right"], "wrong_accepted": g["bad_wrong"]}))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
