"""Speech that moves like the speaker: JA/LI from the recording, stress without one, head motion from prosody.

Prints JSON lines, one section after another (``--only`` runs some):

``realdata``
    For each GRID clip of ``../shared/realdata`` (aligned to its own audio, 25 fps, rendered and analysed as
    ``compare_realdata.py`` does): the opening-height Pearson r over the speech span with the tabled visemes
    (``before``, ``--articulation 0``) and with the JA/LI factors measured on the recording (``after``), whether
    the clip was among those the gains of ``data/phonemes/articulation.csv`` were tuned on (``tuned_on``; the
    other is held out), and every bilabial closure's middle frame before and after (they must agree within one
    frame). ``--out DIR`` writes ``prosody_realdata.png``: real, before and after heights overlaid.
    ``oracle`` is the same r when each phone's JA factor is the real speaker's own opening over ours, phone by
    phone (a bound on what per-phone JA factors can reach with these visemes and this alignment; not a method).
    ``best_lag_frames_after`` and ``r_after_at_best_lag``: the lag (frames within +-5, positive where the real
    mouth leads ours) at which ``after`` correlates best, and r there (a timing error shows as a lag).
``stress``
    "I never said she stole my money" with one word emphasised each time (``*word*``), no recording: the
    mean jaw activation and rendered opening height over each word's vowels, and how much more the emphasised
    word's vowels open than the same word's in the plain reading.
``head``
    The three clips' audio four times over (36 s of speech), aligned to their words: the head's largest
    yaw/pitch/roll, the share of frames with every angle under 2 degrees, and each accent's F0 peak beside the
    nearest nod (head pitch maximum), their offset, and the run again with the same seed (identical).

Run: ``PYTHONPATH=src python scripts/prosody_acceptance.py [--realdata DIR] [--out DIR] [--only realdata,stress,head]``
"""

from __future__ import annotations

import argparse
import json
import sys
import warnings
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "scripts"))

#: The clips the articulation gains were chosen on (the third is held out).
TUNED_ON = ("swwp2s", "bbaf2n")
SENTENCE = "I never said she stole my money"
FPS = 25.0


def _closures(profile, segments, fps):
    """Middle frame of each bilabial's closed run (height 0) nearest its centre, or None where it never closes."""
    shut = (profile["count"].to_numpy() == 0)
    out = []
    for s, e, p in zip(segments["start"], segments["end"], segments["phoneme"]):
        if p not in ("p", "b", "m"):
            continue
        lo, hi = int(np.floor(s * fps)) - 1, int(np.ceil(e * fps)) + 1
        idx = [k for k in range(max(lo, 0), min(hi + 1, len(shut))) if shut[k]]
        out.append(None if not idx else float(np.mean(idx)))
    return out


