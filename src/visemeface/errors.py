"""The project's own error types and the command line's exit statuses.

Every error a user can cause (bad file, bad value, existing output) is an
:class:`InputError`; the CLI prints its message on one line and exits with
status 2. Messages name the file, line and value that were wrong. A physical
simulation that blows up is not bad input: :class:`SimulationDiverged` exits
with status 3 and says where it happened and what to try.

Exit statuses (:data:`EXIT`): 0 done, 2 bad input, 3 simulation diverged,
130 interrupted (Ctrl-C or SIGTERM; nothing half written is left).
"""

from __future__ import annotations

import os
from collections.abc import Iterable


def one_line(text: str) -> str:
    """``text`` with its control characters (a newline or tab read from a user's file) written as escapes,
    so that a message quoting what a file held stays one line."""
    return "".join(c if c.isprintable() else repr(c)[1:-1] for c in str(text))


class VisemefaceError(Exception):
    """Base class of all errors raised on purpose by visemeface."""


class InputError(VisemefaceError, ValueError):
    """Bad user input: a file, an option or a value. CLI exit status 2.

    Parameters
    ----------
    message : str
        What was wrong.
    path : str or Path, optional
        The file concerned; prefixed to the message.
    line : int, optional
        1-based line number in ``path``.
    """

    def __init__(self, message: str, path: str | os.PathLike | None = None, line: int | None = None):
        self.path = None if path is None else str(path)
        self.line = line
        self.reason = message = one_line(message)
        where = ""
        if self.path is not None:
            where = one_line(self.path) + (f":{line}" if line is not None else "") + ": "
        super().__init__(where + message)


class SimulationDiverged(VisemefaceError, RuntimeError):
    """A simulation produced a non-finite value or an inverted element (J <= 0). CLI exit status 3.

    Attributes ``step``, ``time`` (s) and ``element`` say where; the message
    says what to try (smaller time step, more damping, a gentler track).
    """

    def __init__(self, message: str, step: int, time: float, element: int):
        super().__init__(message)
        self.step, self.time, self.element = step, time, element


class RenderUnavailable(VisemefaceError, RuntimeError):
    """No headless OpenGL (EGL) context could be made on this machine."""


#: The modules an optional extra brings, by the distribution that installs them (where the names differ).
DISTRIBUTIONS = {"cv2": "opencv-python-headless", "PIL": "pillow", "distributed": "dask",
                 "imageio_ffmpeg": "imageio-ffmpeg", "ai_edge_litert": "ai-edge-litert",
                 "espeakng_loader": "espeakng-loader"}


class MissingExtra(VisemefaceError, ImportError):
    """A command needs a library of an optional extra that is not installed. CLI exit status 2.

    ``module`` is the missing module, ``extras`` the extras that install it (from the package's own
    metadata), ``command`` the ``pip install`` line that adds the first of them.
    """

    def __init__(self, module: str, extras: list[str]):
        self.module, self.extras = module, list(extras)
        distribution = DISTRIBUTIONS.get(module, module)
        which = self.extras[0] if self.extras else None
        self.command = f'pip install "visemeface[{which}]"' if which else f"pip install {distribution}"
        named = " or ".join(f"[{e}]" for e in self.extras)
        extra = f"the {named} extra" if which else "a library visemeface does not install"
        needs = module if distribution == module else f"{module} ({distribution})"
        super().__init__(f"this needs {needs}, from {extra}, which is not installed: {self.command}")


def extras_providing(distribution: str) -> list[str]:
    """The optional extras of the installed visemeface that require ``distribution``, in declared order."""
    import re
    from importlib import metadata

    try:
        requires = metadata.requires("visemeface") or []
    except metadata.PackageNotFoundError:
        return []
    key = re.sub(r"[-_.]+", "-", distribution).lower()
    found = []
    for line in requires:              # in the order pyproject.toml declares the extras
        m = re.match(r"\s*([A-Za-z0-9_.-]+)[^;]*;\s*extra\s*==\s*[\"']([^\"']+)[\"']", line)
        if m and re.sub(r"[-_.]+", "-", m.group(1)).lower() == key and m.group(2) not in found:
            found.append(m.group(2))
    return [e for e in found if e not in ("all", "test")]


def missing_extra(exc: BaseException) -> MissingExtra | None:
    """``exc`` as a :class:`MissingExtra` when it is an import of an optional extra's library, else None."""
    if not isinstance(exc, ModuleNotFoundError) or not exc.name:
        return None
    module = exc.name.split(".")[0]
    extras = extras_providing(DISTRIBUTIONS.get(module, module))
    return MissingExtra(module, extras) if extras else None


#: Exit statuses of the command line (README "Exit statuses").
EXIT = {"done": 0, "input": 2, "diverged": 3, "interrupted": 130}


def exit_status(exc: BaseException) -> int:
    """The CLI exit status for an exception raised by a command."""
    if isinstance(exc, SimulationDiverged):
        return EXIT["diverged"]
    if isinstance(exc, KeyboardInterrupt):
        return EXIT["interrupted"]
    return EXIT["input"]


def close_matches(name: str, known: Iterable[str], n: int = 3) -> str:
    """Return a hint like ``" (did you mean: a, b?)"`` or ``""``."""
    import difflib

    # a name of another type (a landmark asked for by number) gets no hint, not a TypeError
    matches = difflib.get_close_matches(str(name), [str(k) for k in known], n=n, cutoff=0.5)
    return f" (did you mean: {', '.join(matches)}?)" if matches else ""


def choose(name: str, known: Iterable[str], what: str, aliases: dict[str, str] | None = None) -> str:
    """Normalise ``name`` (trimmed, lower case, ``aliases`` applied) and check it is one of ``known``.

    Raises :class:`InputError` "unknown WHAT 'x'; choose one of a, b (did you mean: ...?)".
    """
    known = list(known)
    key = str(name).strip().lower()
    key = (aliases or {}).get(key, key)
    if key not in known:
        raise InputError(f"unknown {what} {name!r}; choose one of {', '.join(known)}{close_matches(key, known)}")
    return key


def table_name(name, known, what: str) -> str:
    """``name`` (trimmed) as the table ``known`` spells it: itself, or in lower case (emotion names and
    DECtalk symbols are lower case, so "AA" is /aa/). Raises :class:`InputError` "unknown WHAT 'x'
    (did you mean: ...?)" without listing every name, unlike :func:`choose`.
    """
    name = str(name).strip()
    if name not in known and name.lower() in known:
        name = name.lower()
    if name not in known:
        raise InputError(f"unknown {what} {name!r}{close_matches(name.lower(), known)}")
    return name
