"""MkDocs hooks of the visemeface site (``hooks:`` in mkdocs.yml).

* The navigation is built from the files: the home page, the guide (one page per command in the order of
  ``visemeface --help``, then any other page of ``docs/guide/`` by name), the output formats (index first),
  the physics model, the evaluation, the API reference, the conventions and the notes. A page added to one
  of those folders appears by itself; a page elsewhere must be added to ``SECTIONS`` below.
* ``<!-- visemeface-help COMMAND -->`` in a page is replaced by that command's ``--help-all`` text (every option), so option
  lists are never out of date.
"""

from __future__ import annotations

import os
import re
from pathlib import Path

DOCS = Path(__file__).resolve().parent
HELP = re.compile(r"<!--\s*visemeface-help\s+([a-z-]+)\s*-->")


def command_order() -> dict[str, int]:
    """Sub-command name -> its place in ``visemeface --help`` (the commands' ``ORDER``)."""
    from visemeface.cli import _command_modules

    return {m.__name__.rsplit(".", 1)[-1]: i for i, m in enumerate(_command_modules())}


def guide_pages(docs: Path = DOCS) -> list[Path]:
    """docs/guide/*.md: the commands' pages in the CLI's order, then the others by name."""
    order = command_order()
    return sorted((docs / "guide").glob("*.md"), key=lambda p: (order.get(p.stem, len(order)), p.stem))


def _title(path: Path) -> str:
    for line in path.read_text(encoding="utf-8").splitlines():
        if line.startswith("# "):
            return line[2:].strip()
    return path.stem.replace("_", " ").replace("-", " ").capitalize()


def _folder(name: str, first: str | None = None) -> list:
    pages = sorted((DOCS / name).glob("*.md"), key=lambda p: (p.stem != (first or ""), p.stem))
    return [{_title(p): f"{name}/{p.name}"} for p in pages]


def navigation() -> list:
    return [
        {"Home": "index.md"},
        {"Guide": [{_title(p): f"guide/{p.name}"} for p in guide_pages()]},
        {"Output formats": _folder("formats", first="index")},
        {"The physics model": "physics.md"},
        {"Evaluation against real video": "evaluation.md"},
        {"API reference": _folder("reference", first="index")},
        {"Conventions": "conventions.md"},
        {"Notes": _folder("notes", first="index")},
    ]


def on_config(config, **kwargs):
    config["nav"] = navigation()
    return config


def _help_text(command: str) -> str:
    import argparse

    from visemeface.cli import build_parser

    os.environ["COLUMNS"] = "100"
    sub = next(a for a in build_parser()._actions if isinstance(a, argparse._SubParsersAction))
    if command not in sub.choices:
        raise ValueError(f"visemeface-help: no command {command!r}")
    parser = sub.choices[command]
    return getattr(parser, "format_help_all", parser.format_help)().rstrip()       # every option, not --help's few


def on_page_markdown(markdown, page, config, files, **kwargs):
    return HELP.sub(lambda m: "```text\n" + _help_text(m.group(1)) + "\n```", markdown)
