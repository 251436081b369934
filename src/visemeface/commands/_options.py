"""Option groups shared by the commands that animate (speak, say, simulate) and pose the face.

Each ``add_*`` function adds one group of options to a parser; the matching
``*_from_args`` function turns the parsed options into the library's own
objects, checking every value before any work. Choice lists come from the
library (renderer views, physics kinds, interpolation modes, sinks).
"""

from __future__ import annotations

import argparse
import dataclasses
import math
from pathlib import Path


# --------------------------------------------------------------------------- numbers

class Help(argparse.HelpFormatter):
    """Help text as written where the author laid it out (a text holding line breaks: an epilog of
    examples), wrapped to the terminal where not (a description written as one paragraph)."""

    def _fill_text(self, text, width, indent):
        if "\n" in text:
            return "".join(indent + line for line in text.splitlines(keepends=True))
        return super()._fill_text(text, width, indent)


def shown(text, most: int = 24) -> str:
    """``text`` as a message quotes it: itself, or its start and its length when longer than ``most``."""
    text = str(text).strip()
    return text if len(text) <= most else f"{text[:12]}... ({len(text)} characters)"


def check_number(value, name: str = "", low: float | None = None, high: float | None = None, *,
                 integer: bool = False, low_open: bool = False, high_open: bool = False,
                 infinite: bool = False, what: str = ""):
    """``value`` (a number, or its text as typed) as a float, or an int with ``integer``, checked: a number,
    finite (``infinite``: +inf allowed, as "no limit"), in ``low``..``high`` (``low_open``/``high_open``:
    the end itself excluded). Anything else is one :class:`InputError` naming ``name`` (the option) with the
    range and the value as given (shortened: a 309-digit number is not echoed whole); ``what`` adds the unit
    or meaning, e.g. "frames". The one check of every number a user types (options, profile items, cells).
    """
    from visemeface.errors import InputError

    kind = "an integer" if integer else "a number"
    if low is not None and high is not None:
        a, b = ("(" if low_open else "["), (")" if high_open else "]")
        where = f"{kind} from {low:g} to {high:g}" if integer else f"{kind} in {a}{low:g}, {high:g}{b}"
    elif low is not None:
        where = f"{kind} {'>' if low_open else '>='} {low:g}"
    elif high is not None:
        where = f"{kind} {'<' if high_open else '<='} {high:g}"
    else:
        where = f"a finite {kind.split()[-1]}"
    if infinite:
        where += " (or inf)"
    if what:
        where += f" ({what})"
    problem = InputError(f"{name + ' ' if name else ''}must be {where}, got {shown(value)}")
    if isinstance(value, bool):
        raise problem
    try:
        if integer:
            number = int(str(value).strip()) if isinstance(value, str) else value
            if not isinstance(number, int) and not (isinstance(number, float) and number.is_integer()):
                raise problem
            number = int(number)
        else:
            number = float(value)
    except (TypeError, ValueError, OverflowError):
        raise problem from None
    if number != number or (abs(number) == math.inf and not (infinite and number > 0)):
        raise problem
    if low is not None and (number < low or (low_open and number == low)):
        raise problem
    if high is not None and number != math.inf and (number > high or (high_open and number == high)):
        raise problem
    return number


def number(low: float | None = None, high: float | None = None, **kw):
    """An argparse ``type=`` of :func:`check_number`: the option's value checked as it is parsed, so a bad
    one is argparse's one line "argument --fps: must be a number in (0, 10000], got '1e308'"."""
    def parse(text: str):
        from visemeface.errors import InputError

        try:
            return check_number(text, "", low, high, **kw)
        except InputError as e:
            raise argparse.ArgumentTypeError(e.reason) from None

    parse.__name__ = "integer" if kw.get("integer") else "number"
    parse.low, parse.high, parse.infinite = low, high, kw.get("infinite", False)      # read by the tests' fuzz
    return parse


# --------------------------------------------------------------------------- face and rig

def rig_help() -> str:
    """The help of ``--rig`` (the same on every command that takes it)."""
    return "rig file (default: the package's own data/rig/default.toml, a commented TOML to copy and edit)"


