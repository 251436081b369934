"""TLED solver: analytic solutions and invariants (issue 6 acceptance)."""

import numpy as np
import pytest

from visemeface.errors import InputError
from visemeface.physics.hexmesh import HexMesh, box_mesh, boundary_quads, nodal_areas
from visemeface.physics.materials import (SALIVA, SOFT_TISSUE, NeoHookean, second_piola_kirchhoff,
                                          strain_energy_density, uniaxial_stress)
from visemeface.physics.tled import (HOURGLASS_BASE, SimulationDiverged, TLEDSolver, element_geometry,
                                     hourglass_shape_vectors, prescribed_rotation, rigid_rotation)


def _distorted_box(shape=(3, 3, 3), size=(0.03, 0.03, 0.03), amount=0.2, seed=0):
    """A box whose interior nodes are moved randomly by ``amount`` of an element edge."""
    m = box_mesh(shape, size)
    rng = np.random.default_rng(seed)
    h = min(s / n for s, n in zip(size, shape))
    inner = np.setdiff1d(np.arange(m.n_nodes), m.node_sets["surface"])
    nodes = m.nodes.copy()
    nodes[inner] += rng.uniform(-amount * h, amount * h, (len(inner), 3))
    return HexMesh(nodes, m.hexes, node_sets=m.node_sets)


def _random_rotation(rng):
    q, r = np.linalg.qr(rng.normal(size=(3, 3)))
    q *= np.sign(np.diag(r))
    return q if np.linalg.det(q) > 0 else -q


# --------------------------------------------------------------------------- precomputation

def test_uniform_gradients_are_exact_for_affine_fields_on_distorted_elements():
    m = _distorted_box(amount=0.3)
    dhdx, vol = element_geometry(m.nodes, m.hexes)
    x = m.nodes[m.hexes]
    assert np.abs(dhdx.sum(axis=1)).max() < 1e-9 * np.abs(dhdx).max()
    assert np.allclose(np.einsum("eai,eaj->eij", x, dhdx), np.eye(3), atol=1e-12)
    assert np.isclose(vol.sum(), 0.03 ** 3, rtol=1e-12)        # distorted interior, same box


def test_hourglass_vectors_vanish_for_affine_fields_not_for_hourglass_modes():
    m = _distorted_box(amount=0.3)
    dhdx, _ = element_geometry(m.nodes, m.hexes)
    gamma = hourglass_shape_vectors(m.nodes, m.hexes, dhdx)
    rng = np.random.default_rng(1)
    for _ in range(5):
        A, b = rng.normal(size=(3, 3)), rng.normal(size=3)
        u = m.nodes @ A.T + b
        q = np.einsum("eak,eai->eki", gamma, u[m.hexes])
        assert np.abs(q).max() < 1e-13 * np.abs(u).max()
    # The base vectors themselves are the ξη, ηζ, ζξ, ξηζ modes: orthogonal, each 8 long.
    assert np.allclose(HOURGLASS_BASE.T @ HOURGLASS_BASE, 8 * np.eye(4))
    u = np.zeros((m.n_nodes, 3))
    u[m.hexes[13], 0] = 1e-4 * HOURGLASS_BASE[:, 0]
    assert np.abs(np.einsum("eak,eai->eki", gamma, u[m.hexes])).max() > 1e-5


def test_hourglass_forces_vanish_for_any_affine_displacement():
    m = _distorted_box(amount=0.3)
    with_hg = TLEDSolver(m, SOFT_TISSUE, dt=1e-5, hourglass_kappa=0.3)
    without = TLEDSolver(m, SOFT_TISSUE, dt=1e-5, hourglass_kappa=0.0)
    rng = np.random.default_rng(2)
    A = 0.2 * rng.normal(size=(3, 3))
    u = m.nodes @ A.T + rng.normal(size=3) * 0.01
    f1, f0 = with_hg.internal_forces(u), without.internal_forces(u)
    assert np.abs(f1 - f0).max() < 1e-12 * np.abs(f0).max()
    # ... while an hourglass mode is resisted only by the hourglass control.
    v = np.zeros_like(u)
    v[m.hexes[13], 2] = 1e-4 * HOURGLASS_BASE[:, 3]
    assert np.abs(with_hg.internal_forces(v)).max() > 10 * np.abs(without.internal_forces(v)).max()


# --------------------------------------------------------------------------- patch test

