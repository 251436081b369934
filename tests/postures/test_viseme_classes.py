"""Objective class test of the visemes (scripts/viseme_class_test.py): every Table-2 class >= 95%."""

from __future__ import annotations

import numpy as np
import pytest


@pytest.fixture(scope="module")
def ct(load_script):
    return load_script("viseme_class_test")


def test_leave_one_out_excludes_the_sample_from_its_centroid(ct):
    X = np.array([[0.0], [2.9], [4.0], [5.0]])
    y = np.array(["A", "A", "B", "B"])
    # with itself in A's centroid (1.45) 2.9 would stay in A; left out, A's centroid is 0 and B (4.5) is nearer
    assert ct.nearest_centroid_loo(X, y).tolist() == ["A", "B", "B", "B"]
    with pytest.raises(ValueError, match="fewer than two"):
        ct.nearest_centroid_loo(X[:3], np.array(["A", "A", "B"]))


def test_features_of_rest_are_zero(ct):
    from visemeface.muscles.measure import LipGauge
    from visemeface.muscles.rig import default_rig

    rig = default_rig()
    np.testing.assert_allclose(ct.lip_features(LipGauge(rig.face), rig.rest), 0.0, atol=1e-12)


@pytest.fixture(scope="module")
def samples(ct):
    return ct.class_samples()


def test_samples_are_physically_plausible(samples):
    by = samples[samples.condition == "1"].set_index("symbol")
    # bilabials closed, open /ao/ taller than rounded /ow/ taller than /w/
    assert by.loc[["p", "b", "m"], "opening_height"].abs().max() < 0.02
    assert by.loc["ao", "opening_height"] > by.loc["ow", "opening_height"] > by.loc["w", "opening_height"]
    # rounded postures are narrower and more protruded than the spread class
    assert by.loc[["w", "ow"], "mouth_width"].max() < by.loc[["ae", "eh", "ih"], "mouth_width"].min()
    assert by.loc[["w", "ow"], "protrusion"].min() > by.loc[["ae", "eh", "ih"], "protrusion"].max()


def test_image_features_see_the_mouth_interior(ct, samples):
    img = samples[ct.feature_columns(samples)].to_numpy()
    by = (samples["symbol"] + "/" + samples["condition"]).to_numpy()
    n = img.shape[1] // 6                      # two views x (dark, teeth, red) maps
    teeth = img[:, n:2 * n].sum(axis=1)        # the front view's teeth map
    assert teeth[by == "m/1"].max() == 0 < teeth[by == "f/1"].min()


def test_every_class_recognised_at_least_95_percent(ct, samples):
    m = ct.confusion(samples)
    assert m.shape == (8, 8)
    np.testing.assert_allclose(m.sum(axis=1), 1.0)
    rates = np.diag(m.to_numpy())
    assert (rates >= 0.95).all(), m.round(2).to_string()