def add_face_arguments(p: argparse.ArgumentParser, skin: bool = True) -> None:
    """``--face MESH``, ``--landmarks JSON``, ``--rig TOML`` (and ``--skin TYPE`` unless ``skin`` is False)."""
    g = p.add_argument_group("face")
    g.add_argument("--face", metavar="MESH", help="face: 'ict' (the scanned ICT Face Model), 'procedural' (the "
                   "default), or a mesh (OBJ/PLY/GLB/glTF with a .landmarks.json sidecar)")
    g.add_argument("--identity", metavar="SEED|W,...", help="with --face ict: a speaker from ICT's identity space, "
                   "drawn by an integer seed or given as weights of its first modes (standard deviations, +-3)")
    g.add_argument("--landmarks", metavar="JSON", help="landmarks sidecar of --face, if not beside it")
    g.add_argument("--rig", metavar="TOML", help=rig_help())
    if skin:
        add_skin_argument(g)


def _skin_type(text: str) -> str:
    """argparse type of ``--skin``: the preset's name, refused at once when unknown."""
    from visemeface.errors import InputError
    from visemeface.face.colouring import skin_tone

    try:
        skin_tone(text)
    except InputError as exc:
        raise argparse.ArgumentTypeError(str(exc)) from None
    return text.strip().upper()


def add_skin_argument(g) -> None:
    """``--skin TYPE``: the embedded face's skin-tone preset (data/face/skin_tones.toml; checked by
    :func:`visemeface.face.colouring.skin_tone` when the face is built)."""
    g.add_argument("--skin", metavar="TYPE", type=_skin_type,
                   help="skin and lip colours of the embedded face: a Fitzpatrick type from I (lightest) to VI "
                   "(darkest), presets in data/face/skin_tones.toml (default III, the original colours)")


def build_rig(args):
    """The rig of ``--face``/``--landmarks``/``--rig``/``--identity``/``--skin``
    (:func:`visemeface.muscles.rig.rig_for`)."""
    from visemeface.muscles.rig import rig_for

    return rig_for(getattr(args, "face", None), getattr(args, "landmarks", None), getattr(args, "rig", None),
                   getattr(args, "identity", None), getattr(args, "skin", None))


# --------------------------------------------------------------------------- rendering

def add_render_arguments(p: argparse.ArgumentParser, view: str = "face") -> None:
    """``--size``, ``--view``, ``--msaa``."""
    from visemeface.render import VIEWS

    g = p.add_argument_group("rendering")
    g.add_argument("--size", type=int, default=512, help="frame width = height in pixels, a multiple of 16 "
                   "(default 512)")
    g.add_argument("--view", choices=VIEWS, default=view, help=f"camera (default {view})")
    add_msaa_argument(g)


def add_msaa_argument(g) -> None:
    """``--msaa`` (checked by :func:`visemeface.pipeline.check_msaa`)."""
    g.add_argument("--msaa", type=int, default=4, metavar="N",
                   help="antialiasing samples per pixel: 0, 2, 4, 8 or 16 (default 4; 0 renders about twice as fast)")


def render_from_args(args):
    from visemeface.pipeline import RenderSettings

    return RenderSettings(size=args.size, view=args.view, msaa=args.msaa).check()


# --------------------------------------------------------------------------- outputs

def add_output_arguments(p: argparse.ArgumentParser, video_default: str, resumable: str) -> None:
    """``-o OUT.mp4``, ``--no-video``, one option per registered sink, ``--resume``, ``--force``, ``-q``."""
    from visemeface.export import SINKS
    from visemeface.export.sinks import add_sink_arguments

    p.add_argument("-o", "--output", type=Path, metavar="OUT.mp4", help=f"video file (default {video_default})")
    g = p.add_argument_group("outputs")
    g.add_argument("--no-video", action="store_true", help="write no MP4 (only the other outputs)")
    add_sink_arguments(g, skip=("video",))
    g.add_argument("--resume", action="store_true", help=resumable)
    g.add_argument("--force", action="store_true", help="overwrite existing outputs")
    add_quiet(g)
    assert "video" in SINKS


def add_quiet(p, what: str = "no progress bar or summary") -> None:
    """``-q``/``--quiet`` (errors still print); ``what`` is its help."""
    p.add_argument("-q", "--quiet", action="store_true", help=what)


