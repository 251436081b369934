"""Write docs/reference/options.md: every long option of every command, what it means and which commands
take it, from the command-line parsers (so the table is the program's own; tests/cli/test_names.py checks
that the committed page is what this writes).

    python scripts/options_table.py [--check]
"""

from __future__ import annotations

import argparse
import collections
import sys
from pathlib import Path

PAGE = Path(__file__).resolve().parents[1] / "docs" / "reference" / "options.md"


def options_by_name() -> dict:
    """``{--option: [(command, action), ...]}`` over every sub-command's parser, in the commands' order."""
    from visemeface.cli import build_parser

    sub = next(a for a in build_parser()._actions if isinstance(a, argparse._SubParsersAction))
    found = collections.defaultdict(list)
    for command, parser in sub.choices.items():
        for action in parser._actions:
            if isinstance(action, argparse._HelpAction) or type(action).__name__ == "_HelpAll":
                continue
            for s in action.option_strings:
                if s.startswith("--") and not s.startswith("--no-"):
                    found[s].append((command, action))
    return dict(found)


def _what(action) -> str:
    text = " ".join((action.help or "").split())
    cut = next((i for i in range(len(text)) if text[i] in ";(" and i > 20), len(text))
    text = text[:cut].rstrip(" ,:")
    return (text[:117] + "…" if len(text) > 118 else text).replace("|", "\\|")


def page() -> str:
    rows = []
    for name, uses in sorted(options_by_name().items()):
        commands = ", ".join(sorted({c for c, _ in uses}))
        value = "" if uses[0][1].nargs == 0 else f" {uses[0][1].metavar or uses[0][1].dest.upper()}"
        option = f"`{name}{value}`".replace("|", "\\|")
        rows.append(f"| {option} | {commands} | {_what(uses[0][1])} |")
    return ("# Options across the commands\n\n"
            "One name is one idea: an option that several commands take means the same on each, and takes the same\n"
            "kind of value (`tests/cli/test_names.py` checks it). In Python, the one-call functions\n"
            "(`visemeface.speak(...)` and the others) take the same options by their snake_case names\n"
            "(`--physics-config` is `physics_config=`). Written from the parsers by `python scripts/options_table.py`.\n\n"
            "| option | commands | what (as the first command's help says) |\n|---|---|---|\n"
            + "\n".join(rows) + "\n")


def main(argv=None) -> int:
    ns = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ns.add_argument("--check", action="store_true")
    check = ns.parse_args(argv).check
    text = page()
    if check:
        ok = PAGE.is_file() and PAGE.read_text() == text
        print("up to date" if ok else f"{PAGE} is stale: run python scripts/options_table.py")
        return 0 if ok else 1
    PAGE.write_text(text)
    print(f"{len(text.splitlines()) - 7} options -> {PAGE}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
