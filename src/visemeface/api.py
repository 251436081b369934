"""One call per job: :func:`speak`, :func:`say`, :func:`simulate`, :func:`lipsync`, :func:`analyze`.

Each call is the command of the same name: its keyword options are the command's long options in
snake_case (``emotion="happiness=0.6"``, ``no_video=True``, ``gltf="a.glb"``), read by the command's own
parser, so the defaults, the checks and the job are the command line's (there is no second
implementation). The call returns a :class:`Result` (the files written, the frames, the wall time and
the equivalent command line) and raises the command's error instead of printing it:
:class:`~visemeface.errors.InputError` for bad input (the CLI's exit status 2),
:class:`~visemeface.errors.SimulationDiverged` (3), :class:`KeyboardInterrupt`; nothing is half written.

Option values: ``True`` gives a flag (``force=True`` is ``--force``), ``False`` or ``None`` leaves the
option out, a list or tuple repeats it (``emotion=["happiness=0.6", "surprise=0.2"]``), a dict gives
``NAME=VALUE`` items (``emotion={"happiness": 0.6}``); anything else is written with ``str``. Progress
bars and summaries are off unless ``quiet=False``.

Examples
--------
>>> import visemeface
>>> run = visemeface.speak("transcripts/bob_moves_five_boats.txt", "bob.mp4")   # doctest: +SKIP
>>> run.outputs, run.frames                                                      # doctest: +SKIP
([PosixPath('bob.mp4'), PosixPath('bob.mp4.json')], 56)
"""

from __future__ import annotations

import argparse
import shlex
import time
from dataclasses import dataclass, field
from pathlib import Path

__all__ = ["Result", "speak", "say", "simulate", "lipsync", "analyze", "command_line"]


@dataclass
class Result:
    """What one call did.

    Attributes
    ----------
    command : str
        The sub-command run (``"speak"``, ...).
    argv : list of str
        Its arguments, as :func:`command_line` built them (``visemeface`` + ``argv`` is the same job).
    outputs : list of Path
        Every file or folder the job put in place, in the order they were committed.
    frames : int or None
        Frames the job made (animated or analysed); None for a job with no frames (``lipsync``).
    seconds : float
        Wall time of the call.
    runs : list
        The :class:`visemeface.pipeline.RunStats` of each animation run (frames made live, replayed from
        a checkpoint, rendered, reused); empty for ``lipsync`` and ``analyze``.
    """

    command: str
    argv: list[str]
    outputs: list[Path] = field(default_factory=list)
    frames: int | None = None
    seconds: float = 0.0
    runs: list = field(default_factory=list)

    @property
    def command_line(self) -> str:
        """The same job as a shell command."""
        return shlex.join(["visemeface", self.command, *self.argv])


def _subparser(command: str) -> argparse.ArgumentParser:
    from visemeface.cli import build_parser

    parser = build_parser()
    sub = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
    return sub.choices[command]


def _values(name: str, value) -> list[str]:
    if isinstance(value, dict):
        return [f"{k}={v:g}" if isinstance(v, float) else f"{k}={v}" for k, v in value.items()]
    if isinstance(value, (list, tuple)):
        return [str(v) for v in value]
    return [str(value)]


def command_line(command: str, positional, output=None, **options) -> list[str]:
    """The arguments of ``visemeface COMMAND`` for a call's parameters (checked against its parser).

    Raises :class:`TypeError` for an option the command does not have, as Python does for an
    unknown keyword.
    """
    parser = _subparser(command)
    by_dest = {}
    for action in parser._actions:
        long = [s for s in action.option_strings if s.startswith("--")]
        if long:
            by_dest.setdefault(action.dest, (long[0], action))
            by_dest.setdefault(long[0][2:].replace("-", "_"), (long[0], action))
    argv = [str(p) for p in positional]
    if output is not None:
        argv += ["-o", str(output)]
    options.setdefault("quiet", True)
    for name, value in options.items():
        if name not in by_dest:
            known = sorted(k for k in by_dest if k != "help")
            from visemeface.errors import close_matches

            hint = close_matches(name, known)
            raise TypeError(f"{command}() got an unexpected option {name!r}{hint}")
        flag, action = by_dest[name]
        if value is None:
            continue
        if isinstance(action, argparse.BooleanOptionalAction):
            argv.append(flag if value else "--no-" + flag[2:])
        elif action.nargs == 0:                       # store_true and the like
            if value:
                argv.append(flag)
        elif isinstance(action, argparse._AppendAction) or action.nargs in ("+", "*"):
            items = _values(name, value)
            argv += [flag, *items] if action.nargs in ("+", "*") else [x for v in items for x in (flag, v)]
        else:
            if isinstance(value, (list, tuple, dict)):
                raise TypeError(f"{command}() option {name!r} takes one value, got {value!r}")
            argv += [flag, str(value)]
    return argv


