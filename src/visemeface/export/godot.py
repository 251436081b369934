"""Godot Animation resource (``.tres``): one blend-shape track per ARKit weight.

A text resource: ``[gd_resource type="Animation" format=N]`` then a ``[resource]`` section of
``key = value`` lines in Godot's variant syntax (``length``, ``step``, ``tracks/<i>/...``).

- Godot 4 (``format=3``, the default): ``tracks/<i>/type = "blend_shape"``, path
  ``NodePath(".:<name>")``, keys a ``PackedFloat32Array`` of (time, transition, value) triplets
  (Godot's ``BLEND_SHAPE_TRACK_SIZE`` 3).
- Godot 3 (``format=2``, ``--tres-godot 3``): value tracks of the MeshInstance property
  ``blend_shapes/<name>``, keys ``{"times": PoolRealArray(...), "transitions": ..., "update": 0,
  "values": [...]}``.

One key a frame, linear interpolation (``interp = 1``), transition 1 (linear easing). The path's node
``.`` is the AnimationPlayer's root node: give the AnimationPlayer's ``root_node`` the face's
MeshInstance (or edit the tracks' paths) and the ARKit-named blend shapes play.
"""

from __future__ import annotations

import json

import numpy as np

from visemeface.export.retarget import RigFitSink
from visemeface.export.sinks import register

#: ``--tres-godot`` choices: the Godot major version, and the resource format it reads.
VERSIONS = {"4": 3, "3": 2}


def _numbers(values) -> str:
    return ", ".join(f"{float(v):.6g}" for v in values)


def _reals(values) -> str:
    """Floats that Godot reads as floats ("1.0", not "1": an int key makes a value track interpolate ints)."""
    return ", ".join(repr(round(float(v), 6)) for v in values)


def _track4(i: int, name: str, times, values) -> str:
    keys = np.column_stack([times, np.ones(len(times)), values]).reshape(-1)
    return (f'tracks/{i}/type = "blend_shape"\ntracks/{i}/imported = false\ntracks/{i}/enabled = true\n'
            f'tracks/{i}/path = NodePath({json.dumps("." + ":" + name)})\ntracks/{i}/interp = 1\n'
            f"tracks/{i}/loop_wrap = true\ntracks/{i}/keys = PackedFloat32Array({_numbers(keys)})\n")


def _track3(i: int, name: str, times, values) -> str:
    return (f'tracks/{i}/type = "value"\ntracks/{i}/path = NodePath({json.dumps(".:blend_shapes/" + name)})\n'
            f"tracks/{i}/interp = 1\ntracks/{i}/loop_wrap = true\ntracks/{i}/imported = false\n"
            f"tracks/{i}/enabled = true\ntracks/{i}/keys = {{\n"
            f'"times": PoolRealArray( {_numbers(times)} ),\n'
            f'"transitions": PoolRealArray( {_numbers(np.ones(len(times)))} ),\n'
            f'"update": 0,\n"values": [ {_reals(values)} ]\n}}\n')


def tres_text(names, times, weights, fps: float, version: str = "4", clip: str = "speech") -> str:
    """The Animation resource of per-frame weights (F, K) in 0..1 (module docstring)."""
    t = np.asarray(times, np.float64)
    w = np.clip(np.asarray(weights, np.float64), 0.0, 1.0)
    track = _track4 if version == "4" else _track3
    length = float(t[-1]) + 1.0 / fps if len(t) else 0.0
    body = "".join(track(k, n, t, w[:, k]) for k, n in enumerate(names))
    return (f'[gd_resource type="Animation" format={VERSIONS[version]}]\n\n[resource]\n'
            f"resource_name = {json.dumps(clip)}\nlength = {length:.6g}\nstep = {1.0 / fps:.6g}\n{body}")


@register
class GodotSink(RigFitSink):
    """ARKit weights as a Godot Animation resource of blend-shape tracks (module docstring)."""

    name = "godot"
    metavar = "FILE.tres"
    help = "also write a Godot Animation resource (.tres): one blend-shape track per ARKit weight"
    suffixes = (".tres",)
    arguments = ((("--tres-godot",), dict(dest="tres_godot", choices=tuple(VERSIONS), default="4",
                                          help="Godot version of --godot: 4 (blend_shape tracks, default) or 3 "
                                          "(value tracks of blend_shapes/NAME)")),)

    def close(self) -> None:
        text = tres_text(self.names, self.times, self.weight_matrix(), self.run.fps,
                         self.settings.get("tres_godot") or "4", clip=self.path.stem)
        self.tmp[0].write_text(text, encoding="utf-8")
