"""Where the shipped data files (rig, visemes, expressions, transcripts) live.

In an installed wheel they sit inside the package (``visemeface/data``); in a
source checkout they are the repository's top-level ``data/`` and
``transcripts/`` folders.
"""

from __future__ import annotations

from pathlib import Path

_PACKAGE = Path(__file__).resolve().parent
_REPO = _PACKAGE.parent.parent


def _root(name: str) -> Path:
    inside = _PACKAGE / name
    if inside.is_dir():
        return inside
    return _REPO / name


def data_path(*parts: str) -> Path:
    """Path of a shipped data file, e.g. ``data_path("rig", "default.toml")``."""
    return _root("data").joinpath(*parts)


def transcripts_path(*parts: str) -> Path:
    """Path of a shipped example transcript."""
    return _root("transcripts").joinpath(*parts)
