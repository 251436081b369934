"""JA/LI articulation: the acoustic measures, the factors and their place in the activation track."""

import numpy as np
import pandas as pd
import pytest

from visemeface.errors import InputError
from visemeface.postures.library import load_visemes
from visemeface.speech.acoustics import Acoustics, analyse, span_mean
from visemeface.speech.articulation import (JA_COLUMNS, acoustic_scales, articulate, check_articulation,
                                            stress_scales)
from visemeface.speech.g2p import text_to_utterance
from visemeface.speech.timeline import activation_track

RATE = 16000


def _vowel(f0, formants, seconds=0.5, rate=RATE):
    """An impulse train at ``f0`` through two-pole resonators at ``formants`` (Hz, 80 Hz bandwidths)."""
    n = int(seconds * rate)
    x = np.zeros(n)
    x[:: int(rate / f0)] = 1.0
    for f in formants:
        r = np.exp(-np.pi * 80 / rate)
        a1, a2 = 2 * r * np.cos(2 * np.pi * f / rate), -r * r
        y = np.zeros(n)
        for i in range(n):
            y[i] = x[i] + a1 * (y[i - 1] if i else 0) + a2 * (y[i - 2] if i > 1 else 0)
        x = y
    return 0.3 * x / np.abs(x).max()


def test_yin_tracks_the_pitch_of_a_gliding_tone():
    t = np.arange(RATE) / RATE
    f = 120 + 80 * t                                   # 120 -> 200 Hz over a second
    x = 0.3 * np.sign(np.sin(2 * np.pi * np.cumsum(f) / RATE))
    a = analyse(x, RATE)
    mid = (a.times > 0.1) & (a.times < 0.9)
    truth = 120 + 80 * a.times[mid]
    assert np.isfinite(a.f0[mid]).mean() > 0.95
    assert np.nanmax(np.abs(a.f0[mid] / truth - 1)) < 0.03


