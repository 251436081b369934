"""A batch manifest: one CSV row per clip, read into :class:`Job` objects (or :class:`BadRow` ones).

Columns (a header row names them; any order; only ``clip`` and one of
``transcript``/``text`` are needed)::

    clip        the clip's id: its folder in the output (letters, digits, . _ -)
    transcript  a timed transcript file (any format `visemeface speak` reads), relative to the manifest
    text        English text instead (as `visemeface say`)
    audio       a sound file: muxed into the video; with text, the text is timed to it
    emotion     NAME[=W] weights, separated by ; or spaces, e.g. "happiness=0.6; surprise=0.2"
    physics     none, sticky or elastic
    fps, size, view, msaa, interp, rate
    identity    with the batch's --face ict: a speaker of ICT's identity space (an integer seed, or weights
                of its first modes separated by , as --identity takes), so a corpus has many speakers
    outputs     sink names (`visemeface.export.SINKS`: video, frames, obj, pc2, gltf, track, ...),
                separated by ; or spaces

An empty cell (or a missing column) takes the batch's default (the command
line's options, or :func:`defaults`). A row that cannot make a clip (a missing
file, an unknown emotion, a NaN weight, a repeated id) becomes a
:class:`BadRow` with a one-line reason; the other rows are not affected.
"""

from __future__ import annotations

import csv
import math
import re
from dataclasses import asdict, dataclass, fields
from pathlib import Path

from visemeface.errors import InputError, choose, close_matches

#: The columns a manifest may have.
COLUMNS = ("clip", "transcript", "text", "audio", "emotion", "physics", "fps", "size", "view", "msaa",
           "interp", "rate", "outputs", "identity")
#: A clip id: a file name that is not hidden, has no separators and is at most this long.
CLIP_ID = re.compile(r"^[A-Za-z0-9][A-Za-z0-9._-]{0,99}$")
#: Names in the output folder that are not clips.
RESERVED = ("batch_report.csv",)


@dataclass(frozen=True)
class Job:
    """One clip to make: its input and settings (plain values, so it travels to any Dask worker).

    Paths are absolute strings. ``face``, ``landmarks`` and ``rig`` are the
    batch's face and rig files (None: the embedded face and shipped rig).
    """

    clip: str
    transcript: str | None = None
    text: str | None = None
    audio: str | None = None
    emotion: tuple[tuple[str, float], ...] = ()
    physics: str = "none"
    fps: float = 30.0
    size: int = 512
    view: str = "face"
    msaa: int = 4
    interp: str = "coarticulation"
    rate: float | None = None
    outputs: tuple[str, ...] = ("video",)
    identity: str | None = None
    face: str | None = None
    landmarks: str | None = None
    rig: str | None = None

    def settings(self) -> dict:
        """Everything the clip's files depend on (recorded beside them; compared on ``--resume``)."""
        d = asdict(self)
        d["emotion"] = [list(e) for e in self.emotion]
        d["outputs"] = list(self.outputs)
        if self.physics != "none":          # the FEM face's settings the physics runs at
            from visemeface.physics.simulation import PhysicsSettings
            d["lips"] = repr(PhysicsSettings.speech())
        return d


@dataclass(frozen=True)
class BadRow:
    """A manifest row that makes no clip: its id (or ``row N``) and why."""

    clip: str
    error: str


def defaults(**given) -> dict:
    """The default value of every setting column, updated with ``given`` (checked like a row's cells)."""
    base = {f.name: f.default for f in fields(Job) if f.name in COLUMNS and f.name != "clip"}
    unknown = set(given) - set(base) - {"face", "landmarks", "rig"}
    if unknown:
        name = sorted(unknown)[0]
        raise InputError(f"unknown setting {name!r}{close_matches(name, base)}")
    base.update(given)
    return base


def _split(cell: str) -> list[str]:
    return [p for p in re.split(r"[;\s]+", cell.strip()) if p]


