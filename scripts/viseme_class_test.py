#!/usr/bin/env python
"""Objective viseme class test: seed 002 Table 2's eight classes, nearest centroid, leave-one-out.

Seed 002 (§3) asked twelve people to name the class (Table 2: /p,b,m/ /w/ /f,v/
/ae,eh,ih/ /ow/ /r,rx/ /ao/ /sh,zh,z/) of silence-viseme-silence animations;
they were right 20-95% of the time. This test replaces the panel by a
measurement: every posture of the eight classes is posed on the default rig and
**rendered** in two views (the front mouth view and the three-quarter view), and
each sample is classified from what the pictures show by the nearest class
centroid (Euclidean) with that sample left out of its own class's centroid.

Image features: around the rest mouth box of each view the picture is cut out
(0.2 mouth widths either side, from 0.4 lip heights above to 2.2 below), and
three maps are made of it (:mod:`visemeface.render.mouth_pixels`): dark pixels
(the cavity, luminance < 40), teeth (bright, pale) and red pixels (lips,
tongue, gums); each map is averaged down to 32 x 20 cells. The two views' maps
are the feature vector (2 x 3 x 640 values, fractions 0..1). The cell count was
chosen by trying 12 x 8, 16 x 12, 24 x 16, 32 x 20 and 40 x 24: the lowest class
rate is 87.5, 93.8, 93.8, 95.8 and 95.8% (/ae,eh,ih/, the most varied class, is
always the lowest). The mesh's lip
dimensions (``--features lips``, the earlier test) see no teeth or tongue: with
the labiodentals' lower lip tucked under the teeth, /f,v/ and /ae,eh,ih/ have
similar lip dimensions, and the teeth above the lower lip are what tells them apart.

A viseme is not seen alone in speech, so each posture is sampled the way an
expressive speaker would show it: at viseme weights ``0.8`` and ``1.0`` and
blended with nothing or with each of the seven emotions at weight 0.2
(16 samples a posture, 256 in all). A singleton class (/w/, /ow/, /ao/) thus
still has a centroid when one of its samples is left out. ``--sweep`` prints
the recognition rates as the emotion weight grows (emotions, anger's lip
tightening above all, blur the classes).

Usage::

    PYTHONPATH=src python scripts/viseme_class_test.py            # prints the confusion matrix (images)
    PYTHONPATH=src python scripts/viseme_class_test.py --features lips   # the mesh lip dimensions instead
    PYTHONPATH=src python scripts/viseme_class_test.py --json     # one JSON line per class
    PYTHONPATH=src python scripts/viseme_class_test.py --sweep    # JSON lines: rates vs emotion weight

Exit status 1 when a class is recognised below ``--min-rate`` (default 0.95).
"""

from __future__ import annotations

import argparse
import json
import sys

import numpy as np
import pandas as pd

from visemeface.muscles.measure import TARGET_DIMENSIONS as FEATURES  # noqa: E402


def lip_features(gauge, vertices: np.ndarray) -> np.ndarray:
    """Lip dimensions of ``vertices`` as change from rest in rest mouth widths (FEATURES order).

    ``gauge`` is a :class:`visemeface.muscles.measure.LipGauge` of the rig's face.
    """
    d = gauge.changes(vertices)
    return np.array([d[k] for k in FEATURES])


#: The two views of the image features and their render sizes (the three-quarter view frames the whole face).
VIEWS = (("mouth", 128), ("three-quarter", 256))
CELLS = (32, 20)


class ImageFeatures:
    """Renders posed vertices in :data:`VIEWS` and turns the mouth region into pixel-class maps."""

    def __init__(self, face):
        from visemeface.render.renderer import Renderer

        self.renderers = [Renderer(face, size=size, view=view, samples=0) for view, size in VIEWS]
        self.boxes = []
        for r in self.renderers:
            x, y, w, h = r.mouth_box()
            self.boxes.append((max(0, int(x - 0.2 * w)), int(x + 1.2 * w), max(0, int(y - 0.4 * h)),
                               int(y + 2.2 * h)))

    def __call__(self, vertices: np.ndarray) -> np.ndarray:
        import cv2

        from visemeface.render.mouth_pixels import teeth_pixels, tongue_pixels

        out = []
        for r, (x0, x1, y0, y1) in zip(self.renderers, self.boxes):
            img = r.render(vertices)[y0:y1, x0:x1]
            lum = img.astype(np.float32) @ np.array([0.299, 0.587, 0.114], np.float32)
            for m in (lum < 40, teeth_pixels(img), tongue_pixels(img)):
                out.append(cv2.resize(m.astype(np.float32), CELLS, interpolation=cv2.INTER_AREA).ravel())
        return np.concatenate(out)

    def release(self):
        for r in self.renderers:
            r.release()


