"""``visemeface simulate SCENARIO``: the sticky-lip FEM face in one of the seed's experiments.

Builds the FEM face (lower face extruded to hexahedra, saliva between the
lips), drives it with a scenario's activation track, and streams the motion
through the same loop and outputs as ``speak`` (MP4, PNG frames, OBJ, PC2, ...)
plus a per-frame CSV of the saliva state. The simulation saves its state after
every frame; after Ctrl-C, ``--resume`` continues from it.
"""

from __future__ import annotations

import argparse
import math
from pathlib import Path

from visemeface.commands import _options as opt

ORDER = 60

EPILOG = """\
examples:
  visemeface simulate open --glue 0.08 -o open.mp4        # jaw lowered and raised twice (seed 001 Fig. 18)
  visemeface simulate open --physics elastic -o open_elastic.mp4   # the same FEM without glue
  visemeface simulate open-once -o zip.mp4               # the lips unzip from the centre (0.67 of the mouth by its end)
  visemeface simulate open-once --rupture-time 0 --seam-elements 0 --no-film-corners --tissue-limit inf -o seed.mp4   # the seed's model
  visemeface simulate open-once --glue-profile centre=0.18 -o two.mp4   # glue strongest at the centre
  visemeface simulate open --evaporation 40 -o dry.mp4    # later openings unzip faster
  visemeface simulate open-once --side left -o left.mp4   # one-sided lower-lip pull: asymmetric opening
  visemeface simulate open -o open.mp4 --resume           # continue an interrupted run

The lips are refined to 48 elements along the seam, the saliva strands thin
over 0.03 s before they snap, the film runs into the mouth corners (issue 16;
--seam-elements 0 --rupture-time 0 --no-film-corners: the seed's mesh and brittle
film, which parts in one frame), and the tissue stiffens without bound toward a
stretch of 2.8 (Gent), so a strong glue (0.3) lets go at full jaw. With
--tissue-limit inf it is the seed's neo-Hookean, which never stiffens: under that
glue the lips stretch 7x and hold.

Writes OUTPUT (MP4) and OUTPUT's stem + .saliva.csv (--csv; per frame: time,
jaw, broken fraction of the film along the seam, number and span of openings
along the seam, centre gap, largest stretch). The state is saved after every
frame in OUTPUT.checkpoint/, removed when the run completes or diverges. Glue profiles:
WHERE=VALUE items over --glue, WHERE one of centre (the mouth's central twelfth),
left, right, corners, all or a range a..b of the position across the mouth
(-1 right corner .. +1 left corner). Exit status 3: the simulation diverged
(the message says where and what to try).
"""


def register(subparsers) -> None:
    from visemeface.physics.drive import PHYSICS, SCENARIOS, SIDES

    p = subparsers.add_parser(
        "simulate", help="run the sticky-lip FEM face through a scenario (seed 000/001) -> MP4 + saliva CSV",
        description="Simulate the physically-based sticky-lip face (TLED FEM, breaking saliva elements) "
        "through a scenario and write the animation and the saliva state per frame.",
        epilog=EPILOG, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("scenario", choices=sorted(SCENARIOS), help="the jaw eased to --jaw and back: open: opened "
                   "and closed twice; open-once: opened and held; part: opened to 0.45 of --jaw and held (a "
                   "slight opening the speech lips' glue holds shut; elastic lips part)")
    phys = opt.add_physics_arguments(p, "sticky", tuple(PHYSICS))
    phys.add_argument("--glue-file", type=Path, metavar="CSV", help="glue per film element (element,glue; "
                      "0 at the right corner, in order across the mouth) or a profile (s,glue)")
    phys.add_argument("--critical-moisture", type=float, metavar="MC", help="critical moisture Mc (default 100)")
    phys.add_argument("--dt", type=float, help="one time step in s for every node (default: multi-rate, the "
                      "tissue's stable step with the lips' film nodes in substeps at the film's, printed at the "
                      "end; a step above the film's limit is refused)")
    phys.add_argument("--damping", type=float, default=80.0, help="mass damping alpha in 1/s (default 80)")
    phys.add_argument("--jaw", type=float, default=0.35, help="jaw activation when open (default 0.35)")
    phys.add_argument("--side", choices=SIDES, default="both",
                      help="also pull the lower lip down on one side (asymmetric opening)")
    phys.add_argument("--resolution", type=int, help="face vertices (default: the default face's)")
    phys.add_argument("--threads", type=int, help="numba threads (default: the faster of all cores and one, "
                      "timed during the run; the result is the same at any count)")
    p.add_argument("--fps", type=float, default=60.0, help="frame rate (default 60, the seed's camera)")
    opt.add_render_arguments(p, view="mouth")
    opt.add_output_arguments(p, "SCENARIO.mp4", resumable="continue an interrupted run from its checkpoint")
    p.set_defaults(func=run)


def _check(args) -> None:
    from visemeface.errors import InputError

    opt.check_fps_option(args.fps)
    if not (math.isfinite(args.jaw) and 0 <= args.jaw <= 1):
        raise InputError(f"--jaw must be an activation from 0 to 1, got {args.jaw}")
    for name in ("dt", "damping"):
        value = getattr(args, name)
        if value is None:
            continue
        if not (math.isfinite(value) and value > 0 if name == "dt" else math.isfinite(value) and value >= 0):
            raise InputError(f"--{name} must be a finite number {'> 0' if name == 'dt' else '>= 0'}, got {value:g}")
    if args.resolution is not None and not 300 <= args.resolution <= 200_000:
        raise InputError(f"--resolution must be from 300 to 200000 vertices, got {args.resolution}")


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
    face = default_face(resolution=args.resolution)
    rig = MuscleRig.from_file(face)
    track = scenario_track(args.scenario, rig.names, fps=args.fps, jaw=args.jaw, side=args.side)
    motion = opt.simulation_of(rig, track, args.physics, physics)          # every input check happens here
    checkpoint = opt.checkpoint_of(motion, sinks, args)
    stats = pipeline.run(motion, sinks, render,
                         info=dict(rig=rig, track=track, extra={"motion_key": motion.key()}),
                         checkpoint=checkpoint, resume=args.resume, show_progress=not args.quiet)
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
