"""Live2D Cubism motion (``.motion3.json``): the mouth parameters ParamMouthOpenY and ParamMouthForm.

The parameters are Live2D's standard mouth ids, each a weighted sum of ARKit weights clamped to its
range (``data/retarget/live2d.csv``: ``id,recipe,low,high``, recipe terms ``arkitName=W``):
ParamMouthOpenY 0 (shut) .. 1 (open), ParamMouthForm -1 (corners down, rounded) .. 1 (corners up, wide).

The layout is Cubism's motion3.json: ``Version`` 3, ``Meta`` (``Duration``, ``Fps``, ``Loop``,
``AreBeziersRestricted``, ``CurveCount``, ``TotalSegmentCount``, ``TotalPointCount``, ``UserDataCount``,
``TotalUserDataSize``) and ``Curves`` of ``{"Target": "Parameter", "Id", "Segments"}``, where
``Segments`` is the first point ``t0, v0`` then for each linear segment ``0, t, v`` (segment type 0 =
linear). One point a frame; the counts are those the Cubism SDK checks when it loads a motion (one
segment a point after the first; every point counted, the first included).
"""

from __future__ import annotations

import functools
import json

import numpy as np

from visemeface.errors import InputError
from visemeface.export.retarget import RigFitSink
from visemeface.export.sinks import register
from visemeface.resources import data_path

#: Segment type id of a linear segment.
LINEAR = 0


@functools.lru_cache(maxsize=1)
def parameters() -> list[tuple[str, list[tuple[str, float]], float, float]]:
    """``(id, [(arkit name, weight)], low, high)`` of ``data/retarget/live2d.csv``."""
    import csv

    from visemeface.retarget.recipes import parse_recipe

    path = data_path("retarget", "live2d.csv")
    with open(path, newline="", encoding="utf-8") as fh:
        rows = list(csv.DictReader(fh))
    return [(r["id"], parse_recipe(r["recipe"], path, i + 2), float(r["low"]), float(r["high"]))
            for i, r in enumerate(rows)]


def parameter_curves(names, weights) -> dict[str, np.ndarray]:
    """Each parameter's per-frame value (F,) from ARKit weights (F, K) named ``names``."""
    index = {n: k for k, n in enumerate(names)}
    w = np.asarray(weights, np.float64).reshape(-1, len(names))
    out = {}
    for pid, terms, low, high in parameters():
        missing = [n for n, _ in terms if n not in index]
        if missing:
            raise InputError(f"live2d.csv: {pid} uses {missing[0]!r}, not an ARKit weight",
                             data_path("retarget", "live2d.csv"))
        out[pid] = np.clip(sum(c * w[:, index[n]] for n, c in terms), low, high)
    return out


def motion3_document(times, curves: dict[str, np.ndarray], fps: float, duration: float | None = None) -> dict:
    """The motion3.json document of per-frame parameter values at ``times``, lasting ``duration`` (default:
    the last time; module docstring)."""
    t = np.asarray(times, np.float64)
    out, segments, points = [], 0, 0
    for pid, values in curves.items():
        seg = [round(float(t[0]), 4), round(float(values[0]), 4)]
        for ti, vi in zip(t[1:], values[1:]):
            seg += [LINEAR, round(float(ti), 4), round(float(vi), 4)]
        out.append({"Target": "Parameter", "Id": pid, "Segments": seg})
        segments += len(t) - 1
        points += len(t)
    end = float(t[-1]) if duration is None else max(float(duration), float(t[-1]))
    meta = {"Duration": round(end, 4), "Fps": float(fps), "Loop": False, "AreBeziersRestricted": True,
            "CurveCount": len(out), "TotalSegmentCount": segments, "TotalPointCount": points,
            "UserDataCount": 0, "TotalUserDataSize": 0}
    return {"Version": 3, "Meta": meta, "Curves": out}


@register
class Live2dSink(RigFitSink):
    """Live2D's mouth parameters from the ARKit weights (module docstring)."""

    name = "live2d"
    metavar = "FILE.motion3.json"
    help = "also write a Live2D Cubism motion (.motion3.json): ParamMouthOpenY and ParamMouthForm curves"
    suffixes = (".json",)

    def __init__(self, path, force: bool = False, **settings):
        super().__init__(path, force, **settings)
        if not self.path.name.lower().endswith(".motion3.json"):
            raise InputError("the output must end in .motion3.json (Cubism finds motions by it)", self.path)

    def close(self) -> None:
        doc = motion3_document(self.times, parameter_curves(self.names, self.weight_matrix()), self.run.fps,
                               self.run.end_time)
        self.tmp[0].write_text(json.dumps(doc, indent=1) + "\n", encoding="utf-8")
