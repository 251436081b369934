"""Plain English text as tokens: words (numbers, money, ordinals and titles spelled out), pauses at punctuation,
and inline emotion tags ``[name weight]``.

The front end of :func:`visemeface.speech.g2p.text_to_utterance`; the aligner and the emphasis marks
(:mod:`visemeface.speech.stress`) count words with it, so that every part reads a text alike.
"""

from __future__ import annotations

import math
import re

from visemeface.errors import InputError
from visemeface.speech.numbers import SPELLED

__all__ = ["TAG", "TITLES", "line_of", "spoken", "tokens"]

TAG = re.compile(r"\[([^\[\]]*)\]")
_TAG_BODY = re.compile(r"^\s*([A-Za-z_][A-Za-z_\-]*)\s*(?:[=:\s]\s*([-+]?(?:\d+\.?\d*|\.\d+)))?\s*$")
#: Titles before a name, read out (their full stop is no sentence end): "Dr. Smith" is doctor Smith;
#: those CMUdict reads otherwise (Dr. as drive, St. as street, Prof. not at all); Mr., Mrs., Ms. as it has them.
TITLES = {"dr": "doctor", "prof": "professor", "st": "saint"}
_TOKEN = re.compile(r"""
    (?P<money>[$£€]\s?(?:(?:\d{1,3}(?:,\d{3})+|\d+)(?:\.\d+)?|\.\d+)(?:\s+(?i:thousand|million|billion|trillion)\b)?)
  | (?P<ordinal>(?:\d{1,3}(?:,\d{3})+|\d+)(?i:(?<=1)(?<!11)st|(?<=2)(?<!12)nd|(?<=3)(?<!13)rd|th)\b)
  | (?P<number>(?:(?<![\w.])[-−])?(?:\d{1,3}(?:,\d{3})+|\d+)(?:\.\d+)?%?)
  | (?P<title>\b(?i:Dr|Mr|Mrs|Ms|Prof|St)\.(?=\s*[A-Z]))
  | (?P<and>&)
  | (?P<word>[A-Za-z\u00C0-\u024F]+(?:['’][A-Za-z]+)*)
  | (?P<sentence>\.\.\.|…|[.!?]+)
  | (?P<clause>[;:])
  | (?P<comma>[,\u2013\u2014]|\s-\s|--)
""", re.VERBOSE)


def line_of(text: str, pos: int) -> int:
    """The 1-based line of ``text`` holding position ``pos``."""
    return text.count("\n", 0, pos) + 1


def tokens(text: str, path):
    """Yield ('word', str, line) / ('pause', kind, line) / ('emotion', (name, w), line)."""
    pos = 0
    for m in TAG.finditer(text):
        yield from _plain_tokens(text, pos, m.start())
        body = _TAG_BODY.match(m.group(1))
        line = line_of(text, m.start())
        if not body:
            raise InputError(f"bad emotion tag {m.group(0)!r}; write [name weight], e.g. [anger 0.8]",
                             path, line)
        weight = 1.0 if body.group(2) is None else float(body.group(2))
        if not (math.isfinite(weight) and 0.0 <= weight <= 1.0):
            raise InputError(f"emotion weight {body.group(2)} in {m.group(0)!r} is not in 0..1", path, line)
        yield "emotion", (body.group(1).lower(), weight), line
        pos = m.end()
    stray = text.find("[", pos)
    stray = stray if stray >= 0 else text.find("]", pos)
    if stray >= 0:
        raise InputError("unmatched bracket in text", path, line_of(text, stray))
    yield from _plain_tokens(text, pos, len(text))


def _words_of(m) -> list[str] | None:
    """The words a token is read as, or None for a pause (punctuation)."""
    kind = m.lastgroup
    if kind in SPELLED:
        return list(SPELLED[kind](m.group(0)))
    if kind == "word":
        return [m.group(0).replace("’", "'")]
    if kind == "title":
        title = m.group(0)[:-1].lower()
        return [TITLES.get(title, title)]
    if kind == "and":
        return ["and"]
    return None


def _plain_tokens(text: str, start: int, end: int):
    for m in _TOKEN.finditer(text, start, end):
        line = line_of(text, m.start())
        words = _words_of(m)
        if words is None:
            yield "pause", m.lastgroup, line
        else:
            for w in words:
                yield "word", w, line

def spoken(text: str) -> str:
    """``text`` (no tags) written as its words are read here -- numbers, money, ordinals and titles spelled
    out, symbols that are not read (an emoji) left out -- with its punctuation, for a synthesiser to say the
    words the aligner then looks for ("$25.50" is "twenty five dollars fifty cents" to both)."""
    out: list[str] = []
    for m in _TOKEN.finditer(text):
        words = _words_of(m)
        if words is not None:
            out += words
        elif out:
            out[-1] += "," if m.lastgroup == "comma" else m.group(0)
    return " ".join(out)
