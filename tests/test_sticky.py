"""Sticky lips: the breaking saliva material, glue profiles, and the FEM face driven by tracks."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from visemeface.errors import InputError
from visemeface.physics import saliva as sv

# --------------------------------------------------------------------------- moisture, breaking point


def test_moisture_decreases_linearly_then_stays_dry():
    t = np.array([0.0, 1.0, 2.0, 10.0])
    np.testing.assert_allclose(sv.moisture(t, 100.0, 30.0), [100.0, 70.0, 40.0, 0.0])
    np.testing.assert_allclose(sv.moisture(t, 100.0, 0.0), 100.0)


def test_breaking_point_wet_glued_and_dry():
    # Above the critical level saliva breaks as soon as it is stretched; at the
    # critical level it holds up to 1 + glue; drier saliva glues proportionally less.
    Z = sv.breaking_point(np.array([100.1, 100.0, 25.0, 0.0]), 100.0, np.array([0.08, 0.08, 0.08, 0.5]))
    np.testing.assert_allclose(Z, [1.0, 1.08, 1.02, 1.0])


def _box(size=(0.004, 0.0005, 0.003)):
    X = sv.HEX_SIGNS * 0.5 * np.asarray(size)
    return X[None]


def _distorted_hex(rng):
    X = sv.HEX_SIGNS * 0.5 * np.array([0.004, 0.001, 0.003]) + rng.normal(0, 1e-4, (8, 3))
    return X[None]


@settings(max_examples=25, deadline=None)
@given(st.integers(0, 10_000))
def test_centre_deformation_gradient_exact_for_affine_motion(seed):
    rng = np.random.default_rng(seed)
    X = _distorted_hex(rng)
    A = rng.normal(0, 0.2, (3, 3))
    u = X @ A.T + rng.normal(0, 1e-3, 3)           # u = A X + c
    F = sv.deformation_gradient(u, sv.hex_centre_gradients(X))
    np.testing.assert_allclose(F[0], np.eye(3) + A, atol=1e-10)


def test_stretch_is_rotation_invariant_and_squares_the_y_stretch():
    X = _box()
    dNdX = sv.hex_centre_gradients(X)
    axis = sv.element_frames(X)[:, 1]
    np.testing.assert_allclose(axis[0], [0, 1, 0], atol=1e-12)
    c, s = np.cos(0.7), np.sin(0.7)
    R = np.array([[c, -s, 0], [s, c, 0], [0, 0, 1]]) @ np.array([[1, 0, 0], [0, c, -s], [0, s, c]])
    lam = 1.3
    U = np.diag([0.9, lam, 1.1])                     # stretch, then rigidly rotate
    x = X @ (R @ U).T
    Q = sv.stretch_across(sv.deformation_gradient(x - X, dNdX), axis)
    assert Q[0] == pytest.approx(lam ** 2, rel=1e-12)
    Qrot = sv.stretch_across(sv.deformation_gradient(X @ R.T - X, dNdX), axis)
    assert Qrot[0] == pytest.approx(1.0, abs=1e-12)


def test_element_frames_are_right_handed_orthonormal():
    rng = np.random.default_rng(3)
    R = sv.element_frames(np.concatenate([_distorted_hex(rng) for _ in range(5)]))
    np.testing.assert_allclose(R @ np.swapaxes(R, 1, 2), np.broadcast_to(np.eye(3), (5, 3, 3)), atol=1e-12)
    np.testing.assert_allclose(np.linalg.det(R), 1.0, atol=1e-12)


# --------------------------------------------------------------------------- the breaking state machine


def _stretched(X, lam):
    u = X * np.array([1.0, lam, 1.0]) - X
    return sv.deformation_gradient(u, sv.hex_centre_gradients(X))


def test_saliva_breaks_at_Z_then_force_decays_geometrically():
    X = _box()
    sal = sv.SalivaBreaking(X, glue=0.08)
    f = np.ones((1, 8, 3))
    below = _stretched(X, np.sqrt(1.079))
    out = sal.update(0.0, below, f)
    assert not sal.broken[0] and np.allclose(out, f)
    above = _stretched(X, np.sqrt(1.081))
    out = sal.update(1e-5, above, 2 * f)            # breaks: last elastic force is kept
    assert sal.broken[0] and np.allclose(out, 2 * f)
    for n in range(1, 6):
        out = sal.update(1e-5 * (n + 1), above, 100 * f)  # the elastic force is ignored now
        np.testing.assert_allclose(out, 2 * f * 0.99 ** n)
    # Relaxing under Z does not heal it (latched) ...
    out = sal.update(1e-4, below, f)
    assert sal.broken[0] and np.allclose(out, 2 * f * 0.99 ** 6)
    # ... contact does: the lips are back together, saliva re-bonds.
    out = sal.update(2e-4, _stretched(X, 0.99), 3 * f)
    assert not sal.broken[0] and np.allclose(out, 3 * f)


def test_compression_never_breaks_and_no_glue_breaks_on_any_stretch():
    X = np.concatenate([_box(), _box()])
    sal = sv.SalivaBreaking(X, glue=np.array([0.0, 0.08]))
    u = np.concatenate([_stretched(X[:1], 0.5), _stretched(X[1:], 0.5)])
    sal.update(0.0, u, np.ones((2, 8, 3)))
    assert not sal.broken.any()
    u = np.concatenate([_stretched(X[:1], 1.001), _stretched(X[1:], 1.001)])
    sal.update(1e-5, u, np.ones((2, 8, 3)))
    assert sal.broken.tolist() == [True, False]


def test_evaporation_lowers_the_breaking_point_over_time():
    X = _box()
    sal = sv.SalivaBreaking(X, glue=0.08, params=sv.SalivaParams(evaporation=50.0))
    lam = np.sqrt(1.05)
    sal.update(0.0, _stretched(X, lam), np.ones((1, 8, 3)))
    assert not sal.broken[0]                         # Z(0) = 1.08
    sal.update(1.0, _stretched(X, lam), np.ones((1, 8, 3)))
    assert sal.broken[0]                             # Z(1 s) = 1.04


def test_saliva_params_refuse_negative_moisture():
    with pytest.raises(InputError, match="moisture must be >= 0, got -1"):
        sv.SalivaParams(initial_moisture=-1.0)
    with pytest.raises(InputError, match="evaporation"):
        sv.SalivaParams(evaporation=-0.1)


# --------------------------------------------------------------------------- glue profiles

S = np.linspace(-0.9, 0.9, 10)                      # 10 elements, none exactly at 0


def test_centre_profile_names_the_central_elements():
    g = sv.parse_glue_profile("centre=0.18", S)
    assert np.flatnonzero(g == 0.18).tolist() == [4, 5]   # the two straddling s = 0
    assert np.all(np.delete(g, [4, 5]) == sv.GLUE)
    g = sv.parse_glue_profile("left=0.2,right=0", S, base=0.1)
    assert np.all(g[S > 0] == 0.2) and np.all(g[S < 0] == 0.0)
    assert np.all(sv.parse_glue_profile("0.3", S) == 0.3)
    g = sv.parse_glue_profile("-0.1..0.25=0.5", S)
    assert np.flatnonzero(g == 0.5).tolist() == [4, 5]


@pytest.mark.parametrize("spec, message", [
    ("0.95..0.99=0.2", "names no saliva element"),
    ("centre=-1", "glue must be >= 0"),
    ("middle=0.2", "unknown place 'middle'"),
    ("centre:0.2", "cannot read"),
    ("centre=abc", "is not a number"),
])
def test_bad_glue_profiles_are_one_line_input_errors(spec, message):
    with pytest.raises(InputError, match=message) as e:
        sv.parse_glue_profile(spec, S)
    assert "\n" not in str(e.value)


def test_glue_file_layouts(tmp_path):
    p = tmp_path / "glue.csv"
    p.write_text("s,glue\n-1,0\n0,0.2\n1,0\n")
    np.testing.assert_allclose(sv.read_glue_file(p, np.array([-0.5, 0.0, 0.25])), [0.1, 0.2, 0.15])
    p.write_text("element,glue\n" + "".join(f"{i},{i / 10}\n" for i in range(3)))
    np.testing.assert_allclose(sv.read_glue_file(p, np.zeros(3)), [0.0, 0.1, 0.2])
    p.write_text("element,glue\n0,0.1\n7,0.2\n")
    with pytest.raises(InputError, match="element 7 names no saliva element"):
        sv.read_glue_file(p, np.zeros(3))
    p.write_text("s,glue\n0,0.1\n0.5,-2\n")
    with pytest.raises(InputError, match=r"glue.csv:3: glue must be >= 0"):
        sv.read_glue_file(p, np.zeros(3))


def test_compiled_hook_follows_the_same_rule_as_update():
    rng = np.random.default_rng(0)
    X = np.concatenate([_box(), _box(), _box()])
    glue = np.array([0.0, 0.08, 0.3])
    a, b = sv.SalivaBreaking(X, glue), sv.SalivaBreaking(X, glue)
    hook = b.hook(np.array([2, 0, 1]))                 # saliva at mesh ids 2, 0, 1
    for step, lam in enumerate([1.0, 1.02, 1.05, 1.2, 1.1, 0.99, 1.03, 1.5]):
        F = np.concatenate([_stretched(X[i:i + 1], lam + 0.01 * i) for i in range(3)])
        f = rng.normal(size=(3, 8, 3))
        want = a.update(step * 1e-5, F, f)
        Fm, fm = np.zeros((3, 3, 3)), np.zeros((3, 8, 3))
        Fm[[2, 0, 1]], fm[[2, 0, 1]] = F, f
        hook(step, step * 1e-5, Fm, fm)
        np.testing.assert_allclose(fm[[2, 0, 1]], want)
        assert a.broken.tolist() == b.broken.tolist()
