"""Real and synthetic mouths side by side: each ../shared/realdata sentence rendered and compared.

For every GRID clip in the realdata folder (default ``../shared/realdata``; see its README):

1. the sentence is spelled from the file name by the GRID grammar (``swwp2s`` = "set white with p
   two soon") and turned into timed phonemes (``g2p.text_to_utterance``); where a word alignment
   exists (``<clip>.align``: ``start end word``, 1/25000 s) the phonemes are mapped piecewise
   linearly onto it (word by word), otherwise the speech is stretched onto the clip's audio
   (``g2p``'s speech span, which issue 15 replaces with a noise-floor detector);
2. the default face is animated at the clip's 25 fps and rendered (256 x 256, mouth view);
3. real and synthetic frames are analysed with the same :class:`OpeningDetector` settings (the
   real clip with the automatic mouth box, the render with the renderer's box);
4. the figures of ``visemeface compare`` are printed: L2 distance, Pearson r per metric, the best
   lag within +-5 frames and r there; ``--out DIR`` also writes both profiles and an overlay plot.

Run: ``python scripts/compare_realdata.py [--realdata DIR] [--out DIR]``

The GRID clips are the GRID corpus's (Cooke, Barker, Cunningham & Shao, JASA 120:2421, 2006).
"""

from __future__ import annotations

import argparse
import json
import subprocess
import tempfile
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]

GRAMMAR = [
    {"b": "bin", "l": "lay", "p": "place", "s": "set"},
    {"b": "blue", "g": "green", "r": "red", "w": "white"},
    {"a": "at", "b": "by", "i": "in", "w": "with"},
    None,                                   # a letter, said as itself
    {str(d): w for d, w in enumerate("zero one two three four five six seven eight nine".split())},
    {"a": "again", "n": "now", "p": "please", "s": "soon"},
]


def grid_sentence(name: str) -> str:
    """The sentence a six-character GRID file name spells."""
    if len(name) != 6:
        raise ValueError(f"not a GRID name: {name!r}")
    return " ".join(ch if table is None else table[ch] for ch, table in zip(name, GRAMMAR))


def read_align(path: Path) -> list[tuple[float, float, str]]:
    """GRID word alignment: ``start end word`` in 1/25000 s -> seconds, silences dropped."""
    rows = []
    for line in path.read_text().split("\n"):
        parts = line.split()
        if len(parts) == 3 and parts[2] != "sil":
            rows.append((int(parts[0]) / 25000.0, int(parts[1]) / 25000.0, parts[2]))
    return rows


def aligned_utterance(utt, words: list[tuple[float, float, str]], duration: float):
    """Map the utterance's times piecewise linearly so that its words fall on the alignment's."""
    w = utt.words
    if len(w) != len(words):
        raise ValueError(f"{len(w)} words in the text, {len(words)} in the alignment")
    src = [0.0] + [t for s, e in zip(w["start"], w["end"]) for t in (s, e)] + [utt.end]
    dst = [0.0] + [t for s, e, _ in words for t in (s, e)] + [duration]
    src, dst = np.maximum.accumulate(np.asarray(src, float)), np.maximum.accumulate(np.asarray(dst, float))
    seg = utt.segments.copy()
    seg["start"] = np.interp(seg["start"], src, dst)
    seg["end"] = np.interp(seg["end"], src, dst)
    seg = seg[seg["end"] > seg["start"] + 1e-9].reset_index(drop=True)
    return seg


def extract_audio(video: Path, wav: Path) -> None:
    import imageio_ffmpeg
    subprocess.run([imageio_ffmpeg.get_ffmpeg_exe(), "-v", "error", "-y", "-i", str(video), "-ac", "1",
                    "-ar", "16000", str(wav)], check=True)


def synthetic_profile(segments, fps: float, n_frames: int, detector):
    """Render the default face along the segments and analyse it: the profile."""
    from visemeface.analysis.profiles import analyze_frames
    from visemeface.motion import KinematicMotion
    from visemeface.muscles.rig import default_rig
    from visemeface.postures.library import load_visemes
    from visemeface.render.renderer import Renderer
    from visemeface.speech.timeline import activation_track

    rig = default_rig()
    track = activation_track(segments, load_visemes(), fps=fps)
    motion = KinematicMotion(rig, track)
    with Renderer(rig.face, size=(256, 256), view="mouth") as renderer:
        box = renderer.mouth_box()
        frames = [renderer.render(f.vertices) for f in motion.frames()][:n_frames]
    return analyze_frames(frames, box, fps, detector, source="synthetic")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--realdata", type=Path, default=ROOT.parent / "shared" / "realdata")
    ap.add_argument("--out", type=Path, help="also write <clip>_real.csv, <clip>_synth.csv, <clip>.png here")
    args = ap.parse_args()

    from visemeface.analysis.mouthbox import track_mouth
    from visemeface.analysis.openings import OpeningDetector
    from visemeface.analysis.profiles import analyze_frames, correlation, l2_distance, plot_profiles, \
        shifted_profile, write_profile
    from visemeface.analysis.video import open_frames
    from visemeface.speech.g2p import text_to_utterance

    detector = OpeningDetector()
    if args.out:
        args.out.mkdir(parents=True, exist_ok=True)
    for video in sorted(args.realdata.glob("*.mpg")):
        clip = video.stem
        text = grid_sentence(clip)
        source = open_frames(video)
        frames = list(source.frames())
        real = analyze_frames(frames, track_mouth(frames, source=clip), source.fps, detector, source=clip)
        duration = len(frames) / source.fps
        align = video.with_suffix(".align")
        if align.exists():
            segments = aligned_utterance(text_to_utterance(text, warn=False), read_align(align), duration)
            timing = "alignment"
        else:
            with tempfile.TemporaryDirectory() as tmp:
                wav = Path(tmp) / "a.wav"
                extract_audio(video, wav)
                segments = text_to_utterance(text, audio=wav, warn=False).segments
            timing = "audio span"
        synth = synthetic_profile(segments, source.fps, len(frames), detector)
        d = l2_distance(real, synth)
        c = correlation(real, synth, max_lag=5)
        print(json.dumps({"clip": clip, "text": text, "timing": timing, "frames": len(frames),
                          "open_frames_real": int((real["count"] > 0).sum()),
                          "open_frames_synth": int((synth["count"] > 0).sum()),
                          "l2": {k: round(v, 4) for k, v in d.items()},
                          "r": {k: round(v, 3) for k, v in c["r"].items()},
                          "best_lag_frames": c["lag"], "r_height_at_lag": round(c["r_lag"], 3)}), flush=True)
        if args.out:
            write_profile(real, args.out / f"{clip}_real.csv", force=True)
            write_profile(synth, args.out / f"{clip}_synth.csv", force=True)
            plot_profiles({f"{clip} real": real, f"synthetic (shifted {-c['lag_s']:+.2f} s)":
                           shifted_profile(synth, c["lag_s"])}, args.out / f"{clip}.png",
                          metrics=("count", "area", "width", "height"), title=f'"{text}"', force=True)


if __name__ == "__main__":
    main()
