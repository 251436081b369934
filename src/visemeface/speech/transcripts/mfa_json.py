"""``mfa-json``: Montreal Forced Aligner's JSON output.

``{"start", "end", "tiers": {"phones": {"entries": [[start, end, label], ...]}}}``;
MFA leaves the final silence out, so an ``end`` beyond the last entry becomes silence.
"""

from __future__ import annotations

import math

from visemeface.errors import InputError
from visemeface.speech.transcripts.segments import Row, pick_tier

NAME = "mfa-json"
ALPHABETS = ("ipa", "arpabet", "timit", "dectalk")


def _entries(data, tier, where):
    tiers = data["tiers"]
    if isinstance(tiers, dict):
        named = {str(k): v for k, v in tiers.items()}
    elif isinstance(tiers, list):
        named = {str(t.get("name", i)) if isinstance(t, dict) else str(i): t for i, t in enumerate(tiers)}
    else:
        raise InputError("'tiers' is neither an object nor a list", where, 1)
    name = pick_tier(list(named), tier, where)
    t = named[name]
    entries = t.get("entries") if isinstance(t, dict) else t
    if not isinstance(entries, list):
        raise InputError(f"tier {name!r} has no list of entries", where, 1)
    return name, entries


def parse(text, where, tier=None, **_) -> list[Row]:
    from visemeface.textfile import parse_json

    data = parse_json(text, where)
    if not isinstance(data, dict) or "tiers" not in data:
        raise InputError("JSON has no 'tiers': not MFA output", where, 1)
    name, entries = _entries(data, tier, where)
    rows = []
    for k, e in enumerate(entries):
        if isinstance(e, dict):
            e = [e.get("start", e.get("xmin")), e.get("end", e.get("xmax")), e.get("label", e.get("text", ""))]
        if not isinstance(e, (list, tuple)) or len(e) < 3:
            raise InputError(f"tier {name!r} entry {k + 1} is not [start, end, label]", where)
        try:
            start, end = float(e[0]), float(e[1])
        except (TypeError, ValueError, OverflowError):
            raise InputError(f"tier {name!r} entry {k + 1} has non-numeric times", where) from None
        rows.append(Row(start, end, "" if e[2] is None else str(e[2]), None))
    total = data.get("end")
    if isinstance(total, (int, float)) and rows and math.isfinite(total) and total > rows[-1].end:
        rows.append(Row(rows[-1].end, float(total), "", None))
    return rows