def test_patch_test_homogeneous_stretch_gives_the_analytic_stress():
    m = _distorted_box(amount=0.25)
    mat = SOFT_TISSUE
    stretch = np.array([1.3, 0.9, 1.1])
    u = m.nodes * (stretch - 1.0)
    solver = TLEDSolver(m, mat, dt=1e-5)
    # Analytic neo-Hookean S for F = diag(λ): S_ii = μJ^(-2/3)(1 − I1/(3λ_i²)) + K J (J−1)/λ_i².
    J, I1 = stretch.prod(), (stretch ** 2).sum()
    S_exact = np.diag(mat.mu * J ** (-2 / 3) * (1 - I1 / (3 * stretch ** 2)) + mat.K * J * (J - 1) / stretch ** 2)
    S = solver.element_stress(u)["S"]
    assert np.abs(S - S_exact).max() < 1e-6 * np.abs(S_exact).max()
    # The assembled (numba) forces: zero at interior nodes, the traction P·N·A on each face.
    f = solver.internal_forces(u)
    scale = np.abs(f).max()
    inner = np.setdiff1d(np.arange(m.n_nodes), m.node_sets["surface"])
    assert np.abs(f[inner]).max() < 1e-9 * scale
    P = np.diag(stretch) @ S_exact                             # first Piola–Kirchhoff
    for axis, name in enumerate(("xmax", "ymax", "zmax")):
        total = f[m.node_sets[name], axis].sum()
        assert total == pytest.approx(P[axis, axis] * 0.03 * 0.03, rel=1e-6)
    # The per-element strain energy is the analytic density times the volume.
    frames = list(TLEDSolver(m, mat, dt=1e-5, prescribed=[(np.arange(m.n_nodes), lambda t: u)]).run(0))
    W = strain_energy_density(np.diag(stretch), mat.mu, mat.K)
    assert frames[0].strain_energy == pytest.approx(W * 0.03 ** 3, rel=1e-9)


def test_rigid_rotation_produces_no_internal_force():
    m = _distorted_box(amount=0.25)
    solver = TLEDSolver(m, SOFT_TISSUE, dt=1e-5)
    rng = np.random.default_rng(3)
    stretch_force = np.abs(solver.internal_forces(m.nodes * 0.1)).max()  # 10 % stretch for scale
    for angle in (0.3, 1.5, 3.0):
        u = rigid_rotation(m.nodes, rng.normal(size=3) * 0.01, rng.normal(size=3), angle)
        assert np.abs(solver.internal_forces(u)).max() < 1e-10 * stretch_force
    R = _random_rotation(rng)
    assert np.abs(solver.internal_forces(m.nodes @ R.T - m.nodes)).max() < 1e-10 * stretch_force
    # Rotating a pre-stretched state rotates its forces with it (objectivity of S).
    Fs = np.diag([1.2, 1.0, 0.95])
    f_stretched = solver.internal_forces(m.nodes @ Fs.T - m.nodes)
    f_rotated = solver.internal_forces(m.nodes @ (R @ Fs).T - m.nodes)
    assert np.abs(f_rotated - f_stretched @ R.T).max() < 1e-10 * np.abs(f_stretched).max()


def test_prescribed_rotation_of_all_nodes_stores_no_strain_energy():
    m = box_mesh((2, 2, 1), (0.02, 0.02, 0.01))
    bc = prescribed_rotation(m, np.arange(m.n_nodes), centre=[0.0, 0.0, -0.02], axis=[1.0, 0.0, 0.0],
                             angle=lambda t: 20.0 * t)           # 1.2 rad at the end
    solver = TLEDSolver(m, SOFT_TISSUE, dt=1e-4, prescribed=[bc])
    frames = list(solver.run(600, output_every=100))
    u = frames[-1].displacement
    expected = rigid_rotation(m.nodes, [0.0, 0.0, -0.02], [1.0, 0.0, 0.0], 1.2)
    assert np.allclose(u, expected, atol=1e-15)
    kinetic = 0.5 * solver.mass.sum() * (20.0 * 0.02) ** 2    # order of the kinetic energy
    assert max(f.strain_energy for f in frames) < 1e-12 * kinetic


# --------------------------------------------------------------------------- dynamics

