"""``visemeface compare``: L2 distance, correlation and time offset between mouth-opening profiles (seed 001 §5)."""

from __future__ import annotations

ORDER = 81


def register(subparsers) -> None:
    p = subparsers.add_parser(
        "compare",
        help="L2 distance, Pearson correlation and best time offset between opening profiles (CSV from analyze)",
        description="Compare mouth-opening profiles written by `visemeface analyze`. The first profile is "
        "the reference (e.g. the real mouth); for every other one this prints the L2 distance of the area, "
        "width and height curves, their Pearson correlation r, and the time offset (lag, in frames of the "
        "lower frame rate, within +-MAX_LAG) that maximises the correlation of --lag-metric; a positive lag "
        "means the other profile is late. Profiles are aligned by time: over the time span both cover, at "
        "the sample times of the lower frame rate, interpolating linearly. The plot overlays all profiles, "
        "each other one shifted by its best lag.",
        epilog="example: visemeface compare real.csv sticky.csv nonsticky.csv --plot compare.png",
    )
    p.add_argument("reference", metavar="A.csv", help="reference profile")
    p.add_argument("others", nargs="+", metavar="B.csv", help="profile(s) to compare with the reference")
    p.add_argument("--max-lag", type=int, default=5, metavar="N",
                   help="search time offsets of -N..N frames (default 5; 0 = no search)")
    p.add_argument("--lag-metric", choices=("area", "width", "height"), default="height",
                   help="the metric whose correlation the offset maximises (default height)")
    p.add_argument("--plot", metavar="PNG", help="plot all profiles overlaid, each other one shifted by its lag (.png, .pdf or .svg)")
    p.add_argument("--force", action="store_true", help="overwrite the plot if it exists")
    p.set_defaults(func=run)


def _fmt(v: float, spec: str) -> str:
    return format(v, spec) if v == v else format("nan", ">" + spec.split(".")[0].rstrip("f") + "s")


def run(args) -> int:
    from pathlib import Path

    from visemeface.analysis.profiles import (METRICS, correlation, l2_distance, plot_profiles, read_profile,
                                              shifted_profile)
    from visemeface.errors import InputError
    from visemeface.outputs import check_new, check_suffix

    if args.max_lag < 0:
        raise InputError(f"--max-lag must be >= 0, got {args.max_lag}")
    if args.plot:
        check_new(check_suffix(args.plot, ".png", ".pdf", ".svg"), args.force)
    paths = [args.reference, *args.others]
    profiles = {p: read_profile(p) for p in paths}
    ref = profiles[args.reference]
    rows = []
    for p in args.others:
        try:
            d = l2_distance(ref, profiles[p])
            c = correlation(ref, profiles[p], column=args.lag_metric, max_lag=args.max_lag)
        except InputError as exc:
            raise InputError(f"{p} vs {args.reference}: {exc}") from None
        rows.append((f"{p} vs {args.reference}", d, c))
    width = max(len(r[0]) for r in rows)
    head = [f"L2_{m}" for m in METRICS] + [f"r_{m}" for m in METRICS] + ["lag_frames", f"r_{args.lag_metric}_at_lag"]
    print(" " * width + "".join(f"{h:>12}" for h in head[:-1]) + f"{head[-1]:>18}")
    for name, d, c in rows:
        vals = ("".join(f"{d[m]:12.4f}" for m in METRICS) + "".join(_fmt(c["r"][m], "12.3f") for m in METRICS)
                + f"{c['lag']:+12d}" + _fmt(c["r_lag"], "18.3f"))
        print(name.ljust(width) + vals)
    if args.plot:
        labels = {}
        lags = {p: c["lag_s"] for p, (_, _, c) in zip(args.others, rows)}
        for p in paths:
            label = Path(p).stem
            df = profiles[p]
            if p in lags and p != args.reference and lags[p]:
                label += f" (shifted {-lags[p]:+.3f} s)"
                df = shifted_profile(df, lags[p])
            while label in labels:
                label += "'"
            labels[label] = df
        plot_profiles(labels, args.plot, title="mouth-opening profiles", force=args.force)
        print(f"wrote {args.plot}")
    return 0
