#!/usr/bin/env python
"""Objective viseme class test: seed 002 Table 2's eight classes, nearest centroid, leave-one-out.

Seed 002 (§3) asked twelve people to name the class (Table 2: /p,b,m/ /w/ /f,v/
/ae,eh,ih/ /ow/ /r,rx/ /ao/ /sh,zh,z/) of silence-viseme-silence animations;
they were right 20-95% of the time. This test replaces the panel by a
measurement: every posture of the eight classes is posed on the default rig,
its lip dimensions (mouth width, opening height, protrusion, upper-lip raise,
lower-lip drop, corner height; change from rest in mouth widths) are measured
on the mesh, and each sample is classified by the nearest class centroid
(Euclidean) with that sample left out of its own class's centroid.

A viseme is not seen alone in speech, so each posture is sampled the way an
expressive speaker would show it: at viseme weights ``0.8`` and ``1.0`` and
blended with nothing or with each of the seven emotions at weight 0.2
(16 samples a posture, 256 in all). A singleton class (/w/, /ow/, /ao/) thus
still has a centroid when one of its samples is left out. ``--sweep`` prints
the recognition rates as the emotion weight grows (emotions, anger's lip
tightening above all, blur the classes).

Usage::

    PYTHONPATH=src python scripts/viseme_class_test.py            # prints the confusion matrix
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


def class_samples(rig=None, emotion_weight: float = 0.2, viseme_weights=(0.8, 1.0)) -> pd.DataFrame:
    """Measured lip features of every Table-2 posture under the sampling conditions.

    Returns a DataFrame with columns ``class``, ``symbol``, ``condition`` and FEATURES.
    """
    from visemeface.muscles.measure import LipGauge
    from visemeface.muscles.rig import default_rig
    from visemeface.postures.library import load_expressions, posed_vertices
    from visemeface.postures.phonemes import CLASSES

    rig = rig or default_rig()
    gauge = LipGauge(rig.face)
    emotions = [None] + load_expressions(rig=rig).index.tolist()
    rows = []
    for key, members in CLASSES.items():
        for sym in members:
            for wv in viseme_weights:
                for e in emotions:
                    mix = {} if e is None else {e: emotion_weight}
                    f = lip_features(gauge, posed_vertices(rig, sym, mix, w_viseme=wv))
                    rows.append((key, sym, f"{wv:g}" + ("" if e is None else f"+{e}"), *f))
    return pd.DataFrame(rows, columns=["class", "symbol", "condition", *FEATURES])


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


def confusion(samples: pd.DataFrame) -> pd.DataFrame:
    """Confusion matrix (rows: true class, columns: predicted, fractions of the row)."""
    pred = nearest_centroid_loo(samples[list(FEATURES)].to_numpy(), samples["class"].to_numpy())
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
    args = ap.parse_args(argv)
    if args.sweep:
        from visemeface.muscles.rig import default_rig

        rig = default_rig()
        for w in (0.0, 0.1, 0.2, 0.25, 0.3, 0.4, 0.5):
            m = confusion(class_samples(rig, emotion_weight=w))
            rates = {k: round(float(m.loc[k, k]), 4) for k in m.index}
            print(json.dumps({"metric": "viseme_class_recognition_sweep", "emotion_weight": w,
                              "min_rate": min(rates.values()), "rates": rates}))
        return 0
    samples = class_samples(emotion_weight=args.emotion_weight)
    m = confusion(samples)
    rates = pd.Series(np.diag(m.to_numpy()), index=m.index)
    if args.json:
        for k, r in rates.items():
            print(json.dumps({"metric": "viseme_class_recognition", "class": k, "label": class_label(k),
                              "rate": round(float(r), 4), "samples": int((samples["class"] == k).sum())}))
    else:
        shown = m.copy()
        shown.index = [f"{k} {class_label(k)}" for k in m.index]
        with pd.option_context("display.width", 160):
            print("confusion matrix (rows: true class, columns: predicted; % of the row)")
            print((100 * shown).round(1).to_string())
        print(f"lowest recognition: {rates.idxmin()} {class_label(rates.idxmin())} {100 * rates.min():.1f}%")
    return 0 if (rates >= args.min_rate).all() else 1


if __name__ == "__main__":
    sys.exit(main())
