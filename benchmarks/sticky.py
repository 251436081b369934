"""Speed of the sticky-lip FEM face, printed as JSON lines.

    PYTHONPATH=src python benchmarks/sticky.py                 # both figures
    PYTHONPATH=src python benchmarks/sticky.py --seconds 0.2 --skip-speech

1. ``fem_face``: wall seconds per simulated second for the default FEM face
   (the "open" scenario's first ``--seconds``; target <= 10 s on 2 cores, issue 17), at
   each numba thread count in ``--threads`` and each time step in ``--dt``: ``auto`` (the
   default: multi-rate, the tissue's stable step with the film's nodes in substeps at the
   film's), ``single`` (everything at the film's stable step, the default before the
   multi-rate step) and ``1e-5`` (the seed's step), back to back in one run; ``speedup`` =
   each other run's wall time / the auto run's at the same thread count.
2. ``speak_sticky``: the library path ``speak --physics sticky`` takes on the
   3 s example (``transcripts/one_five_zero_zero_six.txt``): transcript ->
   activation track -> :func:`visemeface.animate.simulated_motion` -> render each
   frame (512 px, face view); wall seconds per simulated second, for the speech
   commands' default lips (``PhysicsSettings.speech()``: refined along the seam,
   cohesive film carried into the mouth corners, Gent tissue), the same lips with the neo-Hookean tissue (the cost
   of the stiffening, in one run) and the seed's model (``PhysicsSettings()``). Its
   threads are chosen as ``speak`` chooses them: the faster of the largest ``--threads``
   count and one, timed during the run (``PhysicsSettings.threads`` None).

Figures taken on a shared machine are disturbed by its load: the load
average is printed with them.
"""

from __future__ import annotations

import argparse
import json
import os
import time


def emit(**kw):
    print(json.dumps(kw), flush=True)


def bench_fem_face(seconds: float, threads: int, dt: float | None = None, multirate: bool = True,
                   seam_elements: int | None = None) -> float:
    from visemeface.face.procedural import default_face
    from visemeface.muscles.rig import MuscleRig
    from visemeface.physics.drive import PhysicsSettings, StickySimulation, scenario_track
    from visemeface.physics.face_model import build_fem_face
    from visemeface.runtime import set_threads

    from visemeface.face.refine import refine_lip_seam

    set_threads(threads)
    face = default_face()
    rig = MuscleRig.from_file(face if seam_elements is None else refine_lip_seam(face, seam_elements))
    fem = build_fem_face(face, seam_elements=seam_elements)
    track = scenario_track("open", rig.names, fps=60)
    track = track.iloc[: int(round(seconds * 60)) + 1]
    sim = StickySimulation(fem, rig, track, settings=PhysicsSettings(dt=dt, threads=threads, multirate=multirate))
    it = sim.frames()
    next(it)                                   # compile / warm up (frame 0)
    t0 = time.perf_counter()
    n = 0
    for _ in it:
        n += 1
    wall = time.perf_counter() - t0
    simulated = n / sim.fps
    emit(benchmark="fem_face", threads=threads, nodes=fem.mesh.n_nodes, hexahedra=fem.mesh.n_elements,
         saliva=len(fem.saliva), film_slabs=getattr(getattr(sim, "film", None), "n_elements", None), dt=sim.dt,
         substeps=getattr(sim, "substeps", 1), simulated_s=round(simulated, 4), wall_s=round(wall, 2),
         wall_per_simulated_s=round(wall / simulated, 1), steps_per_s=round(n * sim.steps_per_frame / wall),
         target_wall_per_simulated_s=10, stable_limit=sim.stability["dt"],
         element_bounds=sim.stability["element"], seam_elements=seam_elements, load_average=os.getloadavg()[0])
    return wall / simulated


def bench_speak(threads: int) -> None:
    from visemeface.face.procedural import default_face
    from visemeface.muscles.rig import MuscleRig
    from visemeface.animate import simulated_motion
    from visemeface.physics.drive import PhysicsSettings
    from visemeface.runtime import set_threads
    from visemeface.postures.library import load_visemes
    from visemeface.render.renderer import Renderer
    from visemeface.resources import transcripts_path
    from visemeface.speech.timeline import activation_track
    from visemeface.speech.transcripts import read_transcript

    set_threads(threads)
    for model, settings in (("speech default (lips refined, rupture time, film into the corners, Gent tissue)",
                             PhysicsSettings.speech()),
                            ("speech lips, neo-Hookean tissue (--tissue-limit inf)", PhysicsSettings.speech(tissue_limit=float("inf"))),
                            ("seed (--seam-elements 0 --rupture-time 0 --no-film-corners --tissue-limit inf)", PhysicsSettings())):
        t0 = time.perf_counter()
        face = default_face()
        rig = MuscleRig.from_file(face)
        segments = read_transcript(transcripts_path("one_five_zero_zero_six.txt"))
        ranges = {n: tuple(r) for n, r in zip(rig.names, rig.ranges)}           # as speak builds it
        track = activation_track(segments, load_visemes(rig=rig), fps=30, ranges=ranges)
        motion = simulated_motion(rig, track, "sticky", settings)              # as speak runs it
        renderer = Renderer(motion.render_face, size=(512, 512), view="face")
        n = 0
        for f in motion.frames():
            renderer.render(f.vertices)
            n += 1
        wall = time.perf_counter() - t0
        seconds = (n - 1) / 30.0
        emit(benchmark="speak_sticky", model=model, transcript="one_five_zero_zero_six.txt",
             threads=f"{threads} or 1, timed (auto)", frames=n, simulated_s=round(seconds, 3), wall_s=round(wall, 1),
             wall_per_simulated_s=round(wall / seconds, 1), target_wall_per_simulated_s=15,
             single_rate_frames=len(motion.sim.single_rate_frames), load_average=os.getloadavg()[0])


def main(argv=None):
    from visemeface.runtime import configure

    configure()  # as the CLI does: threading layer, OpenMP spin, cache folder
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--seconds", type=float, default=0.5, help="simulated seconds for fem_face (default 0.5)")
    ap.add_argument("--threads", default="1,2", help="numba thread counts to try (default 1,2)")
    ap.add_argument("--dt", default="auto,single,1e-5", help="time steps: 'auto' (multi-rate at the stable "
                    "limits), 'single' (one step, the film's limit) and/or seconds (default auto,single,1e-5)")
    ap.add_argument("--skip-speech", action="store_true")
    ap.add_argument("--seam-elements", type=int, default=None,
                    help="fem_face: refine the lips to this many tissue elements along the seam (build_fem_face)")
    args = ap.parse_args(argv)
    counts = [int(x) for x in args.threads.split(",")]
    steps = args.dt.split(",")

    def run(n, x):
        if x in ("auto", "single"):
            return bench_fem_face(args.seconds, n, None, multirate=x == "auto", seam_elements=args.seam_elements)
        return bench_fem_face(args.seconds, n, float(x), multirate=False, seam_elements=args.seam_elements)

    for n in counts:
        per = {x: run(n, x) for x in steps}
        if "auto" in per and len(per) > 1:
            for x, w in per.items():
                if x != "auto":
                    emit(benchmark="fem_face_speedup", threads=n, versus=x, speedup=round(w / per["auto"], 2))
    if not args.skip_speech:
        bench_speak(max(counts))


if __name__ == "__main__":
    main()
