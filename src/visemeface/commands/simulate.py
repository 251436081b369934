"""``visemeface simulate SCENARIO``: the sticky-lip FEM face in one of Leach & Maddock's (2018, 2019) experiments.

Builds the FEM face (lower face extruded to hexahedra, saliva between the
lips), drives it with a scenario's activation track, and streams the motion
through the same loop and outputs as ``speak`` (MP4, PNG frames, OBJ, PC2, ...)
plus a per-frame CSV of the saliva state. The simulation saves its state after
every frame; after Ctrl-C, ``--resume`` continues from it.
"""

from __future__ import annotations

import argparse
from pathlib import Path

from visemeface.commands import _options as opt

ORDER = 60

from visemeface.physics.config import MAX_DAMPING, MAX_DT, MIN_DT

EPILOG = """\
examples:
  visemeface simulate open --glue 0.08 -o open.mp4        # jaw lowered and raised twice (Leach & Maddock 2019, Fig. 18)
  visemeface simulate open --physics elastic -o open_elastic.mp4   # the same FEM without glue
  visemeface simulate open-once -o zip.mp4               # the lips unzip from the centre (0.67 of the mouth by its end)
  visemeface simulate open-once --lips seed -o seed.mp4   # Leach & Maddock's (2018) model
  visemeface simulate open-once --glue-profile centre=0.18 -o two.mp4   # glue strongest at the centre
  visemeface simulate open --evaporation 40 -o dry.mp4    # later openings unzip faster
  visemeface simulate open-once --side left -o left.mp4   # one-sided lower-lip pull: asymmetric opening
  visemeface simulate open -o open.mp4 --resume           # continue an interrupted run

The default lips are refined to 48 elements along the seam, the saliva strands
thin over 0.03 s before they snap, the film runs into the mouth corners, and the
tissue stiffens without bound toward a stretch of 2.8 (Gent), so a strong glue
(0.3) lets go at full jaw. --lips seed is Leach & Maddock's (2018) model: the
face's own mesh, a brittle film that parts in one frame, a neo-Hookean tissue
that never stiffens (under that glue the lips stretch 7x and hold).

Writes OUTPUT (MP4) and OUTPUT's stem + .saliva.csv (or --measures CSV), per
frame: frame, time, jaw, broken_fraction (of the saliva film along the seam),
open_count, open_span and open_fraction (openings between the lips along the
seam), centre_gap (m), max_stretch (the saliva film's largest stretch: a strand
stretches many times before it snaps), film_open_count and film_open_span (the
film's own broken runs). The state is saved after every
frame in OUTPUT.checkpoint/, removed when the run completes or diverges. Glue profiles:
WHERE=VALUE items over --glue, WHERE one of centre (the mouth's central twelfth),
left, right, corners, all or a range a..b of the position across the mouth
(-1 right corner .. +1 left corner). Exit status 3: the simulation diverged
(the message says where and what to try).
"""


