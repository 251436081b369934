"""The stable time step from the highest natural frequency (issue 17): exact on a spring chain,
above the element bound, and the integrator really is stable just under it and unstable just over."""

import numpy as np
import pytest

from visemeface.errors import SimulationDiverged

from visemeface.physics.hexmesh import box_mesh
from visemeface.physics.integrator import CentralDifference, FaceModel
from visemeface.physics.materials import SOFT_TISSUE
from visemeface.physics.stability import critical_step, max_eigenvalue
from visemeface.physics.terms import Tissue
from visemeface.physics.tled import TLEDSolver


def test_a_chain_of_springs_has_its_analytic_highest_frequency():
    # N equal masses, springs k between them and to two walls, moving along x only:
    # λ_max = (4k/m) sin²(Nπ / (2(N+1))).
    N, k, m = 40, 250.0, 0.003
    rng = np.random.default_rng(1)
    masses = np.full(N, m)

    def forces(u):
        x = np.concatenate([[0.0], u[:, 0], [0.0]])
        f = np.zeros((N, 3))
        f[:, 0] = k * (2 * x[1:-1] - x[:-2] - x[2:])
        return f

    free = np.zeros((N, 3))
    free[:, 0] = 1.0
    lam = max_eigenvalue(forces, rng.normal(0, 1e-4, (N, 3)) * free, masses, free)
    assert lam == pytest.approx(4 * k / m * np.sin(N * np.pi / (2 * (N + 1))) ** 2, rel=1e-6)
    assert critical_step(lam) == pytest.approx(2 / np.sqrt(lam))
    assert critical_step(0.0) == np.inf


def _box():
    m = box_mesh((6, 3, 3), (0.012, 0.006, 0.006))
    fixed = m.node_sets["xmin"]
    return TLEDSolver(m, SOFT_TISSUE, dt=1e-5, fixed=fixed)


def _model(s, dt):
    return FaceModel(s, s.mass, s.free.astype(float), dt, 0.0, np.zeros(0, np.int64), None, {"tissue": Tissue(s)})


def test_the_element_bound_is_below_the_system_limit():
    s = _box()
    lam = max_eigenvalue(s.internal_forces, np.zeros((s.mesh.n_nodes, 3)), s.mass, s.free, scale=0.002)
    assert s.stable_dt < critical_step(lam) < 3 * s.stable_dt


@pytest.mark.parametrize("factor, stable", [(0.97, True), (1.03, False)])
def test_central_differences_are_stable_just_under_the_limit_and_not_just_over(factor, stable):
    s = _box()
    n = s.mesh.n_nodes
    dt = factor * critical_step(max_eigenvalue(s.internal_forces, np.zeros((n, 3)), s.mass, s.free, scale=0.002))
    integ = CentralDifference(_model(s, dt))
    u0 = np.random.default_rng(2).normal(0.0, 1e-9, (n, 3)) * s.free      # linear regime
    state = integ.start(u0)
    try:
        integ.advance(state, 3000)
    except SimulationDiverged:           # the unstable mode grew until an element inverted
        growth = np.inf
    else:
        growth = np.abs(state.u).max() / np.abs(u0).max()
    assert (growth < 10.0) == stable, growth


@pytest.fixture(scope="module")
def coarse_face():
    from visemeface.face.procedural import default_face
    from visemeface.muscles.rig import MuscleRig
    from visemeface.physics.face_model import build_fem_face

    face = default_face(resolution=1500)
    return build_fem_face(face), MuscleRig.from_file(face)


def test_the_face_takes_its_stable_limit_and_refuses_a_longer_step(coarse_face):
    from visemeface.errors import InputError
    from visemeface.physics import drive

    fem, rig = coarse_face
    track = drive.ramp_track(rig.names, 60.0, 0.0, 0.2, 0.1, 0.2)
    sim = drive.StickySimulation(fem, rig, track)
    st = sim.stability
    assert st["dt"] == min(st["spectral"], *st["element"].values())
    assert st["element"]["saliva"] < st["element"]["tissue"]          # the stiff saliva sets it
    assert st["tissue_only"] > st["element"]["tissue"]                  # the element bound is the safe side
    # multi-rate (the default): the tissue's own step, the film's nodes in substeps at the film's
    assert st["tissue_step"] == min(st["element"]["tissue"], st["tissue_only"], st["natural_shape"])
    assert sim.steps_per_frame == int(np.ceil(1 / (60 * st["tissue_step"]) - 1e-9)) and sim.dt <= st["tissue_step"]
    assert sim.substeps == int(np.ceil(sim.dt / st["dt"] - 1e-9)) > 1 and sim.dt / sim.substeps <= st["dt"]
    single = drive.StickySimulation(fem, rig, track, settings=drive.PhysicsSettings(multirate=False))
    assert 3e-5 < single.dt <= st["dt"] and single.steps_per_frame == int(np.ceil(1 / (60 * st["dt"]) - 1e-9))
    assert single.substeps == 1
    assert drive.StickySimulation(fem, rig, track, settings=drive.PhysicsSettings(dt=1e-5)).dt <= 1e-5
    with pytest.raises(InputError, match=r"exceeds the stable limit .* of this face; give --dt <="):
        drive.StickySimulation(fem, rig, track, settings=drive.PhysicsSettings(dt=1.01 * st["dt"]))


