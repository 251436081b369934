"""``dectalk``: DECtalk phoneme strings, ``[hx<80> eh<120> l ow _<300>]``.

Durations in ms in ``<>`` (an optional pitch after a comma is ignored), symbols
with or without spaces, stress and boundary marks ignored; ``, ; : . ! ?`` are
pauses of the lengths in ``data/phonemes/timing.csv`` (the same pauses the text
front end inserts); a phone without a duration gets its inherent one.
"""

from __future__ import annotations

import re

from visemeface.errors import InputError, close_matches
from visemeface.postures.phonemes import DECTALK, SILENCE
from visemeface.speech.transcripts.lexing import TEXT_OUTSIDE_BRACKETS, number
from visemeface.speech.transcripts.segments import Row

NAME = "dectalk"
ALPHABETS = ("dectalk",)

_TOKEN = re.compile(r"\s+|<\s*([^<>]*)>|[',`\"\-#=*.!?;:()]|[^\s<>',`\"\-#=*.!?;:()]+")
_SYMBOLS = frozenset(DECTALK)


class _Timeline:
    """Rows laid end to end; symbols wait in ``pending`` until their duration is known."""

    def __init__(self):
        from visemeface.speech.g2p import inherent_duration, punctuation_pause

        self.rows: list[Row] = []
        self.now = 0.0
        self.pending: list[tuple[str, int]] = []
        self.inherent, self.pause = inherent_duration, punctuation_pause

    def add(self, sym, duration, line):
        self.rows.append(Row(self.now, self.now + duration, sym, line))
        self.now += duration

    def flush(self):
        for sym, ln in self.pending:
            self.add(sym, self.inherent(sym), ln)
        self.pending.clear()


def _outside_error(text, pos, outside, where):
    k = pos + TEXT_OUTSIDE_BRACKETS.search(outside).start()
    return InputError(f"text outside [ ] in a DECtalk string: {outside.strip()[:20]!r}", where,
                      text.count("\n", 0, k) + 1)


def _symbols(tok, line, where):
    out, i, low = [], 0, tok.lower()
    while i < len(low):
        if low[i:i + 2] in _SYMBOLS:
            out.append((low[i:i + 2], line))
            i += 2
        elif low[i] in _SYMBOLS:
            out.append((low[i], line))
            i += 1
        else:
            raise InputError(f"unknown DECtalk phoneme at {tok[i:i + 3]!r} in {tok!r}"
                             f"{close_matches(low[i:i + 2], DECTALK)}", where, line)
    return out


def _group(tl: _Timeline, text, body, base, where):
    for m in _TOKEN.finditer(body):
        tok = m.group(0)
        line = text.count("\n", 0, base + m.start()) + 1
        if tok.isspace() or tok in "'`\"-#=*()":
            continue
        if m.group(1) is not None:
            if not tl.pending:
                raise InputError(f"duration {tok} follows no phoneme", where, line)
            ms = m.group(1).split(",")[0].strip()
            dur = number(ms, "duration (ms)", where, line) / 1000
            if dur < 0:
                raise InputError(f"duration {ms} ms is negative", where, line)
            sym, ln = tl.pending.pop()
            tl.flush()
            tl.add(sym, dur, ln)
        elif tl.pause(tok) is not None:
            tl.flush()
            tl.add(SILENCE, tl.pause(tok), line)
        else:
            tl.flush()
            tl.pending.extend(_symbols(tok, line, where))
    tl.flush()


def parse(text, where, **_) -> list[Row]:
    tl = _Timeline()
    pos = 0
    for g in re.finditer(r"\[([^\[\]]*)\]", text):
        outside = text[pos:g.start()]
        if TEXT_OUTSIDE_BRACKETS.search(outside):
            raise _outside_error(text, pos, outside, where)
        pos = g.end()
        if g.group(1).lstrip().startswith(":"):
            continue                         # a DECtalk command such as [:phoneme on]
        _group(tl, text, g.group(1), g.start(1), where)
    rest = text[pos:]
    if TEXT_OUTSIDE_BRACKETS.search(rest):
        raise _outside_error(text, pos, rest, where)
    return tl.rows
