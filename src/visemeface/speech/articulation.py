"""JA/LI: how wide each phone is articulated, from the recording or from lexical stress.

After JALI (Edwards, Landreth, Fiume & Singh, "JALI: an animator-centric viseme model for expressive
lip synchronization", SIGGRAPH 2016): a phone's viseme is played with a jaw (JA) and a lip (LI)
intensity. Here each segment ``s`` gets two factors, ``ja[s]`` and ``li[s]``, that
:func:`articulate` applies to its viseme target before the coarticulation blends the targets:

* the JA columns (:data:`JA_COLUMNS`: jaw, lower-lip depressor, upper-lip levator: the functions that
  open the lips) are multiplied by ``ja[s]``;
* the LI columns: spreading (:data:`SPREAD_COLUMNS`) by ``li[s]``, rounding (:data:`ROUND_COLUMNS`)
  by ``1 / li[s]``;
* bilabial and labiodental segments (``p b m f v``) keep their targets: their closure and lip-teeth
  contact are never weakened.

With a recording (:func:`acoustic_scales`), over each segment's middle 60 %:

.. math:: \\log ja_s = a\\,\\big(g_I\\,\\tfrac{L_s - \\tilde L}{10\\,\\mathrm{dB}}
          + g_{F1}\\,(\\log_2 \\tfrac{F1_s}{\\hat F1_p} - m_1)\\big),\\qquad
          \\log li_s = a\\, g_{F2}\\,(\\log_2 \\tfrac{F2_s}{\\hat F2_p} - m_2)

:math:`L_s` the segment's level, :math:`\\tilde L` the median level of the utterance's vowels,
:math:`\\hat F_p` the vowel's typical formants (``data/phonemes/formants.csv``), :math:`m` the median of
the log ratios over the utterance (so only how this vowel differs from the speaker's others counts);
consonants get the level term only, and no LI. Without a recording (:func:`stress_scales`) a vowel's JA
factor is its CMUdict stress's (primary, secondary, unstressed; the vowels of an emphasised word more).
``a`` is ``--articulation`` (0: every factor 1, the tabled visemes exactly; 1 the default; 2 twice the
log-factor). The factors are clipped to ``[ja_min, ja_max]``, ``[li_min, li_max]`` and the result to the
rig's ranges afterwards. The gains are ``data/phonemes/articulation.csv``'s.
"""

from __future__ import annotations

import csv
from functools import lru_cache

import numpy as np

from visemeface.errors import InputError
from visemeface.postures.phonemes import CLOSURE, LABIODENTAL, SILENCE, is_vowel
from visemeface.resources import data_path

__all__ = ["ARTICULATION_MAX", "JA_COLUMNS", "ROUND_COLUMNS", "SPREAD_COLUMNS", "acoustic_scales", "articulate",
           "check_articulation", "gains", "stress_scales", "typical_formants"]

#: Largest --articulation.
ARTICULATION_MAX = 2.0
JA_COLUMNS = ("jaw", "depressor_labii_inferioris_left", "depressor_labii_inferioris_right",
              "levator_labii_superioris_left", "levator_labii_superioris_right")
SPREAD_COLUMNS = ("risorius_left", "risorius_right")
ROUND_COLUMNS = ("orbicularis_oris", "lip_rounding")
_KEPT = frozenset(CLOSURE) | frozenset(LABIODENTAL)
#: Approximants: voiced and open enough that their level says how wide they are, as a vowel's does.
APPROXIMANTS = frozenset({"w", "yx", "r", "l", "hx", "rx", "lx", "el"})


def _rows(name):
    with open(data_path("phonemes", name), encoding="utf-8", newline="") as f:
        return list(csv.DictReader(line for line in f if not line.lstrip().startswith("#")))


@lru_cache(maxsize=1)
def gains() -> dict[str, float]:
    """``data/phonemes/articulation.csv``: name -> value."""
    return {r["name"]: float(r["value"]) for r in _rows("articulation.csv")}


@lru_cache(maxsize=1)
def typical_formants() -> dict[str, tuple[float, float]]:
    """Vowel -> (F1, F2) Hz of ``data/phonemes/formants.csv``."""
    return {r["symbol"]: (float(r["f1"]), float(r["f2"])) for r in _rows("formants.csv")}


def check_articulation(value) -> float:
    """``--articulation`` as a float in 0..:data:`ARTICULATION_MAX`, else an InputError."""
    try:
        a = float(value)
    except (TypeError, ValueError):
        raise InputError(f"--articulation must be a number in 0..{ARTICULATION_MAX:g}, got {value!r}") from None
    if not 0.0 <= a <= ARTICULATION_MAX:
        raise InputError(f"--articulation must be in 0..{ARTICULATION_MAX:g}, got {value!r}")
    return a


def _bounded(log_factor, lo, hi, kept):
    f = np.clip(np.exp(np.nan_to_num(log_factor)), lo, hi)
    f[kept] = 1.0
    return f