def _number(name: str, value, kind=float, low: float = 0.0, high: float = math.inf):
    try:
        x = kind(value)
    except (TypeError, ValueError):
        raise InputError(f"{name} must be a {'whole ' if kind is int else ''}number, got {value!r}") from None
    if not (math.isfinite(x) and low < x <= high):
        raise InputError(f"{name} must be in ({low:g}, {high:g}], got {value!r}")
    return x


def _emotions(value) -> tuple[tuple[str, float], ...]:
    from visemeface.animate import parse_emotions
    from visemeface.postures.library import load_expressions

    if isinstance(value, (tuple, list)) and all(isinstance(v, (tuple, list)) for v in value):
        value = [f"{n}={w!r}" for n, w in value]
    specs = _split(value) if isinstance(value, str) else value if hasattr(value, "items") else list(value or ())
    return tuple(sorted(parse_emotions(specs or None, load_expressions().index).items()))


def _outputs(value) -> tuple[str, ...]:
    from visemeface.export import SINKS

    names = _split(value) if isinstance(value, str) else list(value)
    if not names:
        raise InputError("no outputs: name at least one of " + ", ".join(SINKS))
    return tuple(dict.fromkeys(choose(n, SINKS, "output") for n in names))


def _file(value, base: Path, what: str) -> str | None:
    if value in (None, ""):
        return None
    path = (base / str(value)).resolve()
    if not path.is_file():
        raise InputError(f"{what} not found", path)
    return str(path)


def check_settings(s: dict, base: Path = Path(".")) -> dict:
    """A row's settings (``defaults()`` updated by its cells) checked and typed; :class:`InputError` if not."""
    from visemeface.pipeline import RenderSettings
    from visemeface.physics.drive import PHYSICS
    from visemeface.speech.timeline import MODES
    from visemeface.track import MAX_FPS

    out = dict(s)
    out["transcript"] = _file(s.get("transcript"), base, "transcript")
    from visemeface.speech.audio import is_recording

    if out["transcript"] is not None and is_recording(out["transcript"]):   # was "not UTF-8 text (byte 0x..)"
        raise InputError("a recording is no transcript: put it in the audio column and its words in text",
                         out["transcript"])
    out["audio"] = _file(s.get("audio"), base, "audio file")
    out["text"] = (str(s["text"]).strip() or None) if s.get("text") is not None else None
    if (out["transcript"] is None) == (out["text"] is None):
        raise InputError("give a transcript or a text (one of them)")
    out["emotion"] = _emotions(s.get("emotion"))
    out["physics"] = choose(s.get("physics") or "none", ("none",) + tuple(PHYSICS), "physics")
    out["fps"] = _number("fps", s.get("fps"), float, 0.0, MAX_FPS)
    out["size"] = _number("size", s.get("size"), int)
    out["msaa"] = int(_number("msaa", s.get("msaa"), float, -1.0, 64))
    try:
        RenderSettings(size=out["size"], view=s.get("view"), msaa=out["msaa"]).check()
    except InputError as e:
        raise InputError(str(e).removeprefix("--")) from None
    out["interp"] = choose(s.get("interp") or MODES[0], MODES, "interpolation mode")
    if s.get("rate") not in (None, ""):
        out["rate"] = _number("rate", s.get("rate"), float, 0.0, 1000.0)
        if out["audio"] is not None:
            raise InputError("rate and audio both time the text; give one")
    else:
        out["rate"] = None
    out["outputs"] = _outputs(s.get("outputs"))
    identity = s.get("identity")
    if identity not in (None, ""):
        from visemeface.face.ict import identity_weights

        if s.get("face") != "ict":
            raise InputError("identity draws a speaker of the ICT head: the batch needs --face ict")
        identity_weights(identity)
        out["identity"] = str(identity).strip()
    else:
        out["identity"] = None
    from visemeface.export.sinks import check_physics_outputs

    check_physics_outputs(out["outputs"], out["physics"], option="")
    return out