def test_quasi_static_bar_follows_the_analytic_force_stretch_curve():
    """Quarter bar (symmetry planes x = 0, y = 0), base held in z, top pulled by a
    slowly ramped, damped load; each equilibrium stretch is compared with the
    analytic uniaxial neo-Hookean curve."""
    L, a = 0.04, 0.01
    m = box_mesh((2, 2, 8), (a, a, L))
    mat = SOFT_TISSUE
    fixed = np.zeros((m.n_nodes, 3), dtype=bool)
    fixed[m.node_sets["xmin"], 0] = fixed[m.node_sets["ymin"], 1] = fixed[m.node_sets["zmin"], 2] = True
    top = m.node_sets["zmax"]
    quads = boundary_quads(m.hexes)
    top_quads = quads[np.isin(quads, top).all(axis=1)]
    share = nodal_areas(m.nodes, top_quads)[top] / (a * a)      # sums to 1
    stretches = np.array([1.1, 1.25, 1.45, 0.85])
    P, _ = uniaxial_stress(stretches, mat)
    ramp, hold = 0.1, 0.4

    def load(t):
        k = min(int(t // (ramp + hold)), len(P) - 1)
        before = P[k - 1] if k else 0.0
        s = min((t - k * (ramp + hold)) / ramp, 1.0)
        value = before + (P[k] - before) * (3 * s * s - 2 * s ** 3)  # smooth step
        return np.outer(share * value * a * a, [0.0, 0.0, 1.0])

    dt = 4e-4
    solver = TLEDSolver(m, mat, dt=dt, damping=120.0, fixed=fixed, forces=[(top, load)])
    per_level = int(round((ramp + hold) / dt))
    frames = {f.step: f for f in solver.run(per_level * len(P), output_every=per_level)}
    for k, lam in enumerate(stretches):
        u = frames[per_level * (k + 1)].displacement if k + 1 < len(P) else frames[per_level * len(P)].displacement
        measured = 1.0 + u[top, 2].mean() / L
        assert measured - 1.0 == pytest.approx(lam - 1.0, rel=0.02)
        P_at_measured, lateral = uniaxial_stress(measured, mat)
        assert float(P_at_measured) == pytest.approx(P[k], rel=0.02)
        side = m.node_sets["xmax"]
        assert 1.0 + u[side, 0].mean() / a == pytest.approx(float(lateral), rel=0.02)


def test_free_vibration_conserves_energy_and_travels_at_the_wave_speed():
    """A laterally confined column (uniaxial strain), both ends fixed, released from
    its first mode u_z = A sin(πz/L): period 2L/c with c = sqrt((K + 4μ/3)/ρ)."""
    L, h = 0.04, 0.001
    m = box_mesh((1, 1, 40), (h, h, L))
    mat = SOFT_TISSUE
    fixed = np.zeros((m.n_nodes, 3), dtype=bool)
    fixed[:, :2] = True
    fixed[m.node_sets["zmin"]] = fixed[m.node_sets["zmax"]] = True
    z = m.nodes[:, 2]
    u0 = np.zeros((m.n_nodes, 3))
    u0[:, 2] = 2e-5 * np.sin(np.pi * z / L)
    dt = 1e-5
    solver = TLEDSolver(m, mat, dt=dt, damping=0.0, fixed=fixed)
    frames = list(solver.run(10_000, output_every=10, initial_displacement=u0))
    energy = np.array([f.kinetic_energy + f.strain_energy for f in frames])
    assert energy[0] > 0
    assert np.abs(energy - energy[0]).max() < 0.01 * energy[0]
    # Kinetic and strain energy really exchange (the test could fail).
    assert max(f.kinetic_energy for f in frames) > 0.9 * energy[0]
    mid = np.flatnonzero(np.isclose(z, L / 2))
    t = np.array([f.time for f in frames])
    w = np.array([f.displacement[mid, 2].mean() for f in frames])
    sign = np.signbit(w)
    idx = np.flatnonzero(sign[1:] != sign[:-1])
    crossings = t[idx] - w[idx] * (t[idx + 1] - t[idx]) / (w[idx + 1] - w[idx])
    period = 2.0 * np.mean(np.diff(crossings))
    assert len(crossings) >= 5
    assert 2.0 * L / period == pytest.approx(mat.wave_speed, rel=0.05)


def test_damping_removes_energy():
    m = box_mesh((1, 1, 10), (0.002, 0.002, 0.02))
    fixed = m.node_sets["zmin"]
    u0 = np.zeros((m.n_nodes, 3))
    u0[:, 0] = 1e-4 * (m.nodes[:, 2] / 0.02) ** 2
    solver = TLEDSolver(m, SOFT_TISSUE, dt=1e-4, damping=80.0, fixed=fixed)
    frames = list(solver.run(2000, output_every=1000, initial_displacement=u0))
    e = [f.kinetic_energy + f.strain_energy for f in frames]
    assert e[2] < 0.05 * e[0]


def test_numba_and_numpy_agree_after_100_steps_on_a_random_mesh():
    m = _distorted_box(shape=(3, 2, 2), size=(0.015, 0.01, 0.01), amount=0.25, seed=4)
    m.material = (np.arange(m.n_elements) % 2).astype(np.int64)
    rng = np.random.default_rng(5)
    u0 = rng.normal(0, 2e-4, (m.n_nodes, 3))
    v0 = rng.normal(0, 1e-3, (m.n_nodes, 3))
    scale = rng.uniform(0.5, 1.0, m.n_elements)
    seen = {}

    def hook(step, t, F, forces):
        seen["J"] = np.linalg.det(F).min()
        return scale

    results = {}
    for backend, parallel in (("numba", True), ("numba", False), ("numpy", None)):
        jaw = prescribed_rotation(m, m.node_sets["zmin"], [0, 0, -0.01], [1, 0, 0], lambda t: 5.0 * t)
        solver = TLEDSolver(m, [SOFT_TISSUE, SALIVA], dt=5e-7, damping=80.0, fixed=m.node_sets["xmin"],
                            prescribed=[jaw], forces=[(m.node_sets["xmax"], lambda t: [0.0, 0.02 * t, 0.0])],
                            element_hook=hook, backend=backend, parallel=parallel)
        results[backend, parallel] = list(solver.run(100, output_every=50, initial_displacement=u0,
                                                     initial_velocity=v0))
    b = results["numpy", None][-1]
    for parallel in (True, False):
        a = results["numba", parallel][-1]
        moved = np.abs(a.displacement - u0).max()
        assert moved > 1e-6
        assert np.abs(a.displacement - b.displacement).max() < 1e-10 * np.abs(a.displacement).max()
        assert a.strain_energy == pytest.approx(b.strain_energy, rel=1e-10)
        assert a.kinetic_energy == pytest.approx(b.kinetic_energy, rel=1e-10)
    assert 0 < seen["J"] < 2


def test_hook_can_switch_elements_off_leaving_free_flight():
    """With every element's force scaled to zero a pushed body accelerates as R / M."""
    m = box_mesh((2, 1, 1), (0.02, 0.01, 0.01))
    force = np.array([0.0, 0.0, 1e-3])
    dt = 1e-4
    solver = TLEDSolver(m, SOFT_TISSUE, dt=dt, forces=[(np.arange(m.n_nodes), lambda t: force)],
                        element_hook=lambda step, t, F, fe: np.zeros(len(fe)))
    frame = list(solver.run(100, output_every=100))[-1]
    t = frame.time
    assert np.allclose(frame.displacement, 0.5 * (force / solver.mass[:, None]) * t * t, rtol=1e-9)


def test_lumped_mass_and_stable_step():
    m = box_mesh((2, 2, 2), (0.02, 0.02, 0.02))
    solver = TLEDSolver(m, SOFT_TISSUE, dt=1e-5)
    assert solver.mass.sum() == pytest.approx(SOFT_TISSUE.rho * 0.02 ** 3)
    c = np.sqrt((SOFT_TISSUE.K + 4 * SOFT_TISSUE.mu / 3) / SOFT_TISSUE.rho)
    assert SOFT_TISSUE.wave_speed == pytest.approx(c)
    # Cube of edge h: L = h / sqrt(3 (1 + κ)).
    assert solver.stable_dt == pytest.approx(0.01 / np.sqrt(3 * 1.075) / c)
    # The smallest / stiffest element decides.
    m.material[5] = 1
    assert TLEDSolver(m, [SOFT_TISSUE, SALIVA], dt=1e-5).critical_element == 5


def test_time_step_above_the_stable_limit_is_refused_with_both_numbers():
    m = box_mesh((2, 2, 2), (0.02, 0.02, 0.02))
    stable = TLEDSolver(m, SOFT_TISSUE, dt=1e-5).stable_dt
    with pytest.raises(InputError, match=rf"time step {2 * stable:.4g} s exceeds the stable limit {stable:.4g} s"):
        TLEDSolver(m, SOFT_TISSUE, dt=2 * stable)
    with pytest.raises(InputError, match="material id 1"):
        TLEDSolver(HexMesh(m.nodes, m.hexes, material=np.ones(8, int)), SOFT_TISSUE, dt=1e-5)


def test_a_blow_up_stops_naming_step_time_and_element():
    m = box_mesh((2, 1, 1), (0.02, 0.01, 0.01))
    corner = int(m.node_sets["xmax"][0])
    solver = TLEDSolver(m, SOFT_TISSUE, dt=1e-4, fixed=m.node_sets["xmin"],
                        forces=[([corner], lambda t: [-50.0, 0.0, 0.0])])
    with pytest.raises(SimulationDiverged, match=r"step \d+ \(t = [0-9.e-]+ s\): element 1 .*J = ") as err:
        for _ in solver.run(10_000, output_every=1000):
            pass
    assert err.value.element == 1 and err.value.step > 0
    assert err.value.time == pytest.approx(err.value.step * 1e-4)
    u0 = np.zeros((m.n_nodes, 3))
    u0[corner] = np.nan
    with pytest.raises(SimulationDiverged, match=r"step 0 \(t = 0 s\): element 1 .*non-finite"):
        next(iter(solver.run(10, initial_displacement=u0)))


def test_bad_boundary_conditions_are_input_errors():
    m = box_mesh((1, 1, 1))
    with pytest.raises(InputError, match=r"fixed: node ids must lie in 0..7"):
        TLEDSolver(m, SOFT_TISSUE, dt=1e-3, fixed=[9])
    solver = TLEDSolver(m, SOFT_TISSUE, dt=1e-3, forces=[([0, 1], lambda t: np.zeros((3, 3)))])
    with pytest.raises(InputError, match=r"forces\[0\] at t = 0 s returned shape \(3, 3\)"):
        list(solver.run(1))
    with pytest.raises(InputError, match="unknown TLED backend"):
        TLEDSolver(m, SOFT_TISSUE, dt=1e-3, backend="cuda")


# --------------------------------------------------------------------------- materials

def test_uniaxial_curve_limits():
    mat = NeoHookean(mu=800.0, K=7000.0, rho=1000.0)
    E = 9 * mat.K * mat.mu / (3 * mat.K + mat.mu)
    P, lt = uniaxial_stress(1.0 + 1e-6, mat)
    assert float(P) / 1e-6 == pytest.approx(E, rel=1e-4)
    assert (1.0 - float(lt)) / 1e-6 == pytest.approx(mat.poisson_ratio, rel=1e-4)
    # Nearly incompressible: P → μ (λ − λ⁻²).
    stiff = NeoHookean(mu=800.0, K=8e8, rho=1000.0)
    lam = np.array([0.7, 1.5, 2.0])
    P, lt = uniaxial_stress(lam, stiff)
    assert np.allclose(P, 800.0 * (lam - lam ** -2.0), rtol=1e-4)
    # And the lateral stress of the analytic state really vanishes.
    F = np.diag([float(lt[1]), float(lt[1]), 1.5])
    S = second_piola_kirchhoff(F, stiff.mu, stiff.K)
    assert abs(S[0, 0]) < 1e-8 * abs(S[2, 2]) * 1e3


def test_numba_kernel_matches_numpy_at_large_compression_and_stretch():
    """J from 0.2 to 4: the fast J^(-1/3) of the numba kernel and its fallback."""
    m = _distorted_box(shape=(2, 2, 2), size=(0.01, 0.01, 0.01), amount=0.2, seed=6)
    fast, ref = (TLEDSolver(m, SOFT_TISSUE, dt=1e-5, backend=b) for b in ("numba", "numpy"))
    rng = np.random.default_rng(7)
    for J in (0.2, 0.49, 0.51, 0.9, 1.0, 1.2, 1.99, 2.01, 4.0):
        F = _random_rotation(rng) @ np.diag([J ** (1 / 3)] * 3) @ (np.eye(3) + 0.1 * rng.normal(size=(3, 3)))
        u = m.nodes @ F.T - m.nodes + rng.normal(0, 1e-5, m.nodes.shape)
        a, b = fast.internal_forces(u), ref.internal_forces(u)
        assert np.abs(a - b).max() < 1e-12 * np.abs(b).max()


def test_docstring_examples_run():
    import doctest

    import visemeface.physics as physics
    from visemeface.physics import hexmesh, materials, tled

    for module in (physics, hexmesh, materials, tled):
        result = doctest.testmod(module)
        assert result.failed == 0 and result.attempted > 0, module.__name__


def test_forces_on_all_nodes_and_on_overlapping_sets_add_up():
    """The same loads given as one all-node field or as overlapping node sets move the mesh alike."""
    m = box_mesh((2, 1, 1), (0.02, 0.01, 0.01))
    n = m.n_nodes
    field = np.zeros((n, 3))
    field[m.node_sets["xmax"], 0] = 2e-3
    field[m.node_sets["zmax"], 2] += 1e-3
    whole = TLEDSolver(m, SOFT_TISSUE, dt=1e-4, damping=80.0, fixed=m.node_sets["xmin"],
                       forces=[(np.arange(n), lambda t: field)])
    parts = TLEDSolver(m, SOFT_TISSUE, dt=1e-4, damping=80.0, fixed=m.node_sets["xmin"],
                       forces=[(m.node_sets["xmax"], lambda t: [2e-3, 0.0, 0.0]),
                               (m.node_sets["zmax"], lambda t: [0.0, 0.0, 1e-3])])
    a = list(whole.run(200, output_every=200))[-1].displacement
    b = list(parts.run(200, output_every=200))[-1].displacement
    assert np.abs(a).max() > 1e-5
    assert np.allclose(a, b, rtol=1e-12, atol=1e-18)
    with pytest.raises(InputError, match="node ids repeat"):
        TLEDSolver(m, SOFT_TISSUE, dt=1e-4, forces=[([1, 1], lambda t: [0.0, 0.0, 1.0])])


def test_a_run_restarted_from_a_frame_continues_the_motion():
    """Displacement + velocity of a frame restart the run: the restarted path follows the
    uninterrupted one to second order in dt (the Taylor start)."""
    m = box_mesh((4, 1, 1), (0.02, 0.005, 0.005))
    u0 = np.zeros((m.n_nodes, 3))
    u0[:, 1] = 1e-4 * (m.nodes[:, 0] / 0.02) ** 2
    make = lambda: TLEDSolver(m, SOFT_TISSUE, dt=1e-5, damping=10.0, fixed=m.node_sets["xmin"])
    full = {f.step: f for f in make().run(2000, output_every=1000, initial_displacement=u0)}
    mid = full[1000]
    assert np.abs(mid.velocity).max() > 1e-4
    resumed = list(make().run(1000, output_every=1000, initial_displacement=mid.displacement,
                              initial_velocity=mid.velocity))[-1]
    amplitude = np.abs(full[2000].displacement).max()
    assert np.abs(resumed.displacement - full[2000].displacement).max() < 2e-3 * amplitude


def test_centre_and_uniform_gradients_agree_on_parallelepipeds_only_uniform_passes_distorted_patch():
    box = box_mesh((3, 2, 2), (0.03, 0.02, 0.02))
    shear = np.array([[1.0, 0.3, 0.1], [0.0, 0.9, 0.2], [0.1, 0.0, 1.1]])
    slanted = HexMesh(box.nodes @ shear.T, box.hexes, node_sets=box.node_sets)   # parallelepipeds
    rng = np.random.default_rng(8)
    u = rng.normal(0, 1e-3, slanted.nodes.shape)
    uniform = TLEDSolver(slanted, SOFT_TISSUE, dt=1e-5)
    centre = TLEDSolver(slanted, SOFT_TISSUE, dt=1e-5, gradient="centre")
    f_u, f_c = uniform.internal_forces(u), centre.internal_forces(u)
    assert np.abs(f_u - f_c).max() < 1e-10 * np.abs(f_u).max()
    # Distorted: homogeneous stretch leaves interior forces with the centre rule only.
    m = _distorted_box(amount=0.25)
    u = m.nodes * np.array([0.3, -0.1, 0.1])
    inner = np.setdiff1d(np.arange(m.n_nodes), m.node_sets["surface"])
    residual = {}
    for rule in ("uniform", "centre"):
        f = TLEDSolver(m, SOFT_TISSUE, dt=1e-5, gradient=rule).internal_forces(u)
        residual[rule] = np.abs(f[inner]).max() / np.abs(f).max()
    assert residual["uniform"] < 1e-9 < 1e-3 < residual["centre"]
    with pytest.raises(InputError, match="unknown gradient rule"):
        TLEDSolver(m, SOFT_TISSUE, dt=1e-5, gradient="corner")


@pytest.mark.parametrize("parallel", [True, False])
def test_the_fused_step_is_the_element_loop_then_the_update_bit_for_bit(parallel):
    # Without a hook a step is one compiled call (element forces, then gather and update); a hook that
    # changes nothing takes the separate kernels. Same arithmetic: the same bits after 100 steps.
    m = _distorted_box(shape=(3, 2, 2), size=(0.015, 0.01, 0.01), amount=0.25, seed=7)
    rng = np.random.default_rng(8)
    u0 = rng.normal(0, 2e-4, (m.n_nodes, 3))
    runs = {}
    for hook in (None, lambda step, t, F, forces: None):
        jaw = prescribed_rotation(m, m.node_sets["zmin"], [0, 0, -0.01], [1, 0, 0], lambda t: 5.0 * t)
        solver = TLEDSolver(m, SOFT_TISSUE, dt=5e-7, damping=80.0, fixed=m.node_sets["xmin"], prescribed=[jaw],
                            forces=[(m.node_sets["xmax"], lambda t: [0.0, 0.02 * t, 0.0])], element_hook=hook,
                            parallel=parallel)
        runs[hook is None] = list(solver.run(100, output_every=25, initial_displacement=u0))
    for fused, separate in zip(runs[True], runs[False]):
        assert np.array_equal(fused.displacement, separate.displacement)
        assert fused.strain_energy == separate.strain_energy and fused.kinetic_energy == separate.kinetic_energy
    assert np.abs(runs[True][-1].displacement - u0).max() > 1e-6


@pytest.mark.parametrize("backend", ["numba", "numpy"])
def test_a_run_is_the_same_bits_whatever_the_meshs_node_numbering(backend):
    # run() steps the nodes numbered as the elements first touch them (each thread then loads and steps
    # the nodes of its own elements) and gives the frames back in the mesh's numbering: a mesh with its
    # nodes shuffled, its loads, fixed and prescribed nodes renamed alike, gives the very same frames.
    from visemeface.physics.hexmesh import first_touch_order
    m = _distorted_box(shape=(4, 3, 2), size=(0.02, 0.015, 0.01), amount=0.2, seed=3)
    perm = np.random.default_rng(4).permutation(m.n_nodes)        # new id -> old id
    rank = np.empty_like(perm)
    rank[perm] = np.arange(m.n_nodes)
    shuffled = HexMesh(m.nodes[perm], rank[m.hexes], material=m.material)
    u0 = np.random.default_rng(5).normal(0, 2e-4, (m.n_nodes, 3))
    runs = []
    for mesh, name in ((m, np.arange(m.n_nodes)), (shuffled, rank)):
        sets = {k: name[v] for k, v in m.node_sets.items()}
        jaw = prescribed_rotation(mesh, sets["zmin"], [0, 0, -0.01], [1, 0, 0], lambda t: 5.0 * t)
        solver = TLEDSolver(mesh, SOFT_TISSUE, dt=5e-7, damping=80.0, fixed=sets["xmin"], prescribed=[jaw],
                            forces=[(sets["xmax"], lambda t: [0.0, 0.02 * t, 0.0]),
                                    (sets["ymax"], lambda t: np.full((len(sets["ymax"]), 3), 0.01 * t))],
                            backend=backend)
        frames = list(solver.run(60, output_every=20, initial_displacement=u0[np.argsort(name)]))
        runs.append([(f.displacement[name], f.velocity[name], f.kinetic_energy, f.strain_energy) for f in frames])
    for a, b in zip(*runs):
        assert np.array_equal(a[0], b[0]) and np.array_equal(a[1], b[1]) and a[2] == b[2] and a[3] == b[3]
    assert np.abs(runs[0][-1][0] - u0).max() > 1e-6
    order = first_touch_order(m.hexes, m.n_nodes)
    assert sorted(order.tolist()) == list(range(m.n_nodes)) and order[0] == m.hexes[0, 0]


# --------------------------------------------------------------------------- Gent's limiting stretch

GENT = SOFT_TISSUE.with_limiting_stretch(2.5)


def test_gent_is_neo_hookean_times_its_stiffening_and_its_energy_is_the_stress_potential():
    """S = μ J^(-2/3) g (I − I₁C⁻¹/3) + K J(J−1) C⁻¹ with g = 1/(1 − (Ī₁−3)/J_m): the patch test's stress on
    distorted elements (numba) equals that law, and S = 2 ∂W/∂C by central differences of W."""
    assert GENT.jm == pytest.approx(2.5 ** 2 + 2 / 2.5 - 3) and GENT.limiting_stretch == pytest.approx(2.5)
    assert SOFT_TISSUE.ijm == 0.0 and np.isinf(SOFT_TISSUE.limiting_stretch)
    m = _distorted_box(amount=0.25)
    stretch = np.array([2.0, 0.75, 0.7])
    u = m.nodes * (stretch - 1.0)
    J, I1 = stretch.prod(), (stretch ** 2).sum()
    g = 1.0 / (1.0 - (J ** (-2 / 3) * I1 - 3.0) / GENT.jm)
    assert g > 1.5                                               # well into the stiffening
    S_exact = np.diag(g * GENT.mu * J ** (-2 / 3) * (1 - I1 / (3 * stretch ** 2)) + GENT.K * J * (J - 1) / stretch ** 2)
    solver = TLEDSolver(m, GENT, dt=1e-5)
    assert np.abs(solver.element_stress(u)["S"] - S_exact).max() < 1e-6 * np.abs(S_exact).max()
    f = solver.internal_forces(u)
    P = np.diag(stretch) @ S_exact
    assert f[m.node_sets["xmax"], 0].sum() == pytest.approx(P[0, 0] * 0.03 * 0.03, rel=1e-6)
    # S = 2 dW/dC along each axis: W(λ) with C_ii = λ_i², so S_ii = (1/λ_i) dW/dλ_i
    for i in range(3):
        h = 1e-6
        up, dn = stretch.copy(), stretch.copy()
        up[i] += h
        dn[i] -= h
        dW = (strain_energy_density(np.diag(up), GENT.mu, GENT.K, GENT.ijm)
              - strain_energy_density(np.diag(dn), GENT.mu, GENT.K, GENT.ijm)) / (2 * h)
        assert dW / stretch[i] == pytest.approx(S_exact[i, i], rel=1e-6)
    frames = list(TLEDSolver(m, GENT, dt=1e-5, prescribed=[(np.arange(m.n_nodes), lambda t: u)]).run(0))
    W = strain_energy_density(np.diag(stretch), GENT.mu, GENT.K, GENT.ijm)
    assert frames[0].strain_energy == pytest.approx(W * 0.03 ** 3, rel=1e-9)
    numpy = TLEDSolver(m, GENT, dt=1e-5, backend="numpy")
    assert np.abs(numpy.internal_forces(u) - f).max() < 1e-9 * np.abs(f).max()


def test_gent_bar_stiffens_toward_its_limit_and_matches_neo_hookean_at_small_stretch():
    small, _ = uniaxial_stress(1.05, GENT)
    assert small == pytest.approx(uniaxial_stress(1.05, SOFT_TISSUE)[0], rel=0.02)
    # the limit is on the isochoric stretch; the tissue is compressible (ν 0.45), so its bar swells, never quite
    # locks, and stiffens steeply past 2.5
    ratio = [uniaxial_stress(s, GENT)[0] / uniaxial_stress(s, SOFT_TISSUE)[0] for s in (1.5, 2.0, 2.5, 2.9)]
    assert all(b > a for a, b in zip(ratio, ratio[1:])) and ratio[0] < 1.2 and ratio[-1] > 5
    # A bar held at stretch 2 by a dead load comes to rest there (dynamic relaxation of the TLED bar).
    bar = box_mesh((4, 1, 1), (0.04, 0.01, 0.01))
    P, _ = uniaxial_stress(1.8, GENT)
    ends = bar.node_sets["xmax"]
    per = P * 0.01 * 0.01 / len(ends)
    solver = TLEDSolver(bar, GENT, dt=2e-5, damping=300.0, fixed=bar.node_sets["xmin"],
                        forces=[(ends, lambda t: [per, 0.0, 0.0])])
    # the fixed end holds the bar's lateral contraction there: compare the free half's stretch
    *_, last = solver.run(60_000, output_every=60_000)
    x = bar.nodes[:, 0]
    mid = np.isclose(x, 0.02)
    far = np.isclose(x, 0.04)
    stretch = 1.0 + (last.displacement[far, 0].mean() - last.displacement[mid, 0].mean()) / 0.02
    assert stretch == pytest.approx(1.8, rel=0.03)


def test_an_element_at_the_limiting_stretch_stops_the_run_saying_so():
    m = box_mesh((1, 1, 1), (0.01, 0.01, 0.01))
    u = m.nodes * (np.array([3.0, 3 ** -0.5, 3 ** -0.5]) - 1.0)   # isochoric stretch 3: Ī₁ − 3 = 6.7 > J_m 4.05
    solver = TLEDSolver(m, GENT, dt=1e-5, prescribed=[(np.arange(m.n_nodes), lambda t: u)])
    with pytest.raises(SimulationDiverged, match="limiting stretch.*raise the limit .*a smaller dt does not help"):
        next(iter(solver.run(1)))
    with pytest.raises(InputError, match="limiting stretch must be a number > 1"):
        SOFT_TISSUE.with_limiting_stretch(0.9)
    with pytest.raises(InputError, match="jm must be a positive"):
        NeoHookean(800.0, 7000.0, 1050.0, jm=0.0)


def test_forces_past_the_limit_are_refused_not_made_up():
    """Past the limit there is no finite stress: the kernels give NaN forces (numba and numpy alike), and
    ``internal_forces`` (the muscle loads' path) says so instead of returning numbers; an inverted element
    is still reported as inverted, not as the limit."""
    m = box_mesh((1, 1, 1), (0.01, 0.01, 0.01))
    u = m.nodes * (np.array([3.0, 3 ** -0.5, 3 ** -0.5]) - 1.0)
    for backend in ("numba", "numpy"):
        solver = TLEDSolver(m, GENT, dt=1e-5, backend=backend)
        with pytest.raises(InputError, match="at or past the tissue's limiting stretch"):
            solver.internal_forces(u)
        assert np.isnan(solver._fe).all() and solver._jac[0] == -np.inf
    inverted = m.nodes * np.array([-1.05, 0.0, 0.0])                 # x -> -0.05 x: J = -0.05
    solver = TLEDSolver(m, GENT, dt=1e-5, prescribed=[(np.arange(m.n_nodes), lambda t: inverted)])
    with pytest.raises(SimulationDiverged, match="inverted"):
        next(iter(solver.run(1)))
