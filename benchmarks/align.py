"""Alignment speed: forced alignment and phone recognition as a real-time factor, on one core.

Prints one JSON line per clip and mode (``aligned`` with the clip's words, ``recognised``
without): the recording's length, the first call in a fresh process (decoder set-up, model
loading and decoding of the file included; Python's imports excluded, reported apart) and a
second call, and ``rtf_first`` = audio seconds / first-call seconds (target >= 5, issue 15);
``rtf_first_cpu`` divides by the CPU time of the first call instead (this process and its ffmpeg
children), which a machine busy with other work does not inflate.

Run: ``PYTHONPATH=src python benchmarks/align.py [--realdata ../shared/realdata]``
(the three GRID clips; without them, 1.4 s of synthesised vowels).
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
TEXTS = {"swwp2s": "set white with p two soon", "bbaf2n": "bin blue at f two now",
         "lbax4n": "lay blue at x four now"}


def _cpu() -> float:
    """CPU seconds of this process and its finished children (ffmpeg), user + system."""
    import resource

    me, kids = resource.getrusage(resource.RUSAGE_SELF), resource.getrusage(resource.RUSAGE_CHILDREN)
    return me.ru_utime + me.ru_stime + kids.ru_utime + kids.ru_stime


def child(path: str, text: str) -> None:
    if hasattr(os, "sched_setaffinity"):
        os.sched_setaffinity(0, {sorted(os.sched_getaffinity(0))[0]})     # one core
    t0 = time.perf_counter()
    import warnings

    from visemeface.speech.align import utterance_from_audio
    from visemeface.speech.audio import read_audio

    warnings.simplefilter("ignore")
    imports = time.perf_counter() - t0
    samples, rate = read_audio(path)
    audio_s = samples.size / rate
    c0 = _cpu()
    t0 = time.perf_counter()
    utterance_from_audio(path, text or None)
    first = time.perf_counter() - t0
    first_cpu = _cpu() - c0
    t0 = time.perf_counter()
    utterance_from_audio(path, text or None)
    second = time.perf_counter() - t0
    print(json.dumps({"benchmark": "align", "clip": Path(path).stem, "mode": "aligned" if text else "recognised",
                      "audio_s": round(audio_s, 3), "imports_s": round(imports, 3), "first_s": round(first, 3),
                      "second_s": round(second, 3), "first_cpu_s": round(first_cpu, 3),
                      "rtf_first": round(audio_s / first, 1), "rtf_first_cpu": round(audio_s / first_cpu, 1),
                      "rtf_second": round(audio_s / second, 1)}))


def synthetic_vowels(path: Path) -> None:
    import numpy as np
    import soundfile as sf
    from scipy.signal import lfilter

    rate = 16000

    def vowel(formants):
        x = np.zeros(int(0.4 * rate))
        x[::rate // 120] = 1.0
        for f, bw in formants:
            r = np.exp(-np.pi * bw / rate)
            x = lfilter([1 - r], [1, -2 * r * np.cos(2 * np.pi * f / rate), r * r], x)
        return x / np.abs(x).max() * 0.5

    sf.write(str(path), np.r_[np.zeros(4000), vowel([(730, 90), (1090, 110), (2440, 170)]), np.zeros(1600),
                              vowel([(270, 60), (2290, 100), (3010, 150)]), np.zeros(4000)], rate)


def main() -> int:
    if len(sys.argv) > 1 and sys.argv[1] == "--child":
        child(sys.argv[2], sys.argv[3])
        return 0
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--realdata", type=Path, default=ROOT.parent / "shared" / "realdata")
    args = ap.parse_args()
    cases = [(args.realdata / f"{c}.mpg", t) for c, t in TEXTS.items() if (args.realdata / f"{c}.mpg").is_file()]
    if not cases:
        import tempfile

        path = Path(tempfile.mkdtemp()) / "vowels.wav"
        synthetic_vowels(path)
        cases = [(path, "ah ee")]
    env = dict(os.environ, PYTHONPATH=str(ROOT / "src") + os.pathsep + os.environ.get("PYTHONPATH", ""))
    for path, text in cases:
        for words in (text, ""):
            subprocess.run([sys.executable, __file__, "--child", str(path), words], check=True, env=env)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
