"""The zipper of a cohesive saliva film carried into the mouth corners (issue 16), on the coarse face.

With the film ending at the last seam pair (a free end next to the unglued corner: a notch
tip, 1.2x the centre's stretch) and the seed's brittle release (its pull gone in ~1 ms), the
glued seam gives way in one cascade. Carried into the corners, the film is stretched most at
the centre; with a rupture time (saliva strands thin before they snap) the failure front starts
there and runs out to the corners while the jaw is held.
"""

from __future__ import annotations

import numpy as np
import pytest

from visemeface.physics import drive
from visemeface.physics.materials import TISSUE_LIMIT
from visemeface.physics.saliva import RUPTURE_TIME, SalivaParams

FPS = 60.0


@pytest.fixture(scope="module")
def runs():
    from visemeface.face.procedural import default_face
    from visemeface.muscles.rig import MuscleRig
    from visemeface.physics.face_model import build_fem_face
    from visemeface.runtime import set_threads
    set_threads(1)
    face = default_face(resolution=1500)
    fem, rig = build_fem_face(face), MuscleRig.from_file(face)
    # seed 000/001's opening (scenario open-once: jaw to 0.35 from 0.05 s to 0.40 s), held 0.75 s
    track = drive.ramp_track(rig.names, FPS, 0.05, 0.35, 0.75, 0.35)
    settings = drive.PhysicsSettings(film_corners=True, saliva=SalivaParams(rupture_time=RUPTURE_TIME))
    out = {}
    for physics in ("sticky", "elastic"):
        sim = drive.StickySimulation(fem, rig, track, physics=physics, settings=settings)
        frames = [(fr.vertices, fr.saliva["film_open_span"], sim.film.front_gaps(fr.displacement) - sim.film.rest_gap)
                  for fr in sim.frames()]
        out[physics] = (sim, frames)
    return fem, out


@pytest.mark.slow
def test_cohesive_film_unzips_from_the_centre_over_a_third_of_a_second(runs):
    fem, out = runs
    sim, frames = out["sticky"]
    spans = np.array([f[1] for f in frames])
    k0 = int(np.flatnonzero(spans > 0)[0])
    k_full = int(np.flatnonzero(spans >= 0.95 * spans.max())[0])
    assert abs(sim.film.s[np.argmax(frames[k0][2])]) < 0.15           # first opening at the centre
    assert len(np.unique(np.round(spans[k0:k_full + 1], 4))) >= 8      # the open span grows in many steps
    assert (k_full - k0) / FPS >= 0.2                                  # ... over at least 0.2 s
    assert np.all(np.diff(spans[k0:k_full + 1]) >= 0)                 # and never closes on the way
    esim, eframes = out["elastic"]
    es = np.array([f[1] for f in eframes])
    e0 = int(np.flatnonzero(es > 0)[0])
    assert e0 < k0 and es[e0 + 2] >= 0.8 * es.max()                    # elastic: earlier, most of it in 2 frames
    lips = np.unique(np.concatenate([fem.face.region("upper_lip"), fem.face.region("lower_lip")]))
    d = frames[-1][0][lips] - eframes[-1][0][lips]
    assert np.sqrt(np.mean(np.sum(d * d, axis=1))) <= 0.01 * fem.mouth_width   # the same open mouth at the end


def test_the_film_runs_into_the_mouth_corners_where_the_lips_share_a_node():
    from visemeface.face.procedural import default_face
    from visemeface.physics.face_model import build_fem_face
    from visemeface.physics.film import SalivaFilm
    fem = build_fem_face(default_face(resolution=1500))
    wedges = fem.corner_hexes
    assert wedges.shape == (2, 8) and np.allclose(np.abs(fem.corner_s).max(axis=1), 1.0)
    right, left = wedges                                        # node order: ξ along the seam, η lower -> upper
    assert right[0] == right[3] and right[4] == right[7]        # the right corner: its ξ- face is one edge
    assert left[1] == left[2] and left[5] == left[6]
    hexes = np.concatenate([fem.mesh.hexes[fem.saliva], wedges])
    ends = np.concatenate([fem.seam_s[fem.saliva_pairs], fem.corner_s])
    film = SalivaFilm(fem.mesh.nodes, hexes, ends, lambda s: np.full(len(s), 0.08), across=len(hexes))
    assert film.n_elements >= 48 and film.s.min() < -0.95 and film.s.max() > 0.95
    assert (film.thickness > 0).all() and (film.volumes > 0).all()
    # the lips meet at the corner: the film's rest gap closes toward it
    corner = np.abs(film.s) > 0.9
    assert film.rest_gap[corner].max() < film.rest_gap[~corner].min()


