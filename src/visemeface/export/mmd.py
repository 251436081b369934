"""MikuMikuDance motion (``.vmd``): morph frames of the vowel morphs あ い う え お and まばたき.

The weights are the VRM expressions (:class:`~visemeface.export.retarget.FitSink`, vocabulary ``vrm``)
renamed by ``data/retarget/mmd.csv`` (VRM 1.0's aa ih ou ee oh are MMD's あ い う え お; blink is
まばたき) and re-sampled at MMD's 30 frames a second (linear, MMD's own interpolation of morph frames).

VMD's binary layout (little-endian, names Shift-JIS in zero-padded fields):
``"Vocaloid Motion Data 0002"`` in 30 bytes; the model's name in 20 bytes (left empty: the motion fits
any model with these morphs); uint32 bone-frame count (0); uint32 morph-frame count, then per frame
the morph name (15 bytes), the frame number (uint32) and the weight 0..1 (float32), 23 bytes; then
uint32 counts of camera, light, self-shadow and IK frames (0 each).
"""

from __future__ import annotations

import csv
import functools
import math
import struct

import numpy as np

from visemeface.export.retarget import FitSink
from visemeface.export.sinks import register
from visemeface.resources import data_path

#: MMD's frame rate: VMD frame numbers count thirtieths of a second.
MMD_FPS = 30.0
MAGIC = b"Vocaloid Motion Data 0002"
HEADER, MODEL_NAME, MORPH_NAME = 30, 20, 15
MORPH_FRAME = struct.Struct("<15sIf")


@functools.lru_cache(maxsize=1)
def morphs() -> list[tuple[str, str]]:
    """``(MMD morph, VRM expression)`` pairs of ``data/retarget/mmd.csv``."""
    with open(data_path("retarget", "mmd.csv"), newline="", encoding="utf-8") as fh:
        return [(r["morph"], r["vrm"]) for r in csv.DictReader(fh)]


def resample(times, values, fps: float) -> tuple[np.ndarray, np.ndarray]:
    """Frame numbers and values (F', K) of per-frame ``values`` at ``times`` re-sampled linearly at ``fps``."""
    t = np.asarray(times, np.float64)
    v = np.asarray(values, np.float64).reshape(len(t), -1)
    frames = np.arange(int(math.floor(t[-1] * fps + 1e-6)) + 1)
    at = frames / fps
    return frames, np.column_stack([np.interp(at, t, v[:, k]) for k in range(v.shape[1])])


def vmd_bytes(names, times, weights, model: str = "") -> bytes:
    """The VMD file of VRM weights (F, K) named ``names`` at ``times`` (module docstring)."""
    index = {n: k for k, n in enumerate(names)}
    pairs = [(m, index[v]) for m, v in morphs() if v in index]
    frames, w = resample(times, np.clip(np.asarray(weights, np.float64), 0.0, 1.0)[:, [k for _, k in pairs]],
                         MMD_FPS)
    body = [MORPH_FRAME.pack(m.encode("shift_jis"), int(f), float(w[i, j]))
            for j, (m, _) in enumerate(pairs) for i, f in enumerate(frames)]
    head = MAGIC.ljust(HEADER, b"\0") + model.encode("shift_jis")[:MODEL_NAME].ljust(MODEL_NAME, b"\0")
    return (head + struct.pack("<I", 0) + struct.pack("<I", len(body)) + b"".join(body)
            + struct.pack("<4I", 0, 0, 0, 0))


@register
class MmdSink(FitSink):
    """The vowel and blink morph frames of an MMD motion (module docstring)."""

    name = "mmd"
    vocabulary = "vrm"
    fits_gestures = False      # as --vrm (FitSink.fits_gestures)
    metavar = "FILE.vmd"
    help = "also write a MikuMikuDance motion (.vmd): morph frames of あ い う え お and まばたき at 30 fps"
    suffixes = (".vmd",)

    def close(self) -> None:
        self.tmp[0].write_bytes(vmd_bytes(self.vocab.names, self.times, self.weight_matrix()))