def test_noise_and_silence_have_no_pitch():
    rng = np.random.default_rng(0)
    x = np.r_[np.zeros(RATE // 2), 0.2 * rng.standard_normal(RATE // 2)]
    a = analyse(x, RATE)
    assert np.isfinite(a.f0).mean() < 0.1


def test_lpc_finds_the_first_two_formants_of_a_synthetic_vowel():
    a = analyse(_vowel(110, (700, 1200)), RATE)
    assert np.nanmedian(a.f1) == pytest.approx(700, rel=0.1)
    assert np.nanmedian(a.f2) == pytest.approx(1200, rel=0.1)
    assert np.nanmedian(a.f0) == pytest.approx(110, rel=0.03)


def _acoustics(levels, spans):
    """Acoustics whose level is ``levels[k]`` dB over ``spans[k]``, no pitch or formants."""
    times = np.arange(0.005, spans[-1][1], 0.01)
    level = np.full(times.size, -60.0)
    for (a, b), v in zip(spans, levels):
        level[(times >= a) & (times < b)] = v
    nan = np.full(times.size, np.nan)
    return Acoustics(times, level, nan, nan, nan, float(spans[-1][1]))


SEG = pd.DataFrame({"start": [0.0, 0.2, 0.4, 0.5, 0.7, 0.72], "end": [0.2, 0.4, 0.5, 0.7, 0.72, 0.9],
                    "phoneme": ["_", "aa", "b", "aa", "t", "aa"]})


def test_a_louder_vowel_opens_wider_and_the_closure_is_kept():
    spans = list(zip(SEG["start"], SEG["end"]))
    ac = _acoustics([-60, -10, -40, -25, -40, -10], spans)
    ja, li = acoustic_scales(ac, SEG["start"], SEG["end"], SEG["phoneme"])
    assert ja[1] > ja[3] and ja[5] > ja[3]                 # the quiet /aa/ opens less than the loud ones
    assert ja[2] == 1.0 and ja[0] == 1.0                   # /b/ and silence untouched
    assert ja[4] == pytest.approx(ja[5])                   # /t/ (a silent closure) follows its nearest vowel
    assert (li == 1).all()                                 # no formants measured: no lip change
    zero = acoustic_scales(ac, SEG["start"], SEG["end"], SEG["phoneme"], articulation=0)
    assert (zero[0] == 1).all() and (zero[1] == 1).all()
    double = acoustic_scales(ac, SEG["start"], SEG["end"], SEG["phoneme"], articulation=2)
    assert np.log(double[0][3]) == pytest.approx(2 * np.log(ja[3]))


def test_articulate_scales_the_jaw_and_lip_columns_only_and_never_a_bilabial():
    vis = load_visemes()
    phones = ["aa", "b", "iy"]
    cols = list(vis.select_dtypes("number").columns)
    targets = vis.loc[phones, cols].to_numpy(float)
    out = articulate(targets, cols, phones, np.array([1.5, 0.5, 1.2]), np.array([1.2, 1.2, 0.8]))
    j = cols.index("jaw")
    assert out[0, j] == pytest.approx(1.5 * targets[0, j]) and out[2, j] == pytest.approx(1.2 * targets[2, j])
    np.testing.assert_array_equal(out[1], targets[1])                       # /b/ as tabled
    r = cols.index("risorius_left")
    o = cols.index("orbicularis_oris")
    assert out[0, r] == pytest.approx(1.2 * targets[0, r]) and out[0, o] == pytest.approx(targets[0, o] / 1.2)
    other = [k for k, c in enumerate(cols) if c not in JA_COLUMNS + ("risorius_left", "risorius_right",
                                                                      "orbicularis_oris", "lip_rounding")]
    np.testing.assert_array_equal(out[:, other], targets[:, other])
    with pytest.raises(InputError, match="3"):
        articulate(targets, cols, phones, np.ones(2), np.ones(3))
    with pytest.raises(InputError, match="positive"):
        articulate(targets, cols, phones, np.array([1, 0, 1.0]), np.ones(3))


def test_unit_factors_give_the_tabled_track_and_closures_stay_exact():
    vis = load_visemes()
    plain = activation_track(SEG, vis, fps=50)
    same = activation_track(SEG, vis, fps=50, jali=(np.ones(6), np.ones(6)))
    pd.testing.assert_frame_equal(plain, same)
    wide = activation_track(SEG, vis, fps=50, jali=(np.full(6, 1.6), np.ones(6)))
    assert wide["jaw"].max() > plain["jaw"].max() * 1.3
    b = wide.loc[0.44:0.46]                                # the centre of /b/: its exact target
    np.testing.assert_allclose(b["jaw"], vis.loc["b", "jaw"])


def test_check_articulation_refuses_out_of_range_values():
    assert check_articulation("1.5") == 1.5
    for bad in (-0.1, 2.5, "x", float("nan")):
        with pytest.raises(InputError, match="--articulation"):
            check_articulation(bad)


def test_stress_marks_and_emphasis_of_a_text():
    plain = text_to_utterance("I never said she stole my money")
    stressed = text_to_utterance("I never said *she* stole my money")
    st, em = stressed.phone_stress()
    seg = stressed.segments
    assert len(st) == len(seg) and list(seg.columns) == ["start", "end", "phoneme"]
    she = (seg["start"] >= stressed.words["start"][3] - 1e-9) & (seg["end"] <= stressed.words["end"][3] + 1e-9)
    assert em[she.to_numpy()].all() and not em[~she.to_numpy()].any()
    assert np.isnan(st[seg["phoneme"].to_numpy() == "_"]).all() and st[seg["phoneme"].to_numpy() == "iy"][0] == 1
    pd.testing.assert_frame_equal(plain.segments, stressed.segments)        # emphasis changes no timing
    ja_plain, _ = stress_scales(plain.segments["phoneme"], *plain.phone_stress())
    ja_em, _ = stress_scales(seg["phoneme"], st, em)
    vowel_of_she = np.flatnonzero(she.to_numpy() & (seg["phoneme"].to_numpy() == "iy"))
    assert (ja_em[vowel_of_she] > ja_plain[vowel_of_she] * 1.2).all()
    assert ja_plain[np.flatnonzero(plain.segments["phoneme"].to_numpy() == "rr")][0] < 1   # "nev-er": unstressed
    assert stressed.lasting(stressed.end + 1).phone_stress()[0].size == len(stressed.lasting(stressed.end + 1).segments)


def test_span_mean_ignores_nan_and_reads_the_middle():
    times = np.arange(10) * 0.1 + 0.05
    v = np.array([0, 0, 10, 10, np.nan, 10, 0, 0, 0, 0], float)
    assert span_mean(v, times, [0.0], [0.8], middle=0.5)[0] == pytest.approx(10)
