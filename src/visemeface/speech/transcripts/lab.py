"""``lab``: HTK/HTS label files, or the xwaves/ESPS label files of Festival and CMU ARCTIC.

HTK: ``start end label`` in 100 ns units (HTS full-context labels
``a^b-PHONE+c=d...`` are reduced to PHONE). xwaves: a header ended by a line
``#``, then ``end_time colour label`` in seconds.
"""

from __future__ import annotations

import re

from visemeface.errors import InputError
from visemeface.speech.transcripts.lexing import is_number, number
from visemeface.speech.transcripts.segments import Row

NAME = "lab"
ALPHABETS = ("timit", "arpabet", "dectalk", "ipa")
#: Seconds per HTK time unit.
HTK_UNIT = 1e-7

_HTS = re.compile(r"-([^-+]+)\+")


def parse(text, where, **_) -> list[Row]:
    lines = text.splitlines()
    sep = next((k for k, ln in enumerate(lines[:60]) if ln.strip() == "#"), None)
    if sep is not None:
        return _parse_xwaves(lines, sep, where)
    rows: list[Row] = []
    for i, raw in enumerate(lines, start=1):
        line = raw.strip()
        if not line or line.startswith(("#", ";")) or line == "///":
            continue
        f = line.split()
        if len(f) < 3:
            raise InputError(f"expected 'start end label' (100 ns units), got {line!r}", where, i)
        start = number(f[0], "start time", where, i) * HTK_UNIT
        end = number(f[1], "end time", where, i) * HTK_UNIT
        label = f[2]
        m = _HTS.search(label)
        if m:
            label = m.group(1)
        rows.append(Row(start, end, label, i))
    return rows


def _parse_xwaves(lines, sep, where) -> list[Row]:
    rows: list[Row] = []
    prev = 0.0
    for i in range(sep + 1, len(lines)):
        line = lines[i].strip()
        if not line:
            continue
        f = line.split(None, 2)
        if len(f) < 3:
            if len(f) == 2 and is_number(f[0]):   # an end time without a label: silence
                f = [f[0], f[1], ""]
            else:
                raise InputError(f"expected 'end_time colour label', got {line!r}", where, i + 1)
        end = number(f[0], "end time", where, i + 1)
        rows.append(Row(prev, end, f[2].strip(), i + 1))
        prev = end
    return rows
