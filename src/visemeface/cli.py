"""The ``visemeface`` command line: a thin layer that parses and dispatches.

Each sub-command lives in its own module under :mod:`visemeface.commands`
and exposes ``register(subparsers)``, which adds its parser and sets
``func=run`` where ``run(args) -> int``. Modules are discovered, so adding a
command touches no shared file. ``ORDER`` (an int) sorts them in ``--help``.

Interrupts: the first thing :func:`main` does, before any other import, is to
take Ctrl-C and SIGTERM, so that whenever they come they end the command with
one line, "visemeface: interrupted", and exit status 130. While the commands
are imported and the options parsed nothing is written yet, and the process
ends at once (an interrupt raised inside an extension module's import comes
out as some other error, or not at all). Once the command works, the first
signal unwinds as ``KeyboardInterrupt``, so temporary outputs are removed;
whatever error that unwinding ends in, the interrupt is reported, and a second
signal meanwhile ends the process at once. After the work (the interpreter's
shutdown) a signal ends it at once too, with the command's own status: its
outputs are whole. This module imports nothing else at its top (errors.py is
light).
"""

from __future__ import annotations

import signal
import sys

from visemeface.errors import EXIT

#: The one line an interrupted command prints (exit status ``EXIT["interrupted"]``, 130).
INTERRUPTED = "visemeface: interrupted\n"
_SIGNALS = (signal.SIGINT, signal.SIGTERM)


def _exit_now(signum=None, frame=None):
    """End the process at once with the interrupted line and status (no unwinding, no traceback)."""
    import os

    try:
        os.write(2, INTERRUPTED.encode())
    finally:
        os._exit(EXIT["interrupted"])


#: Set by the first signal of a running command (so an error the interrupt was turned into is reported as it).
_received = False
#: Whether :func:`main` runs as the program (``argv`` None), not called by a script or test.
_program = False
#: Set once the program's command has put its last outputs in place (:func:`_landed`).
_landed_outputs = False


class _Muted:
    """``sys.stderr`` once a command is interrupted: the one line is all it says.

    An interrupt raised inside code that C calls (an extension module importing another, a finaliser) is
    caught there and printed as a traceback through ``sys.stderr`` (``PyErr_Print``, the unraisable hook)
    before the command unwinds; that is not the user's news. :func:`interrupted_line` writes to the real stream.
    """

    def __init__(self, real):
        self.real = real

    def write(self, text):
        return len(text)

    def flush(self):
        pass

    def __getattr__(self, name):
        return getattr(self.real, name)


def _raise_interrupt(signum, frame):
    """The first Ctrl-C/SIGTERM of a running command: unwind as KeyboardInterrupt; a second: :func:`_exit_now`."""
    global _received
    if _landed_outputs:
        for s in _SIGNALS:
            signal.signal(s, _exit_done)
        return
    _received = True
    for s in _SIGNALS:
        signal.signal(s, _exit_now)
    if not isinstance(sys.stderr, _Muted):
        sys.stderr = _Muted(sys.stderr)
    raise KeyboardInterrupt


def _landed():
    """The command's last outputs are in place (:func:`visemeface.runtime.landing`). As the program, a signal
    from now on, while the command only returns (its summary, its temporaries' removal), does not make a
    finished run read as interrupted (status 130 beside whole outputs, which a script would take for a run
    that stopped part way and run again, to be refused by the outputs it left): the first is let pass and
    the command ends as it would have; a second ends the process at once with status 0."""
    global _landed_outputs
    _landed_outputs = _program


def _exit_done(signum=None, frame=None):
    import os

    os._exit(EXIT["done"])


def _take_signals(handler):
    """Handle SIGINT and SIGTERM by ``handler``; returns the previous handlers, or None when signals cannot
    be set (not the main thread)."""
    try:
        return {s: signal.signal(s, handler) for s in _SIGNALS}
    except ValueError:
        return None


