"""``visemeface compare``: L2 distance, correlation and time offset between mouth-opening profiles (Leach & Maddock 2019, §5)."""

from __future__ import annotations

ORDER = 81

#: Largest --max-lag, in frames: 33 s at 30 fps, far beyond any offset between two takes of one sentence
#: (and the search costs one correlation per lag: 999999999999 never ended).
MAX_LAG = 1000


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
    from visemeface.commands._options import number

    p.add_argument("--max-lag", type=number(0, MAX_LAG, integer=True), default=5, metavar="N",
                   help=f"search time offsets of -N..N frames, N up to {MAX_LAG} (default 5; 0 = no search)")
    p.add_argument("--span", default="all", metavar="all|speech|T0..T1",
                   help="the time span compared: all (default: all both profiles cover), speech (the speech "
                   "span of --audio's sound, found relative to its noise floor), "
                   "or T0..T1 in seconds")
    p.add_argument("--audio", metavar="FILE", help="recording or video whose sound gives --span speech (e.g. the "
                   "real clip the reference profile was measured on)")
    p.add_argument("--lag-metric", choices=("area", "width", "height"), default="height",
                   help="the metric whose correlation the offset maximises (default height)")
    p.add_argument("--plot", metavar="PNG", help="plot all profiles overlaid, each other one shifted by its lag (.png, .pdf or .svg)")
    p.add_argument("--force", action="store_true", help="overwrite the plot if it exists")
    p.set_defaults(func=run)


def _span(args):
    """(t0, t1) of ``--span`` (None: all), ``--audio`` checked; the speech span read from the audio."""
    from visemeface.commands._options import check_number
    from visemeface.errors import InputError

    text = str(args.span).strip().lower()
    if text != "speech" and args.audio is not None:
        raise InputError("--audio gives the speech span: it needs --span speech")
    if text == "all":
        return None
    if text == "speech":
        if args.audio is None:
            raise InputError("--span speech needs --audio FILE, the recording whose speech span is compared")
        from visemeface.speech.audio import read_audio, speech_span

        samples, rate = read_audio(args.audio)
        return speech_span(samples, rate, where=args.audio)
    ends = text.split("..")
    if len(ends) != 2:
        raise InputError(f"--span must be all, speech or T0..T1 (seconds), got {args.span!r}")
    t0, t1 = (check_number(v, "--span", 0, 86_400, what="seconds") for v in ends)
    if not t1 > t0:
        raise InputError(f"--span must end after it starts, got {args.span!r}")
    return t0, t1


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
    span = _span(args)
    if args.plot:
        check_new(check_suffix(args.plot, ".png", ".pdf", ".svg"), args.force)
    paths = [args.reference, *args.others]
    profiles = {p: read_profile(p) for p in paths}
    if span is not None:
        from visemeface.analysis.profiles import within

        profiles = {p: within(df, *span) for p, df in profiles.items()}
        print(f"over {span[0]:.2f}..{span[1]:.2f} s" + (" (the speech of " + str(args.audio) + ")"
                                                       if args.span.strip().lower() == "speech" else ""))
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
