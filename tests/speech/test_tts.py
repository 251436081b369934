"""The voice of ``say`` (eSpeak NG, the optional ``tts`` extra): its events, and timing that never fails."""

import json

import numpy as np
import pytest

from visemeface.cli import main
from visemeface.errors import InputError
from visemeface.speech import tts

needs_voice = pytest.mark.skipif(not tts.available(), reason="the tts extra (espeakng-loader) is not installed")

#: 20 texts for ``say``: 1 to 60 words, numbers, money, dates, abbreviations, punctuation, emotion tags.
TEXTS = [
    "Yes.", "OK", "Hi!", "one five zero zero six", "Hello there.", "[happiness] Good morning, everyone!",
    "I paid $25.50 for 3 books on the 1st of May, 2024.", "Dr. Smith's pharmacy: open 9 to 5; closed Sundays.",
    "[anger 0.8] Bob moves five boats. [happiness] One five zero zero six!", "Wait... what? No -- really?!",
    "The year 1999 had 365 days, and 12 months.", "[sadness 0.6] I am sorry; it is over (for now).",
    "Would you rather measure the thought or the rhythm of the azure bridge?",
    "Zebras, yaks and giraffes joined the orchestra's choir at 7:30.",
    "the quick brown fox jumps over the lazy dog " * 3,
    "[surprise] Oh! [fear 0.5] Something moved behind the curtain, and then, slowly, it came closer.",
    "Numbers like 42, 3.14 and 1,000,000 are read aloud.",
    "Peter Piper picked a peck of pickled peppers; a peck of pickled peppers Peter Piper picked.",
    " ".join(["She sells sea shells by the sea shore, and the shells she sells are surely sea shells."] * 3),
    " ".join(f"word number {i}" for i in range(1, 21)),
]


def test_the_plain_text_drops_the_tags_and_knows_where_they_were():
    plain, marks = tts.plain_text("[anger 0.8] Bob  moves\nfive boats. [happiness] One five! [fear]")
    assert plain == "Bob moves five boats. One five!"
    assert marks == [0, plain.index("One"), len(plain) + 1]


def test_the_voice_says_the_words_as_they_are_read_here():
    # eSpeak reads "$25.50" as "dollar twenty five point five zero": the sound then said other words than
    # the aligner looked for, and the timing fell back to its phone events; an emoji was spoken by name
    plain, _ = tts.plain_text("[happiness] I paid $25.50 for 3 books on the 1st of May. Really? \U0001F642")
    assert plain == "I paid twenty five dollars fifty cents for three books on the first of May. Really?"


def test_espeak_phones_map_to_dectalk_whole_or_in_pieces():
    assert tts._ipa_phones("ˈoʊ") == ["ow"]                # stress marks ignored
    assert tts._ipa_phones("ˈɑːɹ") == ["aa", "r"]          # r-coloured: split into what the table knows
    assert tts._ipa_phones("ᵻ") == ["ih"]                   # eSpeak's reduced vowel
    assert tts._ipa_phones("@@") == ["ax"]                  # nothing known: a schwa


def _syn(tmp_path, text):
    return tts.synthesise(text, tmp_path / "s.wav")


@needs_voice
def test_the_synthesiser_reports_its_phones_and_words_inside_the_sound(tmp_path):
    from visemeface.speech.audio import read_audio

    syn = _syn(tmp_path, "[anger 0.8] Hello there, 25 foxes. [happiness] Bye!")
    samples, rate = read_audio(syn.path)
    assert syn.end == pytest.approx(samples.size / rate)
    assert [syn.text[a:a + n] for a, n, _ in syn.words][:2] == ["Hello", "there"]
    starts = [s for _, s, _ in syn.phones]
    assert starts == sorted(starts) and 0 < starts[0] and syn.phones[-1][2] <= syn.end
    assert all(e >= s for _, s, e in syn.phones)
    u = tts.events_utterance(syn, "[anger 0.8] Hello there, 25 foxes. [happiness] Bye!")
    seg = u.segments
    assert seg.start.iloc[0] == 0 and seg.end.iloc[-1] == pytest.approx(syn.end)
    assert np.allclose(seg.start.to_numpy()[1:], seg.end.to_numpy()[:-1])     # contiguous
    assert {"hx", "ow", "f", "z", "b", "ay"} <= set(seg.phoneme)
    assert list(u.words.word) == ["Hello", "there", "twenty", "five", "foxes", "Bye"]   # read as the text is
    assert u.emotion_keys.emotion.tolist() == ["anger", "happiness"]
    assert u.emotion_keys.time.iloc[0] == 0 and u.emotion_keys.time.iloc[1] == pytest.approx(u.words.start.iloc[5])


