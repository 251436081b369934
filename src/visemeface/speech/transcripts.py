"""Read timed phoneme transcripts into Segments.

Segments
--------
A pandas DataFrame with columns ``start``, ``end`` (float seconds) and
``phoneme`` (a DECtalk symbol, see :mod:`visemeface.postures.phonemes`),
sorted, contiguous from 0, without overlaps; gaps are filled with silence
``_`` and consecutive silences are merged. ``attrs["format"]`` names the
format read.

Formats (``fmt=``; detected from the content when None)
-------------------------------------------------------
``"timed"``
    One phone a line, ``start end phone`` or ``start phone`` (seconds; a
    ``start phone`` lasts until the next line's start, the last one for its
    inherent duration, or until a final line holding only a time). ``#`` and
    ``;`` start comments.
``"lab"``
    HTK/HTS label files, ``start end label`` in 100 ns units (HTS
    full-context labels ``a^b-PHONE+c=d...`` are reduced to PHONE); or the
    xwaves/ESPS label files of Festival and CMU ARCTIC (a header ended by a
    line ``#``, then ``end_time colour label`` in seconds).
``"phn"``
    TIMIT ``.PHN``: ``start end label`` in samples at ``sample_rate`` Hz; a
    stop closure and its release (``bcl b``) become one segment.
``"textgrid"``
    Praat TextGrid, long or short text format (read with praatio); the phone
    tier of Montreal Forced Aligner output (``phones``, ``SPEAKER - phones``)
    unless ``tier=`` names one; empty intervals are silence.
``"mfa-json"``, ``"mfa-csv"``
    MFA's JSON output (``{"start", "end", "tiers": {"phones": {"entries":
    [[start, end, label], ...]}}}``) and CSV output (``Begin,End,Label,Type,Speaker``).
``"dectalk"``
    DECtalk phoneme strings, ``[hx<80> eh<120> l ow _<300>]``: durations in
    ms in ``<>`` (an optional pitch after a comma is ignored), symbols with or
    without spaces, stress and boundary marks ignored, ``,`` and ``.`` pauses;
    a phone without a duration gets its inherent one.
``"text"``
    Plain English, timed by :func:`visemeface.speech.g2p.text_to_segments`.

Phone labels are mapped with :func:`visemeface.postures.phonemes.to_dectalk`;
the alphabet (``alphabet=``) is otherwise the first of the format's candidates
(e.g. DECtalk, ARPAbet, TIMIT, IPA for ``timed``) in which every label is known.

Errors
------
Everything wrong with the input raises :class:`~visemeface.errors.InputError`
naming the file and line: unknown phones, non-numeric, negative or non-finite
times, a segment ending before it starts, segments out of order or
overlapping (both lines named). Gaps are filled with silence and reported
with a warning naming the line.
"""

from __future__ import annotations

import csv
import io
import json
import math
import re
import warnings
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pandas as pd

from visemeface.errors import InputError, choose, close_matches
from visemeface.postures.phonemes import DECTALK, SILENCE, to_dectalk

__all__ = ["FORMATS", "Segments", "detect_format", "make_segments", "parse_transcript",
           "read_transcript", "segments_frame"]

Segments = pd.DataFrame

#: Format names accepted by ``fmt=``.
FORMATS = ("timed", "lab", "phn", "textgrid", "mfa-json", "mfa-csv", "dectalk", "text")
_ALIASES = {"htk": "lab", "hts": "lab", "xwaves": "lab", "esps": "lab", "timit": "phn",
            "praat": "textgrid", "json": "mfa-json", "mfa_json": "mfa-json", "csv": "mfa-csv",
            "mfa_csv": "mfa-csv", "plain": "text", "txt": "timed"}

#: Gaps and overlaps shorter than this (s) are rounding, closed silently.
TOLERANCE = 1e-3


@dataclass
class _Row:
    start: float
    end: float | None
    label: str
    line: int | None
    closure: bool = False


# ----------------------------------------------------------------------------- public