def realdata(folder: Path, out: Path | None) -> None:
    import compare_realdata as cr

    from visemeface.analysis.openings import OpeningDetector
    from visemeface.speech.acoustics import analyse
    from visemeface.speech.articulation import acoustic_scales
    from visemeface.speech.audio import read_audio

    detector = OpeningDetector()
    plots = []
    for video in sorted(folder.glob("*.mpg")):
        clip = video.stem
        real, fps, n = cr.real_profile(video, detector)
        segments, _ = cr.timed_segments(video, cr.grid_sentence(clip), "align", n / fps)
        before = cr.synthetic_profile(segments, fps, n, detector)
        ja, li = acoustic_scales(analyse(*read_audio(video)), segments["start"], segments["end"], segments["phoneme"])
        after = cr.synthetic_profile(segments, fps, n, detector, jali=(ja, li))
        # the bound: each phone's JA factor = the real opening over ours over that phone
        oracle = np.ones(len(segments))
        for i, (s, e, p) in enumerate(zip(segments["start"], segments["end"], segments["phoneme"])):
            m = (real["time"] >= s) & (real["time"] < e)
            if m.any() and p not in ("p", "b", "m", "f", "v", "_"):
                oracle[i] = np.clip((real["height"][m].mean() + 0.01) / (before["height"][m].mean() + 0.01), 0.2, 2.5)
        bound = cr.synthetic_profile(segments, fps, n, detector, jali=(oracle, np.ones(len(segments))))
        r = {k: cr.speech_correlation(real, prof, video) for k, prof in (("before", before), ("after", after),
                                                                          ("oracle", bound))}
        cb, ca = _closures(before, segments, fps), _closures(after, segments, fps)
        shifts = [None if a is None or b is None else round(a - b, 1) for a, b in zip(ca, cb)]
        print(json.dumps({"section": "realdata", "clip": clip, "tuned_on": clip in TUNED_ON,
                          "speech_s": r["before"]["span_s"],
                          "r_before": round(r["before"]["r"], 3), "r_after": round(r["after"]["r"], 3),
                          "r_oracle_ja": round(r["oracle"]["r"], 3),
                          "best_lag_frames_after": r["after"]["lag"],
                          "r_after_at_best_lag": round(r["after"]["r_lag"], 3),
                          "ja_range": [round(float(ja.min()), 2), round(float(ja.max()), 2)],
                          "li_range": [round(float(li.min()), 2), round(float(li.max()), 2)],
                          "bilabial_closure_frames_before": cb, "after": ca, "shift_frames": shifts,
                          "closures_within_1_frame": all(s is not None and abs(s) <= 1 for s in shifts)}),
              flush=True)
        plots.append((clip, real, before, after, r))
    if out is not None and plots:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt

        fig, axes = plt.subplots(len(plots), 1, figsize=(9, 2.6 * len(plots)), sharex=True)
        for ax, (clip, real, before, after, r) in zip(np.atleast_1d(axes), plots):
            ax.plot(real["time"], real["height"], "k-", lw=1.8, label=f"{clip} real")
            ax.plot(before["time"], before["height"], "-", color="tab:blue", label=f"before (r {r['before']['r']:.2f})")
            ax.plot(after["time"], after["height"], "-", color="tab:orange",
                    label=f"after JA/LI (r {r['after']['r']:.2f})")
            ax.axvspan(*r["before"]["span_s"], color="0.92", zorder=0)
            tag = "tuned on" if clip in TUNED_ON else "held out"
            ax.set_title(f'"{cr.grid_sentence(clip)}" ({tag})', fontsize=9)
            ax.set_ylabel("height / w")
            ax.legend(fontsize=7, loc="upper right")
        np.atleast_1d(axes)[-1].set_xlabel("time (s); grey: speech span")
        fig.tight_layout()
        out.mkdir(parents=True, exist_ok=True)
        fig.savefig(out / "prosody_realdata.png", dpi=90)
        print(json.dumps({"section": "realdata", "plot": str(out / "prosody_realdata.png")}), flush=True)


def _word_openings(utterance, track, heights, fps):
    """Per word: (mean jaw, mean rendered height) over its vowels' frames."""
    from visemeface.postures.phonemes import is_vowel

    seg = utterance.segments
    out = []
    for ws, we in zip(utterance.words["start"], utterance.words["end"]):
        frames = []
        for s, e, p in zip(seg["start"], seg["end"], seg["phoneme"]):
            if is_vowel(str(p)) and s >= ws - 1e-9 and e <= we + 1e-9:
                frames += list(range(int(np.ceil(s * fps)), int(np.floor(e * fps)) + 1))
        frames = [k for k in frames if k < len(track)]
        out.append((float(track["jaw"].iloc[frames].mean()), float(np.mean(heights[frames]))))
    return out


def stress() -> None:
    from visemeface.analysis.openings import OpeningDetector
    from visemeface.analysis.profiles import analyze_frames
    from visemeface.animate import jali_factors
    from visemeface.motion import KinematicMotion
    from visemeface.muscles.rig import default_rig
    from visemeface.postures.library import load_visemes
    from visemeface.render.renderer import Renderer
    from visemeface.speech.g2p import text_to_utterance
    from visemeface.speech.timeline import activation_track

    rig, visemes, detector = default_rig(), load_visemes(), OpeningDetector()
    words = SENTENCE.split()

    def measure(text):
        utt = text_to_utterance(text)
        track = activation_track(utt, visemes, fps=FPS, jali=jali_factors(utt))
        motion = KinematicMotion(rig, track)
        with Renderer(motion.render_face, size=(256, 256), view="mouth") as renderer:
            box = renderer.mouth_box()
            frames = [renderer.render(f.vertices) for f in motion.frames()]
        prof = analyze_frames(frames, box, FPS, detector, source="synthetic")
        return _word_openings(utt, track, prof["height"].to_numpy(), FPS)

    plain = measure(SENTENCE)
    print(json.dumps({"section": "stress", "reading": SENTENCE, "jaw": [round(j, 3) for j, _ in plain],
                      "height": [round(h, 3) for _, h in plain]}), flush=True)
    for k, w in enumerate(words):
        text = " ".join(f"*{x}*" if i == k else x for i, x in enumerate(words))
        got = measure(text)
        others = [i for i in range(len(words)) if i != k]
        print(json.dumps({"section": "stress", "reading": text, "word": w,
                          "jaw": round(got[k][0], 3), "jaw_plain": round(plain[k][0], 3),
                          "jaw_more_pct": round(100 * (got[k][0] / plain[k][0] - 1), 1),
                          "height": round(got[k][1], 3), "height_plain": round(plain[k][1], 3),
                          "height_more_pct": round(100 * (got[k][1] / plain[k][1] - 1), 1) if plain[k][1] > 0 else None,
                          "other_words_jaw_change_max_pct": round(max(abs(100 * (got[i][0] / plain[i][0] - 1))
                                                                      for i in others), 1)}), flush=True)


