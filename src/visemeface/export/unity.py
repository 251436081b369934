"""Unity AnimationClip (``.anim``): ARKit blendshape curves for a SkinnedMeshRenderer.

Unity serialises assets as YAML 1.1 with its own tag ``!u!`` (``tag:unity3d.com,2011:``); an
AnimationClip is class 74 (document anchor ``&7400000``). Each of the 52 ARKit weights is one float
curve in ``m_FloatCurves`` (and, for the editor, ``m_EditorCurves``) bound to ``blendShape.<name>`` of
class 137 (SkinnedMeshRenderer) at ``path`` "" (the object the Animator sits on; rename the path in
Unity's Animation window when the face mesh is a child). Unity's blend-shape weights run 0–100.

There is one key a frame, less those on the straight line between their neighbours; each key's in
and out slopes are those of the straight lines to its
neighbours and its tangent mode is 69 (both tangents Linear, broken: ``1 | 2 << 1 | 2 << 5``), so
Unity's cubic Hermite evaluation between two keys is exactly the linear interpolation of the frames.
Drop the file into Assets/, add the clip to an Animator Controller on the avatar whose face has
ARKit-named blendshapes ("perfect sync" models), and play.
"""

from __future__ import annotations

import json

import numpy as np

from visemeface.export.retarget import RigFitSink
from visemeface.export.sinks import register

#: Unity's class ids: AnimationClip, SkinnedMeshRenderer.
ANIMATION_CLIP, SKINNED_MESH_RENDERER = 74, 137
#: Tangent mode of a key whose two tangents are Linear (mode 2 in bits 1-4 and 5-8) and broken (bit 0).
LINEAR_TANGENTS = 1 | 2 << 1 | 2 << 5
#: Unity's blend-shape weight of a fully applied shape.
FULL_WEIGHT = 100.0

_HEADER = """%YAML 1.1
%TAG !u! tag:unity3d.com,2011:
--- !u!74 &7400000
AnimationClip:
  m_ObjectHideFlags: 0
  m_CorrespondingSourceObject: {{fileID: 0}}
  m_PrefabInstance: {{fileID: 0}}
  m_PrefabAsset: {{fileID: 0}}
  m_Name: {name}
  serializedVersion: 6
  m_Legacy: 0
  m_Compressed: 0
  m_UseHighQualityCurve: 1
  m_RotationCurves: []
  m_CompressedRotationCurves: []
  m_EulerCurves: []
  m_PositionCurves: []
  m_ScaleCurves: []
"""

_SETTINGS = """  m_PPtrCurves: []
  m_SampleRate: {fps:g}
  m_WrapMode: 0
  m_Bounds:
    m_Center: {{x: 0, y: 0, z: 0}}
    m_Extent: {{x: 0, y: 0, z: 0}}
  m_ClipBindingConstant:
    genericBindings: []
    pptrCurveMapping: []
  m_AnimationClipSettings:
    serializedVersion: 2
    m_AdditiveReferencePoseClip: {{fileID: 0}}
    m_AdditiveReferencePoseTime: 0
    m_StartTime: 0
    m_StopTime: {stop:.6f}
    m_OrientationOffsetY: 0
    m_Level: 0
    m_CycleOffset: 0
    m_HasAdditiveReferencePose: 0
    m_LoopTime: 0
    m_LoopBlend: 0
    m_LoopBlendOrientation: 0
    m_LoopBlendPositionY: 0
    m_LoopBlendPositionXZ: 0
    m_KeepOriginalOrientation: 0
    m_KeepOriginalPositionY: 1
    m_KeepOriginalPositionXZ: 0
    m_HeightFromFeet: 0
    m_Mirror: 0
"""


def linear_slopes(times: np.ndarray, values: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """In and out slopes (F,) of keys joined by straight lines (0 before the first and after the last)."""
    t, v = np.asarray(times, np.float64), np.asarray(values, np.float64)
    step = np.diff(v) / np.maximum(np.diff(t), 1e-12)
    return np.concatenate([[0.0], step]), np.concatenate([step, [0.0]])


def linear_keys(times: np.ndarray, values: np.ndarray, tol: float = 1e-6) -> np.ndarray:
    """Indices of the keys to keep: the ends and every key off the straight line between its neighbours
    (dropping the others leaves the piecewise-linear curve unchanged within ``tol``)."""
    t, v = np.asarray(times, np.float64), np.asarray(values, np.float64)
    if len(t) < 3:
        return np.arange(len(t))
    line = v[:-2] + (v[2:] - v[:-2]) * (t[1:-1] - t[:-2]) / np.maximum(t[2:] - t[:-2], 1e-12)
    inner = np.flatnonzero(np.abs(v[1:-1] - line) > tol) + 1
    return np.concatenate([[0], inner, [len(t) - 1]])


def _curve(name: str, times, values, path: str) -> str:
    keep = linear_keys(times, values)
    times, values = np.asarray(times)[keep], np.asarray(values)[keep]
    ins, outs = linear_slopes(times, values)
    keys = "".join(
        f"      - serializedVersion: 3\n        time: {t:.6f}\n        value: {v:.4f}\n"
        f"        inSlope: {a:.4f}\n        outSlope: {b:.4f}\n        tangentMode: {LINEAR_TANGENTS}\n"
        "        weightedMode: 0\n        inWeight: 0.33333334\n        outWeight: 0.33333334\n"
        for t, v, a, b in zip(times, values, ins, outs))
    return ("  - curve:\n      serializedVersion: 2\n      m_Curve:\n" + keys
            + "      m_PreInfinity: 2\n      m_PostInfinity: 2\n      m_RotationOrder: 4\n"
            f"    attribute: blendShape.{name}\n    path: {path}\n    classID: {SKINNED_MESH_RENDERER}\n"
            "    script: {fileID: 0}\n")


def anim_text(names, times, weights, fps: float, clip: str = "speech", path: str = "") -> str:
    """The AnimationClip YAML of per-frame weights (F, K) in 0..1 named ``names`` (module docstring)."""
    t = np.asarray(times, np.float64)
    w = np.round(np.clip(np.asarray(weights, np.float64), 0.0, 1.0) * FULL_WEIGHT, 4)
    curves = "".join(_curve(n, t, w[:, k], path) for k, n in enumerate(names))
    stop = float(t[-1]) if len(t) else 0.0
    return (_HEADER.format(name=json.dumps(clip)) + "  m_FloatCurves:\n" + curves + _SETTINGS.format(fps=fps, stop=stop)
            + "  m_EditorCurves:\n" + curves
            + "  m_EulerEditorCurves: []\n  m_HasGenericRootTransform: 0\n  m_HasMotionFloatCurves: 0\n"
            "  m_Events: []\n")


@register
class UnitySink(RigFitSink):
    """ARKit weights as a Unity AnimationClip of blendshape curves (module docstring)."""

    name = "unity"
    metavar = "FILE.anim"
    help = "also write a Unity AnimationClip (.anim): ARKit blendshape curves (blendShape.jawOpen, ...; 0-100)"
    suffixes = (".anim",)

    def close(self) -> None:
        text = anim_text(self.names, self.times, self.weight_matrix(), self.run.fps, clip=self.path.stem)
        self.tmp[0].write_text(text, encoding="utf-8")