def _spans(fem, rig, dt, **settings):
    from visemeface.physics import drive

    track = drive.ramp_track(rig.names, 60.0, 0.05, 0.35, 0.75, 0.35)      # the seed's opening, held
    out = {}
    for physics in ("sticky", "elastic"):
        sim = drive.StickySimulation(fem, rig, track, physics=physics, settings=drive.PhysicsSettings(dt=dt, **settings))
        frames = list(sim.frames())
        out[physics] = (np.array([f.saliva["film_open_span"] for f in frames]), frames[-1].vertices)
    return out


@pytest.mark.slow
@pytest.mark.parametrize("film", ["seed", "cohesive"])
def test_the_stable_step_keeps_the_zipper_of_the_seed_step(coarse_face, film):
    """Issue 17: the figures at the automatic step within 5 % of the single-rate 1e-5 s run."""
    from visemeface.physics.saliva import RUPTURE_TIME, SalivaParams

    fem, rig = coarse_face
    settings = {} if film == "seed" else {"film_corners": True, "saliva": SalivaParams(rupture_time=RUPTURE_TIME)}
    fine, auto = _spans(fem, rig, 1e-5, **settings), _spans(fem, rig, None, **settings)
    for physics in ("sticky", "elastic"):
        (a, va), (b, vb) = fine[physics], auto[physics]
        k0a, k0b = int(np.flatnonzero(a > 0)[0]), int(np.flatnonzero(b > 0)[0])
        ka, kb = (int(np.flatnonzero(x >= 0.95 * x.max())[0]) for x in (a, b))
        assert k0a == k0b                                                  # first opening: the same frame
        assert abs((kb - k0b) - (ka - k0a)) <= max(1, 0.05 * (ka - k0a))   # time to full width within 5 %
        assert np.abs(a - b).max() <= 0.1                                   # the open span, frame by frame
        assert np.sqrt(np.mean(np.sum((va - vb) ** 2, axis=1))) <= 0.01 * fem.mouth_width


@pytest.mark.slow
def test_speech_that_starts_mid_gesture_runs_at_the_automatic_step():
    """The 3 s example starts on a silence posture that presses the lips into the film (Q = 0.09): with the
    film formed there, its push inverted a lip element within 0.3 ms at 1e-5 s as at the stable step; it now
    starts squeezed out where the lips are pressed."""
    from visemeface.face.procedural import default_face
    from visemeface.muscles.rig import MuscleRig
    from visemeface.physics import drive
    from visemeface.physics.face_model import build_fem_face
    from visemeface.postures.library import load_visemes
    from visemeface.resources import transcripts_path
    from visemeface.speech.timeline import activation_track
    from visemeface.speech.transcripts import read_transcript

    face = default_face()
    rig = MuscleRig.from_file(face)
    ranges = {n: tuple(r) for n, r in zip(rig.names, rig.ranges)}
    track = activation_track(read_transcript(transcripts_path("one_five_zero_zero_six.txt")),
                             load_visemes(rig=rig), fps=30, ranges=ranges).iloc[:10]
    assert track.iloc[0].abs().max() > 0.1                                 # it does start mid-gesture
    sim = drive.StickySimulation(build_fem_face(face), rig, track)
    assert sim.initial_state().saliva["dry"].any()
    frames = list(sim.frames())
    assert len(frames) == 10 and sim.dt > 3e-5
    assert np.isfinite(frames[-1].vertices).all()


@pytest.mark.slow
@pytest.mark.parametrize("lips", ["seed", "speech"])
def test_speech_that_starts_with_the_lips_crossed_runs(lips):
    """"you ..." starts in the rounding that leads into /yu/, where the outer half of the seam is crossed
    (its film slabs folded over, J <= 0): the film's push there inverted a lip element within 0.8 ms, at
    1e-5 s as at the stable step, sticky and elastic, on the seed's face and the refined one. Crossed slabs
    now start squeezed out, as pressed ones do."""
    from visemeface.animate import simulated_motion
    from visemeface.muscles.rig import default_rig
    from visemeface.physics import drive
    from visemeface.physics.film import FOLDED
    from visemeface.postures.library import load_visemes
    from visemeface.speech.g2p import text_to_segments
    from visemeface.speech.timeline import activation_track

    rig = default_rig()
    ranges = {n: tuple(r) for n, r in zip(rig.names, rig.ranges)}
    track = activation_track(text_to_segments("you blew", warn=False), load_visemes(rig=rig), fps=60,
                             ranges=ranges).iloc[:6]
    settings = drive.PhysicsSettings(threads=1) if lips == "seed" else drive.PhysicsSettings.speech(threads=1)
    sim = simulated_motion(rig, track, "elastic", settings).sim
    start = sim.initial_state()
    folded = sim.film.stretch(start.u) >= FOLDED
    assert folded.sum() >= 8 and start.saliva["dry"][folded].all()
    frames = list(sim.frames())
    assert len(frames) == 6 and np.isfinite(frames[-1].vertices).all()


