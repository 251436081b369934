"""Readers of the takes other tools write (and this project's own outputs), each to a :class:`Take`.

- mouth cues: Rhubarb Lip Sync's TSV, JSON and XML, Moho/OpenToonz switch data (``.dat``, shapes A-H X or
  the Preston Blair names, frames from 1 at ``dat_fps``), a Papagayo project (``.pgo``: its words too);
- weights: the per-frame weight files of ``--arkit``/``--vrm``/``--oculus`` (CSV ``frame,time,<names>``
  or JSON), Live Link Face's CSV, NVIDIA Audio2Face's blendshape JSON;
- the rig's own motion: an activation track CSV (``--track``) or a ``--gltf`` glb (muscle morph targets,
  or ARKit/VRM/Oculus ones).

Every reader refuses what it cannot read with one :class:`~visemeface.errors.InputError` naming the file
(and the line where there is one).
"""

from __future__ import annotations

import csv
import io
import json
import math
import re

import numpy as np

from visemeface.convert.take import Take, cue_take
from visemeface.errors import InputError
from visemeface.textfile import read_text

#: Rhubarb's shapes, and the Preston Blair names of Moho and Papagayo read back into them (WQ, Papagayo's
#: rounded W, is Rhubarb's puckered F).
_PRESTON_BLAIR = {"MBP": "A", "etc": "B", "E": "C", "AI": "D", "O": "E", "U": "F", "WQ": "F", "FV": "G", "L": "H",
                  "rest": "X"}
SHAPES = ("A", "B", "C", "D", "E", "F", "G", "H", "X")


def _number(text, path, line, what="time") -> float:
    try:
        value = float(text)
    except (TypeError, ValueError):
        value = float("nan")
    if not math.isfinite(value) or value < 0:
        raise InputError(f"{what} {text!r} is not a number >= 0", path, line)
    return value


def _shape(text, path, line) -> str:
    s = str(text).strip()
    s = s if s in SHAPES else _PRESTON_BLAIR.get(s, "")
    if not s:
        raise InputError(f"{text!r} is not a Rhubarb mouth shape (A-H, X) nor a Preston Blair one", path, line)
    return s


def rhubarb_tsv(path, text) -> Take:
    """``start<TAB>shape`` lines; the last line's time is the end (Rhubarb's last line ``<duration> X``)."""
    starts = []
    for k, raw in enumerate(text.splitlines(), 1):
        if not raw.strip():
            continue
        parts = raw.split("\t") if "\t" in raw else raw.split()
        if len(parts) != 2:
            raise InputError("expected 'start<TAB>shape'", path, k)
        starts.append((_number(parts[0], path, k), _shape(parts[1], path, k), k))
    if len(starts) < 2:
        raise InputError("a Rhubarb TSV needs a cue and the end line", path)
    cues = [(a, b, s) for (a, s, _), (b, _, _) in zip(starts, starts[1:])]
    return cue_take(cues, starts[-1][0], path, "rhubarb-tsv")


def rhubarb_json(path, doc) -> Take:
    try:
        cues = [(float(c["start"]), float(c["end"]), _shape(c["value"], path, None)) for c in doc["mouthCues"]]
        end = float((doc.get("metadata") or {}).get("duration") or (cues[-1][1] if cues else 0.0))
    except (KeyError, TypeError, ValueError):
        raise InputError("not Rhubarb JSON: mouthCues needs start, end and value", path) from None
    return cue_take(cues, end, path, "rhubarb-json")


def rhubarb_xml(path, text) -> Take:
    import xml.etree.ElementTree as ET

    try:
        root = ET.fromstring(text)
    except ET.ParseError as exc:
        raise InputError(f"not XML ({exc})", path) from None
    if root.tag != "rhubarbResult":
        raise InputError(f"not Rhubarb XML: the root is <{root.tag}>, not <rhubarbResult>", path)
    cues = []
    for c in root.iter("mouthCue"):
        cues.append((_number(c.get("start"), path, None), _number(c.get("end"), path, None),
                     _shape(c.text or "", path, None)))
    duration = root.findtext("metadata/duration")
    end = _number(duration, path, None, "duration") if duration else (cues[-1][1] if cues else 0.0)
    return cue_take(cues, end, path, "rhubarb-xml")


def _centiseconds_up(t: float) -> float:
    return math.ceil(t * 100.0 - 1e-6) / 100.0


