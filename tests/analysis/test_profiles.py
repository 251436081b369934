"""Opening profiles over time: merging openings, L2 distances, CSV and plots."""

import numpy as np
import pandas as pd
import pytest

from visemeface.analysis.openings import OpeningDetector
from visemeface.analysis.profiles import (
    COLUMNS, analyze_frames, l2_distance, opening_onsets, plot_profiles, read_profile, rise_exponent, write_profile)
from visemeface.analysis.synthetic import merging_mouth_frames
from visemeface.errors import InputError

BOX = (28, 78, 200, 100)        # the default box of merging_mouth_frames at 256x256


@pytest.fixture(scope="module")
def merging():
    return analyze_frames(merging_mouth_frames(30, 17, (256, 256)), BOX, fps=30, source="merge17")


def test_merge_shows_as_count_drop_and_width_spike(merging):
    df = merging
    assert list(df.columns) == list(COLUMNS)
    count = df["count"].to_numpy()
    assert (count[:17] == 2).all() and (count[17:] == 1).all()
    d_width = df["d_width"].to_numpy()
    assert np.nanargmax(np.abs(d_width)) == 17
    # the spike is the jump from one half (~0.27 w) to the whole opening (0.6 w)
    assert d_width[17] == pytest.approx(0.6 - 0.27, abs=0.02)
    others = np.delete(d_width[1:], 16)
    assert np.abs(others).max() < 0.02
    assert np.nanargmax(df["d_area"].to_numpy()) == 17
    assert np.isnan(d_width[0])
    np.testing.assert_allclose(df["time"], np.arange(30) / 30)
    assert df.attrs["fps"] == 30 and df.attrs["mouth_width"] == 200


def test_hull_does_not_hide_the_merge():
    df = analyze_frames(merging_mouth_frames(12, 6, (256, 256)), BOX, fps=25,
                        detector=OpeningDetector(hull=True))
    assert list(df["count"]) == [2] * 6 + [1] * 6


def test_on_frame_sees_every_frame():
    seen = []
    analyze_frames(merging_mouth_frames(5, 2, (256, 256)), BOX, 30, on_frame=lambda i, f, o: seen.append((i, o.count)))
    assert seen == [(0, 2), (1, 2), (2, 1), (3, 1), (4, 1)]


def test_no_frames_is_an_input_error():
    with pytest.raises(InputError, match="no frames"):
        analyze_frames(iter([]), BOX, 30)


def _profile(t, width, area=None):
    area = np.zeros_like(t) if area is None else area
    return pd.DataFrame({"time": t, "area": area, "width": width, "height": np.zeros_like(t)})


def test_l2_identical_is_zero_and_constant_offset_is_exact(merging):
    assert l2_distance(merging, merging) == {"area": 0.0, "width": 0.0, "height": 0.0}
    t = np.arange(50) / 30
    d = l2_distance(_profile(t, np.sin(t)), _profile(t, np.sin(t) + 0.1))
    assert d["width"] == pytest.approx(0.1 * np.sqrt(50))
    assert d["area"] == 0.0


def test_l2_resamples_when_frame_rates_differ():
    """The same smooth motion filmed at 30 and 60 fps is (almost) the same profile."""
    t30, t60 = np.arange(31) / 30, np.arange(61) / 60
    f = lambda t: 0.3 + 0.2 * np.sin(2 * np.pi * t)       # noqa: E731
    a, b = _profile(t30, f(t30)), _profile(t60, f(t60))
    a.attrs["fps"], b.attrs["fps"] = 30.0, 60.0
    d_ab, d_ba = l2_distance(a, b)["width"], l2_distance(b, a)["width"]
    assert d_ab == pytest.approx(d_ba)
    assert d_ab < 1e-12                   # sampled at a's instants, which b contains
    # a shifted copy is measured on the common span only, at the slower rate's instants
    c = _profile(t60 + 0.5, f(t60 + 0.5))
    c.attrs["fps"] = 60.0
    assert l2_distance(a, c)["width"] < 1e-12
    assert l2_distance(a, _profile(t30 + 0.5, f(t30) + 0.05))["width"] == pytest.approx(
        np.sqrt(np.sum((f(t30[15:]) - f(t30[:16]) - 0.05) ** 2)))


