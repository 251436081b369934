"""The DECtalk phoneme inventory, Edge & Maddock's (2001) perceptual classes, and maps onto it.

Every timed phoneme in visemeface is a DECtalk symbol, as in Edge & Maddock (2001): 56 symbols,
one speech posture (viseme) each, index 0 being silence ``_``.

Silence and pause
-----------------
A *pause* is not a separate posture: it is a silence segment with a duration
(DECtalk writes ``_<300>`` for a 300 ms pause). Every silence-like label of the
other alphabets -- TIMIT ``h#``, ``pau``, ``epi``; Montreal Forced Aligner's
``sil``, ``sp`` (short pause), ``spn`` (spoken noise: no phones known, the
mouth is treated as at rest) and empty interval labels -- maps to ``_``.
So the 56 postures are the 56 symbols of :data:`DECTALK`, silence/pause
included, and :data:`PAUSE` is :data:`SILENCE`.

Alphabets
---------
``"dectalk"``
    The symbols themselves (case-insensitive).
``"arpabet"``
    CMUdict ARPAbet with or without stress digits (``AH0``, ``AH1``, ``AH``),
    plus the extended symbols (``AX``, ``AXR``, ``IX``, ``DX``, ``EL``, ``EN``...).
    Unstressed ``AH0`` is the schwa ``ax`` and ``IH0`` the reduced ``ix``.
``"timit"``
    TIMIT's 61 labels; a stop closure (``bcl``...) maps to its stop.
``"ipa"`` (alias ``"mfa"``)
    The IPA phones of MFA's English models; length and secondary-articulation
    marks are dropped when the exact phone is not listed.

The tables live in ``data/phonemes/*.csv``.

Examples
--------
>>> to_dectalk("AH0", alphabet="arpabet")
'ax'
>>> to_dectalk("bcl", alphabet="timit")
'b'
>>> to_dectalk("tʰ", alphabet="ipa")
't'
>>> CLASSES["a"]
('p', 'b', 'm')
"""

from __future__ import annotations

import csv
import unicodedata
from functools import lru_cache

from visemeface.errors import InputError, choose, close_matches
from visemeface.resources import data_path

__all__ = [
    "ALPHABETS", "CLASSES", "CLASS_EXAMPLES", "CLOSURE", "DECTALK", "LABIODENTAL", "PAUSE",
    "SILENCE", "SILENCE_LABELS", "VOWELS", "alphabet_symbols", "class_of", "class_label",
    "inventory", "is_vowel", "to_dectalk",
]


def _read_rows(name: str) -> list[dict[str, str]]:
    """Rows of ``data/phonemes/<name>`` (``#`` comment lines skipped)."""
    path = data_path("phonemes", name)
    with open(path, encoding="utf-8", newline="") as f:
        lines = [line for line in f if not line.lstrip().startswith("#")]
    return list(csv.DictReader(lines))


@lru_cache(maxsize=1)
def inventory() -> tuple[dict[str, str], ...]:
    """The 56 DECtalk phonemes as dicts (index, symbol, kind, place, example, description)."""
    rows = tuple(_read_rows("inventory.csv"))
    assert [int(r["index"]) for r in rows] == list(range(len(rows)))
    return rows


#: The 56 DECtalk symbols in index order; ``DECTALK[0] == "_"`` is silence.
DECTALK: tuple[str, ...] = tuple(r["symbol"] for r in inventory())
#: The silence symbol. A pause is a silence segment with a duration.
SILENCE = "_"
PAUSE = SILENCE
#: Vowel symbols (monophthongs, diphthongs, r-coloured vowels).
VOWELS: frozenset[str] = frozenset(r["symbol"] for r in inventory() if r["kind"] == "vowel")
#: Phonemes whose lips must close completely (bilabials).
CLOSURE: tuple[str, ...] = tuple(r["symbol"] for r in inventory() if r["place"] == "bilabial")
#: Phonemes whose lower lip must touch the upper teeth (labiodentals).
LABIODENTAL: tuple[str, ...] = tuple(r["symbol"] for r in inventory() if r["place"] == "labiodental")