def sinks_from_args(args, default_video: Path, defaults: dict | None = None) -> list:
    """The sinks asked for (the video unless ``--no-video``), every target checked before any work.

    ``defaults`` (sink name -> path) adds sinks the command writes unless told otherwise.
    """
    from visemeface.errors import InputError
    from visemeface.export import SINKS
    from visemeface.export.sinks import check_distinct, sinks_from_args as others

    sinks = []
    if args.no_video and args.output is not None:
        raise InputError("-o/--output names a video, but --no-video asks for none")
    if not args.no_video:
        sinks.append(SINKS["video"](args.output or default_video, force=args.force))
    sinks += others(args, force=args.force, skip=("video",), video=None if args.no_video else args.output or default_video,
                    resume=args.resume)
    for name, path in (defaults or {}).items():
        if not any(s.name == name for s in sinks):
            sinks.append(SINKS[name](path, force=args.force))
    if not sinks and getattr(args, "save_transcript", None) is None:
        raise InputError("nothing to write: --no-video and no other output")
    check_distinct(sinks)
    return sinks


# --------------------------------------------------------------------------- physics

def add_physics_arguments(p: argparse.ArgumentParser, default: str, choices: tuple[str, ...]) -> argparse._ArgumentGroup:
    """``--physics`` and the saliva options (their defaults: :meth:`PhysicsSettings.speech`'s)."""
    g = p.add_argument_group("physics (sticky lips: a finite-element lower face, saliva between the lips)")
    g.add_argument("--physics", choices=choices, default=default,
                   help="sticky: the FEM face with saliva that glues the lips until it breaks; elastic: the same "
                   "FEM without glue" + ("; none: the kinematic rig" if "none" in choices else "")
                   + " (the FEM costs about 8 s per second of speech on 2 cores)")
    from visemeface.physics.config import MAX_SEAM_ELEMENTS, keys_summary
    from visemeface.physics.glue import MAX_GLUE

    g.add_argument("--lips", choices=LIPS, default=LIPS[0],
                   help="default: the speech lips (refined along the seam, cohesive saliva strands, the film into "
                   "the corners, a stiffening tissue); seed: Leach & Maddock's (2018) model, the same as "
                   "--seam-elements 0 --rupture-time 0 --no-film-corners --tissue-limit inf. The options below "
                   "change either")
    g.add_argument("--physics-config", type=Path, metavar="FILE.toml", help="the physical face's other "
                   "parameters (damping, hourglass control, saliva moisture and decay, ...), read over --lips; "
                   f"the options here win over it (TOML; its keys: {keys_summary()})")
    g.add_argument("--glue", type=number(0, MAX_GLUE), metavar="G",
                   help=f"glue strength K_glue, 0 to {MAX_GLUE:g} (default 0.08)")
    g.add_argument("--glue-profile", metavar="SPEC", help="glue across the mouth over --glue, e.g. "
                   "centre=0.18 or right=0.3,left=0 (WHERE: centre (the mouth's central twelfth), left, right, corners, "
                   "all, or a..b of s, -1 at the right corner to +1 at the left)")
    g.add_argument("--moisture", type=number(0), metavar="M", help="initial saliva moisture M0 (default 100)")
    g.add_argument("--evaporation", type=number(0), metavar="E", help="moisture lost per second (default 0)")
    g.add_argument("--rupture-time", type=number(0), metavar="S", help="saliva strands thin over S seconds before they "
                   "snap (default 0.03: the lips unzip from the centre; 0: Leach & Maddock's brittle film)")
    g.add_argument("--seam-elements", type=number(0, MAX_SEAM_ELEMENTS, integer=True), metavar="N", help="refine the lips to at least N tissue elements "
                   "along the seam: each seam edge split into equal parts, so the next multiple of the face's "
                   "own count (12 on the default face; default 48, one per saliva slab; 0: the face's own, the "
                   "mesh of Leach & Maddock's model)")
    g.add_argument("--tissue-limit", type=number(1, low_open=True, infinite=True), metavar="L", help="the soft tissue stiffens without bound as its "
                   "stretch, volume change taken out, nears L (Gent's law; default 2.8: a strong --glue 0.3 lets go at "
                   "full jaw; inf: Leach & Maddock's neo-Hookean tissue, which never stiffens: the lips stretch 7x and hold)")
    g.add_argument("--film-corners", action=argparse.BooleanOptionalAction, default=None,
                   help="carry the saliva film into the mouth corners, where the lips meet (default: on; "
                   "--no-film-corners ends it at the last pair of lip vertices, Leach & Maddock's film, whose unglued "
                   "corners open as notches while the rest is stuck)")
    return g


#: ``--lips``: the speech lips (:meth:`PhysicsSettings.speech`) or Leach & Maddock's (2018) model
#: (``PhysicsSettings()``: the face's own seam elements, a brittle film ending at the last lip pair,
#: neo-Hookean tissue).
LIPS = ("default", "seed")


