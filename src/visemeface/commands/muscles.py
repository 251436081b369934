"""``visemeface muscles``: list the rig's muscles (name, kind, side, range, lip side)."""

from __future__ import annotations

import argparse

ORDER = 21


def register(subparsers) -> None:
    p = subparsers.add_parser(
        "muscles",
        help="list the rig's 25 muscles and the jaw (kind, side, range, lip side)",
        description="List the functions of the Waters muscle rig: name (use it with "
        "`visemeface pose --set NAME=VALUE`), kind (linear, sphincter, rotation), side, activation "
        "range (values outside are clamped) and lip side (upper-lip muscles move nothing below the "
        "lip seam, lower-lip muscles nothing above it, both: not trimmed).",
        formatter_class=argparse.RawDescriptionHelpFormatter,
        epilog="examples:\n  visemeface muscles\n  visemeface muscles --csv > muscles.csv",
    )
    p.add_argument("--csv", action="store_true", help="print CSV instead of an aligned table")
    p.add_argument("--rig", metavar="TOML", help="rig file (default: the shipped data/rig/default.toml)")
    p.set_defaults(func=run)


def run(args) -> int:
    import sys

    from visemeface.muscles.rig import SPEECH_FUNCTIONS, MuscleRig, default_rig

    if args.rig:
        from visemeface.face.procedural import default_face
        rig = MuscleRig.from_file(default_face(), args.rig)
    else:
        rig = default_rig()
    table = rig.table()
    table["speech"] = ["yes" if n in SPEECH_FUNCTIONS else "" for n in table.index]
    table["description"] = [m.description for m in rig.muscles] + ["opens the mouth (rotation about the jaw joints)"]
    if args.csv:
        table.to_csv(sys.stdout, lineterminator="\n")
        return 0
    rows = [(n, r["kind"], r["side"], f"{r['min']:g}..{r['max']:g}", r["lip"], r["speech"], r["description"])
            for n, r in table.iterrows()]
    head = ("name", "kind", "side", "range", "lip", "speech", "description")
    widths = [max(len(str(r[i])) for r in rows + [head]) for i in range(6)]
    for r in [head] + rows:
        print("  ".join(str(c).ljust(w) for c, w in zip(r[:6], widths)) + "  " + r[6])
    return 0