def _run(command: str, argv: list[str]) -> Result:
    from visemeface import outputs, pipeline
    from visemeface.runtime import configure

    parser = _subparser(command)
    args = parser.parse_args(argv)           # a bad option raises cli.UsageError (an InputError-like error)
    configure()
    written, runs = [], []
    tokens = outputs.WRITTEN.set(written), pipeline.RUNS.set(runs)
    start = time.perf_counter()
    try:
        args.func(args)
    finally:
        outputs.WRITTEN.reset(tokens[0])
        pipeline.RUNS.reset(tokens[1])
    frames = sum(r.frames for r in runs) if runs else None
    return Result(command, argv, outputs=list(written), frames=frames,
                  seconds=time.perf_counter() - start, runs=runs)


def speak(transcript, output=None, **options) -> Result:
    """Animate a timed transcript or a recording: ``visemeface speak TRANSCRIPT -o OUTPUT``.

    Parameters
    ----------
    transcript : str or Path
        A timed transcript (timed text, ``.lab``, ``.PHN``, TextGrid, MFA JSON/CSV, DECtalk), plain
        English text in a file, or a recording (its phones aligned to ``text=``, else recognised).
    output : str or Path, optional
        The MP4 (default: the transcript's stem + ``.mp4`` in the current folder); ``no_video=True``
        with another output (``gltf=``, ``arkit=``, ...) writes no video.
    **options
        Any long option of ``visemeface speak`` (``emotion``, ``fps``, ``physics``, ``lips``, ``size``,
        ``view``, ``audio``, ``frames``, ``gltf``, ``arkit``, ``force``, ...).

    Returns
    -------
    Result
    """
    return _run("speak", command_line("speak", [transcript], output, **options))


def say(text: str, output=None, **options) -> Result:
    """Animate English text: ``visemeface say TEXT -o OUTPUT`` (default ``say.mp4``).

    The text may carry emotion tags (``"[anger 0.8] Bob moves five boats."``). Options: those of
    :func:`speak` after the transcript, plus ``rate`` (words per minute) and ``silent``.
    """
    return _run("say", command_line("say", [text], output, **options))


def simulate(scenario: str, output=None, **options) -> Result:
    """Run the sticky-lip finite-element face through a scenario: ``visemeface simulate SCENARIO``.

    ``scenario`` is ``"open"``, ``"open-once"`` or ``"part"``; besides the video it writes the saliva
    film's figures per frame (OUTPUT's stem + ``.saliva.csv``). Options: ``physics``, ``lips``
    (``"default"`` or ``"seed"``), ``glue``, ``glue_profile``, ``jaw``, ``fps``, ``resume``, ... (see
    ``visemeface simulate --help``). Minutes on two cores.
    """
    return _run("simulate", command_line("simulate", [scenario], output, **options))


def lipsync(recording, output=None, **options) -> Result:
    """The timed phones of a recording as a transcript: ``visemeface lipsync RECORDING -o OUTPUT``.

    ``output``'s suffix chooses the format (``.txt``, ``.lab``, ``.TextGrid``, ``.json``; default the
    recording's stem + ``.TextGrid``); ``text=`` or ``text_file=`` gives the words (forced alignment),
    else a same-named ``.txt`` beside the recording, else phones are recognised.
    """
    return _run("lipsync", command_line("lipsync", [recording], output, **options))


def analyze(video, output, **options) -> Result:
    """Measure mouth openings frame by frame: ``visemeface analyze VIDEO -o OUTPUT.csv``.

    ``video`` is a video file or a folder of frames; the mouth box comes from ``box="x,y,w,h"``, the
    video's sidecar, or is found automatically. Options: ``plot``, ``overlay``, ``method``
    (``"lips"`` or ``"seed"``), ... (see ``visemeface analyze --help``). ``Result.frames`` is the
    number of frames analysed (the profile's rows).
    """
    result = _run("analyze", command_line("analyze", [video], output, **options))
    import pandas as pd

    result.frames = len(pd.read_csv(output, comment="#"))
    return result
