"""Captions of the utterance's words: SubRip (``.srt``) and WebVTT (``.vtt``).

Words are grouped into cues (:func:`caption_groups`): a new cue starts after a pause of at least
:data:`PAUSE` between two words, or when the cue would pass :data:`MAX_CHARS` characters or
:data:`MAX_SECONDS`. A cue lasts from its first word's start to its last word's end.

- SubRip: numbered blocks ``1`` / ``HH:MM:SS,mmm --> HH:MM:SS,mmm`` / text / blank line.
- WebVTT: ``WEBVTT``, a blank line, then blocks ``HH:MM:SS.mmm --> HH:MM:SS.mmm`` / text, the text
  carrying a cue timestamp ``<HH:MM:SS.mmm>`` before each word after the first (WebVTT's karaoke
  timing: players highlight each word as it is said).

The words come with the utterance (a transcript with a word tier, text, or a recording aligned to its
words); a run without words is refused.
"""

from __future__ import annotations

from visemeface.errors import InputError
from visemeface.export.sinks import Sink, register

#: A pause between words that starts a new cue (s): a breath between phrases, longer than the gaps
#: inside a phrase that forced alignment leaves (tens of ms).
PAUSE = 0.3
#: Longest cue text (characters): the common subtitle guideline of 42 characters a line.
MAX_CHARS = 42
#: Longest cue (s): subtitle guidelines' 7 s.
MAX_SECONDS = 7.0


def caption_groups(words) -> list[list[tuple[float, float, str]]]:
    """The words ``(start, end, word)`` grouped into cues (module docstring)."""
    groups: list[list[tuple[float, float, str]]] = []
    for a, b, w in words:
        g = groups[-1] if groups else None
        if (g is None or a - g[-1][1] >= PAUSE or len(" ".join(x[2] for x in g) + " " + w) > MAX_CHARS
                or b - g[0][0] > MAX_SECONDS):
            groups.append([(a, b, w)])
        else:
            g.append((a, b, w))
    return groups


def clock(t: float, sep: str = ",") -> str:
    """``HH:MM:SS,mmm`` (SubRip; ``sep="."`` for WebVTT) of ``t`` seconds, rounded to the millisecond."""
    ms = int(round(max(t, 0.0) * 1000))
    s, ms = divmod(ms, 1000)
    m, s = divmod(s, 60)
    h, m = divmod(m, 60)
    return f"{h:02d}:{m:02d}:{s:02d}{sep}{ms:03d}"


def srt_text(words) -> str:
    blocks = [f"{i}\n{clock(g[0][0])} --> {clock(g[-1][1])}\n{' '.join(w for _, _, w in g)}\n"
              for i, g in enumerate(caption_groups(words), 1)]
    return "\n".join(blocks)


def vtt_text(words) -> str:
    blocks = []
    for g in caption_groups(words):
        text = g[0][2] + "".join(f" <{clock(a, '.')}>{w}" for a, _, w in g[1:])
        blocks.append(f"{clock(g[0][0], '.')} --> {clock(g[-1][1], '.')}\n{text}\n")
    return "WEBVTT\n\n" + "\n".join(blocks)


def utterance_words(run, option: str) -> list[tuple[float, float, str]]:
    """The run's words ``(start, end, word)``, or :class:`InputError` naming ``option`` when it has none."""
    utt = run.extra.get("utterance")
    words = [] if utt is None else [(float(a), float(b), str(w).strip())
                                    for a, b, w in utt.words[["start", "end", "word"]].itertuples(index=False)]
    words = [x for x in words if x[2]]
    if not words:
        raise InputError(f"{option} needs the utterance's words and this one has none (words come from a "
                         "transcript that has them, text, a recording with its text, or a Papagayo .pgo)")
    return words


class _CaptionSink(Sink):
    metavar = "FILE"
    writer = staticmethod(srt_text)

    def open(self, run) -> None:
        self.words = utterance_words(run, f"--{self.name}")    # before staging: a refused sink leaves nothing
        super().open(run)

    def close(self) -> None:
        self.tmp[0].write_text(self.writer(self.words), encoding="utf-8")


@register
class SrtSink(_CaptionSink):
    """SubRip captions of the words (module docstring)."""

    name = "srt"
    metavar = "FILE.srt"
    help = "also write the words as SubRip captions (.srt)"
    suffixes = (".srt",)


@register
class VttSink(_CaptionSink):
    """WebVTT captions of the words, with a timestamp before each word (module docstring)."""

    name = "vtt"
    metavar = "FILE.vtt"
    help = "also write the words as WebVTT captions (.vtt), each word timed"
    suffixes = (".vtt",)
    writer = staticmethod(vtt_text)
