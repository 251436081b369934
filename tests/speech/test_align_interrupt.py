"""Ctrl-C ends a long alignment at once (pocketsphinx holds the GIL for a whole decode).

Before: ``lipsync`` of a 5-minute recording printed "interrupted" only when the decode ended
(8.6 s after SIGINT here); long recordings are now decoded in a child process that is ended.
"""

import signal
import subprocess
import sys
import time

import numpy as np
import pytest
import soundfile as sf

from visemeface.speech import align


def test_a_child_decode_gives_the_same_phones_and_words(vowels_wav, monkeypatch):
    inline = align.utterance_from_audio(vowels_wav, "ah ee")
    recognised = align.utterance_from_audio(vowels_wav)
    monkeypatch.setattr(align, "CHILD_DECODE_S", 0.0)
    assert align.utterance_from_audio(vowels_wav, "ah ee").segments.equals(inline.segments)
    assert align.utterance_from_audio(vowels_wav).segments.equals(recognised.segments)


def test_a_child_decode_passes_the_refusal_on(vowels_wav, monkeypatch):
    from visemeface.errors import InputError

    monkeypatch.setattr(align, "CHILD_DECODE_S", 0.0)
    with pytest.raises(InputError, match="could not be aligned"):
        align.utterance_from_audio(vowels_wav, "the quick brown fox jumps over the lazy dog again and again")


@pytest.mark.slow
def test_ctrl_c_ends_lipsync_of_a_long_recording_promptly(tmp_path, vowels_wav, prompt_s):
    x, rate = sf.read(str(vowels_wav))
    sf.write(str(tmp_path / "long.wav"), np.tile(x, 160), rate)           # 224 s: a decode of several s
    proc = subprocess.Popen([sys.executable, "-m", "visemeface", "lipsync", "long.wav", "-o", "long.lab"],
                            cwd=tmp_path, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    time.sleep(3.0)                                                        # reading done, decoding
    assert proc.poll() is None, proc.communicate()
    t0 = time.monotonic()
    proc.send_signal(signal.SIGINT)
    try:
        _, err = proc.communicate(timeout=30)
    finally:
        proc.kill()
    assert time.monotonic() - t0 < prompt_s, f"{time.monotonic() - t0:.1f} s after Ctrl-C"
    assert proc.returncode == 130 and err == "visemeface: interrupted\n", err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["long.wav"]


@pytest.mark.slow
def test_the_decoding_child_dies_with_a_killed_lipsync(tmp_path, vowels_wav, prompt_s):
    """SIGKILL of the command left a multiprocessing child decoding on, which then printed a BrokenPipeError
    traceback and a leaked-semaphore warning on the terminal."""
    import os

    import psutil

    x, rate = sf.read(str(vowels_wav))
    sf.write(str(tmp_path / "long.wav"), np.tile(x, 300), rate)
    proc = subprocess.Popen([sys.executable, "-m", "visemeface", "lipsync", "long.wav", "-o", "long.lab"],
                            cwd=tmp_path, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        t0 = time.monotonic()
        while not psutil.Process(proc.pid).children() and time.monotonic() - t0 < 30:
            time.sleep(0.05)
        time.sleep(3.0)                        # the child has the recording and is decoding
        children = psutil.Process(proc.pid).children(recursive=True)
        assert children, "no decoding child"
        os.kill(proc.pid, signal.SIGKILL)
        t0 = time.monotonic()
        _, err = proc.communicate(timeout=60)  # returns when every holder of the command's stderr is gone
        assert time.monotonic() - t0 < prompt_s and err == "", err
        gone, alive = psutil.wait_procs(children, timeout=prompt_s)
        alive = [p for p in alive if p.status() != psutil.STATUS_ZOMBIE]
        assert not alive, f"still running: {alive}"
    finally:
        proc.kill()


def test_the_grid_clip_as_an_mp3_aligns_like_its_wav(tmp_path):
    """The shipped GRID clip encoded by the bundled ffmpeg's MP3 defaults was refused ("the text could not be
    aligned"; pocketsphinx's phone pass found no path) while its WAV aligned; a retry with a trace of seeded
    dither aligns it: boundaries within 10 ms of the WAV's, the last word's end within 30 ms (one frame)."""
    import imageio_ffmpeg

    from visemeface.resources import transcripts_path

    wav = transcripts_path("set_white_with_p_two_soon.wav")
    mp3 = tmp_path / "take.mp3"
    subprocess.run([imageio_ffmpeg.get_ffmpeg_exe(), "-v", "error", "-i", str(wav), str(mp3)], check=True)
    text = "set white with p two soon"
    want, got = align.utterance_from_audio(wav, text).words, align.utterance_from_audio(mp3, text).words
    assert list(got["word"]) == text.split()
    diff = np.abs(got[["start", "end"]].to_numpy() - want[["start", "end"]].to_numpy())
    assert diff.max() <= 0.031 and np.delete(diff.ravel(), -1).max() <= 0.011, diff
