"""``visemeface compare``: L2 distances between mouth-opening profiles (seed 001 §5)."""

from __future__ import annotations

ORDER = 81


def register(subparsers) -> None:
    p = subparsers.add_parser(
        "compare",
        help="L2 distances of area, width and height between opening profiles (CSV from analyze)",
        description="Compare mouth-opening profiles written by `visemeface analyze`. The first profile is "
        "the reference (e.g. the real mouth); for every other one the L2 distance of the area, width "
        "and height curves is printed. Profiles are aligned by time: over the time span both cover, "
        "at the sample times of the lower frame rate, interpolating linearly.",
        epilog="example: visemeface compare real.csv sticky.csv nonsticky.csv --plot compare.png",
    )
    p.add_argument("reference", metavar="A.csv", help="reference profile")
    p.add_argument("others", nargs="+", metavar="B.csv", help="profile(s) to compare with the reference")
    p.add_argument("--plot", metavar="PNG", help="plot all profiles overlaid")
    p.add_argument("--force", action="store_true", help="overwrite the plot if it exists")
    p.set_defaults(func=run)


def run(args) -> int:
    from pathlib import Path

    from visemeface.analysis.profiles import METRICS, l2_distance, plot_profiles, read_profile
    from visemeface.errors import InputError
    from visemeface.outputs import check_new, check_suffix

    if args.plot:
        check_new(check_suffix(args.plot, ".png", ".pdf", ".svg"), args.force)
    paths = [args.reference, *args.others]
    profiles = {p: read_profile(p) for p in paths}
    ref = profiles[args.reference]
    rows = []
    for p in args.others:
        try:
            d = l2_distance(ref, profiles[p])
        except InputError as exc:
            raise InputError(f"{p} vs {args.reference}: {exc}") from None
        rows.append((f"{p} vs {args.reference}", d))
    width = max(len(r[0]) for r in rows)
    print(" " * width + "".join(f"{m:>12}" for m in METRICS))
    for name, d in rows:
        print(name.ljust(width) + "".join(f"{d[m]:12.4f}" for m in METRICS))
    if args.plot:
        labels = {}
        for p in paths:
            label = Path(p).stem
            while label in labels:
                label += "'"
            labels[label] = profiles[p]
        plot_profiles(labels, args.plot, title="mouth-opening profiles", force=args.force)
        print(f"wrote {args.plot}")
    return 0
