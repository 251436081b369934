"""``visemeface muscles``: list the rig's muscles (name, kind, side, range, lip side)."""

from __future__ import annotations

from visemeface.commands._options import Help, rig_help

ORDER = 21


def register(subparsers) -> None:
    p = subparsers.add_parser(
        "muscles",
        help="list the rig's functions: 25 face muscles, tongue, lip-shaping and lid functions, the jaw",
        description="List the functions of the Waters muscle rig: name (use it with "
        "`visemeface pose --set NAME=VALUE`), kind (linear and sphincter: Waters's; local: a Gaussian push; "
        "turn: gaze; rotation: the jaw), side, activation range (values outside are clamped) and lip side "
        "(upper-lip muscles move nothing below the lip seam, lower-lip muscles nothing above it, both: not "
        "trimmed).",
        formatter_class=Help,
        epilog="examples:\n  visemeface muscles\n  visemeface muscles --csv > muscles.csv",
    )
    p.add_argument("--csv", action="store_true", help="print CSV instead of an aligned table")
    p.add_argument("--rig", metavar="TOML", help=rig_help())
    p.set_defaults(func=run)


def run(args) -> int:
    from visemeface.commands._options import build_rig, print_table
    from visemeface.muscles.rig import SPEECH_FUNCTIONS

    rig = build_rig(args)
    table = rig.table()
    table["speech"] = ["yes" if n in SPEECH_FUNCTIONS else "" for n in table.index]
    table["description"] = [m.description for m in rig.muscles] + ["opens the mouth (rotation about the jaw joints)"]
    if args.csv:
        import sys

        table.to_csv(sys.stdout, lineterminator="\n")
        return 0
    rows = [(n, r["kind"], r["side"], f"{r['min']:g}..{r['max']:g}", r["lip"], r["speech"], r["description"])
            for n, r in table.iterrows()]
    print_table(("name", "kind", "side", "range", "lip", "speech", "description"), rows)
    return 0
