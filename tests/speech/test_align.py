"""Timed phones from recordings: forced alignment, recognition, bad audio, transcript writers."""

import numpy as np
import pandas as pd
import pytest
import soundfile as sf

from visemeface.cli import main
from visemeface.errors import InputError
from visemeface.speech.align import assimilate, utterance_from_audio
from visemeface.speech.audio import read_audio, resample, speech_span
from visemeface.speech.transcripts import read_utterance
from visemeface.speech.writers import SUFFIXES, format_of, write_transcript


def _grid_words(path):
    rows = [ln.split() for ln in path.read_text().splitlines() if ln.strip()]
    return pd.DataFrame({"start": [int(r[0]) / 25000 for r in rows], "end": [int(r[1]) / 25000 for r in rows],
                         "word": [r[2] for r in rows]})


@pytest.mark.realdata
def test_alignment_of_a_real_clip_matches_the_grid_word_boundaries(realdata):
    truth = _grid_words(realdata / "swwp2s.align")
    truth = truth[truth.word != "sil"].reset_index(drop=True)
    u = utterance_from_audio(realdata / "swwp2s.mpg", "set white with p two soon")
    assert list(u.words.word) == list(truth.word)
    errors = np.abs(np.r_[u.words.start - truth.start, u.words.end - truth.end])
    assert errors.mean() < 0.030 and errors.max() < 0.080, errors
    seg = u.segments
    assert seg.end.iloc[-1] == pytest.approx(75 / 25, abs=0.03)        # the whole recording
    p = seg[seg.phoneme == "p"]
    assert len(p) == 1 and truth.start[3] - 0.03 <= p.start.iloc[0] <= truth.start[3] + 0.03
    samples, rate = read_audio(realdata / "swwp2s.mpg")
    t0, t1 = speech_span(samples, rate)                              # relative to the noise floor
    assert abs(t0 - truth.start[0]) < 0.08 and abs(t1 - truth.end.iloc[-1]) < 0.05
    with pytest.raises(InputError, match="does not match the audio|could not be aligned"):
        utterance_from_audio(realdata / "swwp2s.mpg", "lay blue at x four now")


def test_synthetic_vowels_align_and_survive_8_khz_and_stereo_48_khz(vowels_wav, tmp_path):
    u = utterance_from_audio(vowels_wav, "ah [happiness 0.5] ee")
    assert list(u.words.word) == ["ah", "ee"]
    assert u.emotion_keys.time.tolist() == [u.words.start[1]] and u.emotion_keys.weight.tolist() == [0.5]
    assert np.allclose(u.words.start, [0.25, 0.75], atol=0.04) and np.allclose(u.words.end, [0.65, 1.15], atol=0.04)
    assert [p for p in u.segments.phoneme if p != "_"] == ["aa", "iy"]
    x, rate = read_audio(vowels_wav)
    sf.write(str(tmp_path / "stereo.wav"), np.c_[resample(x, rate, 48000), resample(x, rate, 48000)], 48000)
    sf.write(str(tmp_path / "tel.wav"), resample(x, rate, 8000), 8000)
    stereo = utterance_from_audio(tmp_path / "stereo.wav", "ah ee")
    assert np.allclose(stereo.words.start, u.words.start, atol=0.02)
    with pytest.warns(UserWarning, match="8000 Hz"):
        tel = utterance_from_audio(tmp_path / "tel.wav", "ah ee")
    assert np.allclose(tel.words.start, u.words.start, atol=0.05)
    recognised = utterance_from_audio(vowels_wav)                      # no text: a phone loop
    assert recognised.source_format == "recognised" and (recognised.segments.phoneme == "iy").any()


def test_text_that_cannot_be_the_audio_is_refused(vowels_wav):
    with pytest.raises(InputError, match="does not match|could not be aligned"):
        utterance_from_audio(vowels_wav, "bob pops the big pipe")


def test_place_assimilation_closes_the_lips_early():
    assert assimilate(["T", "EH1", "N", "B", "OW1", "N", "IY0"]) == ["T", "EH1", "M", "B", "OW1", "N", "IY0"]


