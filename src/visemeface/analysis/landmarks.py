"""Face landmarks for the automatic mouth box: MediaPipe's face detector and 468-point face mesh.

The two Apache-2.0 models ship in ``data/models/`` (``NOTICE.md``: source, version, checksums)
and run with ``ai-edge-litert``, the optional extra ``visemeface[track]``;
:func:`available` says whether it is installed. Everything here is plain numpy
and OpenCV around two interpreter calls, following MediaPipe's graphs
(settings in ``data/models/face.toml``):

1. *Detection* (BlazeFace short range): the frame is letterboxed to a square
   and resized to :math:`128^2`, RGB scaled to :math:`[-1, 1]`. Each of the
   896 SSD anchors :math:`(a_x, a_y)` (cells of the 16x16 and 8x8 grids,
   2 and 6 anchors a cell, unit size) regresses a box and six keypoints,
   :math:`c_x = a_x + r_0 / 128`, :math:`c_y = a_y + r_1 / 128`,
   :math:`w = r_2 / 128`, :math:`h = r_3 / 128`,
   :math:`k_{j} = a + (r_{4+2j}, r_{5+2j}) / 128` (normalised to the square),
   with score :math:`\\sigma(s)`. Boxes scoring at least ``min_score`` are
   merged by weighted non-maximum suppression (each cluster of IoU above
   ``min_suppression_iou`` with the best box becomes their score-weighted mean).
2. *Region*: a square of side ``roi_scale`` x the box's longer side around
   its centre, turned by the angle of the line between the eyes,
   :math:`\\theta = \\operatorname{atan2}(y_l - y_r, x_l - x_r)` (image axes,
   y down), so the face stands upright in the crop.
3. *Landmarks*: the region is resampled to :math:`192^2` (RGB in
   :math:`[0, 1]`); the model returns 468 points :math:`(u, v, z)` in crop
   pixels and a face-presence logit. A crop point maps to the frame as
   :math:`p = c + s\\,R(\\theta)\\,(u / 192 - 1/2,\\; v / 192 - 1/2)^T`
   (pixel-centre coordinates, :math:`s` the region's side).
4. *Tracking* (:class:`FaceTracker`): the next frame's region is the
   bounding square of this frame's landmarks (the same ``roi_scale``, the eye
   corners 33 and 263 for the angle); when the presence falls below
   ``min_presence`` the face is detected afresh.

All coordinates are frame pixels with pixel centres at integers (OpenCV's).
"""

from __future__ import annotations

import contextlib
import importlib.util
import os
import sys
import tomllib
from dataclasses import dataclass
from functools import lru_cache

import cv2
import numpy as np

from visemeface.resources import data_path


def available() -> bool:
    """True when the optional interpreter (``pip install visemeface[track]``) is installed."""
    return importlib.util.find_spec("ai_edge_litert") is not None


@lru_cache(maxsize=1)
def settings() -> dict:
    """``data/models/face.toml``: the models' settings and the face-mesh indices of the mouth."""
    with open(data_path("models", "face.toml"), "rb") as fh:
        return tomllib.load(fh)


def ssd_anchors(size: int, strides, per_layer: int) -> np.ndarray:
    """Anchor centres ``(A, 2)`` normalised to the input square (MediaPipe's SsdAnchorsCalculator).

    Consecutive layers of one stride share a grid of :math:`\\lceil size / stride \\rceil^2`
    cells; each cell gets ``per_layer`` anchors per layer, at the cell centre.
    """
    out, i = [], 0
    strides = list(strides)
    while i < len(strides):
        j = i
        while j < len(strides) and strides[j] == strides[i]:
            j += 1
        n = int(np.ceil(size / strides[i]))
        ys, xs = np.mgrid[0:n, 0:n]
        cells = np.stack([(xs.ravel() + 0.5) / n, (ys.ravel() + 0.5) / n], axis=1)
        out.append(np.repeat(cells, per_layer * (j - i), axis=0))
        i = j
    return np.concatenate(out)


@dataclass(frozen=True)
class Detection:
    """A face found by the detector: ``box`` (x0, y0, x1, y1) and ``keypoints`` (6, 2) in frame pixels."""

    score: float
    box: np.ndarray
    keypoints: np.ndarray


