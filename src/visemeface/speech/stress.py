"""The lexical stress and emphasis of a text's phones: :attr:`Utterance.stress <visemeface.speech.utterance.Utterance>`.

Each vowel gets the stress digit of its word's CMUdict pronunciation (0 unstressed, 1 primary, 2 secondary;
the letter-to-sound rules stress a word's first vowel), consonants and silences NaN. A word written between
two asterisks, ``I never said *she* stole my money``, is emphasised: its phones are marked, and the
articulation (:mod:`visemeface.speech.articulation`) and the accents (:mod:`visemeface.speech.gestures`)
make more of them. An asterisk changes nothing else: the timing is the plain text's.
"""

from __future__ import annotations

import numpy as np
import pandas as pd

__all__ = ["emphasised_words", "with_text_stress"]


def emphasised_words(text: str, path=None) -> list[bool]:
    """Per word of ``text`` (as the text front end counts them, numbers spelled out): inside ``*...*``?"""
    from visemeface.speech.tokens import tokens

    out: list[bool] = []
    for k, piece in enumerate(str(text).split("*")):
        out += [k % 2 == 1] * sum(1 for kind, _, _ in tokens(piece, path) if kind == "word")
    return out


def with_text_stress(utterance, text: str, pronunciations, path=None):
    """``utterance`` (of ``text``, from :func:`~visemeface.speech.g2p.text_to_utterance`) with its ``stress``
    table: the stress digit and emphasis of every segment (module doc). ``pronunciations``: per word of the
    utterance, its DECtalk phones with their stress digits (None for a consonant), as the text front end
    pronounced it."""
    from dataclasses import replace

    seg, words = utterance.segments, utterance.words
    start, end = seg["start"].to_numpy(float), seg["end"].to_numpy(float)
    phones = [str(p) for p in seg["phoneme"]]
    stress = np.full(len(seg), np.nan)
    emphasis = np.zeros(len(seg), dtype=bool)
    try:
        marks = emphasised_words(text, path)
    except Exception:                       # an asterisk inside a tag: no emphasis, the text's own error stands
        marks = []
    if len(marks) != len(words):
        marks = [False] * len(words)
    for (ws, we), emph, pron in zip(words[["start", "end"]].itertuples(index=False), marks, pronunciations):
        rows = np.flatnonzero((start >= ws - 1e-9) & (end <= we + 1e-9) & np.array([p != "_" for p in phones]))
        emphasis[rows] = emph
        if [s for s, _ in pron] == [phones[r] for r in rows]:
            for r, (_, digit) in zip(rows, pron):
                if digit is not None:
                    stress[r] = float(digit)
    return replace(utterance, stress=pd.DataFrame({"stress": stress, "emphasis": emphasis}))
