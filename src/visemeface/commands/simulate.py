"""``visemeface simulate SCENARIO``: the sticky-lip FEM face in one of the seed's experiments.

Builds the FEM face (lower face extruded to hexahedra, saliva between the
lips), drives it with a scenario's activation track, and writes the motion
(MP4, PNG frames, OBJ sequence, PC2) and a per-frame CSV of the saliva state.
The run checkpoints every few frames; after Ctrl-C, ``--resume`` continues
from the last checkpoint.
"""

from __future__ import annotations

import math

import argparse
from pathlib import Path

ORDER = 60

EPILOG = """\
examples:
  visemeface simulate open --glue 0.08 -o open.mp4        # jaw lowered and raised twice (seed 001 Fig. 18)
  visemeface simulate open --physics elastic -o open_elastic.mp4   # the same FEM without glue
  visemeface simulate open-once --glue-profile centre=0.18 -o two.mp4   # two openings that merge
  visemeface simulate open --evaporation 40 -o dry.mp4    # later openings unzip faster
  visemeface simulate open-once --side left -o left.mp4   # one-sided lower-lip pull: asymmetric opening
  visemeface simulate open -o open.mp4 --resume           # continue an interrupted run

Writes OUTPUT (MP4) and OUTPUT's stem + .saliva.csv (per frame: time, broken
fraction, number and span of openings along the seam, centre gap, largest
stretch). The checkpoint OUTPUT's stem + .checkpoint.npz is removed when the
run completes. Glue profiles: WHERE=VALUE items over --glue, WHERE one of
centre, left, right, corners, all or a range a..b of the position across the
mouth (-1 right corner .. +1 left corner).
"""