def moho_dat(path, text, fps: float) -> Take:
    """``MohoSwitch1`` then ``<frame> <shape>`` lines, frames from 1 at ``fps``; the last switch lasts a frame.

    A frame's time is rounded up to the centisecond (under 10 ms later), so that cues written again with
    Rhubarb's centisecond times fall on the same frames (exactly, at rates up to 100 fps)."""
    lines = [(k, ln) for k, ln in enumerate(text.splitlines(), 1) if ln.strip()]
    if not lines or lines[0][1].strip() != "MohoSwitch1":
        raise InputError("not Moho switch data: the first line must be MohoSwitch1", path, 1)
    keys = []
    for k, ln in lines[1:]:
        parts = ln.split()
        if len(parts) != 2 or not parts[0].isdigit() or int(parts[0]) < 1:
            raise InputError("expected '<frame> <shape>' with a frame from 1", path, k)
        keys.append((_centiseconds_up((int(parts[0]) - 1) / fps), _shape(parts[1], path, k), k))
    if not keys:
        raise InputError("Moho switch data with no frame", path)
    for (a, _, _), (b, _, k) in zip(keys, keys[1:]):
        if b <= a:
            raise InputError("frames must increase", path, k)
    end = keys[-1][0] + 1.0 / fps
    cues = [(a, b, s) for (a, s, _), (b, _, _) in zip(keys, keys[1:] + [(end, "", 0)])]
    return cue_take(cues, end, path, "moho-dat")


def papagayo(path, text) -> Take:
    """A Papagayo project (:mod:`visemeface.export.papagayo`): the words and their phonemes' frames."""
    lines = text.split("\n")
    pos = [0]

    def take_line(strip=True):
        if pos[0] >= len(lines):
            raise InputError("the Papagayo project ends early", path, pos[0])
        pos[0] += 1
        return lines[pos[0] - 1].strip() if strip else lines[pos[0] - 1]

    def integer():
        value = take_line()
        if not re.fullmatch(r"-?\d+", value):
            raise InputError(f"expected a whole number, got {value!r}", path, pos[0])
        return int(value)

    if take_line() != "lipsync version 1":
        raise InputError("not a Papagayo project: the first line must be 'lipsync version 1'", path, 1)
    take_line()
    fps, duration, voices = integer(), integer(), integer()
    if fps < 1:
        raise InputError(f"frame rate {fps} is not positive", path, 3)
    words, keys = [], []
    for _ in range(voices):
        take_line(), take_line()
        for _ in range(integer()):
            take_line(), integer(), integer()
            for _ in range(integer()):
                parts = take_line().split()
                if len(parts) != 4 or not all(re.fullmatch(r"\d+", p) for p in parts[1:]):
                    raise InputError("expected '<word> <start> <end> <phonemes>'", path, pos[0])
                a, b, n = (int(p) for p in parts[1:])
                words.append((a / fps, (b + 1) / fps, parts[0]))
                for _ in range(n):
                    frame, _, shape = take_line().partition(" ")
                    if not frame.isdigit():
                        raise InputError(f"expected '<frame> <phoneme>', got {frame!r}", path, pos[0])
                    keys.append((int(frame) / fps, (b + 1) / fps, _shape(shape, path, pos[0])))
    keys.sort()
    cues = [(a, min(end, nxt[0]) if nxt else end, s) for (a, end, s), nxt in zip(keys, keys[1:] + [None])]
    return cue_take(cues, max(duration / fps, max((w[1] for w in words), default=0.0)), path, "papagayo",
                    words=words, fps=float(fps))


def weights_csv(path, text) -> Take:
    from visemeface.convert.take import weights_take

    rows = list(csv.reader(io.StringIO(text)))
    header = [h.strip() for h in rows[0]] if rows else []
    if header[:2] == ["Timecode", "BlendShapeCount"]:
        return live_link(path, header, rows[1:])
    if header[:2] != ["frame", "time"]:
        raise InputError("not a weights CSV: the header must start frame,time (or Timecode,BlendShapeCount)",
                         path, 1)
    times, values = [], []
    for k, rec in enumerate(rows[1:], 2):
        if not any(c.strip() for c in rec):
            continue
        if len(rec) != len(header):
            raise InputError(f"expected {len(header)} values, got {len(rec)}", path, k)
        times.append(_number(rec[1], path, k))
        values.append([_number(c, path, k, "weight") for c in rec[2:]])
    return weights_take(path, header[2:], times, values, "weights-csv")


def weights_json(path, doc) -> Take:
    from visemeface.convert.take import weights_take

    if doc.get("format") != "visemeface-weights":
        raise InputError("convert reads Rhubarb JSON, Audio2Face JSON and visemeface weights JSON "
                         "(format visemeface-weights); this is none of them", path)
    try:
        return weights_take(path, doc["names"], doc["time"], doc["weights"], "weights-json", fps=float(doc["fps"]))
    except (KeyError, TypeError, ValueError):
        raise InputError("a weights JSON needs names, time, weights and fps", path) from None


