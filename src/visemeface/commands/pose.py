"""``visemeface pose``: render one posture of the muscle rig to a PNG."""

from __future__ import annotations

import argparse

from visemeface.commands import _options as opt

ORDER = 20


def register(subparsers) -> None:
    p = subparsers.add_parser(
        "pose",
        help="render a muscle posture (viseme, emotion, single muscles) to a PNG",
        description="Pose the face with the Waters muscle rig and render it. Start from a viseme "
        "(DECtalk symbol) and/or emotions blended as in Edge & Maddock (2001), then set single muscles with --set. "
        "Activations are clamped to each muscle's range (a warning names them). Prints the lip "
        "dimensions of the pose.",
        formatter_class=opt.Help,
        epilog="examples:\n"
        "  visemeface pose --set zygomatic_major_left=0.8 --set jaw=0.3 -o pose.png\n"
        "  visemeface pose uw --emotion happiness=0.5 --view mouth -o uw_happy.png\n"
        "  visemeface pose --show-muscles -o rig.png\n"
        "  visemeface muscles            (lists the muscle names)",
    )
    p.add_argument("posture", nargs="?", metavar="POSTURE",
                   help="viseme to start from (DECtalk symbol, e.g. aa, uw, m); default: rest")
    p.add_argument("--set", dest="sets", action="append", default=[], metavar="NAME=VALUE",
                   help="set one muscle's activation (repeatable; after the posture and emotions)")
    p.add_argument("--emotion", dest="emotions", action="append", default=[], metavar="NAME[=W]",
                   help="blend an emotion with weight W in 0..1 (default 1; repeatable), e.g. happiness=0.6")
    from visemeface.render import VIEWS

    p.add_argument("--view", default="face", choices=VIEWS, help="camera (default face)")
    p.add_argument("--size", default="512", metavar="W[xH]", help="image size in pixels, multiples of 16 (default 512)")
    opt.add_msaa_argument(p)
    opt.add_face_arguments(p)
    p.add_argument("--show-muscles", action="store_true",
                   help="draw the muscles over the render: attachment -> insertion vectors (blue upper lip, "
                   "orange lower lip, green untrimmed) and the zones of the active muscles")
    p.add_argument("-o", "--output", required=True, metavar="PNG", help="output image")
    p.add_argument("--force", action="store_true", help="overwrite the output if it exists")
    opt.add_quiet(p)
    p.set_defaults(func=run)


def parse_assignments(items, option: str) -> dict[str, float]:
    """``["a=0.5", "b=1"]`` -> ``{"a": 0.5, "b": 1.0}``; InputError naming the bad item."""
    from visemeface.errors import InputError

    out = {}
    for item in items:
        name, sep, value = item.partition("=")
        name = name.strip()
        if not sep or not name:
            raise InputError(f"{option} expects NAME=VALUE, got {item!r}")
        try:
            out[name] = float(value)
        except ValueError:
            raise InputError(f"{option} {name}: value {value!r} is not a number") from None
    return out


def activations(rig, posture, emotions: dict, sets: dict):
    """Activation vector: blend(posture, emotions) when given, then the --set values."""
    import numpy as np

    a = np.zeros(len(rig.names))
    if posture or emotions:
        from visemeface.errors import InputError
        try:
            from visemeface.postures.library import blend
        except ImportError:
            raise InputError("postures and emotions need visemeface.postures.library, "
                             "which is not available") from None
        series = blend(posture or "_", emotions, rig=rig)
        a = rig.activation_vector(dict(series.items()))
    if sets:
        override = rig.activation_vector(sets)
        for name in sets:
            a[rig.index[name]] = override[rig.index[name]]
    return a


def run(args) -> int:
    from visemeface.muscles.measure import lip_dimensions
    from visemeface.outputs import check_new, check_suffix
    from visemeface.render.renderer import Renderer, save_png

    check_new(check_suffix(args.output, ".png"), args.force)
    from visemeface.render.renderer import parse_size

    size = parse_size(args.size)
    from visemeface.pipeline import check_msaa

    check_msaa(args.msaa)
    sets = parse_assignments(args.sets, "--set")
    from visemeface.animate import parse_emotions
    from visemeface.commands._options import build_rig
    from visemeface.postures.library import load_expressions

    rig = build_rig(args)
    emotions = parse_emotions(args.emotions or None, load_expressions(rig=rig).index)
    a = activations(rig, args.posture, emotions, sets)
    vertices = rig.pose(a)
    with Renderer(rig.face, size=size, view=args.view, samples=args.msaa) as renderer:
        image = renderer.render(vertices)
        if args.show_muscles:
            from visemeface.muscles.overlay import draw_muscles
            active = [n for n, v in zip(rig.names, a) if v != 0 and n != "jaw"]
            # Every muscle's vector; zones only of the active ones (all of them would hide the face).
            image = draw_muscles(image, renderer, rig, zones=False)
            if active:
                image = draw_muscles(image, renderer, rig, active, zones=True)
    save_png(args.output, image, force=args.force)
    if args.quiet:
        return 0
    active = ", ".join(f"{n}={v:g}" for n, v in zip(rig.names, a) if v != 0) or "rest"
    print(f"pose: {active}")
    dims = lip_dimensions(rig.face, vertices)
    print("lips: " + ", ".join(f"{k}={1000 * dims[k]:.1f} mm" for k in
                               ("mouth_width", "opening_height", "protrusion", "upper_lip_raise",
                                "lower_lip_drop", "corner_height")))
    print(f"wrote {args.output}")
    return 0