def read_transcript(path, fmt: str | None = None, tier: str | None = None, sample_rate: float = 16000,
                    alphabet: str | None = None, rate_wpm: float | None = None, audio=None) -> Segments:
    """Read a transcript file into Segments.

    Parameters
    ----------
    path : str or Path
        The transcript.
    fmt : str, optional
        One of :data:`FORMATS`; detected from the content (and suffix) if None.
    tier : str, optional
        TextGrid / MFA tier holding the phones (default: the phone tier).
    sample_rate : float
        Sample rate of TIMIT ``.PHN`` sample indices (Hz).
    alphabet : str, optional
        Phone alphabet of the labels (``dectalk``, ``arpabet``, ``timit``,
        ``ipa``/``mfa``); default: detected.
    rate_wpm, audio
        For plain text only: speaking rate and audio to align to (see g2p).

    Returns
    -------
    Segments

    Raises
    ------
    InputError
        Unreadable file or bad content (with file and line).
    """
    path = Path(path)
    try:
        raw = path.read_bytes()
    except FileNotFoundError:
        raise InputError("transcript not found", path) from None
    except IsADirectoryError:
        raise InputError("transcript is a folder, not a file", path) from None
    except OSError as exc:
        raise InputError(f"cannot read transcript: {exc.strerror}", path) from None
    text = _decode(raw, path)
    return parse_transcript(text, fmt=fmt, tier=tier, sample_rate=sample_rate, alphabet=alphabet,
                            path=path, rate_wpm=rate_wpm, audio=audio)


def parse_transcript(text: str, fmt: str | None = None, tier: str | None = None,
                     sample_rate: float = 16000, alphabet: str | None = None, path=None,
                     rate_wpm: float | None = None, audio=None) -> Segments:
    """Parse transcript text (see :func:`read_transcript`); ``path`` is named in errors."""
    where = path if path is not None else "<transcript>"
    text = text.lstrip("\ufeff")
    fmt = detect_format(text, path) if fmt is None else _canonical(fmt)
    if fmt == "text":
        from visemeface.speech.g2p import text_to_segments
        seg = text_to_segments(text, rate_wpm=rate_wpm, audio=audio, path=where)
        seg.attrs["format"] = "text"
        return seg
    if not math.isfinite(float(sample_rate)) or float(sample_rate) <= 0:
        raise InputError(f"sample rate must be positive, got {sample_rate!r}")
    parser, candidates = _PARSERS[fmt]
    rows = parser(text, where, tier=tier, sample_rate=float(sample_rate))
    if not rows:
        raise InputError(f"no phone segments found ({fmt} format)", where, max(1, len(text.splitlines())))
    seg = make_segments(rows, where, alphabet=alphabet, candidates=candidates)
    seg.attrs["format"] = fmt
    return seg


def detect_format(text: str, path=None) -> str:
    """Guess a transcript's format from its content (and file suffix).

    Order: TextGrid header; JSON object; MFA CSV header; bracketed DECtalk
    string; label lines of integers (TIMIT samples vs HTK 100 ns told apart by
    suffix, else by their size); xwaves header; timed lines; else plain text.
    """
    stripped = text.lstrip("\ufeff").strip()
    suffix = Path(path).suffix.lower() if path is not None else ""
    where = path if path is not None else "<transcript>"
    if not stripped:
        raise InputError("transcript is empty", where, 1)
    head = stripped[:300]
    if "ooTextFile" in head or suffix == ".textgrid":
        return "textgrid"
    if stripped.startswith("{"):
        return "mfa-json"
    first = stripped.splitlines()[0].lower()
    if "," in first and {"begin", "end", "label"} <= {c.strip() for c in first.split(",")}:
        return "mfa-csv"
    if stripped.startswith("[") and not _TEXT_OUTSIDE_BRACKETS.search(_BRACKETS.sub(" ", stripped)):
        return "dectalk"
    lines = [ln for ln in (_strip_comment(s) for s in stripped.splitlines()) if ln]
    top = stripped.splitlines()[:40]
    if "#" in [ln.strip() for ln in top]:
        header = top[:[ln.strip() for ln in top].index("#")]
        if suffix == ".lab" or any(ln.split()[:1] in (["separator"], ["nfields"], ["signal"], ["type"])
                                   for ln in header):
            return "lab"                       # xwaves/ESPS header ended by "#"
    if suffix == ".phn":
        return "phn"
    if suffix == ".lab":
        return "lab"
    fields = [ln.split() for ln in lines[:200]]
    if fields and all(len(f) >= 1 and _is_number(f[0]) for f in fields):
        ints = [f for f in fields if len(f) >= 3 and _is_int(f[0]) and _is_int(f[1])]
        if len(ints) == len(fields) and max(int(f[1]) for f in ints) > 1000:
            lengths = np.median([int(f[1]) - int(f[0]) for f in ints])
            return "lab" if lengths > 50000 else "phn"
        return "timed"
    return "text"