@pytest.mark.slow
def test_lips_refined_along_the_seam_unzip_the_default_face_from_the_centre():
    """On the default face (12 tissue elements along the seam) the cohesive film parts from its free
    ends near the corners (or, carried into them, holds to jaw 0.35): its 48 slabs share the four
    edge nodes of their lip element. With the lips refined to one tissue element per slab
    (``seam_elements=48``) the film, carried into the corners, unzips from the centre while the jaw is
    held at 0.35 and stops short of the corners, which stay joined (seed 000 Fig. 7: at a slight
    opening sticky lips stay joined toward the corners; measured 0.84 of the mouth against elastic's
    0.95, neo-Hookean 0.71); opened on to 0.6 the lips let go there too and end where the elastic lips do. These are the
    speech commands' lips (:meth:`PhysicsSettings.speech`). The centre's height rises slowly, then
    fast, as seed 001 Fig. 19's sticky and real mouths in its opening action (GRID's speakers in running
    speech taper: ``tests/analysis/test_realdata.py``); the elastic one fast, then tapering."""
    from visemeface.face.procedural import default_face
    from visemeface.physics.scenarios import make_track, smoothstep_keyframes
    from visemeface.runtime import set_threads
    set_threads(1)
    settings = drive.PhysicsSettings.speech(threads=1)
    assert settings.seam_elements == 48 and settings.saliva.rupture_time == RUPTURE_TIME and settings.film_corners
    fem, rig = drive.physics_face(default_face(), seam_elements=settings.seam_elements)
    t = np.arange(int(1.75 * FPS) + 1) / FPS
    jaw = smoothstep_keyframes(t, [(0.0, 0.0), (0.05, 0.0), (0.40, 0.35), (1.15, 0.35), (1.35, 0.6), (1.75, 0.6)])
    track = make_track(t, {"jaw": jaw}, rig.names, FPS)
    held = int(1.15 * FPS)                                              # the last frame at jaw 0.35
    out = {}
    for physics in ("sticky", "elastic"):
        sim = drive.StickySimulation(fem, rig, track, physics=physics, settings=settings)
        assert sim.film.refine == 1                                     # one slab per tissue element
        out[physics] = [(fr.vertices, fr.saliva["film_open_span"], sim.film.front_gaps(fr.displacement)
                         - sim.film.rest_gap, sim.broken[sim.seam_slabs].copy()) for fr in sim.frames()]
    spans = np.array([f[1] for f in out["sticky"]])[:held + 1]
    k0 = int(np.flatnonzero(spans > 0)[0])
    k_full = int(np.flatnonzero(spans >= 0.95 * spans.max())[0])
    assert abs(sim.film.s[np.argmax(out["sticky"][k0][2])]) < 0.15       # first opening at the centre
    assert len(np.unique(np.round(spans[k0:k_full + 1], 4))) >= 8        # many widths ...
    assert (k_full - k0) / FPS >= 0.2 and np.all(np.diff(spans[k0:k_full + 1]) >= 0)   # ... over >= 0.2 s
    es = np.array([f[1] for f in out["elastic"]])[:held + 1]
    e0 = int(np.flatnonzero(es > 0)[0])
    assert e0 < k0 and es[e0 + 2] >= 0.8 * es.max()                      # elastic: earlier, most in 2 frames
    assert spans.max() < es.max() - 2 / 48                              # the corners stay joined at jaw 0.35:
    seam_s, joined = sim.film.s[sim.seam_slabs], ~out["sticky"][held][3]   # the outermost seam slab each side
    assert joined[np.argmin(seam_s)] and joined[np.argmax(seam_s)] and not joined[np.argmin(np.abs(seam_s))]
    # the centre's height (seed 001 Fig. 19): held by the stretched film over its rupture time, then
    # the snap (slowly, then faster: exponent > 1); the elastic lips follow the eased jaw and taper
    from visemeface.analysis.profiles import rise_exponent
    c = int(np.argmin(np.abs(sim.film.s)))
    assert rise_exponent([f[2][c] for f in out["sticky"][k0:held + 1]]) > 1
    assert rise_exponent([f[2][c] for f in out["elastic"][e0:held + 1]]) < 1
    lips = np.unique(np.concatenate([fem.face.region("upper_lip"), fem.face.region("lower_lip")]))
    d = out["sticky"][-1][0][lips] - out["elastic"][-1][0][lips]
    assert np.sqrt(np.mean(np.sum(d * d, axis=1))) <= 0.01 * fem.mouth_width   # the same open mouth at 0.6


