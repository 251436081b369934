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


#: Ordinals whose word is not the cardinal + "th".
_ORDINAL = {"one": "first", "two": "second", "three": "third", "five": "fifth", "eight": "eighth",
            "nine": "ninth", "twelve": "twelfth"}


def ordinal_to_words(token: str) -> list[str]:
    """Spell an ordinal such as ``"21st"`` or ``"1,000th"``: the cardinal with its last word made ordinal.

    >>> ordinal_to_words("21st")
    ['twenty', 'first']
    >>> ordinal_to_words("40th")
    ['fortieth']
    """
    digits = token.strip().rstrip("stndrhSTNDRH")
    if not digits.replace(",", "").isdigit():
        raise ValueError(f"not an ordinal: {token!r}")
    words = number_to_words(str(int(digits.replace(",", ""))))
    last = words[-1]
    words[-1] = _ORDINAL.get(last) or (last[:-1] + "ieth" if last.endswith("y") else last + "th")
    return words


#: Currency signs read after the amount: (one unit, units, one hundredth, hundredths).
CURRENCIES = {"$": ("dollar", "dollars", "cent", "cents"), "£": ("pound", "pounds", "penny", "pence"),
              "€": ("euro", "euros", "cent", "cents")}


def money_to_words(token: str) -> list[str]:
    """Spell an amount of money as it is read aloud: ``"$3.50"`` -> three dollars fifty cents.

    The sign (``$``, ``£``, ``€``) comes first; one or two decimals are the hundredths (``"$0.5"``,
    ``"$.5"``: fifty cents); more decimals, or a scale word after the amount (``"$1.5 million"``), are
    read as a number before the plural unit.

    >>> money_to_words("$1.05")
    ['one', 'dollar', 'five', 'cents']
    >>> money_to_words("$5 million")
    ['five', 'million', 'dollars']
    """
    text = token.strip()
    if not text or text[0] not in CURRENCIES:
        raise ValueError(f"not an amount of money: {token!r}")
    one, many, cent, cents = CURRENCIES[text[0]]
    amount, *scale = text[1:].split()
    whole, _, frac = amount.partition(".")
    if len(frac) > 2 or scale:
        return number_to_words(amount) + [w.lower() for w in scale] + [many]
    units = int(whole.replace(",", "") or 0)
    hundredths = int(frac.ljust(2, "0")) if frac else 0
    words = number_to_words(whole) + [one if units == 1 else many] if units or not hundredths else []
    if hundredths:
        words += number_to_words(str(hundredths)) + [cent if hundredths == 1 else cents]
    return words


#: The text front end's tokens read as words, by kind: numbers, ordinals (21st), amounts of money ($3.50).
SPELLED = {"number": number_to_words, "ordinal": ordinal_to_words, "money": money_to_words}
