"""Blinks: rate, length, spacing, determinism, word boundaries, and what they do to the lids."""

import numpy as np
import pandas as pd
import pytest

from visemeface.speech.blinks import add_blinks, blink_curve, blink_schedule
from visemeface.track import make_track


@pytest.mark.parametrize("seed", range(0, 300, 7))
def test_a_minute_of_speech_blinks_naturally(seed):
    s = blink_schedule(60.0, seed=seed)
    start = np.array([a for a, _ in s])
    length = np.array([b for _, b in s])
    assert 12 <= len(s) <= 25
    assert ((0.1 <= length) & (length <= 0.3)).all()
    assert (start[1:] - (start[:-1] + length[:-1]) >= 1.0 - 1e-9).all()     # >= 1 s apart
    gaps = np.diff(start)
    assert gaps.std() > 0.2 * gaps.mean()                                    # irregular


def test_deterministic_and_seeded():
    assert blink_schedule(30.0, seed=3) == blink_schedule(30.0, seed=3)
    assert blink_schedule(30.0, seed=3) != blink_schedule(30.0, seed=4)


def test_blinks_move_to_word_boundaries():
    words = np.array([[i * 0.5, i * 0.5 + 0.45] for i in range(120)])    # 0.45 s words, 50 ms gaps
    s = blink_schedule(60.0, seed=1, words=words)
    bounds = np.unique(words.ravel())
    for start, _ in s:
        mid_word = ((words[:, 0] < start) & (start < words[:, 1])).any()
        assert not mid_word or np.min(np.abs(bounds - start)) > 0.4


def test_the_curve_closes_fast_and_opens_slowly():
    t = np.linspace(0, 1, 1001)
    b = blink_curve(t, [(0.2, 0.25)])
    assert b.max() == pytest.approx(1.0) and b[t < 0.2].max() == 0 and b[t > 0.45].max() == 0
    up = t[(b > 0.5)]
    closing, opening = up[0] - 0.2, 0.45 - up[-1]
    assert closing < opening


def test_added_to_the_lid_functions_and_nothing_else():
    names = ["upper_lid_close_left", "upper_lid_close_right", "lower_lid_raise_left", "lower_lid_raise_right",
             "upper_lid_raise_left", "upper_lid_raise_right", "jaw"]
    t = np.arange(30) / 30.0
    track = make_track(t, np.column_stack([np.full(30, 0.2)] + [np.zeros(30)] * 3 + [np.ones(30)] * 2
                                          + [np.full(30, 0.3)]), names, 30.0)
    out = add_blinks(track, names, [(0.3, 0.2)])
    k = int(np.argmax(out["upper_lid_close_left"]))
    assert out["upper_lid_close_left"].iloc[k] > 0.95 and out["lower_lid_raise_left"].iloc[k] > 0.35
    assert out["upper_lid_raise_left"].iloc[k] < 0.05                      # AU5 gives way while shut
    pd.testing.assert_series_equal(out["jaw"], track["jaw"])
    assert out["upper_lid_close_left"].iloc[0] == pytest.approx(0.2)       # untouched between blinks