@pytest.mark.slow
def test_central_glue_holds_two_openings_apart_until_they_merge():
    """Seed 001's double opening on the seed's neo-Hookean tissue (``tissue_limit`` inf; the speech lips'
    stiffening tissue shortens it to 7 frames here, README, and merges it at the seed's held jaw, the
    next tests): central glue 0.18 on the mouth's central twelfth (``centre``, glue.CENTRAL_HALF_WIDTH),
    the jaw eased to full over 1 s, the film carried into the corners (no free end to open first). Two openings, one each side of the stuck centre, for 10 or more frames at 60 fps,
    then one; the open span's jump at the merge is over twice any other frame's (seed 001 Fig. 26's one
    spike). Measured: 10 frames, the merge at frame 42 (the paper: about 45), its jump 3.0x the next;
    also 10 with the jaw taking 0.95 or 1.05 s and single-rate at 3.6e-5 s, 11 at 1.1 s."""
    from visemeface.face.procedural import default_face
    from visemeface.runtime import set_threads
    set_threads(1)
    settings = drive.PhysicsSettings.speech(threads=1, film_corners=True, glue_profile="centre=0.18",
                                            tissue_limit=float("inf"))
    fem, rig = drive.physics_face(default_face(), seam_elements=settings.seam_elements)
    track = drive.ramp_track(rig.names, FPS, 0.05, 1.0, 0.0, 1.0).iloc[:56]
    sim = drive.StickySimulation(fem, rig, track, settings=settings)
    s, glued = sim.film.s, sim.film.glue > 0.1
    assert glued.sum() == 4 and np.abs(s[glued]).max() <= 1 / 12               # the central twelfth: 4 slabs
    counts, spans, first = [], [], None
    for fr in sim.frames():
        counts.append(fr.saliva["film_open_count"])
        spans.append(fr.saliva["film_open_span"])
        if counts[-1] == 2 and first is None:
            first = (sim.film.front_gaps(fr.displacement) - sim.film.rest_gap) / fem.mouth_width > 0.02
    two = [i for i, c in enumerate(counts) if c == 2]
    assert len(two) >= 10 and two == list(range(two[0], two[-1] + 1))    # two openings, 10 frames in a row
    assert set(counts[:two[0]]) == {0} and set(counts[two[-1] + 1:]) == {1}   # none before, one after
    assert first[s < -1 / 12].any() and first[s > 1 / 12].any() and not first[glued].any()   # either side
    d = np.diff(spans)
    assert int(np.argmax(d)) == two[-1] and d.max() > 2 * np.sort(d)[-2]   # one dominant jump, at the merge