def test_l2_needs_overlap():
    t = np.arange(10) / 30
    with pytest.raises(InputError, match="do not overlap"):
        l2_distance(_profile(t, t), _profile(t + 5, t))


def test_csv_round_trip(tmp_path, merging):
    path = tmp_path / "p.csv"
    write_profile(merging, path)
    back = read_profile(path)
    pd.testing.assert_frame_equal(back, merging, check_exact=False, rtol=1e-7)
    assert back.attrs["fps"] == 30.0                 # exactly: not 30.000003 from 8-digit times
    with pytest.raises(InputError, match="exists"):
        write_profile(merging, path)


def test_read_profile_errors(tmp_path):
    bad = tmp_path / "bad.csv"
    bad.write_text("time,area,width\n0,1,2\n0.1,1,2\n")
    with pytest.raises(InputError, match="missing column.*height"):
        read_profile(bad)
    bad.write_text("time,area,width,height\n0,1,2,3\n0.1,x,2,3\n")
    with pytest.raises(InputError, match=r"bad.csv:3: column 'area' has a non-number 'x'"):
        read_profile(bad)
    with pytest.raises(InputError, match="no such file"):
        read_profile(tmp_path / "none.csv")


def test_plot_writes_a_png(tmp_path, merging):
    import matplotlib.image as mpimg
    other = merging.copy()
    other["width"] = other["width"] * 0.9
    out = tmp_path / "plot.png"
    plot_profiles({"merge": merging, "scaled": other}, out, title="merge at frame 17")
    img = mpimg.imread(out)
    assert img.shape[0] > img.shape[1] > 500             # stacked panels
    # lines of two colours were drawn: plenty of strongly coloured pixels
    rgb = img[..., :3]
    assert ((rgb.max(axis=2) - rgb.min(axis=2)) > 0.4).sum() > 2000
    with pytest.raises(InputError, match="unknown metric"):
        plot_profiles({"a": merging}, tmp_path / "x.png", metrics=["speed"])


@pytest.mark.parametrize("module", ["visemeface.analysis", "visemeface.analysis.openings"])
def test_docstring_examples_run(module):
    import doctest
    import importlib
    result = doctest.testmod(importlib.import_module(module))
    assert result.attempted > 0 and result.failed == 0


@pytest.mark.parametrize("body,match", [
    ("", "at least 2 frames"),
    ("0,0.0,1,0.1,0.2,0.1\n1,0.033,1,nan,0.2,0.1\n", "non-finite"),
    ("0,0.0,1,0.1,0.2,0.1\n1,0.033,1,0.1,inf,0.1\n", "non-finite"),
])
def test_read_profile_refuses_empty_and_non_finite(tmp_path, body, match):
    from visemeface.analysis.profiles import read_profile

    p = tmp_path / "p.csv"
    p.write_text("frame,time,count,area,width,height\n" + body)
    with pytest.raises(InputError, match=match):
        read_profile(p)


def _series_profile(values, fps=25.0, column="height"):
    from visemeface.analysis.profiles import add_derivatives

    v = np.asarray(values, float)
    df = pd.DataFrame({"frame": np.arange(v.size), "time": np.arange(v.size) / fps, "count": (v > 0).astype(int),
                       "area": v * 0.5, "width": v * 2, "height": v})
    add_derivatives(df)
    df.attrs["fps"] = fps
    return df


def test_correlation_finds_the_lag_of_a_delayed_copy():
    from visemeface.analysis.profiles import correlation

    rng = np.random.default_rng(3)
    base = np.convolve(rng.random(80), np.ones(5) / 5, mode="same")
    for lag in (-4, 0, 3):
        a = _series_profile(base[10:70])
        b = _series_profile(base[10 - lag:70 - lag])           # b(t) = a(t - lag): b is late by `lag` frames
        c = correlation(a, b, max_lag=5)
        assert c["lag"] == lag
        assert c["r_lag"] == pytest.approx(1.0)
        assert c["lag_s"] == pytest.approx(lag / 25.0)
        if lag:
            assert c["r"]["height"] < 0.99


def test_correlation_of_a_constant_profile_is_nan_and_lag_zero():
    from visemeface.analysis.profiles import correlation

    c = correlation(_series_profile(np.zeros(20)), _series_profile(np.linspace(0, 1, 20)))
    assert np.isnan(c["r"]["height"]) and c["lag"] == 0 and np.isnan(c["r_lag"])


