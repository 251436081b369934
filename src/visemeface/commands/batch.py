"""``visemeface batch MANIFEST -o DIR``: many clips from one CSV manifest, on a Dask cluster."""

from __future__ import annotations

import argparse
import os
import re
import sys
from pathlib import Path

from visemeface.commands import _options as opt

ORDER = 65

EPILOG = """\
examples:
  visemeface batch --grid 200 jobs.csv                  # write a manifest of 200 GRID sentences
  visemeface batch jobs.csv -o corpus --outputs "video gltf" --size 256 --workers 2
  visemeface batch jobs.csv -o corpus --resume          # after an interruption: only the missing clips
  visemeface batch jobs.csv -o corpus --scheduler tcp://head:8786   # any running Dask scheduler

The manifest (CSV, a header row, one row per clip):
  clip,transcript,text,audio,emotion,physics,fps,size,outputs
  swwp2s,,set white with p two soon,,happiness=0.6,,,,video gltf
  take1,takes/take1.TextGrid,,takes/take1.wav,,sticky,60,,video
Only clip and one of transcript/text are needed; an empty cell takes this
command's option (--emotion, --physics, --fps, --size, --outputs ...). Files are
relative to the manifest. Outputs are sink names: %(sinks)s.

Each clip goes to DIR/<clip>/ (video.mp4, frames/, gltf.glb, ..., clip.json),
which appears only when the clip is complete. A bad row or a failing clip does
not stop the others: each is one line on stderr and in DIR/batch_report.csv
(clip, status, seconds, error). Exit status: 0 every clip done, 1 some clips
failed (the others are written), 2 the manifest or an option is unusable.

Without --scheduler a local Dask cluster runs --workers processes of one thread
each. With it, start the cluster with Dask's own tools, e.g. over SSH:
  dask scheduler --port 8786 &                      # on the head node
  dask worker tcp://head:8786 --nworkers 8 --nthreads 1   # on each node (visemeface installed)
and give DIR on a file system every node shares.
"""


def _grid_count(value: str):
    if value == "all":
        return value
    try:
        n = int(value)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a number of sentences or 'all', got {value!r}") from None
    if n < 1:
        raise argparse.ArgumentTypeError(f"expected at least 1 sentence, got {n}")
    return n


def register(subparsers) -> None:
    from visemeface.export import SINKS
    from visemeface.physics import PHYSICS
    from visemeface.render import VIEWS
    from visemeface.speech.timeline import MODES

    p = subparsers.add_parser(
        "batch", help="make many clips from a CSV manifest on a Dask cluster (corpora at scale)",
        description="Make one clip per manifest row (a transcript or text, with its own emotion, physics, "
        "frame rate, size and outputs), on a local Dask cluster or any Dask scheduler; idempotent and resumable.",
        epilog=EPILOG % {"sinks": ", ".join(SINKS)}, formatter_class=opt.Help)
    p.add_argument("manifest", type=Path, metavar="MANIFEST", help="CSV manifest, one row per clip")
    p.add_argument("-o", "--output", type=Path, metavar="DIR",
                   help="output folder, one sub-folder per clip (default: MANIFEST's stem)")
    run = p.add_argument_group("cluster")
    run.add_argument("--workers", type=int, metavar="N", help="processes of the local cluster, one thread each "
                     "(default: the CPU count)")
    run.add_argument("--scheduler", metavar="ADDRESS", help="a running Dask scheduler (tcp://host:8786) or its "
                     "scheduler file (JSON) instead of a local cluster")
    run.add_argument("--resume", action="store_true", help="skip the clips already made with the same settings")
    run.add_argument("--force", action="store_true", help="remake clips that exist")
    opt.add_quiet(run)
    d = p.add_argument_group("defaults for empty manifest cells")
    d.add_argument("--outputs", default="video", metavar="NAMES",
                   help=f"sinks to write, separated by spaces or ';' (default video; from {', '.join(SINKS)})")
    d.add_argument("--emotion", action="append", metavar="NAME[=W]", help="emotion over each clip (repeatable)")
    d.add_argument("--physics", choices=("none",) + tuple(PHYSICS), default="none",
                   help="none: the kinematic rig; sticky/elastic: the FEM face (about 8 s per clip second)")
    d.add_argument("--fps", type=float, default=30.0, help="frame rate (default 30)")
    d.add_argument("--size", type=int, default=512, help="frame width = height in pixels, a multiple of 16 "
                   "(default 512)")
    d.add_argument("--view", choices=VIEWS, default="face", help="camera (default face)")
    d.add_argument("--msaa", type=int, default=4, metavar="N", help="antialiasing samples: 0, 2, 4, 8 or 16")
    d.add_argument("--interp", choices=MODES, default=MODES[0], help="interpolation between visemes")
    d.add_argument("--rate", type=float, metavar="WPM", help="speaking rate of text rows (words per minute)")
    opt.add_face_arguments(p, skin=False)          # workers build the face from face/landmarks/rig only
    g = p.add_argument_group("example corpus")
    g.add_argument("--grid", type=_grid_count, metavar="N|all", help="write MANIFEST: N sentences of the GRID "
                   "corpus's grammar (or all 64,000), then stop")
    g.add_argument("--seed", type=int, default=0, help="random seed of the --grid sample (default 0)")
    p.set_defaults(func=run_command)


