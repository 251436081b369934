"""Text-level helpers shared by the transcript readers: decoding, comments, numbers."""

from __future__ import annotations

import math
import re

from visemeface.errors import InputError

BRACKETS = re.compile(r"\[[^\[\]]*\]")
TEXT_OUTSIDE_BRACKETS = re.compile(r"[^\s\[\]]")
_COMMENT = re.compile(r"(^|\s)[#;].*$")


def decode(raw: bytes, path) -> str:
    """Text of a transcript file: UTF-16 with a byte-order mark, else UTF-8 (BOM allowed)."""
    if raw.startswith((b"\xff\xfe", b"\xfe\xff")):
        try:
            return raw.decode("utf-16")
        except UnicodeDecodeError:
            raise InputError("not valid UTF-16 text", path) from None
    try:
        return raw.decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        line = raw[:exc.start].count(b"\n") + 1
        raise InputError(f"not UTF-8 text (byte 0x{raw[exc.start]:02x})", path, line) from None


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