def make_segments(rows, path=None, alphabet: str | None = None,
                  candidates=("dectalk", "arpabet", "timit", "ipa")) -> Segments:
    """Validate raw ``(start, end, label, line)`` rows and build Segments.

    ``end`` may be None (``start phone`` lines): it becomes the next row's
    start, or the phone's inherent duration for the last row. Labels are
    mapped to DECtalk; gaps become silence (with a warning); overlaps, times
    out of order, negative or non-finite times raise InputError with the line.
    """
    where = path if path is not None else "<transcript>"
    rows = [r if isinstance(r, _Row) else _Row(*r) for r in rows]
    if not rows:
        raise InputError("no phone segments found", where, None)
    symbols = _map_labels(rows, where, alphabet, candidates)
    # Fill open ends, check times.
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
        merge = phones and phones[-1] == sym and (sym == SILENCE or closure_prev)
        if merge:
            ends[-1] = r.end
        else:
            _append(starts, ends, phones, begin, r.end, sym)
        closure_prev = r.closure
        prev_line = r.line
    if not phones:
        raise InputError("no phone segment has a positive duration", where, rows[-1].line)
    return segments_frame(starts, ends, phones)


def segments_frame(starts, ends, phones) -> Segments:
    """Build a Segments DataFrame from arrays (no validation)."""
    return pd.DataFrame({"start": np.asarray(starts, dtype=float), "end": np.asarray(ends, dtype=float),
                         "phoneme": list(phones)})


# ----------------------------------------------------------------------------- helpers

def _append(starts, ends, phones, s, e, sym):
    if phones and phones[-1] == sym == SILENCE:
        ends[-1] = e
    else:
        starts.append(s)
        ends.append(e)
        phones.append(sym)


def _canonical(fmt: str) -> str:
    return choose(fmt, FORMATS, "transcript format", _ALIASES)


def _decode(raw: bytes, path) -> str:
    if raw.startswith((b"\xff\xfe", b"\xfe\xff")):
        try:
            return raw.decode("utf-16")
        except UnicodeDecodeError:
            raise InputError("not valid UTF-16 text", path) from None
    try:
        return raw.decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        line = raw[:exc.start].count(b"\n") + 1
        raise InputError(f"not UTF-8 text (byte 0x{raw[exc.start]:02x})", path, line) from None


_BRACKETS = re.compile(r"\[[^\[\]]*\]")
_TEXT_OUTSIDE_BRACKETS = re.compile(r"[^\s\[\]]")
_COMMENT = re.compile(r"(^|\s)[#;].*$")


def _strip_comment(line: str) -> str:
    return _COMMENT.sub("", line).strip()


def _is_number(s: str) -> bool:
    try:
        float(s)
    except ValueError:
        return False
    return True


def _is_int(s: str) -> bool:
    return re.fullmatch(r"[+-]?\d+", s) is not None


def _number(s: str, what: str, where, line) -> float:
    try:
        value = float(s)
    except ValueError:
        raise InputError(f"{what} {s!r} is not a number", where, line) from None
    if not math.isfinite(value):
        raise InputError(f"{what} {s!r} is not finite", where, line)
    return value


def _map_labels(rows: list[_Row], where, alphabet, candidates) -> list[str]:
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


# ----------------------------------------------------------------------------- parsers

def _lines(text: str):
    """(line number, content without comment) of the non-empty lines; handles CRLF."""
    for i, raw in enumerate(text.splitlines(), start=1):
        line = _strip_comment(raw)
        if line:
            yield i, line