def head(folder: Path) -> None:
    import tempfile

    import compare_realdata as cr
    import soundfile as sf

    from visemeface.speech.acoustics import analyse
    from visemeface.speech.align import utterance_from_audio
    from visemeface.speech.audio import read_audio, resample
    from visemeface.speech.gestures import speech_gestures

    videos = sorted(folder.glob("*.mpg"))
    parts, text = [], []
    for _ in range(4):
        for v in videos:
            s, rate = read_audio(v)
            parts.append(resample(s, rate, 16000))
            text.append(cr.grid_sentence(v.stem))
    samples = np.concatenate(parts)
    with tempfile.TemporaryDirectory() as tmp:
        wav = Path(tmp) / "long.wav"
        sf.write(str(wav), samples, 16000)
        utt = utterance_from_audio(wav, " ".join(text))
        ac = analyse(*read_audio(wav))
    n = int(np.ceil(utt.end * 30))
    g = speech_gestures(utt, n, 30.0, ac, seed=0)
    again = speech_gestures(utt, n, 30.0, ac, seed=0)
    other = speech_gestures(utt, n, 30.0, ac, seed=1)
    a = np.abs(g.head)
    nods = g.nod_times()
    pairs = []
    for t, peak, p in zip(g.accent_times, g.f0_peak_times, g.prominence):
        voiced = bool(np.isfinite(peak))       # else YIN found no pitch in the vowel: the accent is at its centre
        at = float(peak) if voiced else float(t)
        near = float(nods[np.argmin(np.abs(nods - at))]) if nods.size else None
        pairs.append({"f0_peak_s" if voiced else "vowel_centre_s": round(at, 2),
                      "nod_s": None if near is None else round(near, 2),
                      "offset_s": None if near is None else round(near - at, 2), "prominence": round(float(p), 2)})
    offsets = [q["offset_s"] for q in pairs if q["offset_s"] is not None]
    print(json.dumps({"section": "head", "speech_s": round(utt.end, 1), "frames": n,
                      "max_abs_deg": {"yaw": round(float(a[:, 0].max()), 2), "pitch": round(float(a[:, 1].max()), 2),
                                      "roll": round(float(a[:, 2].max()), 2)},
                      "p95_abs_deg": {k: round(float(np.percentile(a[:, i], 95)), 2)
                                      for i, k in enumerate(("yaw", "pitch", "roll"))},
                      "frames_all_under_2deg": round(float((a.max(axis=1) < 2).mean()), 3),
                      "brow_raises": int(((g.brow[1:] > 0.05) & (g.brow[:-1] <= 0.05)).sum()),
                      "gaze_max": round(float(np.abs(g.gaze).max()), 2),
                      "accents": len(pairs), "nods": int(nods.size),
                      "median_abs_nod_offset_s": round(float(np.median(np.abs(offsets))), 3) if offsets else None,
                      "same_seed_identical": bool(np.array_equal(g.head, again.head) and np.array_equal(g.gaze, again.gaze)),
                      "other_seed_differs": bool(not np.array_equal(g.head, other.head))}), flush=True)
    print(json.dumps({"section": "head", "accents_f0_peak_vs_nod": pairs}), flush=True)


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--realdata", type=Path, default=ROOT.parent / "shared" / "realdata")
    ap.add_argument("--out", type=Path, help="write the realdata plot here")
    ap.add_argument("--only", default="realdata,stress,head")
    args = ap.parse_args()
    warnings.simplefilter("ignore")
    only = set(args.only.split(","))
    if ({"realdata", "head"} & only) and not sorted(args.realdata.glob("*.mpg")):
        print(f"prosody_acceptance: no GRID clip in {args.realdata}", file=sys.stderr)
        return 2
    if "realdata" in only:
        realdata(args.realdata, args.out)
    if "stress" in only:
        stress()
    if "head" in only:
        head(args.realdata)
    return 0


if __name__ == "__main__":
    sys.exit(main())