def test_the_tissue_step_holds_in_the_tracks_squeezed_natural_shapes(coarse_face):
    """A rounded posture squeezes lip elements in the muscle field's natural shape (the active strain's
    reference): their bound there, with their rest masses, caps the multi-rate step (issue 17; the default
    face's /yu/ inverted an element within 0.06 s at the rest bound)."""
    from visemeface.physics import drive
    from visemeface.physics.stability import natural_shape_step
    from visemeface.postures.library import load_visemes

    fem, rig = coarse_face
    row = load_visemes().loc["yu"]
    extra = {k: float(v) for k, v in row.items() if k != "jaw" and v != 0}
    track = drive.ramp_track(rig.names, 100.0, 0.0, 0.08, 0.17, float(row.get("jaw", 0.0)), extra)
    sim = drive.StickySimulation(fem, rig, track, "elastic")
    st, solver = sim.stability, sim.model.tissue_solver
    assert st["natural_shape"] < min(st["element"]["tissue"], st["tissue_only"])      # squeezed: a lower bound
    assert sim.dt <= st["natural_shape"] and sim.substeps >= 1
    assert natural_shape_step(solver, [np.zeros_like(fem.mesh.nodes)]) == pytest.approx(solver.stable_dt, rel=1e-12)
    frames = list(sim.frames())
    assert len(frames) == len(track) and np.isfinite(frames[-1].vertices).all()


def test_a_posture_spring_runs_single_rate(coarse_face):
    """The substeps hold every force but the film's and the tissue's: a posture spring (a force of u) held
    over them diverged at 300 Hz within 0.07 s (found in review); with one the run takes the film's step."""
    from visemeface.physics import drive

    fem, rig = coarse_face
    track = drive.ramp_track(rig.names, 60.0, 0.0, 0.05, 0.05, 0.3)
    sim = drive.StickySimulation(fem, rig, track, settings=drive.PhysicsSettings(posture_hz=300.0))
    assert sim.substeps == 1 and sim.dt <= sim.stability["dt"]
    frames = list(sim.frames())
    assert len(frames) == len(track) and np.isfinite(frames[-1].vertices).all()
    off = drive.StickySimulation(fem, rig, track, settings=drive.PhysicsSettings(posture_hz=300.0, off=("posture",)))
    assert off.substeps > 1


def test_a_diverged_multirate_frame_runs_again_at_one_rate(coarse_face, monkeypatch):
    """A multi-rate frame that diverges is run again from its start with every node at the film's
    substep (StickySimulation._advance_frame); the state is carried to that step and back (u_prev from the
    velocity, the film nodes' from their last substep), so the run goes on as the plain run goes: the
    same mouth within 0.02 % of its width (measured 3e-6), where carrying u_prev unscaled (the velocity
    times the substeps) moves it 2 %. A frame that diverges at one rate too raises."""
    from visemeface.physics import drive
    from visemeface.physics.integrator import CentralDifference

    fem, rig = coarse_face
    track = drive.ramp_track(rig.names, 60.0, 0.02, 0.15, 0.1, 0.3)
    plain = drive.StickySimulation(fem, rig, track, settings=drive.PhysicsSettings(threads=1))
    assert plain.substeps > 1
    ref = [f.vertices for f in plain.frames()]
    real = CentralDifference.advance

    def diverge_on_frame_6(self, state, n):
        if self is sim.integrator and state.step == 5 * sim.steps_per_frame and n == sim.steps_per_frame:
            real(self, state, n // 2)                    # half a frame in, then it "diverges"
            raise SimulationDiverged("forced", state.step, state.t, 0)
        real(self, state, n)

    monkeypatch.setattr(CentralDifference, "advance", diverge_on_frame_6)
    sim = drive.StickySimulation(fem, rig, track, settings=drive.PhysicsSettings(threads=1))
    got = [f.vertices for f in sim.frames()]
    assert sim.single_rate_frames == [6] and len(got) == len(ref)
    assert np.array_equal(got[5], ref[5])
    err = max(np.abs(a - b).max() for a, b in zip(got[6:], ref[6:])) / fem.mouth_width
    assert 0 < err < 2e-4, err

    def always(self, state, n):
        raise SimulationDiverged("forced", state.step, state.t, 0)
    monkeypatch.setattr(CentralDifference, "advance", always)
    sim = drive.StickySimulation(fem, rig, track, settings=drive.PhysicsSettings(threads=1))
    with pytest.raises(SimulationDiverged):
        list(sim.frames())