def _parse_timed(text, where, **_):
    rows: list[_Row] = []
    for i, line in _lines(text):
        f = line.split()
        if len(f) == 1 and _is_number(f[0]):
            if not rows or rows[-1].end is not None:
                raise InputError(f"a line with only a time ({f[0]}) must end a 'start phone' line",
                                 where, i)
            rows[-1].end = _number(f[0], "end time", where, i)
            continue
        if len(f) == 2:
            rows.append(_Row(_number(f[0], "start time", where, i), None, f[1], i))
        elif len(f) == 3:
            rows.append(_Row(_number(f[0], "start time", where, i), _number(f[1], "end time", where, i),
                             f[2], i))
        else:
            raise InputError(f"expected 'start end phone' or 'start phone', got {line!r}", where, i)
        if len(rows) > 1 and rows[-2].end is None and rows[-2].start > rows[-1].start:
            raise InputError(f"segment starts at {rows[-1].start:g} s, before the previous one "
                             f"(line {rows[-2].line}): times must increase", where, i)
    return rows


_HTS = re.compile(r"-([^-+]+)\+")


def _parse_lab(text, where, **_):
    lines = text.splitlines()
    sep = next((k for k, ln in enumerate(lines[:60]) if ln.strip() == "#"), None)
    if sep is not None:
        return _parse_xwaves(lines, sep, where)
    rows: list[_Row] = []
    for i, raw in enumerate(lines, start=1):
        line = raw.strip()
        if not line or line.startswith(("#", ";")) or line == "///":
            continue
        f = line.split()
        if len(f) < 3:
            raise InputError(f"expected 'start end label' (100 ns units), got {line!r}", where, i)
        start = _number(f[0], "start time", where, i) * 1e-7
        end = _number(f[1], "end time", where, i) * 1e-7
        label = f[2]
        m = _HTS.search(label)
        if m:
            label = m.group(1)
        rows.append(_Row(start, end, label, i))
    return rows


def _parse_xwaves(lines, sep, where):
    rows: list[_Row] = []
    prev = 0.0
    for i in range(sep + 1, len(lines)):
        line = lines[i].strip()
        if not line:
            continue
        f = line.split(None, 2)
        if len(f) < 3:
            if len(f) == 2 and _is_number(f[0]):   # an end time without a label: silence
                f = [f[0], f[1], ""]
            else:
                raise InputError(f"expected 'end_time colour label', got {line!r}", where, i + 1)
        end = _number(f[0], "end time", where, i + 1)
        rows.append(_Row(prev, end, f[2].strip(), i + 1))
        prev = end
    return rows


def _parse_phn(text, where, sample_rate=16000.0, **_):
    rows: list[_Row] = []
    for i, line in _lines(text):
        f = line.split()
        if len(f) != 3:
            raise InputError(f"expected 'start_sample end_sample label', got {line!r}", where, i)
        for s in f[:2]:
            if not _is_int(s):
                raise InputError(f"sample index {s!r} is not an integer", where, i)
        label = f[2]
        closure = label.lower() in ("bcl", "dcl", "gcl", "pcl", "tcl", "kcl")
        rows.append(_Row(int(f[0]) / sample_rate, int(f[1]) / sample_rate, label, i, closure))
    return rows


def _pick_tier(names: list[str], tier, where, line: int | None = None) -> str:
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


def _parse_textgrid(text, where, tier=None, **_):
    from praatio.utilities import textgrid_io
    text = text.replace("\r\n", "\n").replace("\r", "\n")
    try:
        tg = textgrid_io.parseTextgridStr(text, includeEmptyIntervals=True)
        tiers = tg["tiers"]
        names = [t["name"] for t in tiers]
    except InputError:
        raise
    except Exception as exc:  # praatio raises IndexError, ValueError, KeyError... on bad text
        raise InputError(f"not a readable TextGrid ({type(exc).__name__}: {exc})", where,
                         None) from None
    name = _pick_tier(names, tier, where)
    t = tiers[names.index(name)]
    if t.get("class") not in (None, "IntervalTier"):
        raise InputError(f"tier {name!r} is a point tier, not an interval tier", where)
    line_of = _interval_lines(text, names.index(name))
    rows = []
    for k, entry in enumerate(t["entries"]):
        try:
            start, end, label = float(entry[0]), float(entry[1]), str(entry[2])
        except (TypeError, ValueError, IndexError, OverflowError):
            raise InputError(f"tier {name!r} interval {k + 1} is malformed: {entry!r}", where,
                             line_of(k)) from None
        rows.append(_Row(start, end, label, line_of(k)))
    return rows


