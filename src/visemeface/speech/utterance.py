"""What an utterance is made of: timed phones, and optionally its words and emotion keys.

The readers and the text front end return an :class:`Utterance`; everything
the animation needs travels in its fields, not in ``DataFrame.attrs``.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import pandas as pd

#: Timed DECtalk phones: DataFrame ``start``, ``end`` (s), ``phoneme`` (docs/conventions.md).
Segments = pd.DataFrame


def no_words() -> pd.DataFrame:
    """An empty word table (``start``, ``end``, ``word``)."""
    return pd.DataFrame({"start": pd.Series(dtype=float), "end": pd.Series(dtype=float),
                         "word": pd.Series(dtype=object)})


def no_emotion_keys() -> pd.DataFrame:
    """An empty emotion key track (``time``, ``emotion``, ``weight``)."""
    return pd.DataFrame({"time": pd.Series(dtype=float), "emotion": pd.Series(dtype=object),
                         "weight": pd.Series(dtype=float)})


def no_stress() -> pd.DataFrame:
    """An empty stress table (``stress``, ``emphasis``): the stress of the phones is unknown."""
    return pd.DataFrame({"stress": pd.Series(dtype=float), "emphasis": pd.Series(dtype=bool)})


@dataclass(frozen=True)
class Utterance:
    """An utterance ready to animate.

    Attributes
    ----------
    segments : Segments
        Timed DECtalk phones, contiguous from 0.
    words : DataFrame
        ``start``, ``end``, ``word`` (empty when the source had no words).
    emotion_keys : DataFrame
        ``time``, ``emotion``, ``weight``: inline emotion tags of a text
        (``[anger 0.8] ...``), applied by
        :func:`visemeface.speech.timeline.activation_track`; empty if none.
    source_format : str
        The transcript format it was read from (``"text"`` for English text).
    stress : DataFrame
        One row per segment: ``stress`` the CMUdict stress digit of a vowel (0 unstressed, 1 primary,
        2 secondary; NaN for consonants and silences) and ``emphasis`` (the phone is in a word the
        text emphasised, ``*word*``); empty where unknown (transcripts, recordings). Played by
        :mod:`visemeface.speech.articulation` and :mod:`visemeface.speech.gestures` without a recording.
    """

    segments: Segments
    words: pd.DataFrame = field(default_factory=no_words)
    emotion_keys: pd.DataFrame = field(default_factory=no_emotion_keys)
    source_format: str = ""
    stress: pd.DataFrame = field(default_factory=no_stress)

    @classmethod
    def of(cls, value, what: str = "an utterance") -> Utterance:
        """``value`` as an Utterance: itself, or bare timed :data:`Segments` wrapped; else an InputError
        naming ``what`` needs it."""
        if isinstance(value, Utterance):
            return value
        if isinstance(value, pd.DataFrame):
            return cls(value)
        from visemeface.errors import InputError

        raise InputError(f"{what} takes an Utterance (speech.transcripts.read_utterance, "
                         f"speech.g2p.text_to_utterance) or timed Segments, got {type(value).__name__}")

    @property
    def end(self) -> float:
        """End of the last segment (s): the utterance's length."""
        return float(self.segments["end"].iloc[-1]) if len(self.segments) else 0.0

    def lasting(self, seconds: float) -> Utterance:
        """This utterance, silent from its end to ``seconds`` (itself if it lasts that long already)."""
        from dataclasses import replace

        from visemeface.postures.phonemes import SILENCE

        if seconds <= self.end:
            return self
        seg = self.segments.copy()
        stress = self.stress
        if len(seg) and seg["phoneme"].iloc[-1] == SILENCE:
            seg.loc[seg.index[-1], "end"] = float(seconds)
        else:
            row = pd.DataFrame({"start": [self.end], "end": [float(seconds)], "phoneme": [SILENCE]})
            seg = pd.concat([seg, row], ignore_index=True)
            if len(stress):
                stress = pd.concat([stress, pd.DataFrame({"stress": [float("nan")], "emphasis": [False]})],
                                   ignore_index=True)
        return replace(self, segments=seg, stress=stress)

    def phone_stress(self):
        """(stress, emphasis) arrays, one value per segment, or None where the stress is unknown."""
        if len(self.stress) != len(self.segments) or len(self.stress) == 0:
            return None
        return (self.stress["stress"].to_numpy(dtype=float),
                self.stress["emphasis"].to_numpy(dtype=bool))