@pytest.mark.slow
def test_speech_releases_a_bilabial_from_the_centre_over_frames():
    """``speak --physics sticky``'s lips on "bob" at 60 fps: the /b/ released into the vowel opens at the
    centre (the first opening holds the centre and is centred on it: measured, -0.35 to +0.31 of the
    half-width, its gap flat over the middle, 0.44 of the mouth), no earlier than the elastic lips, and
    takes 2 or more frames to 90 % of its span (measured: 0.44, then 0.62 of the mouth; neo-Hookean 0.29,
    then 0.62; real releases grow over 2-4 frames at 25 fps, tests/analysis/test_realdata.py); the elastic
    lips are past 90 % in the frame they open."""
    from visemeface.animate import simulated_motion
    from visemeface.muscles.rig import default_rig
    from visemeface.postures.library import load_visemes
    from visemeface.runtime import set_threads
    from visemeface.speech.g2p import text_to_segments
    from visemeface.speech.timeline import activation_track
    set_threads(1)
    rig = default_rig()
    segs = text_to_segments("bob", warn=False)
    track = activation_track(segs, load_visemes(rig=rig), fps=FPS)
    ends = segs.loc[segs["phoneme"] == "b", "end"].to_numpy()[:1]
    assert len(ends) == 1
    frames = {}
    for physics in ("sticky", "elastic"):
        sim = simulated_motion(rig, track, physics).sim
        frames[physics] = [(fr.saliva["film_open_span"], sim.film.front_gaps(fr.displacement) - sim.film.rest_gap)
                           for fr in sim.frames()]
    for end in ends:
        k = int(np.floor(end * FPS))
        spans = {p: np.array([f[0] for f in frames[p][k:k + 18]]) for p in frames}
        a = {p: int(np.flatnonzero(x > 0)[0]) for p, x in spans.items()}
        b = {p: int(np.flatnonzero(x >= 0.9 * x.max())[0]) for p, x in spans.items()}
        gap, s = frames["sticky"][k + a["sticky"]][1], sim.film.s
        opened = s[gap > 0.5 * gap.max()]
        assert gap[np.argmin(np.abs(s))] > 0.5 * gap.max()               # the centre opens first ...
        assert abs(opened.min() + opened.max()) / 2 < 0.15                # ... the opening is centred on it ...
        assert opened.min() > -0.8 and opened.max() < 0.8                 # ... and the corners are still shut
        assert a["sticky"] >= a["elastic"]
        assert b["sticky"] - a["sticky"] + 1 >= 2                         # over 2 or more frames
        assert b["elastic"] - a["elastic"] + 1 == 1


def _held(params, lam, steps, glue=0.08):
    from test_sticky import _box, _films, _step, _stretched
    film, X, st = _films(glue, params)
    F = _stretched(_box(), lam)[0]
    forces = [np.abs(_step(film, X, st, F, 1e-5 * i)[0]).max() for i in range(steps)]
    return film, st, np.array(forces)


def test_a_strand_lets_go_over_its_rupture_time_and_never_pulls_past_its_peak():
    tau, dt = 1e-3, 1e-5
    lam = np.sqrt(1.12)                                          # past the breaking point Z = 1.08
    _, st, f = _held(SalivaParams(rupture_time=tau), lam, 800)     # 8 tau: snapped at D = 0.999
    _, _, peak = _held(SalivaParams(rupture_time=tau), np.sqrt(1.08) - 1e-9, 1)
    assert f.max() <= peak[0] * (1 + 1e-6)                      # capped at the pull at Z
    # the law's damage is 1 (strand 0: past the peak it has to go), reached at rate 1/tau
    k = int(tau / dt)
    assert f[k] == pytest.approx(f[0] * np.exp(-1.0), rel=0.02)
    assert st["broken"][0] and st["damage"][0] >= 0.999
    # without glue there is no peak: the film lets go at once, as the seed's elastic lips
    _, st0, f0 = _held(SalivaParams(rupture_time=tau), 1.01, 2, glue=0.0)
    assert st0["broken"][0] and f0.max() == 0.0