def class_samples(rig=None, emotion_weight: float = 0.2, viseme_weights=(0.8, 1.0),
                  images: bool = True) -> pd.DataFrame:
    """Lip and image features of every Table-2 posture under the sampling conditions.

    Returns a DataFrame with columns ``class``, ``symbol``, ``condition``, FEATURES
    (lip dimensions) and, with ``images``, ``img0 ..`` (the image features).
    """
    from visemeface.muscles.measure import LipGauge
    from visemeface.muscles.rig import default_rig
    from visemeface.postures.library import load_expressions, posed_vertices
    from visemeface.postures.phonemes import CLASSES

    rig = rig or default_rig()
    gauge = LipGauge(rig.face)
    camera = ImageFeatures(rig.face) if images else None
    emotions = [None] + load_expressions(rig=rig).index.tolist()
    rows, pictures = [], []
    try:
        for key, members in CLASSES.items():
            for sym in members:
                for wv in viseme_weights:
                    for e in emotions:
                        mix = {} if e is None else {e: emotion_weight}
                        v = posed_vertices(rig, sym, mix, w_viseme=wv)
                        rows.append((key, sym, f"{wv:g}" + ("" if e is None else f"+{e}"), *lip_features(gauge, v)))
                        if camera is not None:
                            pictures.append(camera(v))
    finally:
        if camera is not None:
            camera.release()
    out = pd.DataFrame(rows, columns=["class", "symbol", "condition", *FEATURES])
    if pictures:
        P = np.array(pictures)
        out = pd.concat([out, pd.DataFrame(P, columns=[f"img{i}" for i in range(P.shape[1])])], axis=1)
    return out


def feature_columns(samples: pd.DataFrame, features: str = "image") -> list[str]:
    """The columns a classification uses: ``image`` (the pictures) or ``lips`` (mesh lip dimensions)."""
    if features == "lips":
        return list(FEATURES)
    cols = [c for c in samples.columns if c.startswith("img")]
    if not cols:
        raise ValueError("the samples have no image features (class_samples(images=False))")
    return cols


def nearest_centroid_loo(X: np.ndarray, y: np.ndarray) -> np.ndarray:
    """Leave-one-out nearest-centroid labels.

    For sample :math:`i` of class :math:`c` with :math:`n_c` members, the
    centroid of its own class without it is
    :math:`(n_c\\,\\mu_c - x_i)/(n_c - 1)`; other centroids are the plain means.
    The predicted label minimises the Euclidean distance.

    Parameters
    ----------
    X : (S, F) float array
    y : (S,) labels; every class needs at least two samples

    Returns
    -------
    (S,) predicted labels
    """
    X = np.asarray(X, float)
    y = np.asarray(y)
    classes = np.unique(y)
    counts = np.array([(y == c).sum() for c in classes])
    if (counts < 2).any():
        raise ValueError(f"class {classes[counts < 2][0]!r} has fewer than two samples")
    sums = np.stack([X[y == c].sum(axis=0) for c in classes])
    pred = np.empty(len(y), dtype=classes.dtype)
    for i, (x, c) in enumerate(zip(X, y)):
        k = int(np.searchsorted(classes, c))
        cent = sums / counts[:, None]
        cent[k] = (sums[k] - x) / (counts[k] - 1)
        pred[i] = classes[np.argmin(np.linalg.norm(cent - x, axis=1))]
    return pred


def confusion(samples: pd.DataFrame, features: str = "image") -> pd.DataFrame:
    """Confusion matrix (rows: true class, columns: predicted, fractions of the row)."""
    X = samples[feature_columns(samples, features)].to_numpy()
    pred = nearest_centroid_loo(X, samples["class"].to_numpy())
    m = pd.crosstab(samples["class"].rename("true"), pd.Series(pred, name="predicted", index=samples.index),
                    normalize="index")
    labels = sorted(samples["class"].unique())
    return m.reindex(index=labels, columns=labels, fill_value=0.0)


def main(argv=None) -> int:
    from visemeface.postures.phonemes import class_label

    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--json", action="store_true", help="one JSON line per class instead of the table")
    ap.add_argument("--min-rate", type=float, default=0.95, help="fail below this recognition rate (0.95)")
    ap.add_argument("--emotion-weight", type=float, default=0.2, help="weight of the emotions mixed in (0.2)")
    ap.add_argument("--sweep", action="store_true", help="print rates for emotion weights 0 to 0.5 and exit")
    ap.add_argument("--features", choices=("image", "lips"), default="image",
                    help="classify the renders in two views (image, default) or the mesh's lip dimensions (lips)")
    args = ap.parse_args(argv)
    images = args.features == "image"
    if args.sweep:
        from visemeface.muscles.rig import default_rig

        rig = default_rig()
        for w in (0.0, 0.1, 0.2, 0.25, 0.3, 0.4, 0.5):
            m = confusion(class_samples(rig, emotion_weight=w, images=images), args.features)
            rates = {k: round(float(m.loc[k, k]), 4) for k in m.index}
            print(json.dumps({"metric": "viseme_class_recognition_sweep", "emotion_weight": w,
                              "min_rate": min(rates.values()), "rates": rates}))
        return 0
    samples = class_samples(emotion_weight=args.emotion_weight, images=images)
    m = confusion(samples, args.features)
    rates = pd.Series(np.diag(m.to_numpy()), index=m.index)
    if args.json:
        for k, r in rates.items():
            print(json.dumps({"metric": "viseme_class_recognition", "features": args.features, "class": k,
                              "label": class_label(k),
                              "rate": round(float(r), 4), "samples": int((samples["class"] == k).sum())}))
    else:
        shown = m.copy()
        shown.index = [f"{k} {class_label(k)}" for k in m.index]
        with pd.option_context("display.width", 160):
            print(f"confusion matrix, {args.features} features (rows: true class, columns: predicted; % of the row)")
            print((100 * shown).round(1).to_string())
        print(f"lowest recognition: {rates.idxmin()} {class_label(rates.idxmin())} {100 * rates.min():.1f}%")
    return 0 if (rates >= args.min_rate).all() else 1


if __name__ == "__main__":
    sys.exit(main())