def main(argv: list[str] | None = None) -> int:
    """Run the command line ``argv`` (default ``sys.argv[1:]``); returns the exit status.

    As the program (``argv`` None) a signal before the command runs ends the process at once with the
    interrupted line and 130, and one after it is done at once with its status; called with ``argv`` (tests,
    scripts) a signal raises KeyboardInterrupt throughout, and the caller's handlers are put back.
    """
    global _received, _program, _landed_outputs
    _received, _program, _landed_outputs = False, argv is None, False
    previous = _take_signals(_exit_now if argv is None else _raise_interrupt)
    try:
        status = _main(argv, armed=previous is not None)
        if argv is None and previous is not None:
            _end(status)
        return status
    except BaseException as exc:
        if not (isinstance(exc, KeyboardInterrupt) or _received):
            raise
        interrupted_line()
        if argv is None:
            _end_interrupted()
        return EXIT["interrupted"]
    finally:
        if isinstance(sys.stderr, _Muted):
            sys.stderr = sys.stderr.real
        if previous is not None:
            for s, handler in previous.items():
                signal.signal(s, _exit_now if argv is None else handler)


def interrupted_line(text: str = INTERRUPTED) -> None:
    """Write an interrupted command's one line (``text``, ending in a newline) to the real stderr, which is
    muted after the first signal (:class:`_Muted`)."""
    stream = sys.stderr.real if isinstance(sys.stderr, _Muted) else sys.stderr
    stream.write(text)
    stream.flush()


def _end(status: int):
    """End the program with ``status`` once its exit functions have run, not through the interpreter's own
    shutdown: a signal in that window (tens of ms after the work) met Python's default handlers, and the
    process died by it (rc -2, -15) with no line, though its outputs were complete. A signal now ends it at
    once with ``status`` and says nothing: the work is done and its outputs are whole (reported as interrupted,
    a run whose outputs were all written read as one that had stopped part way)."""
    import atexit
    import os

    def done(signum=None, frame=None):
        os._exit(status)

    for s in _SIGNALS:
        signal.signal(s, done)
    try:
        atexit._run_exitfuncs()
        sys.stdout.flush()
        sys.stderr.flush()
    finally:
        os._exit(status)


def _end_interrupted():
    """End the interrupted program with status 130 once its exit functions have run.

    Not by returning: an interrupt that passed through C code running Python source (``PyRun_*``, as
    some extension modules do while they are imported) marks the interpreter, which then ends itself by
    SIGINT (status -2) however the interrupt was handled.
    """
    import atexit
    import os

    for s in _SIGNALS:
        signal.signal(s, _exit_now)
    try:
        # the line is said: what the exit functions or a library's threads print now (Dask closing a
        # cluster the interrupt caught half made, asyncio's unretrieved task) is not the user's news
        sys.stderr.flush()
        os.dup2(os.open(os.devnull, os.O_WRONLY), 2)
    except OSError:
        pass
    try:
        atexit._run_exitfuncs()
        sys.stdout.flush()
    finally:
        os._exit(EXIT["interrupted"])


def _main(argv, armed: bool):
    import argparse
    import warnings

    from visemeface.errors import VisemefaceError, exit_status

    UsageError = _classes()["UsageError"]
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
    if armed:
        from visemeface.runtime import LANDED

        _take_signals(_raise_interrupt)
        if _landed not in LANDED:
            LANDED.append(_landed)
    try:
        return int(args.func(args) or 0)
    except (VisemefaceError, ModuleNotFoundError) as exc:
        if _received:                       # an error the interrupt came out as: report the interrupt
            raise KeyboardInterrupt from None
        if not isinstance(exc, VisemefaceError):    # a library of an optional extra that is not installed
            from visemeface.errors import missing_extra

            exc = missing_extra(exc) or exc
            if not isinstance(exc, VisemefaceError):
                raise
        print(f"visemeface: error: {exc}", file=sys.stderr)
        return exit_status(exc)
    except BrokenPipeError:
        # Output piped into `head` and the like: stop quietly, as Unix tools do.
        import os

        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())
        return 0


def _command_modules():
    import importlib
    import pkgutil

    from visemeface import commands

    mods = []
    for info in pkgutil.iter_modules(commands.__path__):
        if info.name.startswith("_"):
            continue
        mods.append(importlib.import_module(f"visemeface.commands.{info.name}"))
    return sorted(mods, key=lambda m: (getattr(m, "ORDER", 100), m.__name__))


def __getattr__(name):
    # UsageError and Parser are made on first use, so importing this module imports no argparse
    if name in ("UsageError", "Parser"):
        return _classes()[name]
    raise AttributeError(name)