_TG_TOKEN = re.compile(r'"(?:[^"]|"")*"|<exists>|[-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?')


def _interval_lines(text: str, tier_index: int):
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
    except (ValueError, IndexError):
        return lambda k: None
    return lambda k: tokens[start + 3 * k][1] if start + 3 * k < len(tokens) else None


def _parse_mfa_json(text, where, tier=None, **_):
    try:
        data = json.loads(text)
    except json.JSONDecodeError as exc:
        raise InputError(f"not valid JSON: {exc.msg}", where, exc.lineno) from None
    if not isinstance(data, dict) or "tiers" not in data:
        raise InputError("JSON has no 'tiers': not MFA output", where, 1)
    tiers = data["tiers"]
    if isinstance(tiers, dict):
        named = {str(k): v for k, v in tiers.items()}
    elif isinstance(tiers, list):
        named = {str(t.get("name", i)) if isinstance(t, dict) else str(i): t for i, t in enumerate(tiers)}
    else:
        raise InputError("'tiers' is neither an object nor a list", where, 1)
    name = _pick_tier(list(named), tier, where)
    t = named[name]
    entries = t.get("entries") if isinstance(t, dict) else t
    if not isinstance(entries, list):
        raise InputError(f"tier {name!r} has no list of entries", where, 1)
    rows = []
    for k, e in enumerate(entries):
        if isinstance(e, dict):
            e = [e.get("start", e.get("xmin")), e.get("end", e.get("xmax")), e.get("label", e.get("text", ""))]
        if not isinstance(e, (list, tuple)) or len(e) < 3:
            raise InputError(f"tier {name!r} entry {k + 1} is not [start, end, label]: {e!r}", where)
        try:
            start, end = float(e[0]), float(e[1])
        except (TypeError, ValueError, OverflowError):
            raise InputError(f"tier {name!r} entry {k + 1} has non-numeric times: {e!r}", where) from None
        rows.append(_Row(start, end, "" if e[2] is None else str(e[2]), None))
    total = data.get("end")
    if isinstance(total, (int, float)) and rows and math.isfinite(total) and total > rows[-1].end:
        rows.append(_Row(rows[-1].end, float(total), "", None))   # MFA leaves final silence out
    return rows


def _parse_mfa_csv(text, where, tier=None, **_):
    reader = csv.reader(io.StringIO(text.replace("\r\n", "\n")))
    try:
        header = [h.strip().lower() for h in next(reader)]
    except StopIteration:
        raise InputError("CSV is empty", where, 1) from None
    except csv.Error as exc:
        raise InputError(f"bad CSV: {exc}", where, 1) from None
    need = ["begin", "end", "label"]
    missing = [c for c in need if c not in header]
    if missing:
        raise InputError(f"CSV header lacks {', '.join(missing)} (MFA: Begin,End,Label,Type,Speaker)", where, 1)
    ib, ie, il = (header.index(c) for c in need)
    it = header.index("type") if "type" in header else None
    isp = header.index("speaker") if "speaker" in header else None
    records = []
    try:
        for rec in reader:
            records.append((reader.line_num, rec))
    except csv.Error as exc:
        raise InputError(f"bad CSV: {exc}", where, reader.line_num) from None
    records = [(n, r) for n, r in records if any(c.strip() for c in r)]
    if not records:
        raise InputError("no rows after the CSV header", where, 1)
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
    name = _pick_tier(names, tier, where, line=1)    # the tiers are named by the Type/Speaker columns
    rows = []
    for (n, r), key in zip(records, keys):
        if key != name:
            continue
        rows.append(_Row(_number(r[ib], "begin time", where, n), _number(r[ie], "end time", where, n),
                         r[il].strip(), n))
    rows.sort(key=lambda row: row.start)   # MFA writes words and phones interleaved, each in order
    return rows


