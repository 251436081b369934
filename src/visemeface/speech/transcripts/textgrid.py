"""``textgrid``: Praat TextGrid, long or short text format (read with praatio).

The phone tier of Montreal Forced Aligner output (``phones``, ``SPEAKER -
phones``) unless ``tier=`` names one; empty intervals are silence.
"""

from __future__ import annotations

import re

from visemeface.errors import InputError
from visemeface.speech.transcripts.segments import Row, pick_tier

NAME = "textgrid"
ALPHABETS = ("ipa", "arpabet", "timit", "dectalk")

_TG_TOKEN = re.compile(r'"(?:[^"]|"")*"|<exists>|[-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?')


def parse(text, where, tier=None, **_) -> list[Row]:
    from praatio.utilities import textgrid_io
    text = text.replace("\r\n", "\n").replace("\r", "\n")
    try:
        tg = textgrid_io.parseTextgridStr(text, includeEmptyIntervals=True)
        tiers = tg["tiers"]
        names = [t["name"] for t in tiers]
    except InputError:
        raise
    except Exception:  # praatio raises IndexError, ValueError, KeyError... on bad text
        raise InputError("not a readable TextGrid (no valid header, tiers and intervals)", where) from None
    name = pick_tier(names, tier, where)
    t = tiers[names.index(name)]
    if t.get("class") not in (None, "IntervalTier"):
        raise InputError(f"tier {name!r} is a point tier, not an interval tier", where)
    line_of = interval_lines(text, names.index(name))
    rows = []
    for k, entry in enumerate(t["entries"]):
        try:
            start, end, label = float(entry[0]), float(entry[1]), str(entry[2])
        except (TypeError, ValueError, IndexError, OverflowError):
            raise InputError(f"tier {name!r} interval {k + 1} is malformed", where, line_of(k)) from None
        rows.append(Row(start, end, label, line_of(k)))
    return rows


def interval_lines(text: str, tier_index: int):
    """Map interval k of tier ``tier_index`` to its line in the TextGrid text (None if unknown).

    Long format: the line of ``intervals [k]:``. Short format: Praat's token stream
    (``<exists>``, tier count, then per tier class, name, xmin, xmax, size and
    xmin/xmax/text per interval), each token's line counted.
    """
    lines = text.split("\n")
    item = [i for i, ln in enumerate(lines) if re.match(r"\s*item ?\[\d+\]:", ln)]
    if item:
        if tier_index >= len(item):
            return lambda k: None
        lo = item[tier_index]
        hi = item[tier_index + 1] if tier_index + 1 < len(item) else len(lines)
        found = [i + 1 for i in range(lo, hi) if re.match(r"\s*intervals ?\[\d+\]:", lines[i])]
        return lambda k: found[k] if k < len(found) else None
    tokens = [(m.group(0), text.count("\n", 0, m.start()) + 1) for m in _TG_TOKEN.finditer(text)]
    try:
        pos = [t for t, _ in tokens].index("<exists>") + 2          # past <exists> and the tier count
        for _ in range(tier_index + 1):
            klass, size = tokens[pos][0], int(float(tokens[pos + 4][0]))
            start = pos + 5
            pos = start + size * (3 if "Interval" in klass else 2)
    except (ValueError, IndexError, OverflowError):   # e.g. an interval count of 1e309
        return lambda k: None
    return lambda k: tokens[start + 3 * k][1] if start + 3 * k < len(tokens) else None