#: The options ``--help`` shows for the commands with many (``--help-all`` shows every one): what most runs
#: need. Every option stays accepted; only the help is shorter.
BASIC_OPTIONS = {
    "speak": ("-o", "--format", "--text", "--emotion", "--fps", "--audio", "--save-transcript", "--face",
              "--physics", "--lips", "--size", "--view", "--no-video", "--frames", "--gltf", "--arkit", "--oculus",
              "--rhubarb", "--preview", "--resume", "--force", "-q"),
    "say": ("-o", "--rate", "--silent", "--emotion", "--fps", "--audio", "--save-transcript", "--face", "--physics",
            "--lips", "--size", "--view", "--no-video", "--frames", "--gltf", "--arkit", "--oculus", "--rhubarb",
            "--preview", "--resume", "--force", "-q"),
    "simulate": ("-o", "--physics", "--lips", "--glue", "--glue-profile", "--moisture", "--evaporation",
                 "--tissue-limit", "--jaw", "--side", "--fps", "--size", "--view", "--no-video", "--frames",
                 "--measures", "--gltf", "--resume", "--force", "-q"),
}

_CLASSES: dict = {}


def _classes() -> dict:
    """``UsageError`` and ``Parser``, made on first use (importing this module imports no argparse)."""
    if _CLASSES:
        return _CLASSES
    import argparse
    import re

    from visemeface.errors import VisemefaceError

    class UsageError(VisemefaceError):
        """A command line argparse refuses (unknown option, missing or malformed value)."""

    class _HelpAll(argparse.Action):
        """``--help-all``: the help with every option, then exit."""

        def __init__(self, option_strings, dest=argparse.SUPPRESS, default=argparse.SUPPRESS, help=None):
            super().__init__(option_strings, dest=dest, default=default, nargs=0, help=help)

        def __call__(self, parser, namespace, values, option_string=None):
            parser._print_message(parser.format_help_all(), sys.stdout)
            parser.exit()

    class Parser(argparse.ArgumentParser):
        """argparse with the project's error convention: one line, ``visemeface: error:``, exit 2.

        Values that start with a minus sign and a digit (``--box -10,-10,50,20``,
        ``--glue -0.1``) are values, not options: no option of ours looks like a number.
        A parser given ``basic`` options (:meth:`show_basic`) lists only those in ``--help``.
        """

        def __init__(self, *args, **kwargs):
            super().__init__(*args, **kwargs)
            self._negative_number_matcher = re.compile(r"^-\.?\d")
            self._basic: frozenset | None = None
            if self.add_help:       # every command takes it; those with a short --help (show_basic) need it
                self.add_argument("--help-all", action=_HelpAll, help="show every option and exit")

        def show_basic(self, options) -> None:
            """Make ``--help`` list only ``options`` (and ``--help-all`` every option)."""
            known = {s for a in self._actions for s in a.option_strings}
            missing = set(options) - known
            if missing:
                raise ValueError(f"{self.prog}: no option {sorted(missing)} to show in --help")
            self._basic = frozenset(options) | {"-h", "--help", "--help-all"}

        def format_help_all(self) -> str:
            """The help with every option."""
            return super().format_help()

        def format_help(self) -> str:
            if self._basic is None:
                return super().format_help()
            hidden = [a for a in self._actions if a.option_strings and not set(a.option_strings) & self._basic
                      and a.help is not argparse.SUPPRESS]
            saved = [(a, a.help) for a in hidden]
            for a in hidden:
                a.help = argparse.SUPPRESS
            try:
                text = super().format_help()
            finally:
                for a, h in saved:
                    a.help = h
            return text.rstrip("\n") + f"\n\n{len(hidden)} more options: `{self.prog} --help-all`\n"

        def error(self, message):
            command = self.prog.removeprefix("visemeface").strip()
            where = f"{command}: " if command else ""
            raise UsageError(f"{where}{message} (see `{self.prog} --help`)")

    _CLASSES.update(UsageError=UsageError, Parser=Parser)
    return _CLASSES


def build_parser():
    from visemeface import __version__

    parser = _classes()["Parser"](
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
    for name, options in BASIC_OPTIONS.items():
        if name in sub.choices:
            sub.choices[name].show_basic(options)
    return parser


def _show_warning(message, category, filename, lineno, file=None, line=None):
    print(f"visemeface: warning: {message}", file=sys.stderr)


if __name__ == "__main__":
    raise SystemExit(main())
