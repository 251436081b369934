"""``phn``: TIMIT ``.PHN``, ``start end label`` in samples at ``sample_rate`` Hz.

A stop closure and its release (``bcl b``) become one segment.
"""

from __future__ import annotations

from visemeface.errors import InputError
from visemeface.speech.transcripts.lexing import content_lines, is_int
from visemeface.speech.transcripts.segments import Row

NAME = "phn"
ALPHABETS = ("timit",)
_CLOSURES = ("bcl", "dcl", "gcl", "pcl", "tcl", "kcl")


def parse(text, where, sample_rate=16000.0, **_) -> list[Row]:
    rows: list[Row] = []
    for i, line in content_lines(text):
        f = line.split()
        if len(f) != 3:
            raise InputError(f"expected 'start_sample end_sample label', got {line!r}", where, i)
        for s in f[:2]:
            if not is_int(s):
                raise InputError(f"sample index {s!r} is not an integer", where, i)
        label = f[2]
        rows.append(Row(int(f[0]) / sample_rate, int(f[1]) / sample_rate, label, i, label.lower() in _CLOSURES))
    return rows
