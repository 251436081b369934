"""Papagayo lip-sync project (``.pgo``): the words, each with its Preston Blair mouth shapes.

Papagayo (and Papagayo-NG) save a project as text, tab-indented::

    lipsync version 1
    <sound file>
    <fps>
    <sound duration in frames>
    <number of voices>
    \\t<voice name>
    \\t<voice text, lines joined by |>
    \\t<number of phrases>
    \\t\\t<phrase text>
    \\t\\t<start frame>
    \\t\\t<end frame>
    \\t\\t<number of words>
    \\t\\t\\t<word> <start frame> <end frame> <number of phonemes>
    \\t\\t\\t\\t<frame> <phoneme>

Frames count from 0 at ``--pgo-fps`` (default 24, Papagayo's); a word's end frame is its last (the
frame before the one showing its end).
Phrases are the caption cues (:func:`visemeface.export.captions.caption_groups`). A word's phonemes
are the shapes of its phones: Rhubarb's shape of each DECtalk phone (``data/retarget/phoneme_classes.csv``)
by its Preston Blair name (MBP etc E AI O U FV L rest, Papagayo's set), neighbours with the same shape
merged. Papagayo shows ``rest`` between words.
"""

from __future__ import annotations

import argparse
import math

from visemeface.errors import InputError
from visemeface.export.captions import caption_groups, utterance_words
from visemeface.export.sinks import Sink, register

#: Papagayo's default frame rate.
PGO_FPS = 24
VOICE = "Voice 1"


def pgo_fps(text) -> int:
    """``--pgo-fps``: a whole frame rate 1..1000 (Papagayo stores an integer)."""
    try:
        value = int(text)
    except (TypeError, ValueError):
        value = 0
    if not 1 <= value <= 1000:
        raise argparse.ArgumentTypeError(f"must be a whole frame rate in 1..1000, got {text}")
    return value


def _frame(t: float, fps: int) -> int:
    return int(math.floor(t * fps + 1e-6))


def word_phonemes(segments, a: float, b: float, fps: int) -> list[tuple[int, str]]:
    """(frame, Preston Blair shape) of the phones inside the word ``[a, b)``, equal neighbours merged."""
    from visemeface.retarget.classes import PRESTON_BLAIR
    from visemeface.retarget.recipes import phoneme_classes

    table = phoneme_classes()
    out: list[tuple[int, str]] = []
    for s, e, ph in segments[["start", "end", "phoneme"]].itertuples(index=False):
        if e <= a + 1e-9 or s >= b - 1e-9 or ph not in table:
            continue
        shape = PRESTON_BLAIR[table[ph][1]]
        frame = max(_frame(max(s, a), fps), _frame(a, fps))
        if out and out[-1][1] == shape:
            continue
        if out and out[-1][0] == frame:
            out[-1] = (frame, shape)
        else:
            out.append((frame, shape))
    return out


def pgo_text(words, segments, duration: float, fps: int = PGO_FPS, sound: str = "") -> str:
    """The Papagayo project of the words ``(start, end, word)`` and the phones (module docstring)."""
    phrases = caption_groups(words)
    lines = ["lipsync version 1", sound, str(fps), str(max(1, math.ceil(duration * fps - 1e-6))), "1",
             f"\t{VOICE}", "\t" + "|".join(" ".join(w for _, _, w in g) for g in phrases), f"\t{len(phrases)}"]
    for g in phrases:
        spans = [(_frame(a, fps), max(_frame(a, fps), _frame(b, fps) - 1)) for a, b, _ in g]
        lines += ["\t\t" + " ".join(w for _, _, w in g), f"\t\t{spans[0][0]}", f"\t\t{spans[-1][1]}", f"\t\t{len(g)}"]
        for (a, b, w), (fa, fb) in zip(g, spans):
            ph = word_phonemes(segments, a, b, fps) or [(fa, "rest")]
            lines.append(f"\t\t\t{w.replace(' ', '_')} {fa} {fb} {len(ph)}")
            lines += [f"\t\t\t\t{f} {p}" for f, p in ph]
    return "\n".join(lines) + "\n"


@register
class PapagayoSink(Sink):
    """The words and their mouth shapes as a Papagayo project (module docstring)."""

    name = "papagayo"
    metavar = "FILE.pgo"
    help = "also write a Papagayo lip-sync project (.pgo): the words with their Preston Blair mouth shapes"
    suffixes = (".pgo",)
    arguments = ((("--pgo-fps",), dict(dest="pgo_fps", type=pgo_fps, metavar="FPS",
                                       help=f"frame rate of --papagayo (default {PGO_FPS}, Papagayo's)")),)

    def open(self, run) -> None:
        self.words = utterance_words(run, "--papagayo")        # before staging: a refused sink leaves nothing
        super().open(run)

    def close(self) -> None:
        utt = self.run.extra["utterance"]
        fps = self.settings.get("pgo_fps")
        try:
            fps = PGO_FPS if fps is None else pgo_fps(fps)
        except argparse.ArgumentTypeError as exc:
            raise InputError(f"--pgo-fps {exc}") from None
        text = pgo_text(self.words, utt.segments, utt.end, fps, str(self.run.audio) if self.run.audio else "")
        self.tmp[0].write_text(text, encoding="utf-8")