@needs_voice
def test_unalignable_speech_is_timed_by_the_events_then_by_the_duration_model(tmp_path, monkeypatch):
    from visemeface.speech import align

    text = "[happiness] the quick brown fox jumps"
    syn = _syn(tmp_path, text)
    events = [s for _, _, s in syn.words]

    def refuse(*_a, **_k):
        raise InputError("the text could not be aligned to the audio")

    monkeypatch.setattr(align, "utterance_from_audio", refuse)
    u, how = tts.utterance_of(syn, text)
    assert how == "events" and np.allclose(u.words.start, events)
    assert u.end == pytest.approx(syn.end)
    monkeypatch.setattr(tts, "events_utterance", refuse)
    u, how = tts.utterance_of(syn, text)
    assert how == "duration model" and u.end == pytest.approx(syn.end)
    assert list(u.words.word) == ["the", "quick", "brown", "fox", "jumps"]
    assert u.words.start.iloc[0] == pytest.approx(events[0], abs=0.1)            # laid over the speech
    assert u.words.end.iloc[-1] <= syn.end and u.emotion_keys.time.tolist() == [0.0]


@needs_voice
def test_say_with_the_voice_times_a_long_text_by_its_own_sound(tmp_path, monkeypatch):
    """It failed ("the text could not be aligned to the audio"): the default beams pruned every path."""
    monkeypatch.chdir(tmp_path)
    text = "the quick brown fox jumps over the lazy dog " * 3
    assert main(["say", text, "--no-video", "--track", "b.csv", "--save-transcript", "b.json", "-q"]) == 0
    words = json.loads((tmp_path / "b.json").read_text())["tiers"]["words"]["entries"]
    events = [s for _, _, s in _syn(tmp_path, text).words]            # the same text, the same sound
    assert len(words) == 27
    assert np.mean(np.abs(np.array([w[0] for w in words]) - events)) < 0.05


@needs_voice
@pytest.mark.slow
def test_say_with_the_voice_makes_an_audio_synced_video_of_every_text(tmp_path, monkeypatch):
    from visemeface.export.video import read_video_info

    monkeypatch.chdir(tmp_path)
    for i, text in enumerate(TEXTS):
        assert main(["say", text, "--size", "32", "-o", f"v{i}.mp4", "--save-transcript", f"v{i}.json", "-q"]) == 0, text
        info = read_video_info(tmp_path / f"v{i}.mp4")
        syn = tts.synthesise(text, tmp_path / "again.wav")
        assert info["audio_rate"] > 0 and info["audio_samples"] / info["audio_rate"] == pytest.approx(syn.end, abs=0.05)
        assert info["n_frames"] / info["fps"] == pytest.approx(syn.end, abs=1.5 / info["fps"]), text
        data = json.loads((tmp_path / f"v{i}.json").read_text())
        assert data["end"] == pytest.approx(syn.end, abs=1e-3)
        starts = np.array([w[0] for w in data["tiers"]["words"]["entries"]])
        events = np.array([s for _, _, s in tts._event_words(syn)])
        gap = np.min(np.abs(starts[:, None] - events[None, :]), axis=1).mean()
        assert gap <= tts.AGREE_S + 1e-9, (text, gap)                  # the words start where the voice says them
