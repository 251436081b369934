"""Sinks: where the frames of a run go, chosen from one registry.

A run (:func:`visemeface.pipeline.run`) streams the frames of a
:class:`~visemeface.motion.Motion` into a list of sinks. Each output format is
one module of :mod:`visemeface.export` holding its writer and its sink, which
registers itself here with :func:`register`; the command line offers every
registered sink as an option (:func:`add_sink_arguments`), so a new format is
one new module and touches no command.

The life of a sink
------------------
``Sink(path, force=..., **settings)`` checks its target (suffix, no overwrite)
before any work; :meth:`Sink.open` gets the run's :class:`RunInfo` and stages
temporaries; :meth:`Sink.write` takes each :class:`~visemeface.motion.Frame`
(with its rendered ``image`` when the sink :attr:`~Sink.needs_image`);
:meth:`Sink.close` finishes the temporaries; only when every sink closed
without error does the run call :meth:`Sink.commit` on each (renames), else
:meth:`Sink.abort` (removes). So a run writes all of its outputs or none.
"""

from __future__ import annotations

import argparse
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, ClassVar

import numpy as np

from visemeface.errors import InputError, close_matches
from visemeface.outputs import Staged, check_suffix, output_path

#: name -> Sink subclass, in registration order (the order of the CLI options).
SINKS: dict[str, type[Sink]] = {}


@dataclass
class RunInfo:
    """What every sink may need to know about the run it is part of.

    Attributes
    ----------
    face : FaceMesh
        The face the frames pose (vertices, triangles, colours).
    fps : float
    n_frames : int
    size : int
        Rendered frame width = height (px), 0 when nothing is rendered.
    mouth_box : tuple or None
        Pixel box (x, y, w, h) of the rest mouth in the rendered frames.
    audio : Path or None
        Sound to mux into videos.
    rig : MuscleRig or None
        The rig of a speech run (for morph-target exports).
    track : DataFrame or None
        The activation track of a speech run.
    end_time : float or None
        End of the utterance (s); may lie up to a frame after the last frame.
    extra : dict
        Anything else a sink may need (e.g. the physics settings).
    resumable : bool
        Whether ``--resume`` can continue the run if it stops: False once it has stopped at a divergence
        (set before the sinks' ``abort``), which a resumed run, being deterministic, meets again.
    """

    face: Any
    fps: float
    n_frames: int
    size: int = 0
    mouth_box: tuple | None = None
    audio: Path | None = None
    rig: Any = None
    track: Any = None
    end_time: float | None = None
    extra: dict = field(default_factory=dict)
    resumable: bool = True


class Sink:
    """Base class of every output (see the module docstring).

    Class attributes describe the command-line option: ``name`` (registry key
    and ``--NAME`` option unless ``option`` says otherwise), ``metavar``,
    ``help``, ``aliases`` (more option strings), ``suffixes`` (accepted file name endings; empty: any) and
    ``folder`` (the output is a folder). ``needs_image`` asks the run to render
    each frame; ``needs_physics`` says the output holds a simulation's own figures (a kinematic run
    refuses it).
    """

    name: ClassVar[str] = ""
    option: ClassVar[str | None] = None
    aliases: ClassVar[tuple[str, ...]] = ()
    metavar: ClassVar[str] = "FILE"
    help: ClassVar[str] = ""
    suffixes: ClassVar[tuple[str, ...]] = ()
    folder: ClassVar[bool] = False
    needs_image: ClassVar[bool] = False
    needs_physics: ClassVar[bool] = False
    #: A suffix (".html") lets the option be given without a path: the output goes beside the video
    #: (its name with this suffix).
    beside_video: ClassVar[str] = ""
    #: More options of this sink: ``((flag, ...), argparse keywords with a "dest")``; their values reach
    #: the sink as ``settings[dest]``.
    arguments: ClassVar[tuple] = ()

    def __init__(self, path, force: bool = False, **settings):
        known = {kw["dest"] for _, kw in self.arguments}
        unknown = sorted(set(settings) - known - {"resume"})
        if unknown:                     # a misspelt setting would silently give the default output
            raise InputError(f"the {self.name} output has no setting {unknown[0]!r}"
                             + (f"; it has: {', '.join(sorted(known))}" if known else "; it has none")
                             + close_matches(unknown[0], sorted(known)))
        self.path = output_path(path)
        if self.suffixes:
            check_suffix(self.path, *self.suffixes)
        self.force = force
        self.settings = settings
        self.staged = [Staged(self.path, force, folder=self.folder)]
        self.run: RunInfo | None = None

    # ------------------------------------------------------------------ protocol
    def targets(self) -> list[Path]:
        """Every path this sink will write (checked for clashes before the run)."""
        return [s.path for s in self.staged]

    def open(self, run: RunInfo) -> None:
        """Stage the temporaries; ``run`` says what the run is."""
        self.run = run
        self.tmp = [s.open() for s in self.staged]

    def write(self, frame) -> None:
        """Take one frame (:class:`~visemeface.motion.Frame`)."""

    def cached_image(self, index: int) -> np.ndarray | None:
        """An already rendered image of frame ``index`` this sink can give back (resume), or None."""
        return None

    def close(self) -> None:
        """Finish the temporaries (every frame has been written)."""

    def commit(self) -> list[Path]:
        """Rename the finished temporaries into place; returns the paths written."""
        return [s.commit() for s in self.staged]

    def abort(self) -> None:
        """Remove the temporaries (the run failed or was interrupted; ``self.run.resumable`` says whether
        ``--resume`` can continue it)."""
        for s in self.staged:
            s.abort()


