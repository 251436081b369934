"""Rhubarb Lip Sync mouth cues (shapes A–H, X) in Rhubarb's four output formats, chosen by the suffix.

- ``.tsv``: ``start<TAB>shape`` a line, then a last line ``<duration><TAB>X``;
- ``.json``: ``{"metadata": {"soundFile", "duration"}, "mouthCues": [{"start", "end", "value"}, ...]}``;
- ``.xml``: ``<rhubarbResult><metadata>…</metadata><mouthCues><mouthCue start end>shape</mouthCue>…``;
- ``.dat``: Moho/OpenToonz switch data: ``MohoSwitch1`` then ``<frame> <shape>`` lines with frame
  ``1 + int(fps·start)`` (``--dat-fps``, default 24 as Rhubarb's ``--datFrameRate``; with
  ``--dat-preston-blair`` the Preston Blair names MBP etc E AI O U FV L rest).

Times have two decimals (centiseconds, truncated), as Rhubarb writes them. The cues come from the
utterance's phones through ``data/retarget/phoneme_classes.csv`` (:func:`visemeface.retarget.classes.mouth_cues`).
"""

from __future__ import annotations

import json
import math
from xml.sax.saxutils import escape

from visemeface.errors import InputError
from visemeface.export.sinks import Sink, register
from visemeface.outputs import atomic_output
from visemeface.retarget.classes import PRESTON_BLAIR, centiseconds, dat_frame

#: Rhubarb's default ``--datFrameRate``.
DAT_FPS = 24.0


def tsv_text(cues, duration: float) -> str:
    lines = [f"{a:.2f}\t{s}" for a, _, s in cues]
    return "\n".join(lines + [f"{centiseconds(duration) / 100:.2f}\tX"]) + "\n"


def json_text(cues, duration: float, sound_file: str = "") -> str:
    body = ",\n".join(f'    {{ "start": {a:.2f}, "end": {b:.2f}, "value": "{s}" }}' for a, b, s in cues)
    meta = f'    "soundFile": {json.dumps(sound_file)},\n    "duration": {centiseconds(duration) / 100:.2f}\n'
    return "{\n  \"metadata\": {\n" + meta + "  },\n  \"mouthCues\": [\n" + body + "\n  ]\n}\n"


def xml_text(cues, duration: float, sound_file: str = "") -> str:
    rows = "".join(f'    <mouthCue start="{a:.2f}" end="{b:.2f}">{s}</mouthCue>\n' for a, b, s in cues)
    return ('<?xml version="1.0" encoding="utf-8"?>\n<rhubarbResult>\n  <metadata>\n'
            f"    <soundFile>{escape(sound_file)}</soundFile>\n"
            f"    <duration>{centiseconds(duration) / 100:.2f}</duration>\n"
            f"  </metadata>\n  <mouthCues>\n{rows}  </mouthCues>\n</rhubarbResult>\n")


def dat_text(cues, fps: float = DAT_FPS, preston_blair: bool = False) -> str:
    """Moho switch data; a cue that starts on the same frame as the next one is dropped (the later wins)."""
    frames: dict[int, str] = {}
    for a, _, s in cues:
        frames[dat_frame(a, fps)] = PRESTON_BLAIR[s] if preston_blair else s
    return "MohoSwitch1\n" + "".join(f"{f} {s}\n" for f, s in frames.items())


WRITERS = {".tsv": "tsv", ".json": "json", ".xml": "xml", ".dat": "dat"}


def write_cues(path, cues, duration: float, sound_file: str = "", dat_fps: float = DAT_FPS,
               preston_blair: bool = False, force: bool = False) -> None:
    """Write mouth cues in the format of ``path``'s suffix (``.tsv``, ``.json``, ``.xml``, ``.dat``)."""
    kind = WRITERS[str(path)[str(path).rfind("."):].lower()]
    text = {"tsv": lambda: tsv_text(cues, duration), "json": lambda: json_text(cues, duration, sound_file),
            "xml": lambda: xml_text(cues, duration, sound_file),
            "dat": lambda: dat_text(cues, dat_fps, preston_blair)}[kind]()
    with atomic_output(path, force) as tmp:
        tmp.write_text(text, encoding="utf-8")


def dat_fps(text) -> float:
    """``--dat-fps``'s value: a frame rate in (0, 1000] (checked while parsing, with or without --rhubarb)."""
    import argparse

    try:
        value = float(text)
    except (TypeError, ValueError):
        value = float("nan")
    if not (math.isfinite(value) and 0 < value <= 1000):
        raise argparse.ArgumentTypeError(f"must be a frame rate in (0, 1000], got {text}")
    return value


def _fps(value) -> float:
    if value is None:
        return DAT_FPS
    try:
        return dat_fps(value)
    except Exception as exc:
        raise InputError(f"--dat-fps {exc}") from None


@register
class RhubarbSink(Sink):
    """Rhubarb Lip Sync mouth cues of the utterance (module docstring)."""

    name = "rhubarb"
    metavar = "FILE.tsv|.json|.xml|.dat"
    help = "also write Rhubarb Lip Sync mouth cues (A-H, X) as TSV, JSON, XML or Moho DAT (by the suffix)"
    suffixes = tuple(WRITERS)
    arguments = (
        (("--dat-fps",), dict(dest="dat_fps", type=dat_fps, metavar="FPS",
                              help=f"frame rate of a --rhubarb .dat file (default {DAT_FPS:g}, as Rhubarb's)")),
        (("--dat-preston-blair",), dict(dest="dat_preston_blair", action="store_true",
                                        help="Preston Blair shape names in a --rhubarb .dat file (MBP, etc, E, AI, "
                                        "O, U, FV, L, rest)")),
    )

    def __init__(self, path, force: bool = False, **settings):
        super().__init__(path, force, **settings)
        self.dat_fps = _fps(settings.get("dat_fps"))
        if self.path.suffix.lower() != ".dat":
            for dest, flag in (("dat_fps", "--dat-fps"), ("dat_preston_blair", "--dat-preston-blair")):
                if settings.get(dest) not in (None, False):
                    raise InputError(f"{flag} is for a .dat file; this one is {self.path.suffix or 'without suffix'}",
                                     self.path)

    def open(self, run) -> None:
        super().open(run)
        if run.extra.get("utterance") is None:
            raise InputError("--rhubarb needs the utterance's phones (speak or say)", self.path)

    def close(self) -> None:
        from visemeface.retarget.classes import mouth_cues

        utt = self.run.extra["utterance"]
        audio = self.run.audio
        write_cues(self.tmp[0], mouth_cues(utt.segments), utt.end, str(audio) if audio else "",
                   self.dat_fps, bool(self.settings.get("dat_preston_blair")), force=True)