@pytest.mark.parametrize("suffix,magic", [(".svg", b"<?xml"), (".pdf", b"%PDF")])
def test_plot_format_follows_the_suffix_and_is_deterministic(tmp_path, merging, suffix, magic):
    """--plot x.svg / x.pdf are accepted by analyze and compare: they must be SVG / PDF (they were PNG
    bytes under that name), byte for byte the same on a rerun (no date, no random ids)."""
    a, b = tmp_path / f"a{suffix}", tmp_path / f"b{suffix}"
    plot_profiles({"merge": merging}, a)
    plot_profiles({"merge": merging}, b)
    assert a.read_bytes().startswith(magic)
    assert a.read_bytes() == b.read_bytes()


def test_plot_of_a_single_frame_shows_its_values(tmp_path, merging):
    """A still image is a one-frame profile: a line through one point draws nothing, so it gets markers."""
    import matplotlib.image as mpimg

    def coloured(df, name):
        plot_profiles({"one": df}, tmp_path / name, metrics=["area", "width", "height"])
        rgb = mpimg.imread(tmp_path / name)[..., :3]
        return int(((rgb.max(axis=2) - rgb.min(axis=2)) > 0.4).sum())

    legend_only = coloured(merging.iloc[:1].assign(area=np.nan, width=np.nan, height=np.nan), "none.png")
    assert coloured(merging.iloc[:1], "one.png") > legend_only + 3 * 20        # a marker in each panel


def _onset_profile(count, width, height, fps=25.0):
    frame = np.arange(len(count))
    return pd.DataFrame({"frame": frame, "time": frame / fps, "count": count, "area": np.zeros(len(count)),
                         "width": width, "height": height})


def test_rise_exponent_fits_the_rise_not_the_plateau():
    # h = 0.01 t^2 rises for 5 frames, then wobbles on a plateau (its highest frame far out on it):
    # the fit ends where the rise reaches 95 % of the highest, so the plateau does not make it taper
    t = np.arange(1, 6, dtype=float)
    plateau = 0.25 + 0.002 * np.sin(np.arange(30))
    assert rise_exponent(np.r_[0.01 * t ** 2, plateau]) == pytest.approx(2.0, abs=0.02)
    assert rise_exponent(np.r_[0.2 * t ** 0.5, 0.2 * np.sqrt(5) * np.ones(10)]) == pytest.approx(0.5, abs=0.02)
    # frames with no height yet are left out of the log fit; under 3 frames there is nothing to fit
    assert rise_exponent([0.0, 0.02, 0.045, 0.08]) == pytest.approx(2.0)
    assert np.isnan(rise_exponent([0.1, 0.2])) and np.isnan(rise_exponent([0.0, 0.0, 0.0]))
    assert np.isnan(rise_exponent([]))


def test_opening_onsets_measure_how_each_opening_grows():
    # closed, then an opening whose height is 0.01 t^2 (t frames since the last closed one) and whose
    # width reaches 90 % of its widest on its third frame; closed again; then one frame open at full width
    t = np.arange(1, 6, dtype=float)
    count = [0, 0, *[1] * 5, 0, 1, 1, 0]
    width = [0, 0, 0.2, 0.5, 0.65, 0.7, 0.7, 0, 0.8, 0.8, 0]
    height = [0, 0, *(0.01 * t ** 2), 0, 0.1, 0.1, 0]
    o = opening_onsets(_onset_profile(count, width, height))
    assert o["frame"].tolist() == [2, 8] and o["frames"].tolist() == [5, 2]
    assert o["frames_to_90pct"].tolist() == [3, 1]
    assert o["peak_width"].tolist() == [0.7, 0.8]
    assert o["height_exponent"].iloc[0] == pytest.approx(2.0)      # slowly, then faster (seed 001, Fig. 19)
    assert np.isnan(o["height_exponent"].iloc[1])                  # too short to fit
    # a window cuts a long opening; an opening already there on frame 0 has no onset
    assert opening_onsets(_onset_profile(count, width, height), window=2)["frames"].tolist() == [2, 2]
    assert opening_onsets(_onset_profile([1, 1, 0], [0.5, 0.5, 0], [0.1, 0.1, 0])).empty