def check_physics_outputs(names, physics, option: str = "--") -> None:
    """Refuse a sink whose output is a simulation's own figures (``needs_physics``) when ``physics`` is
    None or "none": it would hold nothing. ``option`` prefixes the names in the message."""
    if physics in (None, "none"):
        for name in names:
            if SINKS[name].needs_physics:
                raise InputError(f"{option}{name} writes a simulation's figures: it needs {option}physics "
                                 "sticky or elastic")


def register(cls: type[Sink]) -> type[Sink]:
    """Class decorator: add a sink to :data:`SINKS` under ``cls.name``."""
    if not cls.name or cls.name in SINKS:
        raise ValueError(f"sink name {cls.name!r} is empty or taken")
    SINKS[cls.name] = cls
    return cls


def option_of(cls: type[Sink]) -> str:
    """The command-line option of a sink (``--frames`` ...)."""
    return cls.option or f"--{cls.name.replace('_', '-')}"


def dest_of(cls: type[Sink]) -> str:
    return option_of(cls).lstrip("-").replace("-", "_")


def add_sink_arguments(group: argparse._ActionsContainer, skip: tuple[str, ...] = ()) -> None:
    """Add one option per registered sink (except ``skip``) to an argparse group."""
    for name, cls in SINKS.items():
        if name in skip:
            continue
        more = dict(nargs="?", const=BESIDE_VIDEO) if cls.beside_video else {}
        group.add_argument(option_of(cls), *cls.aliases, dest=dest_of(cls), type=Path, metavar=cls.metavar,
                           help=cls.help, **more)
        for flags, kw in cls.arguments:
            group.add_argument(*flags, **kw)


#: The value of a ``beside_video`` sink's option given without a path.
BESIDE_VIDEO = Path("<beside the video>")


def sinks_from_args(args, force: bool, skip: tuple[str, ...] = (), video: Path | None = None,
                    **settings) -> list[Sink]:
    """The sinks the user asked for with :func:`add_sink_arguments`'s options (``video``: the video's
    path, where a ``beside_video`` sink given without a path writes)."""
    out = []
    for name, cls in SINKS.items():
        if name in skip:
            continue
        path = getattr(args, dest_of(cls), None)
        if path == BESIDE_VIDEO:
            if video is None:
                raise InputError(f"{option_of(cls)} without a path writes beside the MP4, and no MP4 is written "
                                 f"(--no-video): give its path, e.g. {option_of(cls)} take{cls.beside_video}")
            path = Path(video).with_suffix(cls.beside_video)
        own = {kw["dest"]: getattr(args, kw["dest"], kw.get("default")) for _, kw in cls.arguments}
        if path is not None:
            out.append(cls(path, force=force, **settings, **own))
            continue
        given = [f[0] for f, kw in cls.arguments if own[kw["dest"]] not in (None, False, kw.get("default"))]
        if given:                               # an option of an output not asked for: never silently ignored
            raise InputError(f"{given[0]} is an option of {option_of(cls)}, which is not given")
    return out


def check_distinct(sinks: list[Sink]) -> None:
    """Refuse two outputs of one run that are the same path, or one inside another's folder (committing the
    folder would replace it)."""
    seen: dict[Path, str] = {}
    for s in sinks:
        for p in s.targets():
            r = p.resolve()
            if r in seen:
                raise InputError(f"the {s.name} and {seen[r]} outputs are the same path", p)
            seen[r] = s.name
    folders = {s.path.resolve(): s.name for s in sinks if s.folder}
    for r, name in seen.items():
        inside = next((f for f in r.parents if f in folders), None)
        if inside is not None:
            raise InputError(f"the {name} output lies inside the {folders[inside]} output's folder, which the run "
                             "replaces; name another place", r)