def read_manifest(path, settings: dict | None = None) -> list[Job | BadRow]:
    """The manifest's rows as :class:`Job` (good) or :class:`BadRow` (bad, with the reason).

    Parameters
    ----------
    path : str or Path
        The CSV manifest; relative file names in it are relative to its folder.
    settings : dict, optional
        Defaults of the setting columns (:func:`defaults`); also ``face``, ``landmarks``, ``rig``.

    Raises
    ------
    InputError
        When the manifest itself is unusable (missing, no header, an unknown column, no rows).
    """
    path = Path(path)
    settings = defaults(**(settings or {}))
    rows = _rows(path)
    out: list[Job | BadRow] = []
    seen: dict[str, int] = {}
    for line, row in rows:
        clip = (row.get("clip") or "").strip()
        try:
            if not CLIP_ID.match(clip):
                raise InputError(f"bad clip id {clip!r}: 1-100 letters, digits, '.', '_' or '-', "
                                 "not starting with '.', '_' or '-'")
            if clip in RESERVED:
                raise InputError(f"clip id {clip!r} is the name of the batch's report")
            if clip in seen:
                raise InputError(f"clip id {clip!r} repeats line {seen[clip]}")
            seen[clip] = line
            cells = {k: v for k, v in row.items() if k != "clip" and v not in (None, "")}
            given = {**settings, **cells}
            if "audio" in cells and "rate" not in cells:
                given.pop("rate", None)   # a default rate is for the text rows; a recording times its own
            checked = check_settings(given, path.parent)
            out.append(Job(clip=clip, **{k: checked.get(k, settings.get(k)) for k in _JOB_FIELDS}))
        except InputError as e:
            out.append(BadRow(clip or f"row {line}", f"{path.name}:{line}: {e}"))
    return out


_JOB_FIELDS = tuple(f.name for f in fields(Job) if f.name != "clip")


def _rows(path: Path) -> list[tuple[int, dict]]:
    if not path.is_file():
        raise InputError("manifest not found", path)
    try:
        with open(path, newline="", encoding="utf-8-sig") as fh:
            reader = csv.DictReader(fh)
            head = [h.strip() for h in (reader.fieldnames or [])]
            reader.fieldnames = head
            if "clip" not in head:
                raise InputError("the manifest's header row must name a 'clip' column", path, 1)
            for h in head:
                if h not in COLUMNS:
                    raise InputError(f"unknown column {h!r}{close_matches(h, COLUMNS)}; columns: "
                                     + ", ".join(COLUMNS), path, 1)
            if "transcript" not in head and "text" not in head:
                raise InputError("the manifest needs a 'transcript' or 'text' column", path, 1)
            rows = []
            for r in reader:
                extra = [v for v in r.get(None) or () if v.strip()]
                if extra:                   # more cells than the header names (empty trailing ones are fine)
                    raise InputError(f"{len(head) + len(r[None])} cells for the header's {len(head)} columns "
                                     f"(extra: {', '.join(map(repr, extra))}; a value with a comma needs quotes)",
                                     path, reader.line_num)
                rows.append((reader.line_num, {k: (v.strip() if isinstance(v, str) else v) for k, v in r.items()
                                               if k is not None}))
    except (UnicodeDecodeError, csv.Error) as e:
        raise InputError(f"not a CSV manifest ({e})", path) from None
    rows = [(n, r) for n, r in rows if any(r.values())]
    if not rows:
        raise InputError("the manifest has no rows", path)
    return rows


def write_manifest(path, rows: list[dict], force: bool = False) -> Path:
    """Write ``rows`` (dicts keyed by :data:`COLUMNS`) as a manifest, atomically; returns the path."""
    from visemeface.outputs import atomic_output

    used = [c for c in COLUMNS if any(r.get(c) not in (None, "") for r in rows)]
    for r in rows:
        extra = set(r) - set(COLUMNS)
        if extra:
            raise InputError(f"unknown column {sorted(extra)[0]!r}")
    with atomic_output(path, force) as tmp, open(tmp, "w", newline="", encoding="utf-8") as fh:
        w = csv.DictWriter(fh, fieldnames=used, lineterminator="\n", extrasaction="ignore")
        w.writeheader()
        w.writerows(rows)
    return Path(path)


__all__ = ["COLUMNS", "Job", "BadRow", "defaults", "check_settings", "read_manifest", "write_manifest"]
