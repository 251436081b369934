"""Rhubarb Lip Sync mouth cues from an utterance's phones (``data/retarget/phoneme_classes.csv``).

Rhubarb's shapes: A closed (P B M), B slightly open with clenched teeth (most consonants, EE), C open
(EH AE), D wide open (AA), E slightly rounded (AO ER), F puckered (UW OW W), G upper teeth on the lower
lip (F V), H tongue raised (L), X idle (silence). Each phone takes its class's shape; neighbours with the
same shape merge; times are truncated to centiseconds as Rhubarb writes them.
"""

from __future__ import annotations

import math

from visemeface.retarget.recipes import phoneme_classes

#: Rhubarb's mouth shapes, basic then extended.
SHAPES = ("A", "B", "C", "D", "E", "F", "G", "H", "X")
#: ``--datUsePrestonBlair``'s names.
PRESTON_BLAIR = {"A": "MBP", "B": "etc", "C": "E", "D": "AI", "E": "O", "F": "U", "G": "FV", "H": "L", "X": "rest"}


def centiseconds(t: float) -> int:
    """``t`` seconds truncated to whole centiseconds (Rhubarb's time resolution), robust to float noise."""
    return int(math.floor(t * 100.0 + 1e-6))


def mouth_cues(segments) -> list[tuple[float, float, str]]:
    """(start, end, shape) cues covering ``[0, end of the utterance)``, times in whole centiseconds.

    Parameters
    ----------
    segments : Segments
        ``start``, ``end``, ``phoneme`` (DECtalk), contiguous from 0.
    """
    from visemeface.errors import InputError, close_matches

    table = phoneme_classes()
    unknown = sorted({str(p) for p in segments["phoneme"] if p not in table})
    if unknown:
        raise InputError(f"mouth cues need DECtalk phones; {unknown[0]!r} is none{close_matches(unknown[0].lower(), table)}"
                         " (ARPAbet transcripts are read into DECtalk by speech.transcripts.read_utterance)")
    cues: list[list] = []
    for start, end, ph in segments[["start", "end", "phoneme"]].itertuples(index=False):
        a, b = centiseconds(float(start)), centiseconds(float(end))
        if b <= a:
            continue
        shape = table[ph][1]
        if cues and cues[-1][2] == shape:
            cues[-1][1] = b
        elif cues and cues[-1][1] != a:
            cues[-1][1] = a
            cues.append([a, b, shape])
        else:
            cues.append([a, b, shape])
    if cues:
        cues[0][0] = 0
    return [(a / 100.0, b / 100.0, s) for a, b, s in cues]


def dat_frame(t: float, fps: float) -> int:
    """Moho switch-data frame of time ``t``: ``1 + int(fps·t)`` (frames count from 1)."""
    return 1 + int(fps * t + 1e-9)
