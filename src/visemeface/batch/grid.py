"""An example corpus: manifests of GRID sentences (command colour preposition letter digit adverb).

The GRID audiovisual corpus (Cooke et al. 2006) has one grammar of 4 commands,
4 colours, 4 prepositions, 25 letters, 10 digits and 4 adverbs: 64,000
sentences such as "set white with p two soon" (``data/corpora/grid.toml``). A
sentence's clip id is its six initials with the digit as a numeral
(``swwp2s``), as the corpus names its files.
"""

from __future__ import annotations

import functools
import tomllib
from pathlib import Path

import numpy as np

from visemeface.errors import InputError

#: The grammar's slots, in sentence order.
SLOTS = ("command", "colour", "preposition", "letter", "digit", "adverb")


@functools.lru_cache(maxsize=1)
def grammar() -> dict[str, tuple[str, ...]]:
    """The GRID grammar: slot -> its words (``data/corpora/grid.toml``, read once)."""
    from visemeface.resources import data_path

    data = tomllib.loads(data_path("corpora", "grid.toml").read_text())
    return {slot: tuple(data[slot]) for slot in SLOTS}


def n_sentences() -> int:
    """How many sentences the grammar makes (64,000)."""
    return int(np.prod([len(w) for w in grammar().values()]))


def sentence(index: int) -> tuple[str, str]:
    """Sentence ``index`` (0 .. 63,999, mixed radix in slot order): ``(clip id, text)``."""
    g = grammar()
    if not 0 <= index < n_sentences():
        raise InputError(f"GRID sentence index must be in [0, {n_sentences()}), got {index}")
    words = []
    for slot in reversed(SLOTS):
        index, k = divmod(index, len(g[slot]))
        words.append(g[slot][k])
    words.reverse()
    digit = str(g["digit"].index(words[4]))
    clip = "".join(w[0] for w in words[:4]) + digit + words[5][0]
    return clip, " ".join(words)


def grid_rows(n: int | None = None, seed: int = 0, **settings) -> list[dict]:
    """Manifest rows (``clip``, ``text`` and ``settings``) of every GRID sentence or a sample of ``n``.

    The sample is drawn without replacement with ``numpy.random.default_rng(seed)``
    and kept in grammar order, so the same ``n`` and ``seed`` give the same manifest.
    """
    total = n_sentences()
    if n is None:
        picks = range(total)
    else:
        if not 1 <= n <= total:
            raise InputError(f"the GRID sample size must be 1 to {total}, got {n}")
        picks = sorted(np.random.default_rng(seed).choice(total, size=n, replace=False).tolist())
    rows = []
    for i in picks:
        clip, text = sentence(i)
        rows.append({"clip": clip, "text": text, **settings})
    return rows


def write_grid_manifest(path, n: int | None = None, seed: int = 0, force: bool = False, **settings) -> Path:
    """Write a manifest of GRID sentences (:func:`grid_rows`) for ``visemeface batch``; returns its path."""
    from visemeface.batch.manifest import write_manifest

    return write_manifest(path, grid_rows(n, seed, **settings), force=force)
