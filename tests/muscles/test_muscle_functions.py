"""Properties of the pure muscle functions on synthetic grids."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from visemeface.muscles import functions as mf


def grid(n=41, half=0.05, z=0.0):
    xs = np.linspace(-half, half, n)
    X, Y = np.meshgrid(xs, xs)
    return np.column_stack([X.ravel(), Y.ravel(), np.full(X.size, z)])


A = np.array([0.0, 0.0, 0.0])
I = np.array([0.03, 0.0, 0.0])
OMEGA = np.radians(30)
RS, RF = 0.03, 0.045


def test_linear_zero_outside_zone():
    p = grid()
    d = mf.linear_muscle_displacement(p, A, I, OMEGA, RS, RF, k=0.01)
    v = p - A
    dist = np.linalg.norm(v, axis=1)
    alpha = np.arccos(np.clip(v[:, 0] / np.where(dist > 0, dist, 1), -1, 1))
    outside = (alpha >= OMEGA) | (dist >= RF)
    assert np.all(d[outside] == 0.0)
    assert np.abs(d[~outside]).max() > 0


def test_linear_known_values_and_direction():
    # On the axis: angular factor 1, so the magnitude is k * radial(D).
    D = np.array([0.0075, 0.015, 0.03, 0.0375, 0.045])
    p = np.column_stack([D, np.zeros(5), np.zeros(5)])
    d = mf.linear_muscle_displacement(p, A, I, OMEGA, RS, RF, k=0.01)
    expect = 0.01 * np.array([np.cos(0.75 * np.pi / 2), np.cos(0.5 * np.pi / 2), 1.0,
                              np.cos(0.5 * np.pi / 2), 0.0])
    np.testing.assert_allclose(-d[:, 0], expect, atol=1e-15)
    np.testing.assert_allclose(d[:, 1:], 0.0)
    # Off axis at the insertion distance: angular factor cos(alpha/Omega * pi/2).
    alpha = np.radians(15)
    q = RS * np.array([[np.cos(alpha), np.sin(alpha), 0.0]])
    dq = mf.linear_muscle_displacement(q, A, I, OMEGA, RS, RF, k=0.01)
    np.testing.assert_allclose(np.linalg.norm(dq), 0.01 * np.cos(0.5 * np.pi / 2), rtol=1e-12)
    # Pulled toward the attachment.
    np.testing.assert_allclose(dq[0] / np.linalg.norm(dq[0]), -q[0] / np.linalg.norm(q[0]), atol=1e-12)


def test_linear_maximum_at_insertion_and_monotone_falloff():
    D = np.linspace(1e-4, RF, 400)
    p = np.column_stack([D, np.zeros_like(D), np.zeros_like(D)])
    m = np.linalg.norm(mf.linear_muscle_displacement(p, A, I, OMEGA, RS, RF), axis=1)
    i = np.argmax(m)
    assert abs(D[i] - RS) < 2 * (D[1] - D[0])
    assert np.all(np.diff(m[D < RS]) >= 0)
    assert np.all(np.diff(m[D > RS]) <= 0)


@settings(max_examples=40, deadline=None)
@given(st.floats(0.0, 0.99), st.floats(0.01, 0.99), st.floats(0.05, 1.5))
def test_linear_angular_falloff_monotone(frac_d, frac_a, omega):
    # For a fixed distance, influence falls as the angle grows toward the zone edge.
    D = RS * 0.5 + frac_d * (RF - RS * 0.5)
    a1, a2 = frac_a * omega, min(frac_a * omega + 0.05, omega)
    p = D * np.array([[np.cos(a1), np.sin(a1), 0], [np.cos(a2), np.sin(a2), 0]])
    f = mf.linear_muscle_falloff(p, A, I, omega, RS, RF)
    assert f[0] >= f[1] - 1e-12
    assert np.all((f >= 0) & (f <= 1))


def test_linear_bad_parameters():
    with pytest.raises(ValueError):
        mf.linear_muscle_displacement(grid(3), A, I, 0.0, RS, RF)
    with pytest.raises(ValueError):
        mf.linear_muscle_displacement(grid(3), A, I, OMEGA, RF, RS)
    with pytest.raises(ValueError):
        mf.linear_muscle_displacement(grid(3), A, A, OMEGA, RS, RF)


def sphincter(p, **kw):
    args = dict(centre=[0, 0, 0], axis_x=[1, 0, 0], axis_y=[0, 1, 0], semi_x=0.04, semi_y=0.02,
                k=0.6, protrusion=0.004)
    args.update(kw)
    return mf.sphincter_displacement(p, **args)


def test_sphincter_zone_shield_and_direction():
    p = grid(61)
    d = sphincter(p)
    x, y = p[:, 0], p[:, 1]
    rho_e = np.sqrt((x / 0.04) ** 2 + (y / 0.02) ** 2)
    assert np.all(d[rho_e >= 1.0] == 0.0)
    # Shielded centre disc (radius = semi-minor axis): no in-plane pull there.
    disc = np.hypot(x, y) <= 0.02
    assert np.all(d[disc][:, :2] == 0.0)
    # Elsewhere inside, in-plane pull points at the centre.
    ring = (~disc) & (rho_e < 0.95)
    inward = -(d[ring, 0] * x[ring] + d[ring, 1] * y[ring])
    assert np.all(inward > 0)
    # Corners at (+-0.025, 0) move toward the centre: the mouth narrows.
    c = sphincter(np.array([[0.025, 0, 0], [-0.025, 0, 0]]))
    assert c[0, 0] < 0 < c[1, 0]


@settings(max_examples=30, deadline=None)
@given(st.floats(0.0, 0.95), st.floats(0.005, 0.03))
def test_sphincter_never_folds_nor_enters_shield(k, shield):
    # Radial order along any ray is preserved and nothing crosses into the shielded disc.
    for angle in np.linspace(0, np.pi, 7):
        r = np.linspace(0, 0.05, 300)
        p = np.column_stack([r * np.cos(angle), r * np.sin(angle), np.zeros_like(r)])
        q = p + sphincter(p, k=k, shield=shield)
        rq = np.hypot(q[:, 0], q[:, 1])
        assert np.all(np.diff(rq) > 0)
        assert np.all(rq[r >= shield] >= shield - 1e-12)


def test_sphincter_rejects_k_of_one():
    with pytest.raises(ValueError):
        sphincter(grid(3), k=1.0)


def test_sphincter_protrusion_grows_toward_centre():
    x = np.linspace(0, 0.04, 50)
    p = np.column_stack([x, np.zeros_like(x), np.zeros_like(x)])
    z = sphincter(p)[:, 2]
    assert z[0] == pytest.approx(0.004)
    assert np.all(np.diff(z) <= 0) and z[-1] == 0.0


def test_sphincter_depth_fade():
    p = np.array([[0.03, 0.0, 0.0], [0.03, 0.0, -0.05]])
    d = sphincter(p, depth=0.01)
    assert np.linalg.norm(d[0]) > 0 and np.all(d[1] == 0)


def test_lip_trim_weights_separate_lips_and_blend_at_corners():
    u = np.array([0.0, 0.0, 0.0, 0.0, 0.5, 0.5, 3.0])
    v = np.array([0.0, 0.0, 0.004, -0.004, 0.0, 0.0, 0.0])
    side = np.array([1, -1, 0, 0, 1, -1, 0])
    w = mf.lip_trim_weights(u, v, np.zeros_like(u), side, inner_width=0.0005, outer_width=0.01)
    # Coincident seam vertices are separated by their lip tag.
    assert w[0] == 1.0 and w[1] == 0.0
    assert w[2] == 1.0 and w[3] == 0.0
    assert w[4] == 1.0 and w[5] == 0.0
    # Far past the corner, on the seam line: shared half and half.
    assert w[6] == pytest.approx(0.5)


def test_lip_trim_weights_smooth_past_corner():
    # Along a vertical line past the corner, weights change gradually (no crease).
    v = np.linspace(-0.01, 0.01, 201)
    w = mf.lip_trim_weights(np.full_like(v, 1.3), v, np.zeros_like(v), np.zeros_like(v), 0.0005, 0.01)
    assert np.all(np.diff(w) >= 0)
    assert np.max(np.diff(w)) < 0.02
    # Along the seam line from the centre outward, the weight of a lip vertex is continuous.
    u = np.linspace(0, 2, 401)
    wu = mf.lip_trim_weights(u, np.zeros_like(u), np.zeros_like(u), np.ones_like(u), 0.0005, 0.01)
    assert np.max(np.abs(np.diff(wu))) < 0.05


def test_seam_height_interpolates_and_holds():
    su = np.array([-1.0, 0.0, 1.0])
    sv = np.array([0.001, 0.0, 0.001])
    h = mf.seam_height(np.array([-2.0, -0.5, 0.0, 2.0]), su, sv)
    np.testing.assert_allclose(h, [0.001, 0.0005, 0.0, 0.001])
    hs = mf.seam_height(np.linspace(-2, 2, 9), su, sv, smooth=0.1)
    np.testing.assert_allclose(hs, hs[::-1], atol=1e-12)


def test_jaw_rotation_is_rigid_rotation_with_unit_weight():
    rng = np.random.default_rng(0)
    p = rng.normal(size=(50, 3)) * 0.05
    jl, jr = np.array([0.06, 0.01, -0.08]), np.array([-0.06, 0.01, -0.08])
    d = mf.jaw_rotation_displacement(p, jl, jr, 0.2, np.ones(50))
    q = p + d
    # Distances to the axis and positions along it are preserved.
    k = (jl - jr) / np.linalg.norm(jl - jr)
    r0, r1 = p - jr, q - jr
    np.testing.assert_allclose(r0 @ k, r1 @ k, atol=1e-14)
    np.testing.assert_allclose(np.linalg.norm(r0 - np.outer(r0 @ k, k), axis=1),
                               np.linalg.norm(r1 - np.outer(r1 @ k, k), axis=1), atol=1e-14)
    # A chin point in front of and below the axis moves down and back.
    chin = np.array([[0.0, -0.05, 0.02]])
    dc = mf.jaw_rotation_displacement(chin, jl, jr, 0.2, np.ones(1))[0]
    assert dc[1] < 0 and dc[2] < 0
    # Zero weight: no motion; the displacement scales with the weighted angle.
    assert np.all(mf.jaw_rotation_displacement(chin, jl, jr, 0.2, np.zeros(1)) == 0)


def test_jaw_centre_weight():
    w = mf.jaw_centre_weight(np.array([0.0, 0.5, 1.0, -1.0, 2.0, 3.0]), reach=2.0)
    np.testing.assert_allclose(w, [1.0, np.cos(np.pi / 8) ** 2, 0.5, 0.5, 0.0, 0.0], atol=1e-15)


def test_the_modiolus_moves_a_corner_as_one_piece_and_leaves_the_rest():
    """Two lips that move apart (+y above, -y below) meet at a corner: blended, every vertex of the corner's core
    moves alike (no row can pass its neighbour), the share falls monotonically, and beyond the radius and on the
    held vertices the fields are unchanged."""
    p = grid(n=61, half=0.03)
    corner = np.array([0.0, 0.0, 0.0])
    radius, core = 0.01, 0.3
    s = mf.modiolus_share(p, corner, radius, core)
    d = np.linalg.norm(p - corner, axis=1)
    assert np.all(s[d <= core * radius] == 1.0) and np.all(s[d >= radius] == 0.0)
    order = np.argsort(d)
    assert np.all(np.diff(s[order]) <= 1e-12)
    apart = np.where(p[:, 1] >= 0, 1.0, -1.0)[:, None] * np.array([0.0, 0.002, 0.0])
    jaw = (p[:, 1] < 0).astype(float)
    held = p[:, 0] > 0.02
    b, j = mf.modiolus_blend(p, apart[None], jaw, [corner], radius, core, held)
    inner = s >= 1.0
    assert np.ptp(b[0, inner], axis=0).max() < 1e-15 and np.ptp(j[inner]) < 1e-15
    assert abs(j[inner][0] - jaw[inner].mean()) < 1e-12
    untouched = (d >= radius) | held
    assert np.array_equal(b[0, untouched], apart[untouched]) and np.array_equal(j[untouched], jaw[untouched])


def test_a_closing_push_is_sized_by_the_gap_it_closes():
    """An upper margin 5 mm over a flat lower one in the middle, 1 mm at +-9 mm, pushed down by a Gaussian
    of 3 mm: sized, every column of the open eye meets the lower margin and the overlap past it; the row above
    moves by the same factor as the margin below it; a lower row (the target) and far points do not move."""
    from visemeface.muscles.functions import closing_scale

    x = np.linspace(-0.010, 0.010, 41)
    gap = 0.005 - 0.004 * (x / 0.009) ** 2
    margin = np.stack([x, gap, np.zeros_like(x)], 1)
    above = margin + [0.0, 0.003, 0.0]
    lower = np.stack([x, np.zeros_like(x), np.zeros_like(x)], 1)
    points = np.vstack([margin, above, lower])
    push = 0.003 * np.exp(-(points[:, 0] / 0.008) ** 2)
    push[82:] = 0.0                                         # the target does not move
    field = np.stack([np.zeros_like(push), -push, np.zeros_like(push)], 1)
    s = closing_scale(points, field, np.arange(82, 123), np.eye(3), overlap=0.0002)
    closed = points + field * s[:, None]
    open_ = np.abs(x) < 0.008                               # where the gap is over a quarter of its widest
    np.testing.assert_allclose(closed[:41][open_, 1], -0.0002, atol=4e-5)   # between columns: interpolated
    np.testing.assert_allclose(s[41:82], s[:41])
    assert np.all(s[82:] == 1.0)
    # no push, or no target: nothing changes
    assert np.all(closing_scale(points, np.zeros_like(field), np.arange(82, 123), np.eye(3)) == 1.0)


def test_a_sheet_of_parallel_fibres_shortens_evenly_and_falls_off_across_it():
    """The frontalis as a sheet: along the fibres the pull grows linearly from the attachment (every equal
    stretch of skin shortens by the same amount), none at or behind the attachment and none from Waters'
    R_f on; across the sheet it falls off symmetrically to 0 at the fan's half width at the insertion."""
    from visemeface.muscles.sheet import parallel_muscle_displacement

    A, I = np.array([0.0, 0.06, 0.0]), np.array([0.0, 0.0, 0.0])      # fibres run down to the brow
    s = np.linspace(-0.01, 0.09, 101)
    line = np.column_stack([np.zeros_like(s), 0.06 - s, np.zeros_like(s)])
    d = parallel_muscle_displacement(line, A, I, np.radians(30), 0.09, k=0.01)
    assert np.allclose(d[:, [0, 2]], 0) and (d[:, 1] >= 0).all()       # pulled up, toward the attachment
    pull = d[:, 1]
    on = (s >= 0) & (s <= 0.06)
    strain = np.diff(pull[on]) / np.diff(s[on])
    assert np.allclose(strain, 0.01 / 0.06, rtol=1e-9)                  # even: k / L everywhere on the fibres
    assert pull[s <= 0].max() == 0 and pull[s >= 0.09].max() < 1e-12
    assert np.all(np.diff(pull[s >= 0.06]) <= 1e-15)                    # past the insertion it only falls
    w = 0.06 * np.tan(np.radians(30))
    x = np.linspace(-1.2 * w, 1.2 * w, 49)
    row = np.column_stack([x, np.full_like(x, 0.01), np.zeros_like(x)])
    across = parallel_muscle_displacement(row, A, I, np.radians(30), 0.09, k=0.01)[:, 1]
    assert np.allclose(across, across[::-1]) and across[24] == across.max()
    assert across[np.abs(x) >= w].max() < 1e-12
    with pytest.raises(ValueError, match="past the insertion"):
        parallel_muscle_displacement(row, A, I, np.radians(30), 0.05)


@pytest.mark.parametrize("module", ["visemeface.muscles.functions", "visemeface.muscles.sheet"])
def test_docstring_examples_run(module):
    import doctest
    import importlib

    result = doctest.testmod(importlib.import_module(module))
    assert result.attempted > 0 and result.failed == 0
