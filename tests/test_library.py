"""Viseme/expression tables and expressive blending (visemeface.postures.library)."""

from __future__ import annotations

import math

import numpy as np
import pandas as pd
import pytest

from visemeface.errors import InputError
from visemeface.postures import library as lib
from visemeface.postures.phonemes import CLASSES, DECTALK

# ----------------------------------------------------------------------------- targets


@pytest.fixture(scope="module")
def targets():
    return lib.load_targets()


def test_targets_cover_the_56_dectalk_postures_in_order(targets):
    assert targets.index.tolist() == list(DECTALK)
    assert len(targets) == 56
    assert targets["index"].tolist() == list(range(56))
    assert targets["notes"].str.len().min() > 10


def test_targets_opening_is_upper_raise_plus_lower_drop(targets):
    t = targets
    np.testing.assert_allclose(t.opening_height, t.upper_lip_raise + t.lower_lip_drop, atol=1e-12)


def test_targets_follow_articulatory_phonetics(targets):
    t = targets
    # bilabials closed; silence neutral
    assert (t.loc[["p", "b", "m"], "opening_height"] == 0).all()
    assert (t.loc["_", list(lib.TARGET_DIMENSIONS)] == 0).all()
    # labiodentals: lower lip raised (negative drop) and drawn back
    assert (t.loc[["f", "v"], "lower_lip_drop"] < 0).all()
    assert (t.loc[["f", "v"], "protrusion"] < 0).all()
    # rounded vowels narrower and more protruded than every spread vowel
    rounded, spread = t.loc[["ow", "uw", "w"]], t.loc[["iy", "ih", "ae"]]
    assert rounded.mouth_width.max() < spread.mouth_width.min()
    assert rounded.protrusion.min() > spread.protrusion.max()
    # open vowels have the lowest jaw
    assert t.loc[["aa", "ah", "ae"], "lower_lip_drop"].min() > t.loc[["iy", "uw", "s", "t"], "lower_lip_drop"].max()
    # w is the tightest rounding
    assert t.mouth_width.idxmin() == "w"


def _write(tmp_path, text, name="t.csv"):
    p = tmp_path / name
    p.write_text(text)
    return p


def test_targets_errors_name_file_line_and_column(tmp_path):
    src = lib.targets_file().read_text().splitlines()
    bad = src[:]
    bad[6] = bad[6].replace("0.25", "abc", 1)  # ae's opening height
    p = _write(tmp_path, "\n".join(bad))
    with pytest.raises(InputError, match=r"t\.csv:7: column 'opening_height': 'abc' is not a number"):
        lib.load_targets(p)
    bad = src[:]
    bad[0] = bad[0].replace("mouth_width", "mouth_widht")
    with pytest.raises(InputError, match="did you mean: mouth_width"):
        lib.load_targets(_write(tmp_path, "\n".join(bad)))
    with pytest.raises(InputError, match="missing: jh"):
        lib.load_targets(_write(tmp_path, "\n".join(src[:-1])))
    with pytest.raises(InputError, match="file not found"):
        lib.load_targets(tmp_path / "nope.csv")