def decode(raw: np.ndarray, logits: np.ndarray, anchors: np.ndarray, size: int, min_score: float):
    """Scores ``(n,)``, boxes ``(n, 4)`` (x0, y0, x1, y1) and keypoints ``(n, K, 2)``, normalised, of
    the anchors scoring at least ``min_score`` (see the module notes)."""
    scores = 1.0 / (1.0 + np.exp(-np.clip(logits.reshape(-1).astype(np.float64), -100.0, 100.0)))
    keep = scores >= min_score
    r = raw.reshape(len(anchors), -1)[keep] / size
    a = anchors[keep]
    c, half = a + r[:, 0:2], r[:, 2:4] / 2
    kps = a[:, None, :] + r[:, 4:].reshape(len(r), (r.shape[1] - 4) // 2, 2)
    return scores[keep], np.concatenate([c - half, c + half], axis=1), kps


def iou(box: np.ndarray, boxes: np.ndarray) -> np.ndarray:
    """Intersection over union of one box ``(4,)`` with each of ``boxes`` ``(n, 4)`` (x0, y0, x1, y1)."""
    lo, hi = np.maximum(box[:2], boxes[:, :2]), np.minimum(box[2:], boxes[:, 2:])
    inter = np.prod(np.clip(hi - lo, 0, None), axis=1)
    return inter / np.maximum(_area(box) + _area(boxes) - inter, 1e-12)


def _area(boxes: np.ndarray) -> np.ndarray:
    return np.prod(np.clip(boxes[..., 2:] - boxes[..., :2], 0, None), axis=-1)


def weighted_nms(scores, boxes, kps, min_iou: float) -> list[tuple[float, np.ndarray, np.ndarray]]:
    """Clusters of boxes overlapping the best remaining one by more than ``min_iou``, each merged
    into its score-weighted mean ``(best score, box, keypoints)``, best first."""
    order = np.argsort(-scores, kind="stable")
    out = []
    while order.size:
        near = iou(boxes[order[0]], boxes[order]) > min_iou
        near[0] = True
        grp = order[near]
        wts = scores[grp] / scores[grp].sum()
        out.append((float(scores[order[0]]), wts @ boxes[grp], np.tensordot(wts, kps[grp], axes=1)))
        order = order[~near]
    return out


@dataclass(frozen=True)
class Region:
    """A rotated square of the frame: centre ``(x, y)`` (pixels), side ``size``, ``angle`` (radians)."""

    x: float
    y: float
    size: float
    angle: float

    def to_frame(self, n: int) -> np.ndarray:
        """2x3 affine map from pixel centres of an ``n`` x ``n`` crop to frame pixels."""
        c, s = np.cos(self.angle), np.sin(self.angle)
        k = self.size / n
        rot = k * np.array([[c, -s], [s, c]])
        # crop pixel u has normalised position (u + 0.5) / n; the square's centre is n / 2
        off = np.array([self.x, self.y]) - rot @ np.array([n / 2 - 0.5, n / 2 - 0.5])
        return np.hstack([rot, off[:, None]])


def region_around(points: np.ndarray, eyes: tuple[int, int], scale: float) -> Region:
    """The square region of side ``scale`` x the longer side of the points' box, turned by the eye line."""
    lo, hi = points.min(axis=0), points.max(axis=0)
    (xr, yr), (xl, yl) = points[eyes[0]], points[eyes[1]]
    centre = (lo + hi) / 2
    return Region(float(centre[0]), float(centre[1]), float(scale * max(hi - lo)), float(np.arctan2(yl - yr, xl - xr)))


@contextlib.contextmanager
def _quiet_stderr():
    """Silence the interpreter's native log line ("INFO: Created TensorFlow Lite XNNPACK delegate")."""
    try:
        sys.stderr.flush()
        saved = os.dup(2)
    except (OSError, ValueError, AttributeError):         # no file descriptor 2: nothing to silence
        yield
        return
    try:
        with open(os.devnull, "wb") as null:
            os.dup2(null.fileno(), 2)
        yield
    finally:
        os.dup2(saved, 2)
        os.close(saved)


class FaceModels:
    """The two interpreters (one thread each) and the detector's anchors; make once, reuse."""

    def __init__(self, threads: int = 1):
        if not available():
            raise ImportError("face landmarks need the optional extra: pip install 'visemeface[track]'")
        from ai_edge_litert.interpreter import Interpreter

        cfg = settings()
        self.det_cfg, self.lm_cfg = cfg["detector"], cfg["landmarks"]
        with _quiet_stderr():
            self._det = Interpreter(model_path=str(data_path("models", self.det_cfg["file"])), num_threads=threads)
            self._lm = Interpreter(model_path=str(data_path("models", self.lm_cfg["file"])), num_threads=threads)
            for it in (self._det, self._lm):
                it.allocate_tensors()
        self.anchors = ssd_anchors(self.det_cfg["size"], self.det_cfg["strides"], self.det_cfg["anchors_per_layer"])

        self._io = {id(it): (it.get_input_details()[0]["index"], [d["index"] for d in it.get_output_details()])
                    for it in (self._det, self._lm)}

    def _run(self, it, x: np.ndarray) -> list[np.ndarray]:
        inp, outs = self._io[id(it)]
        it.set_tensor(inp, x[None])
        it.invoke()
        return [it.get_tensor(i) for i in outs]

    def detect(self, rgb: np.ndarray) -> list[Detection]:
        """Faces in an RGB uint8 frame, best first (empty when there is none)."""
        cfg, n = self.det_cfg, self.det_cfg["size"]
        h, w = rgb.shape[:2]
        side = max(h, w)
        px, py = (side - w) // 2, (side - h) // 2
        square = cv2.copyMakeBorder(rgb, py, side - h - py, px, side - w - px, cv2.BORDER_CONSTANT, value=0)
        x = cv2.resize(square, (n, n), interpolation=cv2.INTER_AREA).astype(np.float32) / 127.5 - 1.0
        outs = {o.shape[-1]: o for o in self._run(self._det, x)}
        raw, logits = outs[max(outs)], outs[1]
        found = weighted_nms(*decode(raw, logits, self.anchors, n, cfg["min_score"]), cfg["min_suppression_iou"])
        # normalised to the square (0..1 across it) -> frame pixel centres
        off = np.array([px + 0.5, py + 0.5])
        return [Detection(s, (b.reshape(2, 2) * side - off).ravel(), k * side - off) for s, b, k in found]

    def region_of(self, det: Detection) -> Region:
        """The landmark model's region around a detected face."""
        corners = det.box.reshape(2, 2)
        pts = np.vstack([corners, det.keypoints])
        e = self.det_cfg["eyes"]
        return region_around(pts, (2 + e[0], 2 + e[1]), self.lm_cfg["roi_scale"])

    def landmarks(self, rgb: np.ndarray, region: Region) -> tuple[np.ndarray, float]:
        """The 468 face-mesh points ``(468, 2)`` in frame pixels and the face-presence probability."""
        n = self.lm_cfg["size"]
        m = region.to_frame(n)
        crop = cv2.warpAffine(rgb, m, (n, n), flags=cv2.INTER_LINEAR | cv2.WARP_INVERSE_MAP,
                              borderMode=cv2.BORDER_CONSTANT, borderValue=0)
        outs = self._run(self._lm, crop.astype(np.float32) * np.float32(1 / 255))
        pts = next(o for o in outs if o.size > 1).reshape(-1, 3)[:, :2]
        presence = 1.0 / (1.0 + np.exp(-float(next(o for o in outs if o.size == 1).ravel()[0])))
        # model output u is continuous (0..n across the crop): pixel centre u - 0.5
        return (pts - 0.5) @ m[:, :2].T + m[:, 2], presence


class FaceTracker:
    """Per-frame face-mesh landmarks of a video: detect once, then follow (module notes, step 4)."""

    def __init__(self, models: FaceModels | None = None):
        self.models = models or FaceModels()
        self.region: Region | None = None

    def __call__(self, rgb: np.ndarray) -> np.ndarray | None:
        """Landmarks ``(468, 2)`` of the face in this frame, or None when no face is found."""
        cfg = self.models.lm_cfg
        for fresh in (False, True):
            if fresh or self.region is None:
                faces = self.models.detect(rgb)
                if not faces:
                    self.region = None
                    return None
                self.region = self.models.region_of(faces[0])
                fresh = True
            pts, presence = self.models.landmarks(rgb, self.region)
            if presence >= cfg["min_presence"]:
                self.region = region_around(pts, tuple(cfg["eyes"]), cfg["roi_scale"])
                return pts
            if fresh:
                break
        self.region = None
        return None
