"""``visemeface visemes``: list the 56 DECtalk speech postures with their notes."""

from __future__ import annotations

import argparse
import textwrap

ORDER = 40


def register(subparsers) -> None:
    p = subparsers.add_parser(
        "visemes",
        help="list the 56 visemes (DECtalk symbol, class, notes)",
        description="List the 56 speech postures (visemes) of the shipped viseme table: DECtalk index "
        "and symbol, articulatory class, the seed-002 perceptual class where it has one, and notes on "
        "the lip shape.",
        formatter_class=argparse.RawDescriptionHelpFormatter,
        epilog="example:\n  visemeface visemes\n  visemeface visemes --csv > visemes.csv",
    )
    p.add_argument("--csv", action="store_true", help="print CSV instead of an aligned table")
    p.add_argument("--table", metavar="CSV", help="viseme table to list (default: the shipped one)")
    p.set_defaults(func=run)


def _perceptual_classes() -> dict[str, str]:
    """DECtalk symbol -> seed 002 Table 2 class, e.g. ``"p" -> "a /p,b,m/"``."""
    from visemeface.postures.phonemes import CLASSES, class_label

    return {s: f"{key} {class_label(key)}" for key, members in CLASSES.items() for s in members}


def run(args) -> int:
    from visemeface.postures.library import viseme_info

    info = viseme_info(args.table)
    classes = _perceptual_classes()
    rows = [(str(int(r["index"])), sym, r["class"], classes.get(sym, ""), r["notes"])
            for sym, r in info.iterrows()]
    if args.csv:
        import csv
        import sys

        w = csv.writer(sys.stdout, lineterminator="\n")
        w.writerow(["index", "symbol", "class", "perceptual_class", "notes"])
        w.writerows(rows)
        return 0
    head = ("#", "symbol", "class", "seed-002 class", "notes")
    widths = [max(len(r[i]) for r in rows + [head]) for i in range(4)]
    indent = sum(widths) + 8
    print("  ".join(h.ljust(w) for h, w in zip(head, widths + [0])).rstrip())
    for r in rows:
        notes = textwrap.wrap(r[4], width=max(30, 110 - indent)) or [""]
        print("  ".join(c.ljust(w) for c, w in zip(r[:4], widths)) + "  " + notes[0])
        for more in notes[1:]:
            print(" " * indent + more)
    return 0