#: Dask addresses: a protocol and host:port, or a bare host:port.
_ADDRESS = re.compile(r"^([a-z]+://)?[\w.\-\[\]:]+:\d+$")


def _client(args):
    """A Client on ``--scheduler`` (checked), or None for a local cluster."""
    from visemeface.errors import InputError

    if args.scheduler is None:
        return None
    if args.workers is not None:
        raise InputError("--workers sizes the local cluster; with --scheduler the cluster's workers are its own")
    from distributed import Client

    target = args.scheduler
    if not _ADDRESS.match(target):
        if not Path(target).is_file():
            raise InputError(f"--scheduler must be a Dask scheduler address (tcp://host:8786) or an existing "
                             f"scheduler file, got {target!r}")
        target = _address_in(Path(target))
    try:
        return Client(target, timeout="10s")
    except (OSError, TimeoutError, ValueError) as e:
        raise InputError(f"cannot reach the Dask scheduler at {target} ({str(e).splitlines()[0]})") from None


def _address_in(path: Path) -> str:
    """The scheduler's address in a Dask scheduler file (``dask scheduler --scheduler-file``)."""
    import json

    from visemeface.errors import InputError

    try:
        address = json.loads(path.read_text()).get("address")
    except (OSError, ValueError, AttributeError):
        address = None
    if not isinstance(address, str) or not _ADDRESS.match(address):
        raise InputError("not a Dask scheduler file (a JSON object with the scheduler's address)", path)
    return address


def _settings(args) -> dict:
    from visemeface.batch.manifest import check_settings, defaults
    from visemeface.errors import InputError

    from visemeface.face import BUILTIN_FACES

    s = defaults(outputs=args.outputs, emotion=args.emotion or (), physics=args.physics, fps=args.fps,
                 size=args.size, view=args.view, msaa=args.msaa, interp=args.interp, rate=args.rate,
                 identity=args.identity)
    try:
        check_settings({**s, "text": "check", "face": args.face})
    except InputError as e:
        message = str(e)
        raise InputError(("--" if message.split()[0] in s else "") + message) from None
    if args.face or args.rig or args.landmarks:
        opt.build_rig(args)          # refuse a bad face or rig before any worker starts
    for name in ("face", "landmarks", "rig"):
        value = getattr(args, name)
        builtin = name == "face" and value in BUILTIN_FACES
        s[name] = value if builtin else str(Path(value).resolve()) if value else None
    return s


def run_command(args) -> int:
    from visemeface.batch import read_manifest, run
    from visemeface.batch.runner import REPORT, check_outdir
    from visemeface.errors import InputError

    if args.seed < 0:
        raise InputError(f"--seed must be >= 0, got {args.seed}")
    if args.grid is not None:
        return _write_grid(args)
    if args.workers is not None and args.workers < 1:
        raise InputError(f"--workers must be at least 1, got {args.workers}")
    cores = os.cpu_count() or 1
    if args.workers is not None and args.workers > 4 * cores:   # each a Python process with its own renderer
        raise InputError(f"--workers {args.workers} is over 4 processes a core ({cores} cores here); "
                         "more only compete for them (use --scheduler for a bigger cluster)")
    settings = _settings(args)
    outdir = check_outdir(args.output or Path.cwd() / args.manifest.stem, args.resume, args.force)
    jobs = read_manifest(args.manifest, settings)
    client = _client(args)
    try:
        rows = run(jobs, outdir, client=client, workers=args.workers, resume=args.resume, force=args.force,
                   show_progress=not args.quiet)
    finally:
        if client is not None:
            client.close()
    bad = [r for r in rows if r["status"] in ("error", "failed")]
    for r in bad:
        print(f"visemeface: clip {r['clip']}: {r['status']}: {r['error']}", file=sys.stderr)
    if not args.quiet:
        counts = {s: sum(r["status"] == s for r in rows) for s in ("done", "skipped", "error", "failed")}
        print(f"{len(rows)} clips: " + ", ".join(f"{n} {s}" for s, n in counts.items() if n)
              + f" -> {outdir}/ (report: {outdir / REPORT})")
    return 1 if bad else 0


def _write_grid(args) -> int:
    from visemeface.batch.grid import write_grid_manifest
    from visemeface.errors import InputError

    if args.manifest.suffix.lower() != ".csv":
        raise InputError("the manifest must end in .csv", args.manifest)
    n = None if args.grid == "all" else args.grid
    path = write_grid_manifest(args.manifest, n, seed=args.seed, force=args.force)
    if not args.quiet:
        print(f"{path}: {args.grid} GRID sentences")
    return 0