def register(subparsers) -> None:
    from visemeface.physics.drive import PHYSICS, SCENARIOS, SIDES

    p = subparsers.add_parser(
        "simulate", help="run the sticky-lip FEM face through a scenario (seed 000/001) -> MP4 + saliva CSV",
        description="Simulate the physically-based sticky-lip face (TLED FEM, breaking saliva elements) "
        "through a scenario and write the animation and the saliva state per frame.",
        epilog=EPILOG, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("scenario", choices=sorted(SCENARIOS), help="open: opened and closed twice; open-once: "
                   "opened and held; part: a slight opening")
    p.add_argument("-o", "--output", type=Path, help="MP4 to write (default SCENARIO.mp4)")
    phys = p.add_argument_group("physics")
    phys.add_argument("--physics", choices=PHYSICS, default="sticky",
                      help="sticky (default) or elastic: the same FEM with no glue")
    phys.add_argument("--glue", type=float, default=0.08, help="glue strength K_glue (default 0.08)")
    phys.add_argument("--glue-profile", metavar="SPEC", help="glue across the mouth, e.g. centre=0.18")
    phys.add_argument("--glue-file", type=Path, metavar="CSV", help="glue per element (element,glue) or "
                      "profile (s,glue)")
    phys.add_argument("--moisture", type=float, default=100.0, help="initial moisture 0M (default 100)")
    phys.add_argument("--critical-moisture", type=float, default=100.0, help="critical moisture Mc (default 100)")
    phys.add_argument("--evaporation", type=float, default=0.0, help="evaporation rate per second (default 0)")
    phys.add_argument("--dt", type=float, default=1e-5, help="largest time step in s (default 1e-5)")
    phys.add_argument("--damping", type=float, default=80.0, help="mass damping alpha in 1/s (default 80)")
    phys.add_argument("--jaw", type=float, default=0.35, help="jaw activation when open (default 0.35)")
    phys.add_argument("--side", choices=SIDES, default="both",
                      help="also pull the lower lip down on one side (asymmetric opening)")
    phys.add_argument("--resolution", type=int, help="face vertices (default: the default face's)")
    phys.add_argument("--threads", type=int, help="numba threads (default: all cores)")
    out = p.add_argument_group("outputs")
    out.add_argument("--fps", type=float, default=60.0, help="frame rate (default 60, the seed's camera)")
    out.add_argument("--size", type=int, default=512, help="frame size in pixels, multiple of 16 (default 512)")
    out.add_argument("--view", choices=("face", "mouth", "three-quarter"), default="mouth",
                     help="camera (default mouth)")
    out.add_argument("--no-video", action="store_true", help="write no MP4")
    out.add_argument("--frames", type=Path, metavar="DIR", help="also write a PNG per frame")
    out.add_argument("--obj", type=Path, metavar="DIR", help="also write an OBJ per frame")
    out.add_argument("--pc2", type=Path, metavar="FILE.pc2", help="also write a PC2 point cache")
    out.add_argument("--csv", type=Path, metavar="FILE.csv", help="saliva state CSV (default OUTPUT stem"
                     " + .saliva.csv)")
    out.add_argument("--checkpoint-every", type=int, default=10, metavar="N",
                     help="frames between checkpoints (default 10)")
    out.add_argument("--resume", action="store_true", help="continue from the checkpoint of an interrupted run")
    out.add_argument("--force", action="store_true", help="overwrite existing outputs")
    out.add_argument("-q", "--quiet", action="store_true", help="no progress bar or summary")
    p.set_defaults(func=run)


def _paths(args):
    from visemeface.errors import InputError
    from visemeface.outputs import check_new

    video = None if args.no_video else (args.output or Path(f"{args.scenario}.mp4"))
    stem = (args.output or Path(f"{args.scenario}.mp4")).with_suffix("")
    csv = args.csv or Path(f"{stem}.saliva.csv")
    ckpt = Path(f"{stem}.checkpoint.npz")
    if video is not None and video.suffix.lower() != ".mp4":
        raise InputError("video output must end in .mp4", video)
    if args.size <= 0 or args.size % 16:
        raise InputError(f"--size must be a positive multiple of 16, got {args.size}")
    if args.checkpoint_every < 1:
        raise InputError(f"--checkpoint-every must be >= 1, got {args.checkpoint_every}")
    if not (math.isfinite(args.fps) and 1 <= args.fps <= 10_000):
        raise InputError(f"--fps must be a number from 1 to 10000, got {args.fps}")
    if not (math.isfinite(args.jaw) and 0 <= args.jaw <= 1):
        raise InputError(f"--jaw must be an activation from 0 to 1, got {args.jaw}")
    sidecar = None
    if video is not None:
        from visemeface.pipeline import video_sidecar

        sidecar = video_sidecar(video)
    for path in (video, sidecar, csv, args.frames, args.obj, args.pc2):
        if path is not None:
            check_new(path, args.force)
    if args.resume and not ckpt.exists():
        raise InputError("no checkpoint to resume from", ckpt)
    if not args.resume and ckpt.exists() and not args.force:
        raise InputError("a checkpoint of an interrupted run exists; use --resume to continue it or "
                         "--force to start over", ckpt)
    return video, csv, ckpt


def build_simulation(args):
    """The face, model, rig, track and :class:`StickySimulation` of the options (checks everything)."""
    from visemeface.face.procedural import default_face
    from visemeface.muscles.rig import MuscleRig
    from visemeface.physics.drive import PhysicsSettings, StickySimulation, scenario_track
    from visemeface.physics.face_model import build_fem_face
    from visemeface.physics.saliva import SalivaParams

    params = SalivaParams(initial_moisture=args.moisture, critical_moisture=args.critical_moisture,
                          evaporation=args.evaporation)
    settings = PhysicsSettings(dt=args.dt, damping=args.damping, glue=args.glue,
                               glue_profile=args.glue_profile,
                               glue_file=None if args.glue_file is None else str(args.glue_file), saliva=params)
    face = default_face(resolution=args.resolution)
    rig = MuscleRig.from_file(face)
    fem = build_fem_face(face)
    track = scenario_track(args.scenario, rig.names, fps=args.fps, jaw=args.jaw, side=args.side)
    return fem, rig, track, StickySimulation(fem, rig, track, physics=args.physics, settings=settings)


def _save_checkpoint(path, sim, frame, motion, rows):
    import numpy as np
    import pandas as pd

    from visemeface.outputs import atomic_output

    state = sim.checkpoint(frame)
    with atomic_output(path, force=True) as tmp:
        with open(tmp, "wb") as fh:
            np.savez(fh, motion=np.asarray(motion, dtype=np.float32),
                     rows=pd.DataFrame(rows).to_numpy(dtype=np.float64),
                     columns=np.array(list(rows[0].keys())), **state)


def _load_checkpoint(path, sim):
    import numpy as np

    from visemeface.errors import InputError

    with np.load(path, allow_pickle=False) as z:
        data = {k: z[k] for k in z.files}
    if str(data["fingerprint"]) != sim.fingerprint():
        raise InputError("checkpoint belongs to a different run (other options or model); "
                         "use the same options, or --force to start over", path)
    cols = [str(c) for c in data["columns"]]
    rows = [dict(zip(cols, r)) for r in data["rows"].tolist()]
    return data, list(data["motion"]), rows


def run(args) -> int:
    import time

    import numpy as np
    import pandas as pd

    from visemeface.outputs import atomic_output, progress

    video, csv, ckpt = _paths(args)
    if args.threads is not None:
        from visemeface.runtime import set_threads
        set_threads(args.threads)
    fem, rig, track, sim = build_simulation(args)          # every input check happens here
    motion, rows, start = [], [], None
    if args.resume:
        start, motion, rows = _load_checkpoint(ckpt, sim)
    t0 = time.perf_counter()
    bar = _NullBar() if args.quiet else progress(total=sim.n_frames, desc=f"simulate {args.scenario}",
                                                   unit="frame", initial=len(motion))
    try:
        for fr in sim.frames(start):
            motion.append(fr.display.astype(np.float32))
            rows.append({"frame": fr.index, "time": fr.time, "jaw": float(track["jaw"].iloc[fr.index]),
                         **fr.saliva})
            bar.update(1)
            bar.set_postfix_str(f"t={fr.time:.3f}/{sim.duration:.3f} s simulated, "
                                f"broken {fr.saliva['broken_fraction']:.0%}")
            if (fr.index + 1) % args.checkpoint_every == 0 and fr.index + 1 < sim.n_frames:
                _save_checkpoint(ckpt, sim, fr, motion, rows)
    finally:
        bar.close()
    wall = time.perf_counter() - t0
    _write_outputs(args, fem, np.stack(motion), pd.DataFrame(rows), video, csv, track.attrs["fps"])
    ckpt.unlink(missing_ok=True)
    if not args.quiet:
        c = fem.counts()
        print(f"FEM face: {c['nodes']} nodes, {c['elements']} hexahedra ({c['saliva']} saliva); "
              f"dt {sim.dt:.4g} s; {wall:.1f} s wall for {sim.duration:.2f} s simulated")
        for path in (video, csv, args.frames, args.obj, args.pc2):
            if path is not None:
                print(f"wrote {path}")
    return 0


class _NullBar:
    def update(self, n=1):
        pass

    def set_postfix_str(self, s):
        pass

    def close(self):
        pass


def _write_outputs(args, fem, motion, table, video, csv, fps):
    from visemeface.outputs import atomic_output
    from visemeface.render import export

    with atomic_output(csv, force=args.force) as tmp:
        table.to_csv(tmp, index=False, float_format="%.6g")
    if args.obj is not None:
        with export.ObjSequenceWriter(args.obj, [fem.face.quads, fem.face.tris], force=args.force) as w:
            for i, v in enumerate(motion):
                w.write(i, v)
    if args.pc2 is not None:
        with export.Pc2Writer(args.pc2, motion.shape[1], force=args.force) as w:
            for v in motion:
                w.write(v)
    if video is None and args.frames is None:
        return
    from contextlib import ExitStack

    from visemeface.render.renderer import Renderer
    renderer = Renderer(fem.face, size=(args.size, args.size), view=args.view)
    with ExitStack() as stack:
        vw = stack.enter_context(export.VideoWriter(video, (args.size, args.size), fps=fps, force=args.force,
                                                    n_frames=len(motion))) if video is not None else None
        pw = stack.enter_context(export.PngSequenceWriter(args.frames, force=args.force)) \
            if args.frames is not None else None
        for i, v in enumerate(motion):
            img = renderer.render(v)
            if vw is not None:
                vw.write(img)
            if pw is not None:
                pw.write(i, img)
    if video is not None:
        from visemeface.analysis.video import write_sidecar
        from visemeface.pipeline import video_sidecar

        write_sidecar(video_sidecar(video), renderer.mouth_box(), fps=fps, size=(args.size, args.size),
                      force=args.force)