#: Options of the glue alone: the elastic face is the sticky one with no glue (``--physics elastic`` refuses them).
GLUE_OPTIONS = ("glue", "glue_profile", "glue_file", "moisture", "evaporation", "critical_moisture")


def physics_from_args(args, **more):
    """:class:`PhysicsSettings` of the options (checked), or None for ``--physics none``.

    ``more``: the command's own settings (``dt``, ``damping``, ...); None is "not given" (the file's or the lips').
    """
    from visemeface.errors import InputError

    more = {k: v for k, v in more.items() if v is not None}

    given = [f"--{'no-' if getattr(args, n) is False else ''}{n.replace('_', '-')}"       # as typed
             for n in ("glue", "glue_profile", "moisture", "evaporation", "rupture_time", "seam_elements",
                       "film_corners", "tissue_limit") if getattr(args, n, None) is not None]
    if getattr(args, "lips", "default") != "default":
        given.append(f"--lips {args.lips}")
    if getattr(args, "physics_config", None) is not None:
        given.append("--physics-config")
    if args.physics == "none":
        if given:
            raise InputError(f"{given[0]} needs --physics sticky or elastic")
        return None
    if args.physics == "elastic":
        glue = [f"--{n.replace('_', '-')}" for n in GLUE_OPTIONS if getattr(args, n, None) is not None]
        if glue:
            raise InputError(f"{glue[0]} sets the glue between the lips, which --physics elastic leaves out; "
                             "use --physics sticky")
    from visemeface.physics.config import MAX_SEAM_ELEMENTS, apply_physics_config, read_physics_config
    from visemeface.physics.drive import PhysicsSettings

    base = PhysicsSettings() if getattr(args, "lips", "default") == "seed" else PhysicsSettings.speech()
    if getattr(args, "physics_config", None) is not None:
        values = read_physics_config(args.physics_config)
        glue = [k for k in values if k in GLUE_OPTIONS or k == "initial_moisture"]
        if args.physics == "elastic" and glue:
            raise InputError(f"{glue[0]} sets the glue between the lips, which --physics elastic leaves out; "
                             "use --physics sticky", args.physics_config)
        try:
            base = apply_physics_config(base, values)
        except InputError as exc:                      # a check of the model's own (a decay of 1 and the like)
            raise InputError(str(exc), args.physics_config) from None
    params = {}
    if args.moisture is not None:
        params["initial_moisture"] = args.moisture
    if args.evaporation is not None:
        params["evaporation"] = args.evaporation
    if getattr(args, "critical_moisture", None) is not None:
        params["critical_moisture"] = args.critical_moisture
    if getattr(args, "rupture_time", None) is not None:
        params["rupture_time"] = args.rupture_time
    if getattr(args, "film_corners", None) is not None:
        more["film_corners"] = args.film_corners
    if args.glue is not None:
        from visemeface.physics.glue import MAX_GLUE

        more["glue"] = check_number(args.glue, "--glue", 0, MAX_GLUE)
    if getattr(args, "tissue_limit", None) is not None:
        if not args.tissue_limit > 1.0:
            raise InputError(f"--tissue-limit must be a stretch > 1 (inf: none), got {args.tissue_limit:g}")
        more["tissue_limit"] = args.tissue_limit
    if getattr(args, "seam_elements", None) is not None:
        if not 0 <= args.seam_elements <= MAX_SEAM_ELEMENTS:
            raise InputError(f"--seam-elements must be in 0..{MAX_SEAM_ELEMENTS} (0: the face's own elements), "
                             f"got {args.seam_elements}")
        more["seam_elements"] = args.seam_elements or None
    if args.glue_profile is not None:
        more["glue_profile"] = args.glue_profile
    try:
        saliva = dataclasses.replace(base.saliva, **params)
    except InputError as e:
        raise InputError(str(e).replace("moisture must", "--moisture must")
                         .replace("evaporation rate must", "--evaporation must")
                         .replace("saliva rupture time must", "--rupture-time must")) from None
    return dataclasses.replace(base, saliva=saliva, **more)


def simulation_of(rig, track, physics: str, settings):
    """The FEM face of ``rig.face`` driven by ``track`` (:func:`visemeface.animate.simulated_motion`)."""
    from visemeface.animate import simulated_motion

    return simulated_motion(rig, track, physics, settings)


