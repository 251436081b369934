"""Sidecar files: small JSON files that travel beside a mesh or a video. One rule each.

Landmarks of a mesh
    ``face.obj`` -> ``face.landmarks.json`` (:func:`landmarks_sidecar`): the
    landmark vertices and regions the rig places its muscles by
    (:mod:`visemeface.face.mesh` reads and writes it).
Mouth box of a video or frame folder
    ``take.mp4`` -> ``take.mp4.json``, ``frames/`` -> ``frames.json``
    (:func:`video_sidecar`: the full name + ``.json``), written by the renderer's
    video and frames outputs and read by ``visemeface analyze``::

        {"mouth_box": [x, y, w, h],   # pixels, origin top-left, x right, y down;
                                      # x and x + w on the mouth corners at rest
         "fps": 30.0,                 # frame rate (used for image folders)
         "size": [width, height]}     # frame size in pixels, checked against the video

    Only ``mouth_box`` is required; ``w`` is the natural mouth width that
    normalises every metric.
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path

from visemeface.errors import InputError
from visemeface.outputs import atomic_output


def landmarks_sidecar(mesh: str | Path) -> Path:
    """``face.obj`` -> ``face.landmarks.json`` (same folder)."""
    mesh = Path(mesh)
    return mesh.with_name(mesh.stem + ".landmarks.json")


def video_sidecar(media: str | Path) -> Path:
    """``take.mp4`` -> ``take.mp4.json``; ``frames/`` -> ``frames.json``."""
    media = Path(media)
    return media.with_name(media.name + ".json")


def find_video_sidecar(media: str | Path) -> Path | None:
    """The mouth-box sidecar of a video or folder, if there is one (:func:`video_sidecar`)."""
    side = video_sidecar(media)
    return side if side.is_file() else None


@dataclass(frozen=True)
class Sidecar:
    """Contents of a mouth-box sidecar."""

    mouth_box: object            # visemeface.analysis.openings.MouthBox
    fps: float | None = None
    size: tuple[int, int] | None = None


def read_video_sidecar(path: str | Path) -> Sidecar:
    """Read a mouth-box sidecar (module docstring); :class:`InputError` naming what is wrong."""
    from visemeface.analysis.openings import MouthBox

    path = Path(path)
    from visemeface.textfile import parse_json

    try:
        data = parse_json(path.read_text(encoding="utf-8"), path)
    except FileNotFoundError:
        raise InputError("no such file", path) from None
    except (OSError, UnicodeDecodeError) as exc:
        raise InputError(f"cannot read: {exc}", path) from None
    if not isinstance(data, dict) or "mouth_box" not in data:
        raise InputError('expected a JSON object with "mouth_box": [x, y, w, h]', path)
    try:
        box = MouthBox.of(data["mouth_box"])
    except InputError as exc:
        raise InputError(exc.reason, path) from None
    fps = data.get("fps")
    if fps is not None:
        if not isinstance(fps, (int, float)) or isinstance(fps, bool) or not 0 < fps < float("inf"):
            raise InputError(f'"fps" must be a positive number, got {fps!r}', path)
        fps = float(fps)
    size = data.get("size")
    if size is not None:
        if (not isinstance(size, list) or len(size) != 2
                or not all(isinstance(v, int) and not isinstance(v, bool) and v > 0 for v in size)):
            raise InputError(f'"size" must be [width, height] in pixels, got {size!r}', path)
        size = (size[0], size[1])
    return Sidecar(box, fps, size)


def write_video_sidecar(path: str | Path, mouth_box, fps: float | None = None, size=None,
                        force: bool = False) -> bool:
    """Write a mouth-box sidecar; False (nothing written) when the box is too small to measure."""
    from visemeface.analysis.openings import MouthBox

    try:
        box = MouthBox.of(mouth_box)
    except InputError:
        return False
    data = {"mouth_box": [box.x, box.y, box.w, box.h]}
    if fps is not None:
        data["fps"] = float(fps)
    if size is not None:
        data["size"] = [int(size[0]), int(size[1])]
    with atomic_output(path, force) as tmp:
        tmp.write_text(json.dumps(data) + "\n", encoding="utf-8")
    return True
