"""``timed``: one phone a line, ``start end phone`` or ``start phone`` (seconds).

A ``start phone`` line lasts until the next line's start, the last one for its
inherent duration, or until a final line holding only a time. ``#`` and ``;``
start comments.
"""

from __future__ import annotations

from visemeface.errors import InputError
from visemeface.speech.transcripts.lexing import content_lines, is_number, number
from visemeface.speech.transcripts.segments import Row

NAME = "timed"
ALPHABETS = ("dectalk", "arpabet", "timit", "ipa")


def parse(text, where, **_) -> list[Row]:
    rows: list[Row] = []
    for i, line in content_lines(text):
        f = line.split()
        if len(f) == 1 and is_number(f[0]):
            if not rows or rows[-1].end is not None:
                raise InputError(f"a line with only a time ({f[0]}) must end a 'start phone' line",
                                 where, i)
            rows[-1].end = number(f[0], "end time", where, i)
            continue
        if len(f) == 2:
            rows.append(Row(number(f[0], "start time", where, i), None, f[1], i))
        elif len(f) == 3:
            rows.append(Row(number(f[0], "start time", where, i), number(f[1], "end time", where, i), f[2], i))
        else:
            raise InputError(f"expected 'start end phone' or 'start phone', got {line!r}", where, i)
        if len(rows) > 1 and rows[-2].end is None and rows[-2].start > rows[-1].start:
            raise InputError(f"segment starts at {rows[-1].start:g} s, before the previous one "
                             f"(line {rows[-2].line}): times must increase", where, i)
    return rows
