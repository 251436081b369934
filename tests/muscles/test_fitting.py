"""Fitting activations to lip dimensions: recovery of known activations, bounds, errors."""

import numpy as np
import pytest

from visemeface.errors import InputError
from visemeface.muscles.fitting import FIT_DIMENSIONS, fit_activations
from visemeface.muscles.measure import lip_changes, lip_dimensions
from visemeface.muscles.rig import SPEECH_FUNCTIONS, default_rig

# Seven symmetric unknowns need seven independent measures.
DIMS = ("mouth_width", "opening_height", "protrusion", "upper_lip_raise", "lower_lip_drop", "corner_height",
        "corner_depth", "chin_drop")


@pytest.fixture(scope="module")
def rig():
    return default_rig()


@pytest.mark.parametrize("truth", [
    {"orbicularis_oris": 0.6, "jaw": 0.3, "levator_labii_superioris": 0.4},
    {"risorius": 0.5, "zygomatic_major": 0.3, "depressor_labii_inferioris": 0.6, "jaw": 0.15},
    {"depressor_anguli_oris": 0.7, "orbicularis_oris": 0.2, "jaw": 0.5},
])
def test_recovers_known_activations_from_their_own_dimensions(rig, truth):
    full = {}
    for k, v in truth.items():
        if k in ("orbicularis_oris", "jaw"):
            full[k] = v
        else:
            full[f"{k}_left"] = full[f"{k}_right"] = v
    dims = lip_changes(rig.face, rig.pose(full))
    targets = {k: dims[k] for k in DIMS}
    fit = fit_activations(rig, targets, regularization=0.0)
    assert fit.attrs["success"]
    for name in SPEECH_FUNCTIONS:
        assert fit[name] == pytest.approx(full.get(name, 0.0), abs=2e-3), name
    # Functions outside the speech set stay at 0.
    assert fit.drop(list(SPEECH_FUNCTIONS)).abs().max() == 0.0


def test_achieves_reachable_viseme_like_targets(rig):
    # A rounded, protruded, slightly open /uw/-like shape (fractions of mouth width).
    targets = {"mouth_width": -0.25, "protrusion": 0.12, "opening_height": 0.05}
    fit = fit_activations(rig, targets)
    got = lip_changes(rig.face, rig.pose(fit))
    for k, v in targets.items():
        assert got[k] == pytest.approx(v, abs=0.01), k
        assert fit.attrs["achieved"][k] == pytest.approx(got[k], abs=1e-6)  # rig.pose is float32
    assert fit["orbicularis_oris"] > 0.5


def test_respects_ranges_and_metres(rig):
    # An impossible opening: the fit stops at the jaw's limit.
    fit = fit_activations(rig, {"opening_height": 5.0})
    assert fit["jaw"] == pytest.approx(rig.ranges[-1, 1])
    assert np.all(fit.to_numpy() >= rig.ranges[:, 0] - 1e-12)
    assert np.all(fit.to_numpy() <= rig.ranges[:, 1] + 1e-12)
    # Metres: absolute mouth width.
    rest = lip_dimensions(rig.face, rig.rest)["mouth_width"]
    fit = fit_activations(rig, {"mouth_width": rest * 1.08, "opening_height": 0.0}, units="metres")
    assert lip_dimensions(rig.face, rig.pose(fit))["mouth_width"] == pytest.approx(rest * 1.08, abs=2e-4)


def test_base_activations_are_held(rig):
    base = {"zygomatic_major_left": 0.8, "zygomatic_major_right": 0.8}
    fit = fit_activations(rig, {"opening_height": 0.2}, functions=("jaw",), base=base)
    assert fit["zygomatic_major_left"] == 0.8 and fit["jaw"] > 0.3


def test_asymmetric_fit(rig):
    truth = {"zygomatic_major_left": 0.7}
    dims = lip_changes(rig.face, rig.pose(truth))
    targets = {k: dims[k] for k in ("corner_height_left", "corner_height_right")}
    fit = fit_activations(rig, targets, functions=("zygomatic_major_left", "zygomatic_major_right"),
                          symmetric=False, regularization=0.0)
    assert fit["zygomatic_major_left"] == pytest.approx(0.7, abs=1e-3)
    assert fit["zygomatic_major_right"] == pytest.approx(0.0, abs=1e-3)


def test_errors(rig):
    with pytest.raises(InputError, match="did you mean: mouth_width"):
        fit_activations(rig, {"mouth_widht": 0.1})
    with pytest.raises(InputError, match="unknown muscle"):
        fit_activations(rig, {"mouth_width": 0.1}, functions=("orbicularis",))
    with pytest.raises(InputError, match="finite"):
        fit_activations(rig, {"mouth_width": float("nan")})
    with pytest.raises(InputError, match="no target"):
        fit_activations(rig, {})
    assert "opening_height" in FIT_DIMENSIONS
