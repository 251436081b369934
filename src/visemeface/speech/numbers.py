"""Numbers spelled the way they are read aloud (the text front end's first step)."""

from __future__ import annotations

_ONES = ("zero one two three four five six seven eight nine ten eleven twelve thirteen "
         "fourteen fifteen sixteen seventeen eighteen nineteen").split()
_TENS = "_ _ twenty thirty forty fifty sixty seventy eighty ninety".split()
_SCALES = ["", "thousand", "million", "billion", "trillion", "quadrillion"]


def _below_thousand(n: int) -> list[str]:
    words = []
    if n >= 100:
        words += [_ONES[n // 100], "hundred"]
        n %= 100
    if n >= 20:
        words.append(_TENS[n // 10])
        n %= 10
        if n:
            words.append(_ONES[n])
    elif n or not words:
        words.append(_ONES[n])
    return words


def number_to_words(token: str) -> list[str]:
    """Spell a number the way it is read aloud.

    Integers are read as cardinals (``"1500"`` -> one thousand five hundred),
    thousands separators allowed (``"1,500"``); a string of digits with a
    leading zero is read digit by digit (``"007"``, as in phone numbers); a
    decimal point is read ``point`` followed by the digits; a leading minus
    sign is ``minus``; a trailing ``%`` is ``percent``.

    Examples
    --------
    >>> number_to_words("1,500")
    ['one', 'thousand', 'five', 'hundred']
    >>> number_to_words("-3.05")
    ['minus', 'three', 'point', 'zero', 'five']
    """
    text = token.strip()
    words: list[str] = []
    if text.startswith(("-", "−")):
        words.append("minus")
        text = text[1:]
    percent = text.endswith("%")
    text = text.rstrip("%")
    whole, _, frac = text.partition(".")
    whole = whole.replace(",", "")
    if not whole.isdigit() and not (whole == "" and frac.isdigit()):
        raise ValueError(f"not a number: {token!r}")
    if len(whole) > 1 and whole.startswith("0") or len(whole) > 18:
        words += [_ONES[int(d)] for d in whole]
    elif whole:
        n = int(whole)
        if n == 0:
            words.append("zero")
        groups = []
        scale = 0
        while n:
            n, rest = divmod(n, 1000)
            if rest:
                groups.append(_below_thousand(rest) + ([_SCALES[scale]] if scale else []))
            scale += 1
        for g in reversed(groups):
            words += g
    else:
        words.append("zero")
    if frac:
        words.append("point")
        words += [_ONES[int(d)] for d in frac]
    if percent:
        words.append("percent")
    return words
