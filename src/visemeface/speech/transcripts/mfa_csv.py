"""``mfa-csv``: Montreal Forced Aligner's CSV output (``Begin,End,Label,Type,Speaker``).

Tiers are named by the Type and Speaker columns (``phones``, ``SPEAKER - phones``).
"""

from __future__ import annotations

import csv
import io

from visemeface.errors import InputError
from visemeface.speech.transcripts.lexing import number
from visemeface.speech.transcripts.segments import Row, pick_tier

NAME = "mfa-csv"
ALPHABETS = ("ipa", "arpabet", "timit", "dectalk")
_NEED = ("begin", "end", "label")


def _records(text, where):
    reader = csv.reader(io.StringIO(text.replace("\r\n", "\n")))
    try:
        header = [h.strip().lower() for h in next(reader)]
    except StopIteration:
        raise InputError("CSV is empty", where, 1) from None
    except csv.Error as exc:
        raise InputError(f"bad CSV: {exc}", where, 1) from None
    missing = [c for c in _NEED if c not in header]
    if missing:
        raise InputError(f"CSV header lacks {', '.join(missing)} (MFA: Begin,End,Label,Type,Speaker)", where, 1)
    records = []
    try:
        for rec in reader:
            records.append((reader.line_num, rec))
    except csv.Error as exc:
        raise InputError(f"bad CSV: {exc}", where, reader.line_num) from None
    records = [(n, r) for n, r in records if any(c.strip() for c in r)]
    if not records:
        raise InputError("no rows after the CSV header", where, 1)
    return header, records


def parse(text, where, tier=None, **_) -> list[Row]:
    header, records = _records(text, where)
    ib, ie, il = (header.index(c) for c in _NEED)
    it = header.index("type") if "type" in header else None
    isp = header.index("speaker") if "speaker" in header else None
    keys = []
    for n, r in records:
        if len(r) <= max(ib, ie, il, it or 0, isp or 0):
            raise InputError(f"expected {len(header)} columns, got {len(r)}", where, n)
        typ = r[it].strip() if it is not None else "phones"
        spk = r[isp].strip() if isp is not None else ""
        keys.append(f"{spk} - {typ}" if spk else typ)
    names = list(dict.fromkeys(keys))
    if tier is not None and tier not in names:
        # allow --tier phones when there is a single speaker
        alt = [k for k in names if k.endswith(" - " + tier)]
        tier = alt[0] if len(alt) == 1 else tier
    name = pick_tier(names, tier, where, line=1)
    rows = [Row(number(r[ib], "begin time", where, n), number(r[ie], "end time", where, n), r[il].strip(), n)
            for (n, r), key in zip(records, keys) if key == name]
    rows.sort(key=lambda row: row.start)   # MFA writes words and phones interleaved, each in order
    return rows
