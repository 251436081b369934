"""Text-level helpers shared by the transcript readers: decoding, comments, numbers."""

from __future__ import annotations

import math
import re

from visemeface.errors import InputError
from visemeface.textfile import decode  # noqa: F401  (the readers' decoding rule; its home)

BRACKETS = re.compile(r"\[[^\[\]]*\]")
TEXT_OUTSIDE_BRACKETS = re.compile(r"[^\s\[\]]")
_COMMENT = re.compile(r"(^|\s)[#;].*$")


def strip_comment(line: str) -> str:
    """``line`` without a ``#`` or ``;`` comment, stripped."""
    return _COMMENT.sub("", line).strip()


def is_number(s: str) -> bool:
    try:
        float(s)
    except ValueError:
        return False
    return True


def is_int(s: str) -> bool:
    return re.fullmatch(r"[+-]?\d+", s) is not None


def number(s: str, what: str, where, line) -> float:
    """``s`` as a finite float; :class:`InputError` naming ``what``, file and line otherwise."""
    try:
        value = float(s)
    except ValueError:
        raise InputError(f"{what} {s!r} is not a number", where, line) from None
    if not math.isfinite(value):
        raise InputError(f"{what} {s!r} is not finite", where, line)
    return value


def content_lines(text: str):
    """(line number, content without comment) of the non-empty lines; handles CRLF."""
    for i, raw in enumerate(text.splitlines(), start=1):
        line = strip_comment(raw)
        if line:
            yield i, line