def acoustic_scales(acoustics, start, end, phones, articulation: float = 1.0) -> tuple[np.ndarray, np.ndarray]:
    """(ja, li) per segment from a recording's :class:`~visemeface.speech.acoustics.Acoustics` (module doc)."""
    from visemeface.speech.acoustics import span_mean, span_median

    g = gains()
    a = check_articulation(articulation)
    start, end = np.asarray(start, float), np.asarray(end, float)
    phones = [str(p) for p in phones]
    n = len(phones)
    kept = np.array([p in _KEPT or p == SILENCE for p in phones], dtype=bool)
    vowel = np.array([is_vowel(p) for p in phones], dtype=bool)
    if a == 0.0 or n == 0:
        return np.ones(n), np.ones(n)
    sonorant = vowel | np.array([p in APPROXIMANTS for p in phones], dtype=bool)
    level = span_mean(acoustics.level, acoustics.times, start, end)
    if not np.isfinite(level[vowel]).any():
        return np.ones(n), np.ones(n)
    centre = (start + end) / 2
    ref = float(np.nanmedian(level[vowel]))
    log_ja = np.where(sonorant, g["ja_per_10db"] * np.nan_to_num(level - ref) / 10.0, 0.0)
    log_li = np.zeros(n)
    typical = typical_formants()
    f1 = span_median(acoustics.f1, acoustics.times, start, end)
    f2 = span_median(acoustics.f2, acoustics.times, start, end)
    r1 = np.full(n, np.nan)
    r2 = np.full(n, np.nan)
    for s in np.flatnonzero(vowel):
        if phones[s] in typical:
            r1[s] = np.log2(f1[s] / typical[phones[s]][0])
            r2[s] = np.log2(f2[s] / typical[phones[s]][1])
    if np.isfinite(r1).any():
        log_ja += g["ja_per_f1_octave"] * np.nan_to_num(r1 - np.nanmedian(r1))
    if np.isfinite(r2).any():
        log_li += g["li_per_f2_octave"] * np.nan_to_num(r2 - np.nanmedian(r2))
    # Stops, fricatives and nasals: silent or noisy whatever the jaw does, which follows the syllable:
    # they take the factor of the nearest vowel.
    vi = np.flatnonzero(vowel)
    for s in np.flatnonzero(~sonorant & ~kept):
        log_ja[s] = log_ja[vi[np.argmin(np.abs(centre[vi] - centre[s]))]]
    return (_bounded(a * log_ja, g["ja_min"], g["ja_max"], kept),
            _bounded(a * log_li, g["li_min"], g["li_max"], kept | ~vowel))


def stress_scales(phones, stress, emphasis=None, articulation: float = 1.0) -> tuple[np.ndarray, np.ndarray]:
    """(ja, li) per segment from lexical stress: ``stress`` the CMUdict digit of each vowel (0, 1, 2; NaN for
    consonants and silence), ``emphasis`` true for the phones of an emphasised word (module doc)."""
    g = gains()
    a = check_articulation(articulation)
    phones = [str(p) for p in phones]
    n = len(phones)
    st = np.asarray(stress if stress is not None else np.full(n, np.nan), dtype=float)
    em = np.zeros(n, bool) if emphasis is None else np.asarray(emphasis, dtype=bool)
    factor = np.ones(n)
    factor[st == 1] = g["stress_primary"]
    factor[st == 2] = g["stress_secondary"]
    factor[st == 0] = g["stress_unstressed"]
    factor[em & (st == 1)] = g["stress_emphasis"]
    factor[em & (st == 2)] = max(g["stress_emphasis"] ** 0.5, g["stress_secondary"])
    kept = np.array([p in _KEPT or p == SILENCE or not is_vowel(p) for p in phones], dtype=bool)
    ja = _bounded(a * np.log(factor), g["ja_min"], g["ja_max"], kept)
    return ja, np.ones(n)


def articulate(targets: np.ndarray, columns, phones, ja: np.ndarray, li: np.ndarray) -> np.ndarray:
    """The (S, C) viseme targets with each segment's JA and LI factors applied (module doc); a new array."""
    out = np.array(targets, dtype=float, copy=True)
    ja = np.asarray(ja, dtype=float)
    li = np.asarray(li, dtype=float)
    if ja.shape != (out.shape[0],) or li.shape != (out.shape[0],):
        raise InputError(f"articulation factors for {ja.size} and {li.size} segments, the utterance has "
                         f"{out.shape[0]}")
    if not (np.isfinite(ja).all() and np.isfinite(li).all() and (ja > 0).all() and (li > 0).all()):
        raise InputError("articulation factors must be finite and positive")
    keep = np.array([str(p) in _KEPT for p in phones], dtype=bool)
    ja = np.where(keep, 1.0, ja)
    li = np.where(keep, 1.0, li)
    col = {str(c): j for j, c in enumerate(columns)}
    for names, f in ((JA_COLUMNS, ja), (SPREAD_COLUMNS, li), (ROUND_COLUMNS, 1.0 / li)):
        idx = [col[c] for c in names if c in col]
        out[:, idx] *= f[:, None]
    return out
