"""Text to timed DECtalk phonemes: CMUdict words, numbers, unknown words, timing, rate, audio, tags."""

import warnings

import numpy as np
import pandas as pd
import pytest
import soundfile as sf
from hypothesis import given, settings
from hypothesis import strategies as st

from visemeface.errors import InputError
from visemeface.postures.phonemes import DECTALK
from visemeface.speech.audio import read_audio, speech_span
from visemeface.speech.g2p import durations, number_to_words, text_to_segments, text_to_utterance, timing


def phones(seg):
    return [p for p in seg.phoneme]


def durations_of(seg, symbol):
    rows = seg[seg.phoneme == symbol]
    return (rows.end - rows.start).to_numpy()


@pytest.mark.parametrize("token,words", [
    ("0", "zero"), ("7", "seven"), ("13", "thirteen"), ("20", "twenty"), ("21", "twenty one"),
    ("100", "one hundred"), ("105", "one hundred five"), ("1500", "one thousand five hundred"),
    ("1,000,000", "one million"), ("2026", "two thousand twenty six"), ("007", "zero zero seven"),
    ("-3.05", "minus three point zero five"), ("50%", "fifty percent"),
    ("1000001", "one million one"),
])
def test_number_to_words(token, words):
    assert " ".join(number_to_words(token)) == words


@pytest.mark.parametrize("text,words", [
    ("1st", "first"), ("2nd", "second"), ("3rd", "third"), ("12th", "twelfth"), ("21st", "twenty first"),
    ("40th", "fortieth"), ("100th", "one hundredth"), ("1,000th", "one thousandth"),
    ("$3.50", "three dollars fifty cents"), ("$1", "one dollar"), ("$0.99", "ninety nine cents"),
    ("$1.01", "one dollar one cent"), ("£2.5", "two pounds fifty pence"), ("€ 5", "five euros"),
    ("$1,500", "one thousand five hundred dollars"), ("$3.505", "three point five zero five dollars"),
    ("On May 1st it cost $3.50.", "On May first it cost three dollars fifty cents"),
    ("$5 million", "five million dollars"), ("$.50", "fifty cents"), ("the 21ST century", "the twenty first century"),
    ("5th-6th", "fifth sixth"), ("pages 3-4", "pages three four"), ("-3 degrees", "minus three degrees"),
])
def test_ordinals_and_money_are_read_as_words(text, words):
    assert " ".join(text_to_utterance(text, warn=True).words["word"]) == words


def test_seed_utterance():
    seg = text_to_segments("one five zero zero six")
    assert phones(seg) == "_ w ah n f ay v z ih r ow z ih r ow s ih k s _".split()


def test_numbers_in_text_are_spoken():
    assert phones(text_to_segments("15")) == phones(text_to_segments("fifteen"))
    assert phones(text_to_segments("3 cats"))[1:4] == ["th", "r", "iy"]


def test_dectalk_specific_symbols():
    assert "yu" in phones(text_to_segments("cute"))              # K Y UW1 T
    assert phones(text_to_segments("bar"))[1:3] == ["b", "ar"]    # vowel + R in one syllable
    assert phones(text_to_segments("poor"))[1:3] == ["p", "ur"]
    assert "ir" not in phones(text_to_segments("zero"))           # R starts the next syllable


def test_unknown_word_warns_and_is_spelled_by_rules():
    with pytest.warns(UserWarning, match="'Blorptastic' is not in the CMU dictionary"):
        seg = text_to_segments("Blorptastic")
    p = phones(seg)
    assert p[:4] == ["_", "b", "l", "ar"] and p[-1] == "_" and "s" in p and "t" in p   # o+r: /ar/
    with pytest.warns(UserWarning, match="'XQZT'"):
        spelled = phones(text_to_segments("XQZT"))               # no vowel letter: letter names
    assert spelled[1:4] == ["eh", "k", "s"]                     # "ex"


def test_rate_sets_the_spoken_time():
    t = timing()
    for rate in (100, 165, 300):
        seg = text_to_segments("the quick brown fox jumps over the lazy dog", rate_wpm=rate)
        speaking = seg[seg.phoneme != "_"]
        total = float((speaking.end - speaking.start).sum())
        assert total == pytest.approx(9 * 60 / rate, rel=1e-9)
        assert seg.start.iloc[1] == pytest.approx(t["lead_silence_ms"] / 1000)
    with pytest.raises(InputError, match="speaking rate"):
        text_to_segments("hello", rate_wpm=0)


def test_phrase_final_lengthening_and_stress():
    # d = min + (inherent - min) * prod(factors); the rate scale is common to all phones.
    t, table = timing(), durations()
    lo, hi = table.loc["ay", "minimum"], table.loc["ay", "inherent"]
    seg = text_to_segments("five five")
    first, last = durations_of(seg, "ay")
    expected = (lo + (hi - lo) * t["phrase_final"]) / (lo + (hi - lo) * t["nonfinal_vowel"])
    assert last / first == pytest.approx(expected, rel=1e-9) and expected > 1.2
    lo, hi = table.loc["iy", "minimum"], table.loc["iy", "inherent"]
    seg = text_to_segments("city see me")        # S IH1 T IY0 / S IY1 / M IY1
    iy = durations_of(seg, "iy")
    nf = t["nonfinal_vowel"]                     # both are outside the phrase-final syllable
    expected = (lo + (hi - lo) * t["primary_stress"] * nf) / (lo + (hi - lo) * t["unstressed"] * nf)
    assert iy[1] / iy[0] == pytest.approx(expected, rel=1e-9) and expected > 1.25