#: Edge & Maddock (2001) Table 2's eight perceptual classes, keyed by the paper's letters a-h.
CLASSES: dict[str, tuple[str, ...]] = {
    r["class"]: tuple(r["phonemes"].split()) for r in _read_rows("classes.csv")}
#: The paper's example word for each class.
CLASS_EXAMPLES: dict[str, str] = {r["class"]: r["example"] for r in _read_rows("classes.csv")}

#: Labels that mean silence in every alphabet (TIMIT, HTK/HTS, MFA).
SILENCE_LABELS: frozenset[str] = frozenset({"", "_", "sil", "sp", "spn", "pau", "pause", "h#", "epi", "#"})

ALPHABETS = ("dectalk", "arpabet", "timit", "ipa")
_ALIASES = {"mfa": "ipa", "cmu": "arpabet", "cmudict": "arpabet", "decktalk": "dectalk"}

# Length and secondary-articulation marks dropped when an IPA phone is not listed as written.
_IPA_MODIFIERS = "ːˑʰʲʷ\u032a\u0303"


def class_label(key: str) -> str:
    """The paper's notation of class ``key``, e.g. ``"/p,b,m/"``."""
    return "/" + ",".join(CLASSES[key]) + "/"


def class_of(symbol: str) -> str | None:
    """The Table-2 class letter of a DECtalk symbol, or None if it is in none."""
    for key, members in CLASSES.items():
        if symbol in members:
            return key
    return None


def is_vowel(symbol: str) -> bool:
    """True for DECtalk vowel symbols."""
    return symbol in VOWELS


@lru_cache(maxsize=None)
def _table(alphabet: str) -> dict[str, str]:
    if alphabet == "dectalk":
        return {s: s for s in DECTALK}
    rows = _read_rows(f"{alphabet}.csv")
    table = {r[alphabet]: r["dectalk"] for r in rows}
    bad = sorted(set(table.values()) - set(DECTALK))
    assert not bad, f"{alphabet}.csv maps to unknown DECtalk symbols {bad}"
    return table


def alphabet_symbols(alphabet: str) -> tuple[str, ...]:
    """The symbols :func:`to_dectalk` accepts for ``alphabet`` (silence labels aside)."""
    return tuple(_table(_canonical(alphabet)))


def _canonical(alphabet: str) -> str:
    return choose(alphabet, ALPHABETS, "phone alphabet", _ALIASES)


def to_dectalk(symbol: str, alphabet: str = "dectalk") -> str:
    """Map one phone label onto its DECtalk symbol.

    Parameters
    ----------
    symbol : str
        The label, e.g. ``"AH1"`` (ARPAbet), ``"tcl"`` (TIMIT), ``"ɑː"`` (IPA).
        Surrounding white space is ignored; silence labels (``sil``, ``sp``,
        ``spn``, ``pau``, ``h#``, ``epi``, empty) map to ``"_"`` in every alphabet.
    alphabet : {"dectalk", "arpabet", "timit", "ipa", "mfa"}
        The label's alphabet.

    Returns
    -------
    str
        A member of :data:`DECTALK`.

    Raises
    ------
    InputError
        Unknown symbol (the message names it and the nearest known symbols) or
        unknown alphabet.
    """
    name = _canonical(alphabet)
    raw = "" if symbol is None else str(symbol)
    label = unicodedata.normalize("NFC", raw.strip())
    if label.lower() in SILENCE_LABELS:
        return SILENCE
    table = _table(name)
    if name == "ipa":
        if label in table:
            return table[label]
        bare = "".join(ch for ch in unicodedata.normalize("NFD", label) if ch not in _IPA_MODIFIERS)
        bare = unicodedata.normalize("NFC", bare)
        if bare in table:
            return table[bare]
    elif name == "arpabet":
        up = label.upper()
        if up in table:
            return table[up]
        if up[-1:] in "012" and up[:-1] in table:
            return table[up[:-1]]
    else:
        low = label.lower()
        if low in table:
            return table[low]
    known = list(table)
    raise InputError(f"unknown {name} phone {raw!r}"
                     + (close_matches(label if name == "ipa" else
                                      (label.upper() if name == "arpabet" else label.lower()), known)
                        or f" (known: {' '.join(known[:12])} ...)"))