def audio2face(path, doc) -> Take:
    from visemeface.convert.take import weights_take

    try:
        fps, names, mat = float(doc["exportFps"]), list(doc["facsNames"]), doc["weightMat"]
    except (KeyError, TypeError, ValueError):
        raise InputError("Audio2Face JSON needs exportFps, facsNames and weightMat", path) from None
    names = [n[:1].lower() + n[1:] for n in names]           # A2F's solver may capitalise the ARKit names
    return weights_take(path, names, np.arange(len(mat)) / fps, mat, "audio2face", fps=fps)


#: Frame rates a Live Link Face take may have been recorded at (its CSV does not say).
LIVE_LINK_RATES = (24.0, 25.0, 30.0, 48.0, 50.0, 60.0, 120.0)


def live_link(path, header, rows) -> Take:
    """Live Link Face's CSV: ``Timecode`` ``HH:MM:SS:FF.fff``; the rate is the smallest of
    :data:`LIVE_LINK_RATES` above every frame number ``FF`` (a take of a second or more shows it exactly)."""
    from visemeface.convert.take import weights_take

    from visemeface.export.retarget import LIVE_LINK_ROTATIONS

    stamps, values = [], []
    shapes = [j for j, h in enumerate(header) if j >= 2 and h not in LIVE_LINK_ROTATIONS]   # not head and eyes
    for k, rec in enumerate(rows, 2):
        if not any(c.strip() for c in rec):
            continue
        m = re.fullmatch(r"(\d+):(\d\d):(\d\d):(\d+)(?:\.(\d+))?", rec[0].strip())
        if m is None or len(rec) != len(header):
            raise InputError("expected Timecode HH:MM:SS:FF.fff and every column", path, k)
        h, mi, s, ff = (int(x) for x in m.groups()[:4])
        stamps.append((3600 * h + 60 * mi + s, ff + float("0." + (m[5] or "0"))))
        values.append([_number(rec[j], path, k, "weight") for j in shapes])
    if not stamps:
        raise InputError("a Live Link CSV with no frame", path)
    top = max(f for _, f in stamps)
    fps = next((r for r in LIVE_LINK_RATES if r > top), None)
    if fps is None:
        raise InputError(f"frame number {top:g} is above every Live Link rate", path)
    times = [sec - stamps[0][0] + f / fps for sec, f in stamps]
    names = [header[j][:1].lower() + header[j][1:] for j in shapes]
    return weights_take(path, names, np.array(times) - times[0], values, "livelink", fps=fps)


def track_csv(path) -> Take:
    from visemeface.track import load_track, track_fps

    track = load_track(path)
    return Take("track", float(track.index[-1]) + 1.0 / track_fps(track), str(path), "track",
                fps=track_fps(track), track=track)


def read_take(path, dat_fps: float = 24.0) -> Take:
    """The take in ``path``, its format from the suffix and, for ``.csv`` and ``.json``, the content."""
    from pathlib import Path

    from visemeface.convert.gltf import glb_take

    path = Path(path)
    suffix = path.suffix.lower()
    if suffix == ".glb":
        return glb_take(path)
    if suffix not in (".tsv", ".xml", ".dat", ".pgo", ".csv", ".json"):
        raise InputError(f"cannot read {suffix or 'a file without suffix'}: convert reads .tsv .json .xml .dat "
                         "(Rhubarb, Moho), .pgo (Papagayo), .csv (weights, Live Link, track) and .glb", path)
    text = read_text(path, "take")
    if suffix == ".tsv":
        return rhubarb_tsv(path, text)
    if suffix == ".xml":
        return rhubarb_xml(path, text)
    if suffix == ".dat":
        return moho_dat(path, text, dat_fps)
    if suffix == ".pgo":
        return papagayo(path, text)
    if suffix == ".csv":
        first = text.lstrip().split("\n", 1)[0]
        return track_csv(path) if first.startswith("#") or first.split(",")[0].strip() == "time" else \
            weights_csv(path, text)
    if suffix == ".json":
        try:
            doc = json.loads(text)
        except json.JSONDecodeError as exc:
            raise InputError(f"not JSON ({exc.msg}, line {exc.lineno})", path) from None
        if not isinstance(doc, dict):
            raise InputError("not a take: the JSON is not an object", path)
        if "mouthCues" in doc:
            return rhubarb_json(path, doc)
        if "weightMat" in doc:
            return audio2face(path, doc)
        return weights_json(path, doc)