_DEC_TOKEN = re.compile(r"\s+|<\s*([^<>]*)>|[',`\"\-#=*.!?;:()]|[^\s<>',`\"\-#=*.!?;:()]+")
_DEC_SYMBOLS = frozenset(DECTALK)
_DEC_PAUSE = {",": 0.2, ";": 0.3, ":": 0.3, ".": 0.45, "!": 0.45, "?": 0.45}


def _parse_dectalk(text, where, **_):
    from visemeface.speech.g2p import inherent_duration
    rows: list[_Row] = []
    now = 0.0
    pending: list[tuple[str, int]] = []   # symbols waiting for a duration (the last may get one)

    def flush():
        nonlocal now
        for sym, ln in pending:
            d = inherent_duration(sym)
            rows.append(_Row(now, now + d, sym, ln))
            now += d
        pending.clear()

    pos = 0
    groups = list(re.finditer(r"\[([^\[\]]*)\]", text))
    for g in groups:
        outside = text[pos:g.start()]
        if _TEXT_OUTSIDE_BRACKETS.search(outside):
            k = pos + _TEXT_OUTSIDE_BRACKETS.search(outside).start()
            raise InputError(f"text outside [ ] in a DECtalk string: {outside.strip()[:20]!r}",
                             where, text.count("\n", 0, k) + 1)
        pos = g.end()
        body = g.group(1)
        if body.lstrip().startswith(":"):
            continue                         # a DECtalk command such as [:phoneme on]
        base = g.start(1)
        for m in _DEC_TOKEN.finditer(body):
            tok = m.group(0)
            line = text.count("\n", 0, base + m.start()) + 1
            if tok.isspace() or tok in "'`\"-#=*()":
                continue
            if m.group(1) is not None:
                if not pending:
                    raise InputError(f"duration {tok} follows no phoneme", where, line)
                ms = m.group(1).split(",")[0].strip()
                dur = _number(ms, "duration (ms)", where, line) / 1000
                if dur < 0:
                    raise InputError(f"duration {ms} ms is negative", where, line)
                sym, ln = pending.pop()
                flush()
                rows.append(_Row(now, now + dur, sym, ln))
                now += dur
                continue
            if tok in _DEC_PAUSE:
                flush()
                rows.append(_Row(now, now + _DEC_PAUSE[tok], SILENCE, line))
                now += _DEC_PAUSE[tok]
                continue
            flush()
            i = 0
            low = tok.lower()
            while i < len(low):
                if low[i:i + 2] in _DEC_SYMBOLS:
                    pending.append((low[i:i + 2], line))
                    i += 2
                elif low[i] in _DEC_SYMBOLS:
                    pending.append((low[i], line))
                    i += 1
                else:
                    raise InputError(f"unknown DECtalk phoneme at {tok[i:i + 3]!r} in {tok!r}"
                                     f"{close_matches(low[i:i + 2], DECTALK)}", where, line)
        flush()
    rest = text[pos:]
    if _TEXT_OUTSIDE_BRACKETS.search(rest):
        k = pos + _TEXT_OUTSIDE_BRACKETS.search(rest).start()
        raise InputError(f"text outside [ ] in a DECtalk string: {rest.strip()[:20]!r}",
                         where, text.count("\n", 0, k) + 1)
    return rows


_PARSERS = {
    "timed": (_parse_timed, ("dectalk", "arpabet", "timit", "ipa")),
    "lab": (_parse_lab, ("timit", "arpabet", "dectalk", "ipa")),
    "phn": (_parse_phn, ("timit",)),
    "textgrid": (_parse_textgrid, ("ipa", "arpabet", "timit", "dectalk")),
    "mfa-json": (_parse_mfa_json, ("ipa", "arpabet", "timit", "dectalk")),
    "mfa-csv": (_parse_mfa_csv, ("ipa", "arpabet", "timit", "dectalk")),
    "dectalk": (_parse_dectalk, ("dectalk",)),
}