def test_bad_audio_is_one_line_exit_2_and_writes_nothing(tmp_path, capsys, monkeypatch):
    monkeypatch.chdir(tmp_path)
    sf.write("empty.wav", np.zeros(0), 16000)
    sf.write("nan.wav", np.r_[np.zeros(100), np.nan, np.zeros(100)], 16000, subtype="FLOAT")
    sf.write("silence.wav", np.zeros(16000), 16000)
    sf.write("hum.wav", 0.3 * np.sin(2 * np.pi * 50 * np.arange(16000) / 16000), 16000)
    (tmp_path / "corrupt.wav").write_bytes(b"RIFF\x00\x00\x00\x00WAVEfmt garbage")
    (tmp_path / "notes.mp3").write_text("not audio at all")
    cases = {"empty.wav": "no samples", "nan.wav": "non-finite", "silence.wav": "no speech",
             "hum.wav": "no speech", "corrupt.wav": "unreadable audio", "notes.mp3": "unreadable audio",
             "missing.wav": "not found"}
    before = sorted(p.name for p in tmp_path.iterdir())
    for name, message in cases.items():
        code = main(["lipsync", name, "-o", "out.lab"])
        err = capsys.readouterr().err
        assert code == 2 and err.startswith("visemeface: error: ") and message in err, (name, err)
        assert err.count("\n") == 1, err
    assert sorted(p.name for p in tmp_path.iterdir()) == before


@pytest.mark.parametrize("suffix", sorted(SUFFIXES))
def test_writers_round_trip_through_the_readers(vowels_wav, tmp_path, suffix):
    u = utterance_from_audio(vowels_wav, "ah ee")
    suffix = ".TextGrid" if suffix == ".textgrid" else suffix
    path = write_transcript(u, tmp_path / f"t{suffix}")
    back = read_utterance(path)
    assert list(back.segments.phoneme) == list(u.segments.phoneme)
    assert np.allclose(back.segments[["start", "end"]], u.segments[["start", "end"]], atol=1e-4)
    with pytest.raises(InputError, match="exists"):
        write_transcript(u, path)
    with pytest.raises(InputError, match="transcript format"):
        format_of(tmp_path / "t.docx")


@pytest.mark.parametrize("start, end, message", [
    ([0.0, float("nan")], [0.2, 0.5], "must be finite"),
    ([0.0, 0.3], [0.2, 0.25], "positive length"),
    ([0.0, 0.1], [0.2, 0.5], "non-overlapping"),
    ([], [], "no segments to write"),
])
def test_a_transcript_that_would_not_read_back_is_not_written(tmp_path, start, end, message):
    segs = pd.DataFrame({"start": start, "end": end, "phoneme": ["aa", "b"][:len(start)]})
    with pytest.raises(InputError, match=message):
        write_transcript(segs, tmp_path / "t.lab")
    assert not any(tmp_path.iterdir())


def test_speak_a_recording_end_to_end(vowels_wav, tmp_path, monkeypatch, capsys):
    from visemeface.export.video import read_video_info

    monkeypatch.chdir(tmp_path)
    code = main(["speak", str(vowels_wav), "--text", "ah ee", "-o", "v.mp4", "--size", "32", "--msaa", "0",
                 "--fps", "25", "--save-transcript", "v.TextGrid", "-q"])
    assert code == 0, capsys.readouterr().err
    info = read_video_info("v.mp4")
    assert info["n_frames"] == 35 and info["audio_rate"] == 16000               # 1.4 s at 25 fps, its sound
    assert info["audio_samples"] == pytest.approx(1.4 * 16000, abs=400)
    assert [p for p in read_utterance("v.TextGrid").segments.phoneme if p != "_"] == ["aa", "iy"]
    assert main(["speak", str(vowels_wav), "--audio", str(vowels_wav), "-o", "w.mp4"]) == 2
    assert "--audio" in capsys.readouterr().err and not (tmp_path / "w.mp4").exists()
    copy = tmp_path / "take.mp4"
    copy.write_bytes(b"a video")
    assert main(["speak", "take.mp4", "--force"]) == 2                           # never the input itself
    assert "overwrite an input" in capsys.readouterr().err and copy.read_bytes() == b"a video"


