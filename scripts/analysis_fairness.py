"""The opening measure across people and recordings: agreement with hand labels per group.

Groups (each printed as one JSON line, every clip of it as another):

- ``real``: the three GRID clips of ../shared/realdata against their hand labels
  (tests/analysis/data/realdata_labels.csv, every 5th frame);
- ``dark``, ``moustache``, ``dark+moustache``, ``grey``, ``low-contrast``, ``mirrored``: altered copies of
  them (:mod:`visemeface.analysis.augment`; the mouth's geometry is unchanged, so the labels hold);
- ``render-I`` ... ``render-VI``: the default face at each ``--skin`` preset (view face, 256 px,
  jaw and lip poses), against the truth the renderer itself gives (the same poses with every skin
  and lip vertex painted green: what is not green inside the mouth is the opening).

Per group: open/closed agreement, the largest height error (px) on frames open in both, and
``outside``: openings reaching beyond the lips' outer contour (the original clip's face mesh, grown
by 0.05 w): a detection on a moustache, beard or nostril.

Run: ``PYTHONPATH=src python scripts/analysis_fairness.py [--method mesh] [--groups real,dark] [--clips ...]
[--show]`` (``--show`` lists every disagreeing frame). The tracked face-mesh points of the originals are
cached in ``--cache`` (default /tmp/visemeface_fairness).
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import cv2
import numpy as np
import pandas as pd

from visemeface.analysis import augment
from visemeface.analysis.landmarks import FaceTracker, settings
from visemeface.analysis.mouthbox import track_mouth
from visemeface.analysis.openings import OpeningDetector
from visemeface.analysis.video import open_frames

ROOT = Path(__file__).resolve().parents[1]
LABELS = ROOT / "tests" / "analysis" / "data" / "realdata_labels.csv"
CLIPS = ("swwp2s", "bbaf2n", "lbax4n")
AUGMENTED = ("dark", "moustache", "dark+moustache", "grey", "low-contrast", "mirrored")
SKINS = ("I", "II", "III", "IV", "V", "VI")
#: Poses of the rendered face: (jaw, extra muscle activations).
POSES = [(0.0, {}), (0.04, {}), (0.08, {}), (0.12, {}), (0.18, {}), (0.25, {}), (0.35, {}), (0.5, {}),
         (0.0, {"orbicularis_oris": 0.6}), (0.2, {"orbicularis_oris": 0.5}), (0.3, {"risorius_left": 0.6,
                                                                                     "risorius_right": 0.6})]


def original(realdata: Path, clip: str, cache: Path):
    """Frames and the face-mesh points (468, 2) of every frame (cached)."""
    frames = list(open_frames(realdata / f"{clip}.mpg").frames())
    f = cache / f"{clip}.npy"
    if f.exists():
        pts = np.load(f)
    else:
        tracker = FaceTracker()
        pts = np.array([tracker(fr) for fr in frames])
        cache.mkdir(parents=True, exist_ok=True)
        np.save(f, pts)
    return frames, pts


def altered(frames, pts, kind: str):
    """The frames altered by ``kind`` and the (mirrored where needed) mesh points."""
    if kind == "real":
        return frames, pts
    if kind in ("dark", "dark+moustache"):
        f = np.median([augment.darkening_factor(fr, p) for fr, p in zip(frames[::15], pts[::15])])
        frames = [augment.darken_skin(fr, p, f) for fr, p in zip(frames, pts)]
    if kind in ("moustache", "dark+moustache"):
        frames = [augment.moustache(fr, p, seed=i) for i, (fr, p) in enumerate(zip(frames, pts))]
    if kind == "grey":
        frames = [augment.grey(fr) for fr in frames]
    if kind == "low-contrast":
        frames = [augment.low_contrast(fr) for fr in frames]
    if kind == "mirrored":
        w = frames[0].shape[1]
        frames = [augment.mirror(fr) for fr in frames]
        pts = pts.copy()
        pts[..., 0] = w - 1 - pts[..., 0]
    return frames, pts


def outside(op, pts, w: float, shape) -> int:
    """Openings reaching beyond the outer lip contour grown by 0.05 w."""
    outer = pts[settings()["mouth"]["outer"]]
    m = augment._poly(shape, outer)
    g = max(1, int(round(0.05 * w)))
    m = cv2.dilate(m, np.ones((2 * g + 1, 2 * g + 1), np.uint8)).astype(bool)
    bad = 0
    for c in op.contours:
        c = c.reshape(-1, 2)
        c = c[(c[:, 0] >= 0) & (c[:, 1] >= 0) & (c[:, 0] < shape[1]) & (c[:, 1] < shape[0])]
        bad += int((~m[c[:, 1], c[:, 0]]).any())
    return bad


def real_rows(realdata: Path, kinds, detector, cache: Path, clips):
    lab = pd.read_csv(LABELS, comment="#")
    rows = []
    for clip in clips:
        frames0, pts0 = original(realdata, clip, cache)
        for kind in kinds:
            frames, pts = altered(frames0, pts0, kind)
            boxes = track_mouth(frames, source=f"{clip} {kind}")
            found = {r.frame: detector.detect(frames[r.frame], boxes[r.frame]) for r in lab[lab["clip"] == clip].itertuples()}
            for r in lab[lab["clip"] == clip].itertuples():
                op = found[r.frame]
                w = op.mouth_width
                rows.append(dict(group=kind, clip=clip, frame=r.frame, open=int(r.open), height_px=float(r.height_px),
                                 found=int(op.count > 0), found_px=op.largest_height * w, count=op.count,
                                 outside=outside(op, pts[r.frame], w, frames[r.frame].shape)))
    return rows


def render_rows(skins, detector):
    """Rendered poses at each skin preset against the renderer's own truth (module notes)."""
    from visemeface.face.procedural import default_face
    from visemeface.muscles.rig import MuscleRig
    from visemeface.render.renderer import Renderer

    rows = []
    for skin in skins:
        face = default_face(skin=skin)
        rig = MuscleRig.from_file(face)
        truth_face = default_face(skin=skin)
        interior = np.unique(np.concatenate([face.regions[k] for k in ("mouth_cavity", "cavity_wall", "upper_teeth",
                                                                        "lower_teeth", "upper_gum", "lower_gum",
                                                                        "tongue")]))
        colours = np.tile([0.0, 1.0, 0.0], (face.n_vertices, 1))
        colours[interior] = face.colors[interior]
        truth_face.colors = colours
        with Renderer(face, size=256, view="face") as r, Renderer(truth_face, size=256, view="face") as rt:
            poses = [rig.pose(rig.activation_vector({"jaw": j, **m})) for j, m in POSES]
            frames = [r.render(v) for v in poses]
            truths = [rt.render(v) for v in poses]
            bx, by, bw, bh = r.mouth_box()
        boxes = track_mouth(frames, source=f"render {skin}")
        for i, (fr, tr, b) in enumerate(zip(frames, truths, boxes)):
            op = detector.detect(fr, b)
            region = np.zeros(tr.shape[:2], bool)
            region[by - bw // 4:by + bh + bw // 2, bx - bw // 8:bx + bw + bw // 8] = True
            t = tr.astype(int)
            not_green = region & ~((t[..., 1] > t[..., 0] + 30) & (t[..., 1] > t[..., 2] + 30))
            n, lab, st, _ = cv2.connectedComponentsWithStats(not_green.view(np.uint8), connectivity=8)
            h = int(st[1:, cv2.CC_STAT_HEIGHT].max()) if n > 1 else 0
            rows.append(dict(group=f"render-{skin}", clip=f"render-{skin}", frame=i, open=int(h >= 3),
                             height_px=float(h), found=int(op.count > 0), found_px=op.largest_height * op.mouth_width,
                             count=op.count, outside=0, ambiguous=int(1 <= h <= 2)))
    return rows


def summary(df: pd.DataFrame) -> dict:
    df = df[df.get("ambiguous", pd.Series(0, index=df.index)).fillna(0) == 0]
    both = df[(df["open"] == 1) & (df["found"] == 1)]
    err = (both["found_px"] - both["height_px"]).abs()
    return {"frames": len(df), "agreement": round(float((df["open"] == df["found"]).mean()), 3),
            "open_frames": int(df["open"].sum()), "height_err_max_px": round(float(err.max()), 2) if len(err) else None,
            "height_err_median_px": round(float(err.median()), 2) if len(err) else None,
            "outside": int(df["outside"].sum())}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--realdata", type=Path, default=ROOT.parents[0] / "shared" / "realdata")
    ap.add_argument("--method", default="mesh")
    ap.add_argument("--groups", default=",".join(("real", *AUGMENTED, "render")))
    ap.add_argument("--clips", default=",".join(CLIPS))
    ap.add_argument("--cache", type=Path, default=Path("/tmp/visemeface_fairness"))
    ap.add_argument("--show", action="store_true", help="list the frames where the measure disagrees")
    args = ap.parse_args()
    detector = OpeningDetector(method=args.method)
    groups = args.groups.split(",")
    kinds = [g for g in groups if g != "render"]
    rows = real_rows(args.realdata, kinds, detector, args.cache, args.clips.split(",")) if kinds else []
    if "render" in groups:
        rows += render_rows(SKINS, detector)
    df = pd.DataFrame(rows)
    for g, sub in df.groupby("group", sort=False):
        print(json.dumps({"bench": "analysis.fairness", "method": args.method, "group": g, **summary(sub)}), flush=True)
        for c, s2 in sub.groupby("clip", sort=False):
            if c != g:
                print(json.dumps({"bench": "analysis.fairness", "method": args.method, "group": g, "clip": c,
                                  **summary(s2)}), flush=True)
    if args.show:
        bad = df[(df["open"] != df["found"]) | ((df["open"] == 1) & ((df["found_px"] - df["height_px"]).abs() > 2))
                 | (df["outside"] > 0)]
        print(bad.to_string())


if __name__ == "__main__":
    main()