def register(subparsers) -> None:
    from visemeface.physics import PHYSICS
    from visemeface.physics.scenarios import SCENARIOS, SIDES

    p = subparsers.add_parser(
        "simulate", help="run the sticky-lip FEM face through a scenario (Leach & Maddock 2018, 2019) -> MP4 + saliva CSV",
        description="Simulate the physically-based sticky-lip face (TLED FEM, breaking saliva elements) "
        "through a scenario and write the animation and the saliva state per frame.",
        epilog=EPILOG, formatter_class=opt.Help)
    p.add_argument("scenario", choices=sorted(SCENARIOS), help="the jaw eased to --jaw and back: open: opened "
                   "and closed twice; open-once: opened and held; part: opened to 0.45 of --jaw and held (a "
                   "slight opening the speech lips' glue holds shut; elastic lips part)")
    phys = opt.add_physics_arguments(p, "sticky", tuple(PHYSICS))
    phys.add_argument("--glue-file", type=Path, metavar="CSV", help="glue per film element (element,glue; "
                      "0 at the right corner, in order across the mouth) or a profile (s,glue)")
    phys.add_argument("--critical-moisture", type=opt.number(0), metavar="MC", help="critical moisture Mc (default 100)")
    phys.add_argument("--dt", type=opt.number(MIN_DT, MAX_DT), help=f"one time step in s for every node, {MIN_DT:g} "
                      f"to {MAX_DT:g} (default: multi-rate, the "
                      "tissue's stable step with the lips' film nodes in substeps at the film's, printed at the "
                      "end; a step above the film's limit is refused)")
    phys.add_argument("--damping", type=opt.number(0, MAX_DAMPING),
                      help=f"mass damping alpha in 1/s, 0 to {MAX_DAMPING:g} (default 80)")
    phys.add_argument("--jaw", type=opt.number(0, 1), default=0.35, help="jaw activation when open, 0 to 1 "
                      "(default 0.35)")
    phys.add_argument("--side", choices=SIDES, default="both",
                      help="also pull the lower lip down on one side (asymmetric opening)")
    phys.add_argument("--resolution", type=opt.number(300, 200_000, integer=True),
                      help="face vertices, 300 to 200000 (default: the default face's)")
    opt.add_skin_argument(phys)
    phys.add_argument("--threads", type=opt.number(1, integer=True), help="numba threads (default: the faster of all cores and one, "
                      "timed during the run; the result is the same at any count)")
    p.add_argument("--fps", type=float, default=60.0, help="frame rate (default 60, Leach & Maddock's camera)")
    opt.add_render_arguments(p, view="mouth")
    opt.add_output_arguments(p, "SCENARIO.mp4", resumable="continue an interrupted run from its checkpoint")
    p.set_defaults(func=run)


def _check(args) -> None:
    from visemeface.physics.glue import check_glue_sources
    from visemeface.runtime import check_threads

    opt.check_fps_option(args.fps)
    if args.threads is not None:
        check_threads(args.threads)
    if args.physics != "elastic":            # elastic refuses any glue option itself
        check_glue_sources(args.glue_profile, args.glue_file)     # before the FEM face is built (seconds)


def run(args) -> int:
    from visemeface import pipeline
    from visemeface.face.procedural import default_face
    from visemeface.muscles.rig import MuscleRig
    from visemeface.physics.drive import scenario_track

    _check(args)
    stem = (args.output or Path(f"{args.scenario}.mp4")).with_suffix("")
    sinks = opt.sinks_from_args(args, Path(f"{args.scenario}.mp4"), defaults={"measures": Path(f"{stem}.saliva.csv")})
    render = opt.render_from_args(args)
    physics = opt.physics_from_args(args, dt=args.dt, damping=args.damping, threads=args.threads,
                                    glue_file=None if args.glue_file is None else str(args.glue_file))
    face = default_face(resolution=args.resolution, skin=args.skin)
    rig = MuscleRig.from_file(face)
    track = scenario_track(args.scenario, rig.names, fps=args.fps, jaw=args.jaw, side=args.side)
    motion = opt.simulation_of(rig, track, args.physics, physics)          # every input check happens here
    checkpoint = opt.checkpoint_of(motion, sinks, args)
    stats = pipeline.run(motion, sinks, render,
                         info=dict(rig=rig, track=track, extra={"motion_key": motion.key()}),
                         checkpoint=checkpoint, resume=args.resume, show_progress=not args.quiet, final=True)
    if not args.quiet:
        c = motion.sim.fem.counts()
        print(f"FEM face: {c['nodes']} nodes, {c['elements']} hexahedra ({c['saliva']} saliva); "
              f"dt {motion.sim.dt:.4g} s in {motion.sim.substeps} film substep(s) "
              f"(stable limits: tissue {motion.sim.stability['tissue_step']:.4g} s, film {motion.sim.stability['dt']:.4g} s)")
        if motion.sim.single_rate_frames:
            print(f"{len(motion.sim.single_rate_frames)} frame(s) diverged multi-rate and ran again at one rate "
                  f"(the first: frame {motion.sim.single_rate_frames[0]})")
        print(pipeline.summary(stats, args.fps))
    return 0
