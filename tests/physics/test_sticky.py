"""Sticky lips: the breaking saliva material, glue profiles, and the FEM face driven by tracks."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from visemeface.errors import InputError
from visemeface.physics import saliva as sv
from visemeface.physics.materials import SOFT_TISSUE

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


def _films(glue, params=sv.SalivaParams(), n=1, refine_to=None):
    """``n`` separate box-shaped saliva slabs (8 nodes each) as one :class:`SalivaFilm`."""
    from visemeface.physics.film import SalivaFilm
    X = np.concatenate([_box()[0] + [0.01 * i, 0.0, 0.0] for i in range(n)])
    hexes = np.arange(8 * n).reshape(n, 8)
    film = SalivaFilm(X, hexes, np.tile([-0.5, 0.5], (n, 1)), lambda s: np.resize(np.asarray(glue, float), len(s)),
                      params, across=n, min_elements=refine_to or n)
    return film, X, film.initial_state()


def _step(film, X, state, F, t=0.0):
    """One compiled step with every slab deformed by F (3, 3) or (n, 3, 3): the nodal forces (n·8, 3)."""
    F = np.broadcast_to(F, (len(X) // 8, 3, 3))
    Xc = X.reshape(-1, 8, 3) - X.reshape(-1, 8, 3).mean(axis=1, keepdims=True)
    u = np.einsum("eij,eaj->eai", F - np.eye(3), Xc).reshape(-1, 3)
    R = np.zeros_like(u)
    film.add_forces(u, t, state, R)
    return -R, u


BRITTLE = sv.SalivaParams(rupture_time=0.0)        # the seed's film: breaks at Z, its pull frozen and decayed


def test_saliva_breaks_at_Z_then_force_decays_geometrically():
    film, X, st = _films(0.08, BRITTLE)
    f, _ = _step(film, X, st, _stretched(_box(), np.sqrt(1.079))[0])
    assert not st["broken"][0] and np.abs(f).max() > 0
    above = _stretched(_box(), np.sqrt(1.081))[0]
    f0, _ = _step(film, X, st, above, 1e-5)             # breaks: this step's pull is kept
    assert st["broken"][0]
    for n in range(1, 6):
        f, _ = _step(film, X, st, above @ np.diag([1.0, 1.0, 1.3]), 1e-5 * (n + 1))   # its own force ignored
        np.testing.assert_allclose(f, f0 * 0.99 ** n, rtol=1e-12)
    # Relaxing under Z does not heal it (latched) ...
    f, _ = _step(film, X, st, _stretched(_box(), np.sqrt(1.07))[0], 1e-4)
    assert st["broken"][0]
    np.testing.assert_allclose(f, f0 * 0.99 ** 6, rtol=1e-12)
    # ... contact does: the lips are back together, saliva re-bonds and pushes.
    f, _ = _step(film, X, st, _stretched(_box(), 0.99)[0], 2e-4)
    assert not st["broken"][0] and np.abs(f).max() > 0


def test_pressed_puckered_lips_rebond_and_stick_again():
    # /m/: the lips pressed (film squeezed out) and gathered along the seam by the
    # sphincter (in-plane strain 0.4); on release the film re-forms as soon as the
    # lips are back at the film's thickness, and holds until Q reaches Z again.
    film, X, st = _films(0.08, sv.SalivaParams(squeeze=0.25, rupture_time=0.0))
    pucker = np.diag([0.6, 1.0, 1.0])
    _step(film, X, st, _stretched(_box(), 0.4)[0] @ pucker)
    assert st["broken"][0]                                # squeezed out (Q = 0.16)
    f, _ = _step(film, X, st, _stretched(_box(), 0.9)[0] @ pucker, 1e-5)
    assert st["broken"][0] and not f.any()                # still pressed: no film, no force jump
    _step(film, X, st, _stretched(_box(), 1.0)[0] @ pucker, 2e-5)
    assert not st["broken"][0]                            # back apart to its thickness: re-formed
    f, _ = _step(film, X, st, _stretched(_box(), np.sqrt(1.07))[0] @ pucker, 3e-5)
    assert not st["broken"][0] and np.abs(f).max() > 0    # glued: pulls the lips together
    _step(film, X, st, _stretched(_box(), np.sqrt(1.09))[0] @ pucker, 4e-5)
    assert st["broken"][0]


def _film(u, X):
    from visemeface.physics.materials import SALIVA
    grads, vols = sv.film_gradients(X)
    pull, push, _ = sv.film_forces(u, sv.element_frames(X)[:, 1], grads, vols, SALIVA.p_wave_modulus)
    return pull + push


def test_film_matches_the_solid_across_the_lips_and_ignores_in_plane_motion():
    from visemeface.physics.hexmesh import HexMesh
    from visemeface.physics.materials import SALIVA
    from visemeface.physics.tled import TLEDSolver
    X = _box()
    solver = TLEDSolver(HexMesh(X[0].copy(), np.arange(8)[None], material=np.zeros(1, np.int64)), [SALIVA], dt=1e-6)
    u = np.zeros((8, 3))
    u[:, 1] = 0.002 * X[0, :, 1]                                  # 0.2 % across the film
    solid = solver.internal_forces(u)
    film = _film(u[None], X)[0]
    np.testing.assert_allclose(film[:, 1], solid[:, 1], rtol=0.01)
    # in-plane stretch, compression and sliding of the lips along each other: no force
    for A in (np.diag([0.3, 0.0, 0.0]), np.diag([-0.4, 0.0, 0.2]), np.array([[0, 0, 0.5], [0, 0, 0], [0, 0, 0.0]])):
        np.testing.assert_allclose(_film((X[0] @ A.T)[None], X), 0.0, atol=1e-15)
        assert np.abs(solver.internal_forces(X[0] @ A.T)).max() > 1e-6   # the solid would push back
    # the keystone mode (one end of the film opens, the other closes: no mean stretch)
    # is resisted: two points along the seam see each end
    key = np.zeros((8, 3))
    key[:, 1] = 0.002 * X[0, :, 1] * np.sign(X[0, :, 0])
    assert np.abs(sv.deformation_gradient(key[None], sv.hex_centre_gradients(X))[0, 1, 1] - 1) < 1e-12
    f = _film(key[None], X)[0]
    assert np.sum(f * key) > 0                                         # positive work: stiff


@pytest.mark.parametrize("seed,squash", [(0, 0.0), (1, 0.0), (2, -0.7), (3, 0.2)])
def test_film_forces_are_the_gradient_of_its_energy(seed, squash):
    # squash -0.7: the film pressed to lambda ~ 0.3, the capped compressive branch
    from visemeface.physics.materials import SALIVA
    rng = np.random.default_rng(seed)
    X = _box()
    grads, V = sv.film_gradients(X)
    n, M = sv.element_frames(X)[:, 1], SALIVA.p_wave_modulus
    u = 1e-5 * rng.normal(size=(1, 8, 3))
    u[0, :, 1] += squash * X[0, :, 1]

    def energy(u):
        lam = np.sqrt(sv.film_forces(u, n, grads, V, M)[2])
        lc = sv.FILM_STIFF_STRETCH
        W = np.where(lam >= 1, (lam ** 2 - 1) ** 2 / 8, np.where(
            lam >= lc, lam - 1 - np.log(np.maximum(lam, lc)),
            lc - 1 - np.log(lc) + (1 - 1 / lc) * (lam - lc) + (lam - lc) ** 2 / (2 * lc ** 2)))
        return float((V * M * W).sum())
    assert V.sum() == pytest.approx(np.prod([0.004, 0.0005, 0.003]), rel=1e-12)
    lam = np.sqrt(sv.film_forces(u, n, grads, V, M)[2])
    assert {0.0: (np.abs(lam - 1) < 0.1).all(), -0.7: (lam < sv.FILM_STIFF_STRETCH).all(),
            0.2: (lam > 1.1).all()}[squash]
    f = _film(u, X)
    h = 1e-9
    num = np.zeros_like(u)
    for a in range(8):
        for i in range(3):
            d = np.zeros_like(u)
            d[0, a, i] = h
            num[0, a, i] = (energy(u + d) - energy(u - d)) / (2 * h)
    np.testing.assert_allclose(f, num, rtol=1e-5, atol=1e-9 * np.abs(num).max())
    np.testing.assert_allclose(f.sum(axis=1), 0.0, atol=1e-12)            # no net force


def test_compression_never_breaks_and_no_glue_breaks_on_any_stretch():
    film, X, st = _films([0.0, 0.08], n=2)
    _step(film, X, st, _stretched(_box(), 0.5)[0])
    assert not st["broken"].any()
    _step(film, X, st, _stretched(_box(), 1.001)[0], 1e-5)
    assert st["broken"].tolist() == [True, False]


def test_evaporation_lowers_the_breaking_point_over_time():
    film, X, st = _films(0.08, sv.SalivaParams(evaporation=50.0, rupture_time=0.0))
    lam = np.sqrt(1.05)
    _step(film, X, st, _stretched(_box(), lam)[0])
    assert not st["broken"][0]                       # Z(0) = 1.08
    _step(film, X, st, _stretched(_box(), lam)[0], 1.0)
    assert st["broken"][0]                           # Z(1 s) = 1.04
    # a film with a rupture time starts to let go at the lower breaking point too
    film, X, st = _films(0.08, sv.SalivaParams(evaporation=50.0, rupture_time=sv.RUPTURE_TIME))
    _step(film, X, st, _stretched(_box(), lam)[0])
    assert st["damage"][0] == 0.0
    _step(film, X, st, _stretched(_box(), lam)[0], 1.0)
    assert 0.0 < st["damage"][0] < 1.0 and not st["broken"][0]


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


def test_centre_profile_is_the_mouths_central_twelfth_however_fine_the_film():
    """Seed 001's central element is 1/12 of the mouth on the seed-scale face: on 48 film slabs that is the
    central 4, not the 2 nearest the centre (a patch half as wide that lets go at a lower jaw)."""
    slabs = -1 + (np.arange(48) + 0.5) * 2 / 48
    g = sv.parse_glue_profile("centre=0.18", slabs)
    assert np.flatnonzero(g == 0.18).tolist() == [22, 23, 24, 25]
    twelve = -1 + (np.arange(12) + 0.5) * 2 / 12            # the seed-scale face's elements: the two beside 0
    assert np.flatnonzero(sv.parse_glue_profile("centre=0.18", twelve) == 0.18).tolist() == [5, 6]


@pytest.mark.parametrize("spec, message", [
    ("0.95..0.99=0.2", "names no saliva element"),
    ("centre=-1", "glue must be from 0 to 10"),
    ("centre=1e308", "glue must be from 0 to 10, got 1e308"),
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
    # element k is the k-th from the right corner, whatever order the film lists its slabs in (its
    # wedges into the corners come last)
    np.testing.assert_allclose(sv.read_glue_file(p, np.array([0.0, -0.9, 0.9])), [0.1, 0.0, 0.2])
    p.write_text("element,glue\n0,0.1\n7,0.2\n")
    with pytest.raises(InputError, match="element 7 names no saliva element"):
        sv.read_glue_file(p, np.zeros(3))
    p.write_text("s,glue\n0,0.1\n0.5,-2\n")
    with pytest.raises(InputError, match=r"glue.csv:3: glue must be from 0 to 10"):
        sv.read_glue_file(p, np.zeros(3))


@pytest.mark.parametrize("refine,soften,viscosity,strand,rupture", [
    (1, 0.0, np.inf, 0.0, 0.0), (4, 0.0, np.inf, 0.0, 0.0), (4, 0.05, np.inf, 0.0, 0.0), (4, 0.0, 3e-4, 0.0, 0.0),
    (1, 0.0, 3e-3, 0.0, 0.0), (4, 0.0, np.inf, 1e-4, 0.0), (1, 0.0, 3e-3, 1e-3, 0.0), (4, 0.0, np.inf, 0.0, 3e-6),
    (1, 0.0, np.inf, 1e-4, 3e-6)])
def test_compiled_film_follows_the_numpy_reference(refine, soften, viscosity, strand, rupture):
    from film_reference import reference_step
    rng = np.random.default_rng(0)
    params = sv.SalivaParams(squeeze=0.25, soften=soften, viscosity=viscosity, strand=strand, rupture_time=rupture)
    a, X, sa = _films([0.0, 0.08, 0.3], params, n=3, refine_to=3 * refine)
    b, _, sb = _films([0.0, 0.08, 0.3], params, n=3, refine_to=3 * refine)
    assert a.n_elements == 3 * refine
    shear = np.array([[1.0, 0.3, 0.0], [0.0, 1.0, 0.0], [0.1, 0.0, 0.8]])
    Xc = X.reshape(3, 8, 3) - X.reshape(3, 8, 3).mean(axis=1, keepdims=True)
    seen, flowed, softened = set(), False, False
    for step, lam in enumerate([1.0, 1.02, 1.05, 1.2, 1.1, 0.99, 0.3, 0.9, 1.03, 1.5]):
        F = np.stack([_stretched(_box(), lam + 0.01 * i)[0] @ shear for i in range(3)])
        u = np.einsum("eij,eaj->eai", F - np.eye(3), Xc).reshape(-1, 3)
        u += 2e-6 * rng.normal(size=u.shape)              # not affine: slabs differ along the seam
        R = np.zeros_like(u)
        a.add_forces(u, step * 1e-5, sa, R)
        want = reference_step(b, u, step * 1e-5, sb)
        np.testing.assert_allclose(-R, want, rtol=1e-9, atol=1e-12 * np.abs(want).max())
        for k in ("broken", "dry"):
            assert sa[k].tolist() == sb[k].tolist()
        np.testing.assert_allclose(sa["stored"], sb["stored"], rtol=1e-9, atol=1e-15)
        np.testing.assert_allclose(sa["flow"], sb["flow"], rtol=1e-9, atol=1e-15)
        np.testing.assert_allclose(sa["damage"], sb["damage"], rtol=1e-9, atol=1e-15)
        softened = softened or bool(((sa["damage"] > 0) & (sa["damage"] < 1)).any())
        flowed = flowed or bool(sa["flow"].any())
        seen.update(zip(sa["broken"].tolist(), sa["dry"].tolist()))
    assert seen == {(False, False), (True, False), (True, True)}      # intact, broken and squeezed out
    assert flowed == np.isfinite(viscosity)                           # a viscous film flows, a solid one not
    assert softened == (strand > 0 or rupture > 0)                    # a cohesive film softens before it breaks


def test_film_slabs_tile_their_hexahedron_and_their_forces_add_up():
    # A coarse slab split in 8 along the seam: under a homogeneous stretch every slab
    # has the same Q and the nodal forces equal the unsplit film's.
    one, X, s1 = _films(0.0)
    eight, _, s8 = _films(0.0, refine_to=8)
    assert eight.n_elements == 8 and np.allclose(eight.s, np.linspace(-0.5, 0.5, 17)[1::2])
    np.testing.assert_allclose(np.sort(eight.X.reshape(-1, 3), axis=0)[[0, -1]],
                               np.sort(X, axis=0)[[0, -1]], atol=1e-15)
    F = _stretched(_box(), 0.98)[0]
    f1, _ = _step(one, X, s1, F)
    f8, _ = _step(eight, X, s8, F)
    np.testing.assert_allclose(s8["stretch"], s1["stretch"][0], rtol=1e-12)
    np.testing.assert_allclose(f8, f1, rtol=1e-10, atol=1e-14 * np.abs(f1).max())


# --------------------------------------------------------------------------- the FEM face driven by a track
# A coarse face (about 600 hexahedra, 6 saliva elements) and short jaw ramps keep these fast.

from visemeface.physics import drive  # noqa: E402


@pytest.fixture(scope="module")
def model():
    from visemeface.face.procedural import default_face
    from visemeface.muscles.rig import MuscleRig
    from visemeface.physics.face_model import build_fem_face
    from visemeface.runtime import set_threads
    set_threads(1)          # shared 2-core CI: one thread avoids oversubscription
    face = default_face(resolution=1500)
    return build_fem_face(face), MuscleRig.from_file(face)


def _ramp(rig, fps, start=0.02, ramp=0.1, hold=0.15, jaw=0.35, extra=None):
    return drive.ramp_track(rig.names, fps, start, ramp, hold, jaw, extra)


def _run(model, track, physics="sticky", **settings):
    fem, rig = model
    sim = drive.StickySimulation(fem, rig, track, physics=physics,
                                 settings=drive.PhysicsSettings(**settings))
    frames = []
    for fr in sim.frames():
        frames.append((fr.index, fr.time, fr.vertices, sim.broken.copy(), fr.saliva))
    return sim, frames


@pytest.fixture(scope="module")
def opened(model):
    fem, rig = model
    track = _ramp(rig, fps=1000, hold=0.12)
    return {p: _run(model, track, physics=p) for p in ("sticky", "elastic")}


def _lips(fem):
    return np.unique(fem.seam_pairs.ravel())


@pytest.mark.slow
def test_same_equilibrium_with_and_without_glue_once_open_wide(model, opened):
    fem, rig = model
    lips = np.unique(np.concatenate([fem.face.region("upper_lip"), fem.face.region("lower_lip")]))
    sticky, elastic = opened["sticky"][1][-1][2], opened["elastic"][1][-1][2]
    rms = np.sqrt(np.mean(np.sum((sticky[lips] - elastic[lips]) ** 2, axis=1))) / fem.mouth_width
    assert rms <= 0.01
    # ... and that equilibrium is the kinematic posture (the force calibration). The FEM
    # face carries the 1 mm saliva gap, so compare displacements from each rest shape.
    sim = opened["elastic"][0]
    kin = rig.pose(sim.values[-1]) - rig.face.vertices
    fe = elastic - fem.face.vertices
    rms_kin = np.sqrt(np.mean(np.sum((fe[lips] - kin[lips]) ** 2, axis=1))) / fem.mouth_width
    assert rms_kin <= 0.05


@pytest.mark.slow
@pytest.mark.xfail(strict=True, reason="the seed's model (PhysicsSettings(), the unrefined face): its film's free ends "
                   "by the unglued corner slit carry 1.2-1.3x the centre's stretch and its brittle release cascades over "
                   "the seam in one frame; the speech commands' lips (PhysicsSettings.speech(): refined along the seam, "
                   "rupture time, film into the corners) unzip the default face from the centre (test_zipper.py)")
def test_sticky_lips_part_at_the_centre_first_and_later_than_elastic(model, opened):
    fem, _ = model
    s_frames = opened["sticky"][1]
    e_frames = opened["elastic"][1]
    rest = fem.rest_gaps

    def first_parting(frames):
        for f in frames:
            g = (fem.seam_gaps(f[2]) - rest) / fem.mouth_width
            if g.max() > 0.002:
                return f[1], g
    # Without glue the whole width parts at once, following the jaw (corners already apart).
    t_e, g_e = first_parting(e_frames)
    assert g_e.min() > 0.0
    # With glue the lips hold longer and part at the centre while the corners stay together.
    t_s, g_s = first_parting(s_frames)
    assert t_s > t_e
    assert np.argmax(g_s) == np.argmin(np.abs(fem.seam_s))
    assert g_s.min() / g_s.max() < 0.7 * g_e.min() / g_e.max()
    # The saliva fails at the centre first and the failure runs to the corners.
    first_s = next(i for i, f in enumerate(s_frames) if f[3].any())
    broken = s_frames[first_s][3]
    s_film = opened["sticky"][0].film.s
    assert np.abs(s_film[broken]).max() < np.abs(s_film[~broken]).min()
    counts = [f[3].sum() for f in s_frames[first_s:]]
    assert counts[-1] == len(s_film) and np.all(np.diff(counts[:counts.index(len(s_film)) + 1]) >= 0)
    # The opening (gap beyond the film > 2 % of the mouth width) comes at a wider jaw with glue.
    open_s = next(f[1] for f in s_frames if f[4]["open_count"] > 0)
    open_e = next(f[1] for f in e_frames if f[4]["open_count"] > 0)
    assert open_s > open_e


@pytest.mark.slow
def test_one_sided_glue_opens_the_other_side_first(model):
    fem, rig = model
    _, frames = _run(model, _ramp(rig, fps=1000, hold=0.0), glue_profile="right=0.3,left=0")
    first = next(f for f in frames if f[4]["open_count"] > 0)
    from visemeface.physics.face_model import seam_openings
    op = seam_openings(fem, first[2])["open"]
    assert op[fem.seam_s > 0].any() and not op[fem.seam_s < 0].any()


@pytest.mark.slow
def test_evaporation_makes_a_later_opening_unzip_sooner(model):
    fem, rig = model
    wet_early = _ramp(rig, fps=250, start=0.02, hold=0.0, ramp=0.08)
    late = _ramp(rig, fps=250, start=0.12, hold=0.0, ramp=0.08)

    def jaw_at_break(track, evaporation):
        _, frames = _run(model, track, saliva=drive.SalivaParams(evaporation=evaporation))
        i = next(i for i, f in enumerate(frames) if f[3].all())
        return track["jaw"].iloc[i]

    early = jaw_at_break(wet_early, 600.0)      # moisture ~90 at the break
    later = jaw_at_break(late, 600.0)           # moisture ~30 by then: weaker glue
    assert later < 0.8 * early


@pytest.mark.slow
@pytest.mark.parametrize("viscosity", [np.inf, 3.0])
def test_resume_from_a_checkpoint_continues_the_run(model, viscosity):
    fem, rig = model
    track = _ramp(rig, fps=200, hold=0.0, ramp=0.05)
    settings = drive.PhysicsSettings(saliva=drive.SalivaParams(viscosity=viscosity))
    sim = drive.StickySimulation(fem, rig, track, settings=settings)
    full = list(sim.frames())
    assert (sim.state.saliva["flow"] > 0).any() == np.isfinite(viscosity)
    sim2 = drive.StickySimulation(fem, rig, track, settings=settings)
    it = sim2.frames()
    for fr in it:
        if fr.index == 5:
            ck = sim2.checkpoint(fr)
            break
    sim3 = drive.StickySimulation(fem, rig, track, settings=settings)
    rest = list(sim3.frames(ck))
    assert [f.index for f in rest] == [f.index for f in full[6:]]
    for a, b in zip(rest, full[6:]):                      # exact: the state is (u, u_prev, step, film)
        np.testing.assert_array_equal(a.vertices, b.vertices)
        np.testing.assert_array_equal(a.displacement, b.displacement)


def test_bad_physics_input_is_refused_before_simulating(model):
    fem, rig = model
    track = _ramp(rig, fps=100, hold=0.0)
    with pytest.raises(InputError, match="exceeds the stable limit"):
        drive.StickySimulation(fem, rig, track, settings=drive.PhysicsSettings(dt=1e-3))
    with pytest.raises(InputError, match="names no saliva element"):
        drive.StickySimulation(fem, rig, track, settings=drive.PhysicsSettings(glue_profile="1.2..1.5=1"))
    with pytest.raises(InputError, match="saliva viscosity must be > 0"):
        drive.SalivaParams(viscosity=0.0)
    with pytest.raises(InputError, match="film thickness must be > 0"):
        drive.SalivaParams(film_thickness=float("nan"))
    with pytest.raises(InputError, match="unknown physics 'stiky'"):
        drive.StickySimulation(fem, rig, track, physics="stiky")
    bad = track.copy()
    bad["nonsense_muscle"] = 0.0
    with pytest.raises(InputError, match="unknown muscle"):
        drive.StickySimulation(fem, rig, bad)


@pytest.mark.slow
def test_simulate_track_yields_renderable_frames_at_the_track_rate(model):
    fem, rig = model
    track = _ramp(rig, fps=50, hold=0.0, ramp=0.04)
    states = []
    frames = list(drive.simulate_track(fem.face, rig, track, physics="elastic", fem=fem, states=states))
    assert len(frames) == len(track) and frames[0].shape == (fem.face.n_vertices, 3)
    assert frames[0].dtype == np.float32 and len(states) == len(track)
    assert np.allclose(fem.seam_gaps(frames[0]), 0.0, atol=1e-7)     # closed at rest


@pytest.mark.slow
def test_a_track_that_starts_mid_gesture_starts_in_that_posture(model):
    fem, rig = model
    t = np.arange(6) / 100.0
    a = {"jaw": np.full(6, 0.2), "risorius_left": np.full(6, 0.5), "risorius_right": np.full(6, 0.5)}
    track = drive.make_track(t, a, rig.names, 100.0)
    sim = drive.StickySimulation(fem, rig, track, physics="elastic")
    frames = list(sim.frames())
    kin = rig.pose(sim.values[0]) - rig.face.vertices
    for fr in (frames[0], frames[-1]):
        got = fr.vertices - fem.face.vertices
        assert np.abs(got - kin)[fem.surface_vertices].max() < 0.02 * fem.mouth_width
    assert np.abs(frames[-1].velocity).max() < 0.01          # at rest, not thrown from the rest face


def test_untangle_lifts_crushed_target_elements_and_keeps_the_rest(model):
    from visemeface.physics.saliva import deformation_gradient, hex_centre_gradients
    fem, rig = model
    track = _ramp(rig, fps=100, hold=0.0)
    sim = drive.StickySimulation(fem, rig, track, physics="elastic")
    d = sim.drive
    hx = fem.mesh.hexes[fem.tissue]
    G = hex_centre_gradients(fem.mesh.nodes[hx])
    U = d.kinematic_field(sim.values[-1])
    J = np.linalg.det(deformation_gradient(U[hx], G))
    assert J.min() >= d.min_jacobian
    # fold one lip element inside out: push its front nodes through its back ones
    e = int(np.argmin(np.abs(fem.mesh.nodes[hx].mean(axis=1)[:, 0])))   # a central element
    bad = U.copy()
    front, back = hx[e, 4:], hx[e, :4]
    bad[front] += 1.5 * (fem.mesh.nodes[back] - fem.mesh.nodes[front])
    assert np.linalg.det(deformation_gradient(bad[hx], G)).min() < 0
    fixed = d.untangle(bad)
    Jf = np.linalg.det(deformation_gradient(fixed[hx], G))
    assert Jf.min() >= d.min_jacobian
    far = np.linalg.norm(fem.mesh.nodes - fem.mesh.nodes[front].mean(axis=0), axis=1) > 0.02
    np.testing.assert_array_equal(fixed[far], bad[far])       # a local repair


def test_a_step_is_its_parts_bit_for_bit(model):
    # The integrator's step (the terms' R first, then the tissue and the update in one compiled call, the
    # natural shape and the drag updated in place) against its parts, done the plain numpy way.
    from visemeface.physics import tled
    fem, rig = model
    track = _ramp(rig, fps=100, start=0.0, hold=0.0)
    sim = drive.StickySimulation(fem, rig, track, settings=drive.PhysicsSettings(multirate=False))
    integ, mdl = sim.integrator, sim.model
    tissue, s, dt = mdl.terms["tissue"], mdl.tissue_solver, mdl.dt
    state = sim.initial_state()
    n = int(0.025 / dt)
    integ.advance(state, n - n % tissue.refresh + 3)       # mid-ramp, between refreshes and frames
    ref = state.copy()
    integ.step(state)

    t = ref.step * dt
    s0 = ref.step - ref.step % tissue.refresh              # the natural shape as of the last refresh
    f = s0 * dt * sim.fps
    i = int(f + 1e-9)
    w = min(max(f - i, 0.0), 1.0)
    geo = [(y - x) * w + x for x, y in zip(tissue.geometry(i), tissue.geometry(i + 1))]
    uY = ref.u - mdl.terms["tissue"].drive.target(t)
    fe, jac = np.zeros_like(s._fe), np.zeros_like(s._jac)
    tled._element_forces_np(uY, s.conn, *geo, s.mu, s.K, s.ijm, fe, jac, s._fdef, False, np.zeros_like(jac), False)
    R = np.zeros_like(ref.u)
    mdl.terms["saliva"].add(ref, t, R)
    R += mdl.terms["drag"].alpha_m * mdl.terms["drag"].drive.target_velocity(t)
    F = np.zeros_like(ref.u)
    np.add.at(F, s.conn.ravel(), fe.reshape(-1, 3))
    new = integ._A * (R - F) + integ._B * ref.u + integ._C * ref.u_prev
    new[mdl.jaw_nodes] = mdl.jaw((ref.step + 1) * dt)
    scale = np.abs(state.u).max()
    assert scale > 0 and np.abs(state.u - new).max() < 1e-12 * scale
    assert np.array_equal(state.u_prev, ref.u) and state.step == ref.step + 1
    assert all(np.array_equal(state.saliva[k], ref.saliva[k]) for k in ref.saliva)


def test_a_multirate_step_is_its_parts(model):
    # The multi-rate step (issue 17) against its definition done the plain numpy way: every node but the
    # film's steps Δt under R − F(uⁿ); the film's nodes take m substeps δt under the film's force and the
    # whole tissue's force with the other nodes interpolated between uⁿ and uⁿ⁺¹, drag held at tⁿ.
    from visemeface.physics import tled
    fem, rig = model
    track = _ramp(rig, fps=100, start=0.0, hold=0.0)
    sim = drive.StickySimulation(fem, rig, track)
    integ, mdl = sim.integrator, sim.model
    assert mdl.multirate and sim.substeps > 1
    tissue, s, dt, m = mdl.terms["tissue"], mdl.tissue_solver, mdl.dt, sim.substeps
    film, fast = mdl.terms["saliva"].film, mdl.film_nodes
    state = sim.initial_state()
    integ.advance(state, int(0.03 / dt) // tissue.refresh * tissue.refresh + 1)   # mid-ramp, between refreshes
    ref = state.copy()
    integ.step(state)

    t = ref.step * dt
    s0 = ref.step - ref.step % tissue.refresh
    f = s0 * dt * sim.fps
    i = int(f + 1e-9)
    w = min(max(f - i, 0.0), 1.0)
    geo = [(y - x) * w + x for x, y in zip(tissue.geometry(i), tissue.geometry(i + 1))]

    def tissue_force(u, tt):
        fe, jac = np.zeros_like(s._fe), np.zeros_like(s._jac)
        tled._element_forces_np(u - tissue.drive.target(tt), s.conn, *geo, s.mu, s.K, s.ijm, fe, jac, s._fdef, False,
                                np.zeros_like(jac), False)
        F = np.zeros_like(u)
        np.add.at(F, s.conn.ravel(), fe.reshape(-1, 3))
        return F

    R = mdl.terms["drag"].alpha_m * mdl.terms["drag"].drive.target_velocity(t)
    new = integ._A * (R - tissue_force(ref.u, t)) + integ._B * ref.u + integ._C * ref.u_prev
    new[mdl.jaw_nodes] = mdl.jaw((ref.step + 1) * dt)
    h, mass, free = dt / m, mdl.mass[fast][:, None], mdl.free[fast]
    a = free / (mass / h ** 2 + mdl.damping * mass / (2 * h))
    b, c = 2 * mass * a / h ** 2, mdl.damping * mass * a / (2 * h) - mass * a / h ** 2
    x, xp, sal = ref.u[fast].copy(), ref.fine_prev.copy(), {k: v.copy() for k, v in ref.saliva.items()}
    for j in range(m):
        U = ref.u + j / m * (new - ref.u)
        U[fast] = x
        Rf = np.zeros_like(U)
        film.add_forces(U, t + j * h, sal, Rf, h)
        x, xp = a * (R[fast] - tissue_force(U, t + j * h)[fast] + Rf[fast]) + b * x + c * xp, x
    new[fast] = x
    scale = np.abs(state.u).max()
    assert scale > 0 and np.abs(state.u - new).max() < 1e-12 * scale
    assert np.abs(state.fine_prev - xp).max() < 1e-12 * scale
    for k in sal:        # the film read positions equal to rounding: its flags equal, its numbers to rounding
        assert np.array_equal(state.saliva[k], sal[k]) if sal[k].dtype == bool else \
            np.allclose(state.saliva[k], sal[k], rtol=1e-9, atol=1e-300)
    assert np.array_equal(state.u_prev, ref.u) and state.step == ref.step + 1


def test_threads_timed_during_a_run_give_the_same_frames_as_one_thread(model, monkeypatch):
    # Without fixed threads a run times a few steps (on a copy) at numba's count and at one, at the start
    # and every THREAD_CHECK_SECONDS, and runs on the faster; the frames are the same bits either way.
    import numba
    from visemeface.physics import simulation
    if numba.config.NUMBA_NUM_THREADS < 2:
        pytest.skip("one core: nothing to choose")
    fem, rig = model
    track = _ramp(rig, fps=100, start=0.0, ramp=0.05, hold=0.0)
    monkeypatch.setattr(simulation, "THREAD_CHECK_SECONDS", 0.02)      # re-time every 2 frames
    runs = {}
    try:
        for threads in (None, 1):
            numba.set_num_threads(numba.config.NUMBA_NUM_THREADS)
            sim = drive.StickySimulation(fem, rig, track, settings=drive.PhysicsSettings(threads=threads))
            runs[threads] = [(f.vertices, f.displacement) for f in sim.frames()]
            assert sim.threads in (1, numba.config.NUMBA_NUM_THREADS)
    finally:
        numba.set_num_threads(1)
    assert len(runs[None]) == len(runs[1]) > 4
    for (va, ua), (vb, ub) in zip(runs[None], runs[1]):
        assert np.array_equal(va, vb) and np.array_equal(ua, ub)
    with pytest.raises(InputError, match="--threads must be from 1 to"):
        drive.StickySimulation(fem, rig, track, settings=drive.PhysicsSettings(threads=0))


def test_no_force_term_knows_the_seam_and_terms_switch_off(model):
    # Free lips: tissue (the muscles as its active strain), saliva and drag; no dead loads,
    # no spring toward the rig's posture unless asked for, and then the same per unit mass everywhere.
    from visemeface.physics.terms import ActiveTissue
    fem, rig = model
    track = _ramp(rig, fps=100, hold=0.0)
    sim = drive.StickySimulation(fem, rig, track)
    assert [n for n, t in sim.model.terms.items() if t.enabled] == ["tissue", "saliva", "drag"]
    assert isinstance(sim.model.terms["tissue"], ActiveTissue)
    loads = drive.StickySimulation(fem, rig, track, settings=drive.PhysicsSettings(muscles="loads"))
    assert [n for n, t in loads.model.terms.items() if t.enabled] == ["tissue", "muscles", "saliva", "drag"]
    spring = drive.StickySimulation(fem, rig, track, settings=drive.PhysicsSettings(posture_hz=50.0))
    k = spring.model.terms["posture"].k / spring.model.mass[:, None]
    free = spring.model.free > 0
    np.testing.assert_allclose(k[free], (2 * np.pi * 50.0) ** 2)
    assert (k[~free] == 0).all()
    off = drive.StickySimulation(fem, rig, track, settings=drive.PhysicsSettings(off=("saliva", "drag")))
    assert [n for n, t in off.model.terms.items() if t.enabled] == ["tissue"]
    with pytest.raises(InputError, match="unknown force term 'salvia'"):
        drive.StickySimulation(fem, rig, track, settings=drive.PhysicsSettings(off=("salvia",)))
    # a limiting stretch makes the tissue term's solver Gent (the same μ, K); none leaves it neo-Hookean
    gent = drive.StickySimulation(fem, rig, track, settings=drive.PhysicsSettings(tissue_limit=2.5))
    assert (gent.model.tissue_solver.ijm == 1.0 / SOFT_TISSUE.with_limiting_stretch(2.5).jm).all()
    assert (sim.model.tissue_solver.ijm == 0.0).all()
    assert gent.fingerprint() != sim.fingerprint()
    for bad in (1.0, None, float("nan"), "2.5", True):
        with pytest.raises(InputError, match="limiting stretch must be a number > 1"):
            drive.StickySimulation(fem, rig, track, settings=drive.PhysicsSettings(tissue_limit=bad))


def test_each_term_alone_pushes_the_way_it_should(model):
    # The active tissue alone is stress-free in the muscle field's posture and pulls toward
    # it from rest; the dead loads alone push along the field; the film alone (lips pulled
    # apart) pulls them back together.
    fem, rig = model
    track = _ramp(rig, fps=100, start=0.0, ramp=0.01, hold=0.02, jaw=0.3)
    sim = drive.StickySimulation(fem, rig, track, settings=drive.PhysicsSettings(off=("saliva", "drag")))
    U = sim.drive.target(0.02).copy()
    free = sim.model.free[:, 0] > 0
    tissue, solver = sim.model.terms["tissue"], sim.model.tissue_solver

    def internal(u):
        tissue.element_forces(u, 0.02, 2000)
        out = np.zeros_like(u)
        np.add.at(out, solver.conn.ravel(), solver._fe.reshape(-1, 3))
        return out
    assert np.abs(internal(U)[free]).max() < 1e-9 * np.abs(internal(np.zeros_like(U))[free]).max()
    assert np.sum(-internal(np.zeros_like(U))[free] * U[free]) > 0      # pulls the rest face toward U
    loads = drive.StickySimulation(fem, rig, track, settings=drive.PhysicsSettings(muscles="loads", off=("saliva", "drag")))
    st = loads.initial_state()
    R = loads.model.external(st, 0.02, np.zeros_like(st.u))
    assert np.sum(R[free] * U[free]) > 0                         # dead loads do work along the field
    film_only = drive.StickySimulation(fem, rig, track, settings=drive.PhysicsSettings(off=("drag",)))
    st = film_only.initial_state()
    up, lo = np.unique(film_only.film.n0[:, [2, 3, 6, 7]]), np.unique(film_only.film.n0[:, [0, 1, 4, 5]])
    corner = np.intersect1d(up, lo)                               # the mouth corners: both lips' node
    up, lo = np.setdiff1d(up, corner), np.setdiff1d(lo, corner)
    st.u[up, 1] += 5e-5                                           # lips 5 % further apart than the film
    st.u[lo, 1] -= 5e-5
    R = film_only.model.external(st, 0.0, np.zeros_like(st.u))
    assert (R[up, 1] < 0).all() and (R[lo, 1] > 0).all()       # glue pulls them together


@pytest.mark.parametrize("extra,message", [
    (["--threads", "0"], "--threads"),
    (["--jaw", "5"], "--jaw"),
    (["--fps", "nan"], "--fps"),
])
def test_simulate_option_errors_exit_2_before_any_work(tmp_path, monkeypatch, capsys, extra, message):
    from visemeface.cli import main

    monkeypatch.chdir(tmp_path)
    assert main(["simulate", "part", "--size", "64", "-q", *extra]) == 2
    assert message in capsys.readouterr().err
    assert list(tmp_path.iterdir()) == []


def test_simulate_never_overwrites_a_users_json_next_to_the_video(tmp_path, monkeypatch, capsys):
    from visemeface.cli import main

    monkeypatch.chdir(tmp_path)
    (tmp_path / "part.mp4.json").write_text("mine")
    assert main(["simulate", "part", "--size", "64", "-q"]) == 2
    assert "--force" in capsys.readouterr().err
    assert (tmp_path / "part.mp4.json").read_text() == "mine"


def test_viscous_film_flows_at_stefans_rate_instead_of_breaking():
    # Held at a stretch under its breaking point, a solid film (viscosity ∞) keeps its
    # pull; a viscous one thickens at Stefan's rate dh/dt = σ h³ / (4 η b²) and its pull
    # relaxes to nothing, without breaking (a liquid bridge thins, it does not snap).
    eta, dt = 0.02, 1e-5
    solid, X, s_st = _films(0.08)
    fluid, _, f_st = _films(0.08, sv.SalivaParams(viscosity=eta))
    F = _stretched(_box(), np.sqrt(1.05))[0]
    f0, _ = _step(solid, X, s_st, F)
    g0, _ = _step(fluid, X, f_st, F)
    np.testing.assert_allclose(g0, f0, rtol=1e-12)                 # the same pull at the first step
    lam = np.sqrt(1.05)
    sigma = 0.5 * fluid.modulus * (lam * lam - 1.0) * lam
    h0, b, H = fluid.params.film_thickness, fluid.band[0], fluid.thickness[0]
    assert b == pytest.approx(0.0015) and H == pytest.approx(0.0005)   # half the box's depth, its height
    np.testing.assert_allclose(f_st["flow"][0] * H, dt * sigma * h0 ** 3 / (4 * eta * b * b), rtol=1e-12)
    for _ in range(3000):
        f, _ = _step(solid, X, s_st, F)
        g, _ = _step(fluid, X, f_st, F)
    np.testing.assert_allclose(f, f0, rtol=1e-12)
    assert np.abs(g).max() < 0.05 * np.abs(f0).max()
    assert not f_st["broken"].any() and not s_st["broken"].any()
    assert f_st["flow"][0] == pytest.approx(lam - 1.0, rel=0.05)   # it took up the whole stretch
    # Brought back together, the thickened film pushes and is squeezed out by the same law.
    g, _ = _step(fluid, X, f_st, np.eye(3))
    assert g[:, 1] @ np.sign(X[:, 1]) < 0.0                         # it pushes the lips apart
    for _ in range(20000):
        _step(fluid, X, f_st, np.eye(3))
    assert 0.0 <= f_st["flow"][0] < 0.1 * (lam - 1.0)