def checkpoint_of(motion, sinks, args):
    """The checkpoint folder of a resumable motion beside its first output (checked), else None."""
    if not motion.resumable:
        return None
    from visemeface.checkpoint import RunCheckpoint, checkpoint_folder

    ck = RunCheckpoint(checkpoint_folder(sinks[0].targets()[0]), motion.key(), motion.render_face.n_vertices, motion.fps,
                       motion.settings())
    ck.check(resume=args.resume, force=args.force)
    return ck


def check_fps_option(fps: float) -> float:
    from visemeface.track import MAX_FPS

    return check_number(fps, "--fps", 0, MAX_FPS, low_open=True, what="frames per second")


# --------------------------------------------------------------------------- listings

def print_table(head: tuple[str, ...], rows: list[tuple], as_csv: bool = False, width: int = 110) -> None:
    """Rows as CSV, or as aligned columns with the last one wrapped to ``width`` characters."""
    import sys
    import textwrap

    rows = [tuple(str(c) for c in r) for r in rows]
    if as_csv:
        import csv

        w = csv.writer(sys.stdout, lineterminator="\n")
        w.writerow(head)
        w.writerows(rows)
        return
    widths = [max(len(r[i]) for r in rows + [head]) for i in range(len(head) - 1)]
    indent = sum(widths) + 2 * len(widths)
    print("  ".join(h.ljust(w) for h, w in zip(head, widths + [0])).rstrip())
    for r in rows:
        last = textwrap.wrap(r[-1], width=max(30, width - indent)) or [""]
        print("  ".join(c.ljust(w) for c, w in zip(r[:-1], widths)) + "  " + last[0])
        for more in last[1:]:
            print(" " * indent + more)


# ------------------------------------------------------------------ the words of a recording (speak, lipsync)
def add_text_arguments(g) -> None:
    """``--text``, ``--text-file`` (the words of a recording)."""
    g.add_argument("--text", metavar="WORDS", help="what the recording says: forced alignment (accurate); "
                   "default: the text of a same-named .txt beside the recording, else phone recognition")
    g.add_argument("--text-file", type=Path, metavar="TXT", help="read the words from a text file")


def check_not_words(targets, recording: Path, text_file) -> None:
    """Refuse an output that is the words file of ``recording``: ``--text-file``, or the same-named .txt
    beside it, which a later run reads as its words, whether it exists yet or not (and whatever --force)."""
    from visemeface.outputs import check_not_inputs

    words = [Path(text_file)] if text_file is not None else []
    check_not_inputs(targets, words + [recording.with_suffix(".txt")],
                     f"the words of {recording.name} (a .txt beside a recording is read as its words)")


def text_of(recording: Path, text, text_file, quiet: bool = False):
    """The words for ``recording``: ``text``, the file's, a same-named .txt beside it, or None."""
    from visemeface.errors import InputError
    from visemeface.textfile import read_text

    if text is not None and text_file is not None:
        raise InputError("--text and --text-file both give the words; give one")
    if text is not None:
        if not text.strip():
            raise InputError("--text is empty")
        return text, None
    beside = recording.with_suffix(".txt")
    path = text_file if text_file is not None else (beside if beside.is_file() else None)
    if path is None:
        return None, None
    words = read_text(path, "text file")
    if text_file is None and not quiet:
        import sys

        print(f"visemeface: aligning the words of {path}", file=sys.stderr)
    return words, path


def recording_utterance(recording: Path, text, text_file, quiet: bool = False):
    """Utterance of a recording: aligned to its words if any, else recognised."""
    from visemeface.pipeline import check_audio
    from visemeface.speech.align import utterance_from_audio

    check_audio(recording)                     # an unreadable recording is the only line, before any note
    words, path = text_of(recording, text, text_file, quiet)
    utterance = utterance_from_audio(recording, words, text_where=path)
    if not quiet and words is None:            # after the recognition: an error stays the only line
        import sys

        print(f"visemeface: note: no text for {recording.name}: its phones were recognised (give --text \"...\" "
              "to align its words: more accurate)", file=sys.stderr)
    if not quiet and "confidence" in utterance.words:
        doubtful = utterance.words[utterance.words["confidence"] < 0.5]
        if len(doubtful):
            import sys

            shown = ", ".join(f"{w!r} at {s:.2f} s ({c:.2f})" for s, w, c in
                              doubtful[["start", "word", "confidence"]].itertuples(index=False))
            print(f"visemeface: note: doubtful in the audio: {shown}; check these words", file=sys.stderr)
    return utterance
