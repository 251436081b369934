"""Read timed phoneme transcripts into Segments (one module per format, behind a registry).

Segments
--------
A pandas DataFrame with columns ``start``, ``end`` (float seconds) and
``phoneme`` (a DECtalk symbol, see :mod:`visemeface.postures.phonemes`),
sorted, contiguous from 0, without overlaps; gaps are filled with silence
``_`` and consecutive silences are merged. :func:`read_utterance` returns it
inside an :class:`~visemeface.speech.utterance.Utterance` with the format
read (and, for English text, the words and inline emotion keys).

Formats (``fmt=``; detected from the content when None)
-------------------------------------------------------
Each lives in its own module with ``NAME``, ``ALPHABETS`` (the phone alphabets
tried, in order) and ``parse(text, where, **options) -> list[Row]``:
:mod:`.timed`, :mod:`.lab` (HTK/HTS and xwaves), :mod:`.phn` (TIMIT),
:mod:`.textgrid` (Praat/MFA), :mod:`.mfa_json`, :mod:`.mfa_csv`,
:mod:`.dectalk`; ``"text"`` is plain English, timed by
:func:`visemeface.speech.g2p.text_to_utterance`.

Phone labels are mapped with :func:`visemeface.postures.phonemes.to_dectalk`;
the alphabet (``alphabet=``) is otherwise the first of the format's candidates
in which every label is known.

Errors
------
Everything wrong with the input raises :class:`~visemeface.errors.InputError`
naming the file and line: unknown phones, non-numeric, negative or non-finite
times, a segment ending before it starts, segments out of order or
overlapping (both lines named), phones lasting seconds on average (wrong time
units or format). Gaps are filled with silence and reported with a warning.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from visemeface.errors import InputError, choose
from visemeface.postures.phonemes import SILENCE
from visemeface.speech.transcripts import dectalk, lab, mfa_csv, mfa_json, phn, textgrid, timed
from visemeface.speech.transcripts.lexing import (BRACKETS, TEXT_OUTSIDE_BRACKETS, decode, is_int, is_number,
                                                  strip_comment)
from visemeface.speech.transcripts.segments import Row, make_segments, segments_frame
from visemeface.speech.utterance import Segments, Utterance

__all__ = ["FORMATS", "PARSERS", "Row", "Segments", "detect_format", "make_segments", "parse_transcript",
           "parse_utterance", "read_transcript", "read_utterance", "segments_frame"]

#: Format name -> its module (``NAME``, ``ALPHABETS``, ``parse``).
PARSERS = {m.NAME: m for m in (timed, lab, phn, textgrid, mfa_json, mfa_csv, dectalk)}
#: Format names accepted by ``fmt=``.
FORMATS = tuple(PARSERS) + ("text",)
_ALIASES = {"htk": "lab", "hts": "lab", "xwaves": "lab", "esps": "lab", "timit": "phn",
            "praat": "textgrid", "json": "mfa-json", "mfa_json": "mfa-json", "csv": "mfa-csv",
            "mfa_csv": "mfa-csv", "plain": "text", "txt": "timed"}
#: Formats with several tiers, among which ``tier=`` chooses.
TIERED = ("textgrid", "mfa-json", "mfa-csv")
#: A transcript whose median phone lasts longer than this (s) has wrong time units or format:
#: speech phones last 0.03-0.3 s and even a sung vowel rarely 5 s, while TIMIT samples read as
#: HTK units (or the reverse) are off by a factor of 625.
MAX_MEDIAN_PHONE = 5.0
#: ... or shorter than this (s): seconds read as HTK's 100 ns units come out 10⁷ times too short, and
#: even very fast speech keeps its median phone above 20 ms.
MIN_MEDIAN_PHONE = 0.005


def read_utterance(path, fmt: str | None = None, tier: str | None = None, sample_rate: float = 16000,
                   alphabet: str | None = None, rate_wpm: float | None = None, audio=None) -> Utterance:
    """Read a transcript file into an :class:`Utterance`.

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
        For plain text only: speaking rate, or a recording of the text to align it to
        (:func:`timed_text`); ``rate_wpm`` given for a timed format is an error.

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
    return parse_utterance(decode(raw, path), fmt=fmt, tier=tier, sample_rate=sample_rate, alphabet=alphabet,
                           path=path, rate_wpm=rate_wpm, audio=audio)


def read_transcript(path, fmt: str | None = None, tier: str | None = None, sample_rate: float = 16000,
                    alphabet: str | None = None, rate_wpm: float | None = None, audio=None) -> Segments:
    """The Segments of :func:`read_utterance` (same parameters)."""
    return read_utterance(path, fmt, tier, sample_rate, alphabet, rate_wpm, audio).segments


def timed_text(text: str, rate_wpm: float | None = None, audio=None, where=None) -> Utterance:
    """English text timed: by forced alignment to ``audio``, a recording of it
    (:func:`visemeface.speech.align.utterance_from_audio`; ``rate_wpm`` is then ignored), else by the
    text-to-phoneme rules at ``rate_wpm`` (:func:`visemeface.speech.g2p.text_to_utterance`)."""
    if audio is not None:
        from visemeface.speech.align import utterance_from_audio
        return utterance_from_audio(audio, text, text_where=where)
    from visemeface.speech.g2p import text_to_utterance
    return text_to_utterance(text, rate_wpm=rate_wpm, path=where)