def test_punctuation_pauses():
    t = timing()
    seg = text_to_segments("one, two; three. four")
    pauses = (seg.end - seg.start)[seg.phoneme == "_"].to_numpy()
    expected = [t["lead_silence_ms"], t["pause_comma_ms"], t["pause_clause_ms"], t["pause_sentence_ms"],
                t["tail_silence_ms"]]
    assert pauses == pytest.approx(np.array(expected) / 1000)


def test_emotion_tags_become_a_key_track():
    utt = text_to_utterance("[anger 0.8] I told you [neutral] fine [happiness=0.5] thanks [fear]")
    keys = utt.emotion_keys
    assert list(keys.emotion) == ["anger", "neutral", "happiness", "fear"]
    assert list(keys.weight) == [0.8, 1.0, 0.5, 1.0]
    words = utt.words
    assert keys.time.iloc[0] == 0.0
    assert keys.time.iloc[1] == pytest.approx(words.start[words.word == "fine"].iloc[0])
    assert keys.time.iloc[2] == pytest.approx(words.start[words.word == "thanks"].iloc[0])
    assert keys.time.iloc[3] == pytest.approx(words.end.iloc[-1])     # a final tag: at the end of speech
    assert text_to_utterance("plain").emotion_keys.empty
    # Nothing rides on the Segments' attrs: they concatenate and compare as plain tables.
    assert text_to_segments("[anger] plain").attrs == {}


@pytest.mark.parametrize("text,match", [
    ("hello\n[anger 0.5 0.2] there", "bad emotion tag"),
    ("hello\n[anger 1.5] there", "not in 0..1"),
    ("hello [anger there", "unmatched bracket"),
])
def test_bad_tags(text, match):
    with pytest.raises(InputError, match=match) as e:
        text_to_segments(text, path="speech.txt")
    assert e.value.path == "speech.txt" and e.value.line == (2 if "\n" in text else 1)


def test_no_words():
    with pytest.raises(InputError, match="no words"):
        text_to_segments(" ... !? [happiness] ")


def make_wav(path, lead, speech, tail, rate=16000):
    rng = np.random.default_rng(0)
    n = [int(lead * rate), int(speech * rate), int(tail * rate)]
    t = np.arange(n[1]) / rate
    voiced = 0.5 * np.sin(2 * np.pi * 150 * t) * (0.6 + 0.4 * np.sin(2 * np.pi * 3 * t))
    signal = np.concatenate([1e-4 * rng.standard_normal(n[0]), voiced, 1e-4 * rng.standard_normal(n[2])])
    sf.write(str(path), signal, rate)


def test_speech_span_trims_silence(tmp_path):
    wav = tmp_path / "s.wav"
    make_wav(wav, 0.5, 1.2, 0.8)
    samples, rate = read_audio(wav)
    t0, t1 = speech_span(samples, rate)
    assert t0 == pytest.approx(0.5, abs=0.02) and t1 == pytest.approx(1.7, abs=0.02)
    assert samples.size / rate == pytest.approx(2.5)


def test_bad_audio(tmp_path):
    from visemeface.speech.transcripts import timed_text

    bad = tmp_path / "bad.wav"
    bad.write_bytes(b"RIFF not really a wave")
    with pytest.raises(InputError, match="unreadable audio") as e:
        timed_text("hello", audio=bad)
    assert e.value.path == str(bad)
    silent = tmp_path / "silent.wav"
    sf.write(str(silent), np.zeros(8000), 16000)
    with pytest.raises(InputError, match="silent"):
        timed_text("hello", audio=silent)


@settings(max_examples=40, deadline=None)
@given(st.text(alphabet=st.characters(codec="utf-8", exclude_categories=["Cs"]), max_size=40)
       | st.lists(st.sampled_from(["one", "5", "1,500", "-2.5", "Zyx", "[anger 0.3]", "[neutral]", ",", ".",
                                   "[", "]", "hello", "ñandú", "'s", "\n", "[x 9]"]), max_size=12).map(" ".join))
def test_property_any_text_gives_segments_or_input_error(text):
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            seg = text_to_segments(text, path="p.txt")
    except InputError as e:
        assert e.path == "p.txt"
        return
    s, e = seg.start.to_numpy(), seg.end.to_numpy()
    assert s[0] == 0 and (e > s).all() and np.allclose(s[1:], e[:-1], atol=0, rtol=0)
    assert set(seg.phoneme) <= set(DECTALK)


def test_ampersand_titles_and_accented_words_are_read_as_said():
    said = lambda text: " ".join(text_to_segments(text).phoneme)          # noqa: E731
    assert said("salt & pepper") == said("salt and pepper")
    assert said("Dr. Smith") == said("doctor Smith")                   # no sentence pause after the title
    assert said("Elm Dr. is long") == said("Elm drive. is long")       # an address keeps CMUdict's first
    assert said("naïve café") == said("naive cafe")


@pytest.mark.parametrize("rate", [100, 165, 300])
def test_no_phone_is_squeezed_below_its_incompressible_part(rate):
    from visemeface.speech.g2p import durations, timing

    floor = timing()["default_rate_wpm"] / rate
    seg = text_to_segments("internationalization", rate_wpm=rate)
    sp = seg[seg.phoneme != "_"]
    minimum = durations()["minimum"].reindex(sp.phoneme).to_numpy() * floor
    assert ((sp.end - sp.start).to_numpy() >= minimum - 1e-12).all()
    assert sp.end.iloc[-1] - sp.start.iloc[0] > 2.5 * 60 / rate           # not one short word's time
    running = text_to_segments("set white with p two soon", rate_wpm=rate)   # the rate still holds there
    spoken = running[running.phoneme != "_"]
    assert (spoken.end - spoken.start).sum() == pytest.approx(6 * 60 / rate, rel=1e-9)
