"""scripts/compare_realdata.py's per-phone table: a phone is judged against its own clip's scale."""

from __future__ import annotations

import pytest


@pytest.fixture(scope="module")
def cr(load_script):
    return load_script("compare_realdata")


def test_a_clip_that_opens_everything_wider_does_not_make_its_own_phone_look_under_opened(cr):
    # clip A: the speaker opens every phone twice as wide as ours; clip B: the same as ours.
    # "iy" is only in A, "aa" in both; ours and the speaker's agree up to A's scale.
    rows = [("A", "aa", 0.40, 0.20), ("A", "iy", 0.20, 0.10), ("A", "t", 0.16, 0.08), ("A", "m", 0.0, 0.0),
            ("B", "aa", 0.20, 0.20), ("B", "t", 0.08, 0.08), ("B", "s", 0.10, 0.10)]
    table, scales = cr.phone_table(rows)
    assert scales.to_dict() == pytest.approx({"A": 0.5, "B": 1.0})
    assert table.loc["iy", "ours_minus_real"] == pytest.approx(-0.10)      # pooled: looks under-opened
    assert table.loc["iy", "clip_adjusted"] == pytest.approx(0.0)           # against its clip: as the speaker
    assert table.loc["m", "clip_adjusted"] == 0.0                           # a shut mouth stays shut
    assert table.loc["aa", "clips"] == 2 and table.loc["aa", "frames"] == 2


def test_a_phone_under_opened_within_its_clip_stays_under_opened(cr):
    rows = [("A", "aa", 0.40, 0.20), ("A", "t", 0.16, 0.08), ("A", "s", 0.20, 0.10), ("A", "iy", 0.20, 0.03)]
    table, _ = cr.phone_table(rows)
    assert table.loc["iy", "clip_adjusted"] == pytest.approx(0.03 - 0.5 * 0.20)
    assert table.index[0] == "iy"                                           # sorted: the most under-opened first


def test_a_clip_without_a_frame_both_open_has_no_scale_and_unknown_heights_are_left_out(cr):
    rows = [("A", "aa", 0.40, 0.20), ("A", "t", 0.20, 0.10), ("C", "iy", 0.30, 0.0), ("C", "m", 0.0, 0.0),
            ("A", "aa", float("nan"), 0.30), ("A", "aa", 0.40, float("nan"))]
    table, scales = cr.phone_table(rows)
    assert scales["A"] == pytest.approx(0.5) and scales.isna()["C"]      # no made-up 1.0 for C
    assert table.loc["iy", "ours_minus_real"] == pytest.approx(-0.30) and table.isna().loc["iy", "clip_adjusted"]
    assert table.loc["aa", "frames"] == 1 and table.loc["aa", "ours_minus_real"] == pytest.approx(-0.20)
