"""The ``visemeface`` command line: a thin layer that parses and dispatches.

Each sub-command lives in its own module under :mod:`visemeface.commands`
and exposes ``register(subparsers)``, which adds its parser and sets
``func=run`` where ``run(args) -> int``. Modules are discovered, so adding a
command touches no shared file. ``ORDER`` (an int) sorts them in ``--help``.
"""

from __future__ import annotations

import argparse
import importlib
import re
import pkgutil
import signal
import sys
import warnings

from visemeface import __version__, commands
from visemeface.errors import EXIT, VisemefaceError, exit_status


def _command_modules():
    mods = []
    for info in pkgutil.iter_modules(commands.__path__):
        if info.name.startswith("_"):
            continue
        mods.append(importlib.import_module(f"visemeface.commands.{info.name}"))
    return sorted(mods, key=lambda m: (getattr(m, "ORDER", 100), m.__name__))


class UsageError(VisemefaceError):
    """A command line argparse refuses (unknown option, missing or malformed value)."""


class Parser(argparse.ArgumentParser):
    """argparse with the project's error convention: one line, ``visemeface: error:``, exit 2.

    Values that start with a minus sign and a digit (``--box -10,-10,50,20``,
    ``--glue -0.1``) are values, not options: no option of ours looks like a number.
    """

    def __init__(self, *args, **kwargs):
        super().__init__(*args, **kwargs)
        self._negative_number_matcher = re.compile(r"^-\.?\d")

    def error(self, message):
        command = self.prog.removeprefix("visemeface").strip()
        where = f"{command}: " if command else ""
        raise UsageError(f"{where}{message} (see `{self.prog} --help`)")


def build_parser() -> argparse.ArgumentParser:
    parser = Parser(
        prog="visemeface",
        description="Expressive visual-speech synthesis: Waters muscle functions, visemes and emotions, "
        "coarticulated speech animation and a physically-based sticky-lip face.",
        epilog="exit status: 0 done, 2 bad input (one line on stderr, nothing written), "
        "3 a physical simulation diverged, 130 interrupted",
    )
    parser.add_argument("--version", action="version", version=f"visemeface {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    for mod in _command_modules():
        mod.register(sub)
    return parser


def _show_warning(message, category, filename, lineno, file=None, line=None):
    print(f"visemeface: warning: {message}", file=sys.stderr)


def main(argv: list[str] | None = None) -> int:
    parser = build_parser()
    try:
        args, extra = parser.parse_known_args(argv)
        if extra:                         # named by the command they were given to, which lists its options
            commands = next(a.choices for a in parser._actions if isinstance(a, argparse._SubParsersAction))
            commands.get(getattr(args, "command", None), parser).error(f"unrecognized arguments: {' '.join(extra)}")
    except UsageError as exc:
        print(f"visemeface: error: {exc}", file=sys.stderr)
        return 2
    if not getattr(args, "func", None):
        print("visemeface: error: name a command (`visemeface --help` lists them)", file=sys.stderr)
        return 2
    warnings.showwarning = _show_warning
    from visemeface.runtime import configure

    configure()
    previous = _terminate_like_interrupt()
    try:
        return int(args.func(args) or 0)
    except VisemefaceError as exc:
        print(f"visemeface: error: {exc}", file=sys.stderr)
        return exit_status(exc)
    except BrokenPipeError:
        # Output piped into `head` and the like: stop quietly, as Unix tools do.
        import os

        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())
        return 0
    except KeyboardInterrupt:
        print("visemeface: interrupted", file=sys.stderr)
        return EXIT["interrupted"]
    finally:
        if previous is not None:
            signal.signal(signal.SIGTERM, previous)


def _terminate_like_interrupt():
    """Make SIGTERM (``kill``, a CI timeout) unwind like Ctrl-C, so temporary outputs are removed.

    Returns the previous handler, or None when signals cannot be set (not the main thread).
    """
    def handler(signum, frame):
        raise KeyboardInterrupt

    try:
        return signal.signal(signal.SIGTERM, handler)
    except ValueError:
        return None


if __name__ == "__main__":
    raise SystemExit(main())
