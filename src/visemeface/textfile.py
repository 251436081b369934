"""Reading a user's text file: one decoding rule and one set of messages for every reader.

UTF-16 with a byte-order mark, else UTF-8 (a byte-order mark allowed); a file that is
neither, a folder, a missing or unreadable file is an :class:`~visemeface.errors.InputError`
naming the file (and the line of a bad byte).
"""

from __future__ import annotations

from pathlib import Path

from visemeface.errors import InputError


def decode(raw: bytes, path=None) -> str:
    """Text of a file's bytes: UTF-16 with a BOM, else UTF-8 (BOM allowed)."""
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


def read_text(path, what: str = "file") -> str:
    """The text of ``path``; ``what`` names the file in the messages ("track not found")."""
    path = Path(path)
    try:
        raw = path.read_bytes()
    except FileNotFoundError:
        raise InputError(f"{what} not found", path) from None
    except IsADirectoryError:
        raise InputError(f"{what} expected, got a folder", path) from None
    except OSError as exc:
        raise InputError(f"cannot read the {what} ({exc.strerror or exc.__class__.__name__})", path) from None
    return decode(raw, path)


def parse_json(text: str, path=None):
    """The value of JSON ``text``; an :class:`InputError` naming ``path`` (and the line) for text that is not
    JSON, or JSON nested too deeply or holding a number too long to read (Python refuses integers of over
    4,300 digits), instead of the parser's RecursionError or ValueError."""
    import json

    try:
        return json.loads(text)
    except json.JSONDecodeError as exc:
        raise InputError(f"not valid JSON: {exc.msg} (column {exc.colno})", path, exc.lineno) from None
    except RecursionError:
        raise InputError("not usable JSON: nested too deeply", path) from None
    except ValueError:                     # "Exceeds the limit (4300 digits) for integer string conversion"
        raise InputError("not usable JSON: a number of over 4300 digits", path) from None


def parse_toml(text: str, path=None) -> dict:
    """The tables of TOML ``text``; an :class:`InputError` naming ``path`` and the line for text that is
    not TOML (the parser's message without its "(at line N, column M)", which Python < 3.14 appends)."""
    import re
    import tomllib

    try:
        return tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        msg = str(getattr(exc, "msg", exc))
        at = re.search(r"\s*\(at line (\d+), column \d+\)$", msg)
        line = getattr(exc, "lineno", None) or (int(at.group(1)) if at else None)
        raise InputError(f"not valid TOML: {msg[:at.start()] if at else msg}", path, line) from None
    except RecursionError:
        raise InputError("not usable TOML: nested too deeply", path) from None
    except ValueError:
        raise InputError("not usable TOML: a number of over 4300 digits", path) from None
