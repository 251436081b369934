"""Write a timed transcript (phones, and words where known) in the formats the readers take.

So an aligned or recognised utterance can be corrected by hand (Praat, a text
editor) and animated again with ``visemeface speak``. Every writer's output
reads back through :func:`visemeface.speech.transcripts.read_utterance` to the
same Segments (times to 0.1 ms).

========  ============  ======================================================
suffix    format        content
========  ============  ======================================================
``.txt``  ``timed``     ``start end phone`` lines (s), ``#`` header comment
``.lab``  ``lab``       HTK labels ``start end phone`` in 100 ns units
``.TextGrid`` ``textgrid``  Praat long TextGrid, tiers ``words`` (if any) and ``phones``; silence is empty
``.json`` ``mfa-json``  Montreal Forced Aligner JSON, tiers ``words`` and ``phones``; an aligned
                        text adds ``word_confidence``: per word ``word``, ``start``, ``end``,
                        ``confidence`` (0..1, below 0.5 doubtful) and ``margin``
========  ============  ======================================================

Phones are DECtalk symbols (the project's own). A reader that guesses the
alphabet reads them as DECtalk except in the rare file whose every label is
also a TIMIT label (``.lab``: ``er`` and ``nx`` then mean TIMIT's): give
``--alphabet dectalk`` when reading such a file back.
"""

from __future__ import annotations

import json
from pathlib import Path

from visemeface.errors import InputError
from visemeface.outputs import atomic_output
from visemeface.postures.phonemes import SILENCE
from visemeface.speech.utterance import Utterance

__all__ = ["WRITERS", "format_of", "write_transcript"]

#: Suffix (lower case) -> format name.
SUFFIXES = {".txt": "timed", ".lab": "lab", ".textgrid": "textgrid", ".json": "mfa-json"}
#: Seconds per HTK unit.
_HTK = 1e-7


def format_of(path) -> str:
    """The transcript format written for ``path``'s suffix (:data:`SUFFIXES`)."""
    suffix = Path(path).suffix.lower()
    if suffix not in SUFFIXES:
        raise InputError(f"cannot tell the transcript format from {suffix or 'no suffix'!r}; "
                         f"name the file {', '.join(s if s != '.textgrid' else '.TextGrid' for s in SUFFIXES)}",
                         path)
    return SUFFIXES[suffix]


def _timed(u: Utterance) -> str:
    lines = ["# visemeface timed transcript: start end phone (seconds, DECtalk symbols)"]
    lines += [f"{s:.4f} {e:.4f} {p}" for s, e, p in u.segments[["start", "end", "phoneme"]].itertuples(index=False)]
    return "\n".join(lines) + "\n"


def _lab(u: Utterance) -> str:
    seg = u.segments
    return "".join(f"{round(s / _HTK)} {round(e / _HTK)} {'sil' if p == SILENCE else p}\n"
                   for s, e, p in seg[["start", "end", "phoneme"]].itertuples(index=False))


def _tiers(u: Utterance) -> dict[str, list[tuple[float, float, str]]]:
    tiers = {}
    if len(u.words):
        tiers["words"] = [(float(s), float(e), str(w)) for s, e, w in u.words[["start", "end", "word"]]
                          .itertuples(index=False)]
    tiers["phones"] = [(float(s), float(e), "" if p == SILENCE else str(p))
                       for s, e, p in u.segments[["start", "end", "phoneme"]].itertuples(index=False)]
    return tiers


def _textgrid(u: Utterance) -> str:
    tiers = _tiers(u)
    end = u.end
    out = ['File type = "ooTextFile"', 'Object class = "TextGrid"', "", "xmin = 0", f"xmax = {end!r}",
           "tiers? <exists>", f"size = {len(tiers)}", "item []:"]
    for k, (name, entries) in enumerate(tiers.items(), start=1):
        entries = _fill(entries, end)
        out += [f"    item [{k}]:", '        class = "IntervalTier"', f'        name = "{name}"',
                "        xmin = 0", f"        xmax = {end!r}", f"        intervals: size = {len(entries)}"]
        for i, (s, e, label) in enumerate(entries, start=1):
            text = label.replace('"', '""')
            out += [f"        intervals [{i}]:", f"            xmin = {s!r}", f"            xmax = {e!r}",
                    f'            text = "{text}"']
    return "\n".join(out) + "\n"


def _fill(entries, end):
    """Intervals covering 0..end (Praat needs no gaps): gaps become empty intervals."""
    out, t = [], 0.0
    for s, e, label in entries:
        if s > t + 1e-9:
            out.append((t, s, ""))
        out.append((max(s, t), e, label))
        t = e
    if end > t + 1e-9:
        out.append((t, end, ""))
    return out


def _word_confidence(u: Utterance) -> list[dict]:
    """Each aligned word's confidence and margin (:mod:`visemeface.speech.align`); null where not judged."""
    import math

    if "confidence" not in u.words:
        return []

    def number(value):
        return None if value is None or not math.isfinite(float(value)) else round(float(value), 4)

    return [{"word": str(w), "start": float(s), "end": float(e), "confidence": number(c), "margin": number(m)}
            for s, e, w, c, m in u.words[["start", "end", "word", "confidence", "margin"]].itertuples(index=False)]


def _mfa_json(u: Utterance) -> str:
    tiers = {name: {"type": "interval", "entries": [[s, e, label] for s, e, label in entries]}
             for name, entries in _tiers(u).items()}
    data = {"start": 0.0, "end": u.end, "tiers": tiers}
    confidence = _word_confidence(u)
    if confidence:
        data["word_confidence"] = confidence
    return json.dumps(data, indent=1) + "\n"


#: Format name -> function(Utterance) -> text.
WRITERS = {"timed": _timed, "lab": _lab, "textgrid": _textgrid, "mfa-json": _mfa_json}


def write_transcript(utterance, path, fmt: str | None = None, force: bool = False) -> Path:
    """Write an Utterance (or bare Segments) as a transcript file; the format from the suffix unless ``fmt``.

    The file appears complete or not at all; an existing one is replaced only with ``force``.
    """
    from visemeface.speech.timeline import check_segments

    utterance = Utterance.of(utterance, "write_transcript")
    check_segments(utterance.segments, "write")        # NaN or reversed times would not read back
    fmt = format_of(path) if fmt is None else fmt
    if fmt not in WRITERS:
        raise InputError(f"no writer for transcript format {fmt!r}; one of {', '.join(WRITERS)}")
    text = WRITERS[fmt](utterance)
    with atomic_output(path, force) as tmp:
        Path(tmp).write_text(text, encoding="utf-8")
    return Path(path)
