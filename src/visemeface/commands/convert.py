"""``visemeface convert IN OUT``: move a take between tools (mouth cues, weights, tracks, engines' formats).

IN is read by :func:`visemeface.convert.read_take`; OUT is any output of the animating commands that needs
no rendering or simulation, chosen by its suffix (``--to`` where the suffix is shared).
"""

from __future__ import annotations

import argparse
from pathlib import Path

from visemeface.commands import _options as opt

ORDER = 24

EPILOG = """\
examples:
  visemeface convert take.tsv take.anim                 # Rhubarb cues -> a Unity blendshape clip
  visemeface convert livelink.csv take.vmd              # a Live Link Face take -> MMD morph frames
  visemeface convert take.json take.csv --to livelink   # Rhubarb JSON -> a Live Link CSV
  visemeface convert take.pgo take.vtt                  # a Papagayo project's words -> WebVTT captions
  visemeface convert take.dat take.json --to rhubarb --dat-fps 30

Reads: Rhubarb Lip Sync .tsv .json .xml, Moho switch data .dat, Papagayo .pgo, the weights CSV/JSON of
--arkit/--vrm/--oculus, Live Link Face CSV, Audio2Face JSON, a track CSV (--track), a visemeface .glb.
Mouth cues are the phones of their shapes, animated as `speak` does; weights are played on the face
as a blend-shape client plays them and fitted again for the output. Curves are re-sampled at --fps.
"""


def writable() -> dict:
    """The sinks convert writes: every registered one that needs no rendered image, simulation or folder."""
    from visemeface.export import SINKS

    return {n: c for n, c in SINKS.items() if not (c.needs_image or c.needs_physics or c.folder)}


def register(subparsers) -> None:
    from visemeface.export.rhubarb import dat_fps
    from visemeface.speech.timeline import MODES

    p = subparsers.add_parser(
        "convert", help="convert a lip-sync take between formats (Rhubarb, Moho, ARKit/Live Link, Unity, ...)",
        description="Read a take (mouth cues, per-frame weights, an activation track or a glb) and write it in "
        "another tool's format, its curves re-sampled and its shapes mapped through the retargeting tables.",
        epilog=EPILOG, formatter_class=opt.Help)
    p.add_argument("input", type=Path, metavar="IN", help="the take to read")
    p.add_argument("output", type=Path, metavar="OUT", help="the file to write (its format from the suffix)")
    p.add_argument("--to", choices=tuple(writable()), help="the output's format where its suffix is shared "
                   "(.csv: arkit, livelink, vrm, oculus, track; .json: arkit, vrm, oculus, rhubarb, audio2face; "
                   "default: the input's own where it is one of them)")
    p.add_argument("--fps", type=float, help="frame rate of the output (default: the input's; 30 for mouth cues)")
    p.add_argument("--interp", choices=MODES, default=MODES[0],
                   help="interpolation between the phones of mouth cues (default: coarticulation)")
    p.add_argument("--dat-fps", dest="dat_fps", type=dat_fps, metavar="FPS",
                   help="frame rate of a Moho .dat input, and of a .dat output (default 24, as Rhubarb's)")
    g = p.add_argument_group("output settings")
    for name, cls in writable().items():
        for flags, kw in cls.arguments:
            if kw["dest"] != "dat_fps":
                g.add_argument(*flags, **kw)
    p.add_argument("--force", action="store_true", help="overwrite OUT")
    opt.add_quiet(p)
    p.set_defaults(func=run)


def choose_sink(out: Path, to: str | None, take=None) -> str:
    """The output format: ``--to``, else the one sink whose suffix OUT has, else (a suffix several write)
    the input's own: Rhubarb's for mouth cues read from Rhubarb or Moho, the weights' vocabulary."""
    from visemeface.errors import InputError

    sinks = writable()
    name = out.name.lower()
    if to is not None:
        return to
    if name.endswith(".motion3.json"):
        return "live2d"
    fits = [n for n, c in sinks.items() if out.suffix.lower() in c.suffixes and n != "live2d"]
    if len(fits) == 1:
        return fits[0]
    if not fits:
        known = sorted({s for c in sinks.values() for s in c.suffixes})
        raise InputError(f"convert writes {' '.join(known)} (and .motion3.json); not {out.suffix or 'no suffix'}", out)
    own = None if take is None else ("rhubarb" if take.format.startswith(("rhubarb", "moho")) else take.vocabulary)
    if own in fits:
        return own
    raise InputError(f"a {out.suffix} file may be {', '.join(fits)}: say which with --to", out)


def make_sink(args, name: str):
    from visemeface.errors import InputError

    cls = writable()[name]
    own = {kw["dest"]: getattr(args, kw["dest"], kw.get("default")) for _, kw in cls.arguments}
    if name == "rhubarb" and args.output.suffix.lower() != ".dat":
        own.pop("dat_fps", None)
    for other, c in writable().items():
        for flags, kw in c.arguments:
            if other != name and kw["dest"] != "dat_fps" and getattr(args, kw["dest"], None) not in (
                    None, False, kw.get("default")):
                raise InputError(f"{flags[0]} is a setting of the {other} output; OUT is {name}")
    return cls(args.output, force=args.force, **own)


def run(args) -> int:
    from visemeface.convert import read_take, write_take
    from visemeface.errors import InputError
    from visemeface.outputs import check_not_inputs
    from visemeface.track import check_fps

    if not args.input.is_file():
        raise InputError("input not found", args.input)
    fps = None if args.fps is None else check_fps(args.fps, "--fps")
    take = read_take(args.input, dat_fps=args.dat_fps or 24.0)
    sink = make_sink(args, choose_sink(args.output, args.to, take))
    check_not_inputs(sink.targets(), [args.input])
    stats = write_take(take, sink, fps=fps, interp=args.interp, show_progress=not args.quiet)
    if not args.quiet:
        print(f"{args.input} ({take.format}, {take.end:.2f} s) -> " + ", ".join(str(p) for p in stats.written))
    return 0