def test_say_speaks_with_the_tts_extra_and_hints_without_it(tmp_path, monkeypatch, capsys):
    from visemeface.export.video import read_video_info
    from visemeface.speech import tts

    monkeypatch.chdir(tmp_path)
    monkeypatch.setattr(tts, "available", lambda: False)
    assert main(["say", "mama", "--size", "32", "--msaa", "0", "-o", "quiet.mp4"]) == 0
    err = capsys.readouterr().err
    assert err.count("visemeface[tts]") == 1 and read_video_info("quiet.mp4")["audio_rate"] == 0
    monkeypatch.undo()
    pytest.importorskip("espeakng_loader", reason="the optional tts extra (GPL eSpeak NG) is not installed")
    monkeypatch.chdir(tmp_path)
    assert main(["say", "Bob moves five boats", "--size", "32", "--msaa", "0", "-o", "loud.mp4", "-q"]) == 0
    info = read_video_info("loud.mp4")
    assert info["audio_rate"] > 0 and info["audio_samples"] / info["audio_rate"] == pytest.approx(
        info["n_frames"] / info["fps"], abs=0.05)


def test_lipsync_takes_the_words_of_a_text_beside_the_recording(vowels_wav, tmp_path, monkeypatch, capsys):
    import shutil

    monkeypatch.chdir(tmp_path)
    shutil.copy(vowels_wav, "take.wav")
    (tmp_path / "take.txt").write_text("ah ee\n")
    assert main(["lipsync", "take.wav", "-o", "take.json"]) == 0
    out = capsys.readouterr()
    assert "take.txt" in out.err and "2 words aligned" in out.out
    assert main(["lipsync", "take.wav", "--text", "ah", "--text-file", "take.txt", "-o", "x.lab"]) == 2
    assert main(["lipsync", "take.wav", "-o", "take.json"]) == 2                 # exists: --force
    assert "--force" in capsys.readouterr().err
    # a recording's words are an input: no output replaces them, --force or not (the next alignment would
    # fail), nor writes the .txt beside a recording, which the next run would read as its words
    (tmp_path / "words.txt").write_text("ah ee\n")
    shutil.copy(vowels_wav, "other.wav")
    for argv in (["lipsync", "take.wav", "-o", "take.txt", "--force"],
                 ["lipsync", "take.wav", "--text", "ah ee", "-o", "take.txt", "--force"],
                 ["lipsync", "take.wav", "--text-file", "words.txt", "-o", "words.txt", "--force"],
                 ["lipsync", "other.wav", "--text", "ah ee", "-o", "other.txt"],
                 ["speak", "take.wav", "--no-video", "--save-transcript", "take.txt", "--force"],
                 ["speak", "take.wav", "--text-file", "words.txt", "--no-video", "--save-transcript",
                  "words.txt", "--force"]):
        assert main(argv) == 2, argv
        assert "would overwrite the words of" in capsys.readouterr().err
    assert (tmp_path / "take.txt").read_text() == "ah ee\n" == (tmp_path / "words.txt").read_text()
    assert not (tmp_path / "other.txt").exists()


@pytest.mark.realdata
def test_speak_a_video_muxes_its_sound(realdata, tmp_path, monkeypatch):
    from visemeface.export.video import read_video_info

    monkeypatch.chdir(tmp_path)
    assert main(["speak", str(realdata / "bbaf2n.mpg"), "--text", "bin blue at f two now", "--size", "32",
                 "--msaa", "0", "--fps", "25", "-o", "b.mp4", "-q"]) == 0
    info = read_video_info("b.mp4")
    assert info["n_frames"] == 75 and info["size"] == (32, 32)                 # our frames, not the clip's
    assert info["audio_samples"] / info["audio_rate"] == pytest.approx(3.0, abs=0.03)