def parse_utterance(text: str, fmt: str | None = None, tier: str | None = None, sample_rate: float = 16000,
                    alphabet: str | None = None, path=None, rate_wpm: float | None = None,
                    audio=None) -> Utterance:
    """Parse transcript text (see :func:`read_utterance`); ``path`` is named in errors."""
    where = path if path is not None else "<transcript>"
    text = text.lstrip("\ufeff")
    fmt = detect_format(text, path) if fmt is None else choose(fmt, FORMATS, "transcript format", _ALIASES)
    if tier is not None and fmt not in TIERED:
        raise InputError(f"--tier applies to {', '.join(TIERED)} transcripts, not to the {fmt} format", where)
    if fmt == "text":
        return timed_text(text, rate_wpm, audio, where)
    if rate_wpm is not None:
        raise InputError(f"--rate applies to plain text only; this transcript is timed ({fmt} format)", where)

    if not math.isfinite(float(sample_rate)) or float(sample_rate) <= 0:
        raise InputError(f"sample rate must be positive, got {sample_rate!r}")
    reader = PARSERS[fmt]
    rows = reader.parse(text, where, tier=tier, sample_rate=float(sample_rate))
    if not rows:
        raise InputError(f"no phone segments found ({fmt} format)", where, max(1, len(text.splitlines())))
    seg = make_segments(rows, where, alphabet=alphabet, candidates=reader.ALPHABETS)
    _check_plausible(seg, rows, fmt, where)
    return Utterance(seg, source_format=fmt)


def parse_transcript(text: str, fmt: str | None = None, tier: str | None = None,
                     sample_rate: float = 16000, alphabet: str | None = None, path=None,
                     rate_wpm: float | None = None, audio=None) -> Segments:
    """The Segments of :func:`parse_utterance` (same parameters)."""
    return parse_utterance(text, fmt, tier, sample_rate, alphabet, path, rate_wpm, audio).segments


def _check_plausible(seg: Segments, rows: list[Row], fmt: str, where) -> None:
    """Refuse phones lasting many seconds or a few microseconds: wrong time units, sample rate or format.

    ``rows`` are the rows read (their ends filled by :func:`make_segments`): the
    error names the line of the first phone as long as the median.
    """
    speech = seg[seg["phoneme"] != SILENCE]
    if not len(speech):
        return
    median = float((speech["end"] - speech["start"]).median())
    if median > MAX_MEDIAN_PHONE or median < MIN_MEDIAN_PHONE:
        sign = 1.0 if median > MAX_MEDIAN_PHONE else -1.0     # the first phone as long (as short) as the median
        line = next((r.line for r in rows if r.end is not None and sign * (r.end - r.start - median) >= -1e-9 * median),
                    None)
        raise InputError(f"the median phone lasts {median:.3g} s (speech: 0.03-0.3 s): wrong time units "
                         f"for the {fmt} format? (try --format, or --sample-rate for TIMIT .PHN)", where, line)


def detect_format(text: str, path=None) -> str:
    """Guess a transcript's format from its content (and file suffix).

    Order: TextGrid header; JSON object; MFA CSV header; bracketed DECtalk
    string; label lines of integers (TIMIT samples vs HTK 100 ns told apart by
    suffix, else by their size); xwaves header; timed lines; else plain text.
    A file of comments only is empty.
    """
    stripped = text.lstrip("\ufeff").strip()
    suffix = Path(path).suffix.lower() if path is not None else ""
    where = path if path is not None else "<transcript>"
    lines = [ln for ln in (strip_comment(s) for s in stripped.splitlines()) if ln]
    if not stripped or not lines:
        raise InputError("transcript is empty" + (" (only comments)" if stripped else ""), where, 1)
    head = stripped[:300]
    if "ooTextFile" in head or suffix == ".textgrid":
        return "textgrid"
    if stripped.startswith("{"):
        return "mfa-json"
    first = stripped.splitlines()[0].lower()
    if "," in first and {"begin", "end", "label"} <= {c.strip() for c in first.split(",")}:
        return "mfa-csv"
    if stripped.startswith("[") and not TEXT_OUTSIDE_BRACKETS.search(BRACKETS.sub(" ", stripped)):
        return "dectalk"
    top = [ln.strip() for ln in stripped.splitlines()[:40]]
    if "#" in top:
        header = top[:top.index("#")]
        if suffix == ".lab" or any(ln.split()[:1] in (["separator"], ["nfields"], ["signal"], ["type"])
                                   for ln in header):
            return "lab"                       # xwaves/ESPS header ended by "#"
    if suffix in (".phn", ".lab"):
        return suffix[1:]
    fields = [ln.split() for ln in lines[:200]]
    if all(len(f) >= 1 and is_number(f[0]) for f in fields):
        ints = [f for f in fields if len(f) >= 3 and is_int(f[0]) and is_int(f[1])]
        if len(ints) == len(fields) and max(int(f[1]) for f in ints) > 1000:
            lengths = np.median([int(f[1]) - int(f[0]) for f in ints])
            return "lab" if lengths > 50000 else "phn"
        return "timed"
    return "text"