def test_a_strand_softens_linearly_with_the_separation_and_its_energy_is_its_length():
    # bilinear law: at half the strand past the peak separation, half the peak traction
    from test_sticky import _box, _films, _step, _stretched
    strand = 2e-4
    film, X, st = _films(0.08, SalivaParams(strand=strand))
    h = film.thickness[0]
    xp = np.sqrt(1.08)
    f_peak = np.abs(_step(film, X, st, _stretched(_box(), xp - 1e-9)[0])[0]).max()
    x_half = xp + 0.5 * strand / h
    f_half = np.abs(_step(film, X, st, _stretched(_box(), x_half)[0], 1e-5)[0]).max()
    assert f_half == pytest.approx(0.5 * f_peak, rel=1e-6)      # the traction halved (nodal force ∝ dW/dλ)
    assert 0.0 < st["damage"][0] < 1.0 and not st["broken"][0]
    _step(film, X, st, _stretched(_box(), xp + 1.01 * strand / h)[0], 2e-5)
    assert st["broken"][0]


@pytest.mark.slow
def test_a_stiffening_tissue_lets_central_glue_merge_two_openings_at_the_seeds_jaw():
    """Central glue 0.18 at the seed scenario's jaw 0.35 (held): with the neo-Hookean tissue the glued centre
    never lets go (the tissue beside it stretches instead of the film); with the speech lips' Gent tissue
    (materials.TISSUE_LIMIT) it does: two openings for 10 or more frames in a row, then one, the open span's
    largest jump at the merge (measured at 2.8: 16 frames, 24-39, the jump 3.8x any other; 2.5: 14)."""
    from visemeface.face.procedural import default_face
    from visemeface.runtime import set_threads
    set_threads(1)
    fem, rig = drive.physics_face(default_face(), seam_elements=48)
    track = drive.ramp_track(rig.names, FPS, 0.05, 0.35, 0.75, 0.35)
    counts = {}
    for limit in (float("inf"), TISSUE_LIMIT):
        settings = drive.PhysicsSettings.speech(threads=1, glue_profile="centre=0.18", tissue_limit=limit)
        sim = drive.StickySimulation(fem, rig, track, settings=settings)
        frames = [(fr.saliva["film_open_count"], fr.saliva["film_open_span"]) for fr in sim.frames()]
        counts[limit] = [c for c, _ in frames]
        spans = [w for _, w in frames]
    assert 2 in counts[float("inf")] and 1 not in counts[float("inf")]          # neo-Hookean: two to the end
    c = counts[TISSUE_LIMIT]
    two = [i for i, n in enumerate(c) if n == 2]
    assert len(two) >= 10 and two == list(range(two[0], two[-1] + 1))
    assert set(c[:two[0]]) == {0} and set(c[two[-1] + 1:]) == {1}
    d = np.diff(spans)
    assert int(np.argmax(d)) == two[-1] and d.max() > 2 * np.sort(d)[-2]


@pytest.mark.slow
def test_glue_0_3_parts_the_lips_fully_at_full_jaw_later_than_the_default_glue():
    """Issue 16: "glue 0.3: the lips still part fully at full jaw, later than with 0.08". At the seed's jaw
    0.35 it holds; with the jaw eased to 1.0 over the same 0.35 s the whole film parts (the seed's film)."""
    from visemeface.face.procedural import default_face
    from visemeface.muscles.rig import MuscleRig
    from visemeface.physics.face_model import build_fem_face

    face = default_face(resolution=1500)
    fem, rig = build_fem_face(face), MuscleRig.from_file(face)
    first, span = {}, {}
    for glue in (0.08, 0.3):
        for jaw in (0.35, 1.0):
            track = drive.ramp_track(rig.names, FPS, 0.05, 0.35, 0.75, jaw)
            sim = drive.StickySimulation(fem, rig, track, settings=drive.PhysicsSettings(glue=glue, threads=1))
            s = np.array([fr.saliva["film_open_span"] for fr in sim.frames()])
            first[glue, jaw] = int(np.flatnonzero(s > 0)[0]) if (s > 0).any() else None
            span[glue, jaw] = s.max()
    assert first[0.3, 0.35] is None and first[0.08, 0.35] is not None          # glue 0.3 holds at jaw 0.35
    assert first[0.3, 1.0] is not None and first[0.3, 1.0] > first[0.08, 1.0]  # ... parts at full jaw, later
    assert span[0.3, 1.0] >= 0.99 * span[0.08, 1.0]                          # ... and fully


