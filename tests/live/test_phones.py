"""The live decoder: the phones of a stream, contiguous across the utterances a long session is cut into."""

import numpy as np
import pytest

from visemeface.live import phones as live_phones


@pytest.fixture(scope="module")
def grid16k(realdata):
    from visemeface.speech.audio import read_audio, resample

    x, rate = read_audio(realdata / "swwp2s.mpg")
    return resample(x, rate, 16000)


def _decode(x, block=160):
    d = live_phones.LivePhones()
    for i in range(0, x.size, block):
        d.feed(x[i:i + block])
    d.finish()
    return d


@pytest.mark.realdata
def test_the_phones_cover_the_stream_and_find_the_words_sounds(grid16k):
    d = _decode(grid16k)
    ph = d.phones
    assert ph[0][1] == 0.0 and abs(ph[-1][2] - grid16k.size / 16000) <= 0.011
    assert all(abs(a[2] - b[1]) < 1e-9 for a, b in zip(ph, ph[1:]))
    labels = [p[0] for p in ph]
    assert "B" in labels or "P" in labels                    # "p two"'s closure (recognised as /b/)
    assert {"S", "T", "N"} <= set(labels)


@pytest.mark.realdata
def test_a_long_session_is_cut_at_pauses_and_stays_contiguous(grid16k, monkeypatch):
    monkeypatch.setattr(live_phones, "UTTERANCE_S", 2.0)
    x = np.concatenate([grid16k, np.zeros(8000), grid16k])
    d = live_phones.LivePhones()
    ends_seen = []
    for i in range(0, x.size, 320):
        d.feed(x[i:i + 320])
        if d.offset and not ends_seen:
            ends_seen.append(d.offset)
    d.finish()
    assert ends_seen, "the utterance was never ended at a pause"
    ph = d.phones
    assert all(abs(a[2] - b[1]) < 1e-9 for a, b in zip(ph, ph[1:])) and abs(ph[-1][2] - x.size / 16000) <= 0.011
    assert [p[0] for p in d.since(3.5)] and all(p[2] > 3.5 for p in d.since(3.5))


def test_a_partial_frame_waits_for_the_next_block():
    d = live_phones.LivePhones()
    d.feed(np.zeros(100))
    assert d.samples == 0
    d.feed(np.zeros(100))
    assert d.samples == 160
