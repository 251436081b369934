"""The text judged against what the audio itself supports: word margins, confidence, refusal, degraded copies."""

import json
import warnings

import numpy as np
import pytest

from visemeface.cli import main
from visemeface.errors import InputError
from visemeface.speech import align
from visemeface.speech.align import DOUBTFUL_MARGIN, confidence, utterance_from_audio
from visemeface.speech.audio import read_audio
from visemeface.speech.degrade import KINDS, degrade

TEXTS = {"swwp2s": "set white with p two soon", "bbaf2n": "bin blue at f two now",
         "lbax4n": "lay blue at x four now"}
#: The degradations DOUBTFUL_MARGIN was not chosen on (docs/notes/alignment_margin.md).
HELD_OUT = ("quiet20floor", "white10", "speech10", "speed1.2", "telephone", "reverb")


def _verdict(audio, text):
    try:
        return utterance_from_audio(audio, text, where="clip")
    except InputError as exc:
        assert "does not match the audio" in str(exc) or "could not be aligned" in str(exc), exc
        return None


def test_confidence_is_a_half_at_the_doubtful_margin_and_grows_with_the_margin():
    c = confidence([DOUBTFUL_MARGIN - 30, DOUBTFUL_MARGIN, 0.0, 20.0, np.nan])
    assert c[1] == pytest.approx(0.5) and c[0] < 0.05 and 0.8 < c[2] < c[3] < 1 and np.isnan(c[4])


@pytest.mark.parametrize("margins, refused", [
    ([5, 5, 5, 5, 5, -40], False),             # one doubtful word in six passes
    ([5, 5, 5, 5, -40, -40], True),            # two do not
    ([-40], True),                             # a one-word text: that word
    ([5, -40], False),                         # one doubtful word of two passes (it is not the only word)
    ([-40, -40], True),
    ([5] * 8 + [-40] * 4, True),               # more than a quarter
    ([5] * 9 + [-40] * 3, False),              # a quarter passes
])
def test_a_text_is_refused_when_more_than_a_quarter_of_its_words_are_doubtful(margins, refused):
    words = [f"w{i}" for i in range(len(margins))]
    if refused:
        with pytest.raises(InputError, match=r"does not match the audio: \d+ of its"):
            align._check_match(words, np.asarray(margins, float), "clip")
    else:
        align._check_match(words, np.asarray(margins, float), "clip")


def test_no_reference_to_judge_by_warns_and_takes_the_text():
    with pytest.warns(UserWarning, match="no free phone decoding"):
        align._check_match(["a", "b"], np.array([np.nan, np.nan]), "clip")


def test_degraded_copies_are_what_they_say(vowels_wav):
    x, rate = read_audio(vowels_wav)
    for kind in KINDS:
        y, r = degrade(x, rate, kind)
        assert np.all(np.isfinite(y)) and y.size > 0, kind
        assert np.array_equal(y, degrade(x, rate, kind)[0]), kind           # seeded
    white, _ = degrade(x, rate, "white10")
    snr = 10 * np.log10(np.mean(x ** 2) / np.mean((white - x) ** 2))
    assert snr == pytest.approx(10.0, abs=0.01)
    assert np.abs(degrade(x, rate, "quiet30")[0]).max() == pytest.approx(np.abs(x).max() * 10 ** -1.5, rel=0.01)
    assert degrade(x, rate, "speed1.2")[0].size == pytest.approx(x.size / 1.2, abs=2)
    assert degrade(x, rate, "telephone")[1] == 8000
    with pytest.raises(ValueError, match="unknown degradation"):
        degrade(x, rate, "underwater")


def test_the_json_transcript_gives_each_aligned_word_its_confidence(vowels_wav, tmp_path, monkeypatch):
    from visemeface.speech.transcripts import read_utterance

    monkeypatch.chdir(tmp_path)
    assert main(["lipsync", str(vowels_wav), "--text", "ah ee", "-o", "v.json", "-q"]) == 0
    data = json.loads((tmp_path / "v.json").read_text())
    words = data["word_confidence"]
    assert [w["word"] for w in words] == ["ah", "ee"]
    assert all(0.5 < w["confidence"] <= 1 and isinstance(w["margin"], float) for w in words), words
    assert read_utterance(tmp_path / "v.json").segments.phoneme.tolist().count("iy") == 1   # still MFA JSON
    assert main(["lipsync", str(vowels_wav), "-o", "r.json", "-q"]) == 0          # recognised: no words to judge
    assert "word_confidence" not in json.loads((tmp_path / "r.json").read_text())


@pytest.mark.realdata
def test_each_clip_takes_its_own_text_and_refuses_the_others(realdata):
    for clip, right in TEXTS.items():
        audio = read_audio(realdata / f"{clip}.mpg")
        u = _verdict(audio, right)
        assert u is not None, f"{clip}: its own text refused"
        assert (u.words["confidence"] >= 0.5).all(), u.words
        for other, text in TEXTS.items():
            if other != clip:
                assert _verdict(audio, text) is None, f"{clip} took {other}'s text"


@pytest.mark.realdata
def test_a_doubtful_word_is_named_on_stderr_and_the_text_still_passes(realdata, tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    assert main(["lipsync", str(realdata / "lbax4n.mpg"), "--text", "lay red at x four now", "-o", "n.json"]) == 0
    err = capsys.readouterr().err
    assert "doubtful in the audio: 'red'" in err, err
    confidence = {w["word"]: w["confidence"] for w in json.loads((tmp_path / "n.json").read_text())["word_confidence"]}
    assert confidence["red"] < 0.5 and confidence["lay"] > 0.5


@pytest.mark.slow
@pytest.mark.realdata
@pytest.mark.parametrize("kind", HELD_OUT)
def test_degraded_clips_take_their_own_text_and_refuse_the_others(realdata, kind):
    warnings.simplefilter("ignore")                      # the telephone copy's 8 kHz warning
    for clip, right in TEXTS.items():
        audio = degrade(*read_audio(realdata / f"{clip}.mpg"), kind)
        assert _verdict(audio, right) is not None, f"{clip} {kind}: its own text refused"
        for other, text in TEXTS.items():
            if other != clip:
                assert _verdict(audio, text) is None, f"{clip} {kind}: took {other}'s text"
