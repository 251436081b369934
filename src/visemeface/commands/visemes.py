"""``visemeface visemes``: list the 56 DECtalk speech postures with their notes."""

from __future__ import annotations

import argparse

from visemeface.commands._options import Help, print_table

ORDER = 40


def register(subparsers) -> None:
    p = subparsers.add_parser(
        "visemes",
        help="list the 56 visemes (DECtalk symbol, class, notes)",
        description="List the 56 speech postures (visemes) of the shipped viseme table: DECtalk index "
        "and symbol, articulatory class, the Edge & Maddock (2001) perceptual class where it has one, and notes on "
        "the lip shape.",
        formatter_class=Help,
        epilog="example:\n  visemeface visemes\n  visemeface visemes --csv > visemes.csv",
    )
    p.add_argument("--csv", action="store_true", help="print CSV instead of an aligned table")
    p.add_argument("--table", metavar="CSV", help="viseme table to list (default: the shipped one)")
    p.set_defaults(func=run)


def _perceptual_classes() -> dict[str, str]:
    """DECtalk symbol -> Edge & Maddock (2001) Table 2 class, e.g. ``"p" -> "a /p,b,m/"``."""
    from visemeface.postures.phonemes import CLASSES, class_label

    return {s: f"{key} {class_label(key)}" for key, members in CLASSES.items() for s in members}


def run(args) -> int:
    from visemeface.postures.library import viseme_info

    info = viseme_info(args.table)
    classes = _perceptual_classes()
    rows = [(str(int(r["index"])), sym, r["class"], classes.get(sym, ""), r["notes"])
            for sym, r in info.iterrows()]
    head = ("index", "symbol", "class", "perceptual_class", "notes") if args.csv else \
        ("#", "symbol", "class", "Edge & Maddock class", "notes")
    print_table(head, rows, args.csv)
    return 0
