"""Real and synthetic mouths side by side: each ../shared/realdata sentence rendered and compared.

For every GRID clip in the realdata folder (default ``../shared/realdata``; see its README):

1. the sentence is spelled from the file name by the GRID grammar (``swwp2s`` = "set white with p
   two soon") and timed (``--timing``): ``align`` (default) force-aligns it to the clip's own audio
   (:func:`visemeface.speech.align.utterance_from_audio`, phone by phone); ``grid`` keeps the older
   timing: ``g2p.text_to_utterance`` mapped piecewise linearly onto the word alignment where one
   exists (``<clip>.align``: ``start end word``, 1/25000 s), else stretched onto the audio's
   speech span (:func:`visemeface.speech.audio.speech_span`, relative to the noise floor);
2. the default face is animated at the clip's 25 fps and rendered (256 x 256, mouth view);
3. real and synthetic frames are analysed with the same :class:`OpeningDetector` settings (the
   real clip with the automatic mouth box, the render with the renderer's box);
4. the figures of ``visemeface compare`` are printed: L2 distance, Pearson r per metric, the best
   lag within +-5 frames and r there, over the whole clip; and the opening-height r over the
   audio's speech span (:func:`speech_correlation`, the figure ``lipsync_acceptance.py`` prints
   too); ``--out DIR`` also writes both profiles and an overlay plot.

``--releases`` also prints how each opening grows, real and ours
(:func:`visemeface.analysis.profiles.opening_onsets`: frames to 90 % of its width, the height's
power-law exponent), and the medians over the openings that last ``RELEASE_RUN`` frames or more.

Run: ``python scripts/compare_realdata.py [--realdata DIR] [--timing align|grid] [--physics sticky|elastic]
[--out DIR] [--per-phone] [--releases] [--tissue-limit L]`` (``--physics``: the FEM face instead of the kinematic
one).

The GRID clips are the GRID corpus's (Cooke, Barker, Cunningham & Shao, JASA 120:2421, 2006).
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
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
    """Map the utterance's times piecewise linearly so that its words fall on the alignment's: with one
    "word" spanning the whole text (``len(words) == 1``), its speech is stretched onto that span."""
    w = utt.words
    if len(words) == 1:
        w = {"start": [w["start"].iloc[0]], "end": [w["end"].iloc[-1]]}
    elif len(w) != len(words):
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


def synthetic_profile(segments, fps: float, n_frames: int, detector, physics: str | None = None,
                      tissue_limit: float | None = None, jali=None):
    """Render the default face along the segments (kinematic, or the FEM face with ``physics`` sticky or
    elastic as ``speak --physics [--tissue-limit]`` runs it; ``tissue_limit`` None: speak's) and analyse it: the
    profile. ``jali``: per-segment (ja, li) articulation factors (:mod:`visemeface.speech.articulation`)."""
    from visemeface.analysis.profiles import analyze_frames
    from visemeface.motion import KinematicMotion
    from visemeface.muscles.rig import default_rig
    from visemeface.postures.library import load_visemes
    from visemeface.render.renderer import Renderer
    from visemeface.speech.timeline import activation_track

    rig = default_rig()
    track = activation_track(segments, load_visemes(), fps=fps, jali=jali)
    if physics is None:
        motion = KinematicMotion(rig, track)
    else:
        from visemeface.animate import simulated_motion
        from visemeface.physics.drive import PhysicsSettings
        motion = simulated_motion(rig, track, physics,          # the speech commands' FEM face
                                  PhysicsSettings.speech() if tissue_limit is None
                                  else PhysicsSettings.speech(tissue_limit=tissue_limit))
    with Renderer(motion.render_face, size=(256, 256), view="mouth") as renderer:
        box = renderer.mouth_box()
        frames = [renderer.render(f.vertices) for f in motion.frames()][:n_frames]
    return analyze_frames(frames, box, fps, detector, source="synthetic")


def real_profile(video: Path, detector=None):
    """The real clip's profile (automatic mouth box), its fps and frame count."""
    from visemeface.analysis.mouthbox import track_mouth
    from visemeface.analysis.openings import OpeningDetector
    from visemeface.analysis.profiles import analyze_frames
    from visemeface.analysis.video import open_frames

    source = open_frames(video)
    frames = list(source.frames())
    detector = detector or OpeningDetector()
    return analyze_frames(frames, track_mouth(frames, source=video.stem), source.fps, detector,
                          source=video.stem), source.fps, len(frames)


def speech_correlation(real, synth, video: Path, max_lag: int = 5) -> dict:
    """Opening-height Pearson r of two profiles over the audio's speech span, at lag 0 and the best lag.

    The span is :func:`visemeface.speech.audio.speech_span` of the clip's audio (relative to its noise
    floor); both profiles are cut to it before :func:`~visemeface.analysis.profiles.correlation`.
    Returns ``{"span_s": (t0, t1), "r": r at lag 0, "lag": frames, "r_lag": r there}``.
    """
    from visemeface.analysis.profiles import correlation, within
    from visemeface.speech.audio import read_audio, speech_span

    samples, rate = read_audio(video)
    t0, t1 = speech_span(samples, rate)
    cut = [within(df, t0, t1) for df in (real, synth)]
    c = correlation(*cut, columns=("height",), max_lag=max_lag)
    return {"span_s": (round(t0, 2), round(t1, 2)), "r": c["r"]["height"], "lag": c["lag"], "r_lag": c["r_lag"]}


def timed_segments(video: Path, text: str, timing: str, duration: float):
    """The sentence's timed phonemes: forced to the clip's audio (``align``) or the older ``grid`` timing."""
    from visemeface.speech.g2p import text_to_utterance

    if timing == "align":
        from visemeface.speech.align import utterance_from_audio
        return utterance_from_audio(video, text).segments, "forced alignment"
    align = video.with_suffix(".align")
    if align.exists():
        return aligned_utterance(text_to_utterance(text, warn=False), read_align(align), duration), "GRID .align"
    from visemeface.speech.audio import read_audio, speech_span

    with tempfile.TemporaryDirectory() as tmp:
        wav = Path(tmp) / "a.wav"
        extract_audio(video, wav)
        t0, t1 = speech_span(*read_audio(wav))
    return aligned_utterance(text_to_utterance(text, warn=False), [(t0, t1, text)], duration), "audio span"


def phone_heights(real, synth, segments, span_s, clip: str = "") -> list[tuple[str, str, float, float]]:
    """(clip, phone, real height, our height) for every frame inside ``span_s`` that a phone (not ``_``) covers."""
    rows = []
    for t, hr, hs in zip(real["time"], real["height"], synth["height"]):
        at = segments[(segments["start"] <= t) & (segments["end"] > t)]
        if span_s[0] <= t <= span_s[1] and len(at) and at["phoneme"].iloc[0] != "_":
            rows.append((clip, str(at["phoneme"].iloc[0]), float(hr), float(hs)))
    return rows


def phone_table(rows):
    """Mean opening height (mouth widths) per phone, real vs ours, pooled over the clips, and the same
    difference with each clip's own scale taken out.

    One recording of the speaker opens every phone wider or narrower than another, relative to its mouth
    width (measured: our heights are 0.61 to 1.32 times the speaker's, clip by clip, over the frames both
    mouths are open), so a phone seen in one clip only is otherwise judged by that clip's scale. A clip's
    scale is the median of ours / real over the frames where both are open (NaN for a clip with none:
    its frames then count in the pooled columns only); ``clip_adjusted`` is the mean of ours − scale × real
    (a shut mouth stays shut). Frames where either height is unknown (NaN) are left out. Returns (table,
    scales).
    """
    import pandas as pd

    df = pd.DataFrame(rows, columns=["clip", "phone", "real", "ours"]).dropna(subset=["real", "ours"])
    both = df[(df["real"] > 0) & (df["ours"] > 0)]
    scales = (both["ours"] / both["real"]).groupby(both["clip"]).median().reindex(df["clip"].unique())
    df["diff"] = df["ours"] - df["real"]
    df["adjusted"] = df["ours"] - df["clip"].map(scales) * df["real"]
    table = df.groupby("phone").agg(frames=("real", "size"), clips=("clip", "nunique"), real=("real", "mean"),
                                    ours=("ours", "mean"), real_open=("real", lambda x: float((x > 0).mean())),
                                    ours_minus_real=("diff", "mean"), clip_adjusted=("adjusted", "mean"))
    return table.sort_values("clip_adjusted"), scales


def print_phone_table(rows) -> None:
    """:func:`phone_table`, printed."""
    table, scales = phone_table(rows)
    print("opening height per aligned phone over the speech spans (mouth widths), all clips pooled; "
          "clip scales (median ours / real, both open): "
          + ", ".join(f"{c} {v:.2f}" if v == v else f"{c} n/a (no frame with both open)" for c, v in scales.items()))
    print(table.round(3).to_string())


#: An opening counts as a release into a vowel (``--releases``' medians) when it stays open this many frames.
RELEASE_RUN = 4


def release_rows(clip: str, profile) -> list[dict]:
    """:func:`opening_onsets` of a profile as JSON-ready rows."""
    from visemeface.analysis.profiles import opening_onsets

    o = opening_onsets(profile)
    return [{"clip": clip, "t": round(r.time, 2), "frames": int(r.frames), "peak_width": round(r.peak_width, 3),
             "frames_to_90pct": int(r.frames_to_90pct),
             "height_exponent": None if np.isnan(r.height_exponent) else round(r.height_exponent, 2)}
            for r in o.itertuples()]


def print_release_summary(rows: dict[str, list[dict]]) -> None:
    """Medians of frames to 90 % width and of the height exponent over the long openings, real vs ours."""
    out = {}
    for who, rs in rows.items():
        long = [r for r in rs if r["frames"] >= RELEASE_RUN]
        ex = [r["height_exponent"] for r in long if r["height_exponent"] is not None]
        out[who] = {"openings": len(long),
                    "frames_to_90pct": [r["frames_to_90pct"] for r in long],
                    "median_frames_to_90pct": float(np.median([r["frames_to_90pct"] for r in long])) if long else None,
                    "median_height_exponent": round(float(np.median(ex)), 2) if ex else None}
    print(json.dumps({"releases_summary": out, "min_frames_open": RELEASE_RUN}), flush=True)


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--realdata", type=Path, default=ROOT.parent / "shared" / "realdata")
    ap.add_argument("--timing", choices=("align", "grid"), default="align",
                    help="align: forced alignment of the text to the clip's audio (default); grid: the "
                         "word alignment file, else the text stretched onto the speech span")
    ap.add_argument("--out", type=Path, help="also write <clip>_real.csv, <clip>_synth.csv, <clip>.png here")
    ap.add_argument("--physics", choices=("sticky", "elastic"),
                    help="animate the FEM face (default: the kinematic face)")
    ap.add_argument("--tissue-limit", type=float,
                    help="with --physics: the tissue's limiting stretch (Gent; default speak's, 2.8; inf: the seed's "
                         "neo-Hookean)")
    ap.add_argument("--per-phone", action="store_true",
                    help="also print the mean opening height per aligned phone, real vs ours, also with each "
                         "clip's scale taken out")
    ap.add_argument("--releases", action="store_true",
                    help="also print how each opening grows (frames to 90 %% width, height exponent), real vs ours")
    args = ap.parse_args()

    import warnings

    from visemeface.analysis.openings import OpeningDetector
    from visemeface.analysis.profiles import correlation, l2_distance, plot_profiles, shifted_profile, \
        write_profile
    from visemeface.physics.materials import TISSUE_LIMIT

    if args.tissue_limit is not None and not args.physics:
        print("compare_realdata: --tissue-limit needs --physics sticky or elastic", file=sys.stderr)
        return 2
    tissue_limit = TISSUE_LIMIT if args.tissue_limit is None else args.tissue_limit      # speak's unless given
    limit = {"tissue_limit": tissue_limit if tissue_limit < float("inf") else "inf"} if args.physics else {}  # strict JSON
    videos = sorted(args.realdata.glob("*.mpg"))
    if not videos:
        print(f"compare_realdata: no GRID clip (*.mpg) in {args.realdata} (--realdata: the folder of "
              "../shared/realdata/README.md)", file=sys.stderr)
        return 2
    warnings.simplefilter("ignore")
    detector = OpeningDetector()
    if args.out:
        args.out.mkdir(parents=True, exist_ok=True)
    rows, releases = [], {"real": [], "ours": []}
    for video in videos:
        clip = video.stem
        text = grid_sentence(clip)
        real, fps, n = real_profile(video, detector)
        segments, timing = timed_segments(video, text, args.timing, n / fps)
        synth = synthetic_profile(segments, fps, n, detector, args.physics, tissue_limit)
        d = l2_distance(real, synth)
        c = correlation(real, synth, max_lag=5)
        sp = speech_correlation(real, synth, video)
        rows += phone_heights(real, synth, segments, sp["span_s"], clip)
        print(json.dumps({"clip": clip, "text": text, "timing": timing, "physics": args.physics, **limit, "frames": n,
                          "open_frames_real": int((real["count"] > 0).sum()),
                          "open_frames_synth": int((synth["count"] > 0).sum()),
                          "l2": {k: round(v, 4) for k, v in d.items()},
                          "r": {k: round(v, 3) for k, v in c["r"].items()},
                          "best_lag_frames": c["lag"], "r_height_at_lag": round(c["r_lag"], 3),
                          "speech_s": sp["span_s"], "r_height_speech": round(sp["r"], 3),
                          "best_lag_speech": sp["lag"], "r_height_speech_at_lag": round(sp["r_lag"], 3)}),
              flush=True)
        if args.releases:
            for who, prof in (("real", real), ("ours", synth)):
                found = release_rows(clip, prof)
                releases[who] += found
                print(json.dumps({"clip": clip, "releases": who, "openings": found}), flush=True)
        if args.out:
            write_profile(real, args.out / f"{clip}_real.csv", force=True)
            write_profile(synth, args.out / f"{clip}_synth.csv", force=True)
            plot_profiles({f"{clip} real": real, f"synthetic (shifted {-c['lag_s']:+.2f} s)":
                           shifted_profile(synth, c["lag_s"])}, args.out / f"{clip}.png",
                          metrics=("count", "area", "width", "height"), title=f'"{text}"', force=True)
    if args.per_phone:
        print_phone_table(rows)
    if args.releases:
        print_release_summary(releases)
    return 0


if __name__ == "__main__":
    sys.exit(main())
