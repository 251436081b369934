"""Size of a text to speak, checked before any letter-to-sound: its longest word and its length in time."""

from __future__ import annotations

import re

from visemeface.errors import InputError

#: Longest word spoken, in letters: English's longest dictionary words have 45; a longer run of letters is
#: no word (a 120,000-letter one took 143 s of letter-to-sound before it was accepted).
MAX_WORD_LETTERS = 100


def check_text_size(text: str, rate_wpm: float, path) -> None:
    """Refuse, before any letter-to-sound, a word over :data:`MAX_WORD_LETTERS` letters or a text whose words
    at ``rate_wpm`` last longer than one run may (a 2 MB line was read for 514 s before it was refused)."""
    from visemeface.animate import MAX_UTTERANCE_S

    long = re.search(r"[^\W\d_]{%d,}" % (MAX_WORD_LETTERS + 1), text)
    if long:
        n = len(re.match(r"[^\W\d_]+", text[long.start():]).group())
        line = text[:long.start()].count("\n") + 1 if path is not None else None
        raise InputError(f"a word of {n} letters ({text[long.start():long.start() + 12]!r}...); words have at "
                         f"most {MAX_WORD_LETTERS}", path, line)
    words = len(re.findall(r"[^\W_]+", re.sub(r"\[[^\]]*\]", " ", text)))     # tags ([pause], ...) aside
    seconds = words * 60.0 / rate_wpm
    if seconds > MAX_UTTERANCE_S:
        raise InputError(f"the text's {words} words last about {seconds:.0f} s at {rate_wpm:g} words/min, over "
                         f"the {MAX_UTTERANCE_S} s limit of one run", path)
