"""``visemeface emotions``: list the emotions with their FACS action units."""

from __future__ import annotations

import textwrap

ORDER = 41


def register(subparsers) -> None:
    p = subparsers.add_parser(
        "emotions",
        help="list the emotions (name, FACS action units, muscles)",
        description="List the emotions of the shipped expression table with the FACS action units they "
        "are built from and the muscles they activate. Blend one with a viseme in `visemeface pose`, "
        "e.g. `--emotion happiness=0.6`.",
    )
    p.add_argument("--table", metavar="CSV", help="expression table to list (default: the shipped one)")
    p.set_defaults(func=run)


def run(args) -> int:
    from visemeface.postures.library import expression_info, load_expressions

    info = expression_info(args.table)
    acts = load_expressions(args.table)
    width = max(len(e) for e in info.index)
    for name, row in info.iterrows():
        active = acts.loc[name]
        active = active[active != 0]
        muscles = ", ".join(f"{m}={v:g}" for m, v in active.items())
        lines = textwrap.wrap(row["action_units"], width=100 - width) or [""]
        lines += textwrap.wrap("muscles: " + muscles, width=100 - width)
        print(name.ljust(width) + "  " + lines[0])
        for line in lines[1:]:
            print(" " * (width + 2) + line)
    return 0
