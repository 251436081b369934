"""Raw rows of a transcript to validated Segments (shared by every reader)."""

from __future__ import annotations

import math
import re
import warnings
from dataclasses import dataclass

import numpy as np
import pandas as pd

from visemeface.errors import InputError, close_matches
from visemeface.postures.phonemes import SILENCE, to_dectalk
from visemeface.speech.utterance import Segments

#: Gaps and overlaps shorter than this (s) are rounding, closed silently.
TOLERANCE = 1e-3


@dataclass
class Row:
    """One labelled interval as read (``end`` None: until the next row's start)."""

    start: float
    end: float | None
    label: str
    line: int | None
    closure: bool = False


def segments_frame(starts, ends, phones) -> Segments:
    """Build a Segments DataFrame from arrays (no validation)."""
    return pd.DataFrame({"start": np.asarray(starts, dtype=float), "end": np.asarray(ends, dtype=float),
                         "phoneme": list(phones)})


def map_labels(rows: list[Row], where, alphabet, candidates) -> list[str]:
    """DECtalk symbols of the rows' labels; the alphabet is the first candidate knowing all."""
    labels = [r.label for r in rows]
    if alphabet is not None:
        order = [alphabet]
    else:
        order = list(candidates)
        if any(re.search(r"[A-Z]{1,2}[012]$", lab) for lab in labels) and "arpabet" in order:
            order.remove("arpabet")
            order.insert(0, "arpabet")
    best = None
    for name in order:
        out, bad = [], None
        for r in rows:
            try:
                out.append(to_dectalk(r.label, name))
            except InputError as exc:
                if "unknown phone alphabet" in str(exc):
                    raise
                bad = bad or (r, exc)
                out.append(None)
        if bad is None:
            return out
        score = sum(o is not None for o in out)
        if best is None or score > best[0]:
            best = (score, bad)
    r, exc = best[1]
    raise InputError(exc.reason, where, r.line)


def pick_tier(names: list[str], tier, where, line: int | None = None) -> str:
    """The tier holding the phones: ``tier`` if given, else the one phone-like tier."""
    if tier is not None:
        if tier in names:
            return tier
        hint = close_matches(tier, names)
        containing = [n for n in names if tier.lower() in n.lower()]
        if not hint and containing:
            hint = f" (did you mean: {', '.join(containing[:3])}?)"
        raise InputError(f"no tier {tier!r}; tiers: {', '.join(names)}{hint}", where, line)
    phones = [n for n in names if n.lower() in ("phones", "phone", "phonemes", "phoneme")
              or n.lower().endswith((" - phones", "- phones", "-phones", "_phones"))]
    if len(phones) == 1:
        return phones[0]
    if len(phones) > 1:
        raise InputError(f"several phone tiers ({', '.join(phones)}); choose one with --tier", where, line)
    if len(names) == 1:
        return names[0]
    raise InputError(f"no phone tier among {', '.join(names) or 'no tiers'}; choose one with --tier", where, line)


def _close_open_ends(rows: list[Row], symbols: list[str], where) -> None:
    """Check every time; an open end becomes the next start (or the inherent duration)."""
    for i, r in enumerate(rows):
        for name, value in (("start", r.start), ("end", r.end)):
            if value is not None and not math.isfinite(value):
                raise InputError(f"{name} time {value!r} is not finite", where, r.line)
            if value is not None and value < 0:
                raise InputError(f"{name} time {value:g} s is negative", where, r.line)
        if r.end is None:
            if i + 1 < len(rows):
                r.end = rows[i + 1].start
            else:
                from visemeface.speech.g2p import inherent_duration
                r.end = r.start + inherent_duration(symbols[i])
        if r.end < r.start:
            raise InputError(f"segment ends ({r.end:g} s) before it starts ({r.start:g} s)", where, r.line)


def _append(starts, ends, phones, s, e, sym):
    if phones and phones[-1] == sym == SILENCE:
        ends[-1] = e
    else:
        starts.append(s)
        ends.append(e)
        phones.append(sym)


def make_segments(rows, path=None, alphabet: str | None = None,
                  candidates=("dectalk", "arpabet", "timit", "ipa")) -> Segments:
    """Validate raw ``(start, end, label, line)`` rows and build Segments.

    ``end`` may be None (``start phone`` lines): it becomes the next row's
    start, or the phone's inherent duration for the last row. Labels are
    mapped to DECtalk; gaps become silence (with a warning); overlaps, times
    out of order, negative or non-finite times raise InputError with the line.
    """
    where = path if path is not None else "<transcript>"
    rows = [r if isinstance(r, Row) else Row(*r) for r in rows]
    if not rows:
        raise InputError("no phone segments found", where, None)
    symbols = map_labels(rows, where, alphabet, candidates)
    _close_open_ends(rows, symbols, where)
    starts, ends, phones = [], [], []
    closure_prev = False
    prev_line = None
    for r, sym in zip(rows, symbols):
        if r.end - r.start <= 0:
            continue                                  # empty interval: nothing to show
        now = ends[-1] if ends else 0.0
        if r.start < now - TOLERANCE:
            if starts and r.start < starts[-1] - TOLERANCE:
                raise InputError(f"segment starts at {r.start:g} s, before the previous one "
                                 f"(line {prev_line}, {starts[-1]:g} s): times must increase", where, r.line)
            raise InputError(f"segment {r.label!r} at {r.start:g}-{r.end:g} s overlaps the previous one "
                             f"(line {prev_line}, ending {now:g} s) by {now - r.start:.3g} s", where, r.line)
        if r.start > now + TOLERANCE:
            if ends and sym != SILENCE and phones[-1] != SILENCE:
                warnings.warn(f"{where}:{r.line}: gap of {r.start - now:.3g} s before {r.label!r} "
                              f"filled with silence", UserWarning, stacklevel=2)
            _append(starts, ends, phones, now, r.start, SILENCE)
            closure_prev = False
        # Tiny gaps and overlaps (< TOLERANCE) are closed by starting at the previous end.
        begin = ends[-1] if ends else 0.0
        if r.end <= begin:
            continue
        if phones and phones[-1] == sym and (sym == SILENCE or closure_prev):
            ends[-1] = r.end
        else:
            _append(starts, ends, phones, begin, r.end, sym)
        closure_prev = r.closure
        prev_line = r.line
    if not phones:
        raise InputError("no phone segment has a positive duration", where, rows[-1].line)
    return segments_frame(starts, ends, phones)