@pytest.mark.slow
def test_glue_0_3_at_full_jaw_holds_neo_hookean_lips_and_parts_the_stiffening_ones():
    """Issue 16's glue 0.3 on the speech lips, measured to its cause. With the seed's neo-Hookean tissue
    the film holds at full jaw: not one slab breaks, while the lip tissue beside it stretches several-fold
    (it gives instead of the film, 10x stiffer in shear). A tissue that stiffens toward a limiting stretch
    (Gent, the speech lips' ``materials.TISSUE_LIMIT``) carries the load into the film, and every slab along the seam breaks (the
    two wedges into the corners, where the lips meet, hold: measured 1.195 against their 1.30)."""
    from visemeface.face.procedural import default_face
    from visemeface.runtime import set_threads
    set_threads(1)
    fem, rig = drive.physics_face(default_face(), seam_elements=48)
    track = drive.ramp_track(rig.names, FPS, 0.05, 0.35, 0.75, 1.0)
    broken = {}
    for limit in (float("inf"), TISSUE_LIMIT):
        sim = drive.StickySimulation(fem, rig, track, settings=drive.PhysicsSettings.speech(
            glue=0.3, tissue_limit=limit, threads=1))
        for _ in sim.frames():
            pass
        broken[limit] = (sim.broken[sim.seam_slabs].mean(), sim.broken[sim.seam_slabs.stop:].mean())
    assert broken[float("inf")] == (0.0, 0.0)
    assert broken[TISSUE_LIMIT][0] == 1.0          # every slab along the seam; the corner wedges may hold


@pytest.mark.slow
@pytest.mark.parametrize("limit", [float("inf"), TISSUE_LIMIT], ids=["neo-Hookean", "Gent"])
def test_the_speech_lips_keep_the_seeds_asymmetry_and_evaporation(limit):
    """On the speech commands' lips (refined seam, rupture time, film into the corners), as on the seed's model
    (test_sticky.py): glue on one side only opens the other side first, and a film that has dried
    (evaporation 600 a second) lets go fully at a smaller jaw later on (measured: 0.15 against 0.35). The
    same with the tissue stiffening toward a limiting stretch (``tissue_limit``)."""
    from visemeface.face.procedural import default_face
    from visemeface.physics.face_model import seam_openings
    from visemeface.runtime import set_threads
    set_threads(1)
    fem, rig = drive.physics_face(default_face(), seam_elements=48)

    def run(track, **kw):
        sim = drive.StickySimulation(fem, rig, track, settings=drive.PhysicsSettings.speech(
            threads=1, tissue_limit=limit, **kw))
        return [(fr.vertices, fr.saliva) for fr in sim.frames()]

    frames = run(drive.ramp_track(rig.names, 200, 0.02, 0.1, 0.0, 0.35), glue_profile="right=0.3,left=0")
    first = next(f for f in frames if f[1]["open_count"] > 0)
    op = seam_openings(fem, first[0])["open"]
    assert op[fem.seam_s > 0].any() and not op[fem.seam_s < 0].any()

    def jaw_at_break(start):
        track = drive.ramp_track(rig.names, 250, start, 0.08, 0.3, 0.35)    # held: a strand snaps over ~7 τ
        fr = run(track, saliva=SalivaParams(evaporation=600.0, rupture_time=RUPTURE_TIME))
        # the film along the seam all broken (its wedges into the corners, where the lips meet, never part)
        return track["jaw"].iloc[next(i for i, f in enumerate(fr) if f[1]["broken_fraction"] == 1.0)]

    assert jaw_at_break(0.12) < 0.8 * jaw_at_break(0.02)
