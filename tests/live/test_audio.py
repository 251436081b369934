"""Live audio in: the streaming resampler, WAV and raw streams, and streams of the wrong sample format."""

import io
import os
import struct
import threading

import numpy as np
import pytest
import soundfile as sf

from visemeface.errors import InputError
from visemeface.live.audio import Resampler, StreamSource


def _resample_in_blocks(x, rate, sizes):
    r = Resampler(rate, 16000)
    out, i, k = [], 0, 0
    while i < x.size:
        n = sizes[k % len(sizes)]
        out.append(r(x[i:i + n]))
        i, k = i + n, k + 1
    return np.concatenate(out)


@pytest.mark.parametrize("rate", [44100, 48000, 8000])
def test_a_tone_keeps_its_phase_and_level_across_the_resampling(rate):
    t = np.arange(rate) / rate
    y = _resample_in_blocks(np.sin(2 * np.pi * 440 * t), rate, [441])
    ts = np.arange(y.size) / 16000 - Resampler(rate).delay / rate       # the filter's delay, left in
    inner = slice(200, y.size - 200)
    assert np.max(np.abs(y[inner] - np.sin(2 * np.pi * 440 * ts[inner]))) < 0.03
    assert abs(y.size - 16000) <= 2 * 16000 * 0.01 + 70


def test_the_output_does_not_depend_on_how_the_input_was_cut():
    x = np.random.default_rng(1).normal(0, 0.1, 44100)
    a = _resample_in_blocks(x, 44100, [441])
    b = _resample_in_blocks(x, 44100, [1, 999, 37, 4410])
    n = min(a.size, b.size)
    assert n > 15000 and np.allclose(a[:n], b[:n], atol=1e-12)


def test_a_tone_above_the_new_nyquist_is_filtered_out():
    t = np.arange(48000) / 48000
    y = _resample_in_blocks(np.sin(2 * np.pi * 12000 * t), 48000, [480])
    assert np.sqrt(np.mean(y[500:] ** 2)) < 0.05


def _pipe_source(data: bytes, **kw):
    r, w = os.pipe()

    def write():
        with os.fdopen(w, "wb") as fh:
            fh.write(data)

    threading.Thread(target=write, daemon=True).start()
    return StreamSource(r, **kw), r


def _read_all(source, fd):
    try:
        return np.concatenate(list(source.blocks()))
    finally:
        os.close(fd)


@pytest.mark.parametrize("subtype,rate,channels", [("PCM_16", 44100, 1), ("PCM_24", 22050, 2), ("FLOAT", 16000, 1),
                                                  ("PCM_U8", 8000, 1)])
def test_a_wav_stream_says_its_own_rate_channels_and_format(subtype, rate, channels):
    x = 0.5 * np.sin(2 * np.pi * 300 * np.arange(rate // 2) / rate)
    buf = io.BytesIO()
    sf.write(buf, np.column_stack([x] * channels), rate, format="WAV", subtype=subtype)
    source, fd = _pipe_source(buf.getvalue(), rate=16000, fmt="s16le")
    y = _read_all(source, fd)
    assert source.rate == rate and source.channels == channels
    assert y.size == x.size and np.max(np.abs(y - x)) < 0.01


def test_raw_pcm_of_the_given_format():
    x = 0.25 * np.sin(np.arange(8000) / 10)
    source, fd = _pipe_source(x.astype("<f4").tobytes(), rate=8000, fmt="f32le")
    assert np.allclose(_read_all(source, fd), x, atol=1e-6)


def test_floats_sent_as_16_bit_pcm_are_refused():
    x = 0.3 * np.sin(np.arange(16000) / 7)
    source, fd = _pipe_source(x.astype("<f4").tobytes(), fmt="s16le")
    with pytest.raises(InputError, match="32-bit float"):
        _read_all(source, fd)


def test_16_bit_pcm_sent_as_floats_is_refused():
    x = (0.3 * np.sin(np.arange(16000) / 7) * 32767).astype("<i2")
    source, fd = _pipe_source(x.tobytes(), fmt="f32le")
    with pytest.raises(InputError, match="not 32-bit floats"):
        _read_all(source, fd)


def test_speech_like_16_bit_pcm_is_not_mistaken_for_floats(realdata):
    from visemeface.speech.audio import read_audio

    x, rate = read_audio(realdata / "swwp2s.mpg")
    pcm = (np.clip(x, -1, 1) * 32767).astype("<i2").tobytes()
    source, fd = _pipe_source(pcm, fmt="s16le", rate=rate)
    assert _read_all(source, fd).size == x.size


def test_a_wav_stream_of_mu_law_is_refused_in_one_line():
    fmt = struct.pack("<HHIIHH", 7, 1, 8000, 8000, 1, 8)
    data = b"\x7f" * 800
    wav = b"RIFF" + struct.pack("<I", 36 + len(data)) + b"WAVE" + b"fmt " + struct.pack("<I", 16) + fmt
    wav += b"data" + struct.pack("<I", len(data)) + data
    source, fd = _pipe_source(wav)
    with pytest.raises(InputError, match="mu-law"):
        _read_all(source, fd)


@pytest.mark.parametrize("rate", [0, 100, 10 ** 7])
def test_a_rate_no_audio_has_is_refused(rate):
    with pytest.raises(InputError, match="sample rate"):
        StreamSource(0 if not os.isatty(0) else os.open(os.devnull, os.O_RDONLY), rate=rate)
