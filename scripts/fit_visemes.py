#!/usr/bin/env python
"""Regenerate ``data/visemes/visemes.csv`` from the lip-shape targets.

For every DECtalk posture of ``data/visemes/targets.csv`` the rig's fitting
tool (:func:`visemeface.muscles.fitting.fit_activations`, bounded least
squares) finds the activations of seed 002's twelve speech functions
(Table 1: orbicularis oris; left/right risorius, depressor labii inferioris,
levator labii superioris, zygomatic major, triangularis; jaw) whose pose on the
default rig best reproduces the target lip dimensions (change from rest, in
rest mouth widths). Left/right pairs are tied (the targets are symmetric).
Silence is the rest posture by definition.

Usage::

    PYTHONPATH=src python scripts/fit_visemes.py --force          # rewrite the shipped table
    PYTHONPATH=src python scripts/fit_visemes.py -o /tmp/v.csv    # somewhere else
    PYTHONPATH=src python scripts/fit_visemes.py --force --images docs/images

Prints one JSON line per posture (target, achieved, worst error) and a summary
line; ``--images DIR`` then renders ``visemes.png``, ``emotions.png`` and
``happy_ah.png`` (seed 002 Fig. 6) into DIR.
"""

from __future__ import annotations

import argparse
import csv
import json
import sys
from pathlib import Path

import numpy as np

#: Per-dimension weights of the fit: closure/opening and rounding (width,
#: protrusion) carry the phonetic contrasts; corner height is mostly emotion.
WEIGHTS = {"mouth_width": 1.0, "opening_height": 2.0, "protrusion": 1.5, "upper_lip_raise": 1.0,
           "lower_lip_drop": 1.0, "corner_height": 0.5}
DECIMALS = 4
#: Functions the fit may use: the twelve of seed 002 Table 1 but zygomatic major.
#: Raised lip corners are not a phonetic feature of English visemes; left to the
#: emotions, the smile keeps its whole range when blended with a viseme instead of
#: being clamped away (the viseme table still has the zygomatic columns, at 0).
EXCLUDED = ("zygomatic_major_left", "zygomatic_major_right")


def articulation() -> dict:
    """Per symbol, the functions set by phonetics, not fitted (``data/visemes/articulation.csv``):
    the tongue's (the lip gauge cannot see the tongue), lip rounding and the lower-lip tuck.
    They are held while the twelve speech functions are fitted, then copied into the table."""
    from visemeface.resources import data_path

    with open(data_path("visemes", "articulation.csv"), newline="") as f:
        return {r["symbol"]: {k: float(v) for k, v in r.items() if k not in ("symbol", "source")}
                for r in csv.DictReader(f)}


def fit_table(rig=None, targets=None):
    """Fit every posture; return (rows, report) with rows as dicts for the CSV."""
    from visemeface.muscles.fitting import fit_activations
    from visemeface.muscles.measure import TARGET_DIMENSIONS
    from visemeface.muscles.rig import SPEECH_FUNCTIONS, default_rig
    from visemeface.outputs import progress
    from visemeface.postures.library import load_targets

    rig = rig or default_rig()
    targets = load_targets() if targets is None else targets
    fitted = [f for f in SPEECH_FUNCTIONS if f not in EXCLUDED]
    rows, report = [], []
    held = articulation()
    for sym, t in progress(list(targets.iterrows()), desc="fitting", unit="viseme"):
        goal = {k: float(t[k]) for k in TARGET_DIMENSIONS}
        if all(v == 0 for v in goal.values()):
            acts = dict.fromkeys(SPEECH_FUNCTIONS, 0.0)  # rest posture: nothing to fit
            achieved = dict(goal)
        else:
            a = fit_activations(rig, goal, functions=fitted, symmetric=True, weights=WEIGHTS, base=held[sym])
            acts = {f: round(float(a[f]), DECIMALS) for f in SPEECH_FUNCTIONS}
            achieved = a.attrs["achieved"]
        err = {k: achieved[k] - goal[k] for k in TARGET_DIMENSIONS}
        rows.append({"index": int(t["index"]), "symbol": sym, "class": t["class"], **acts, **held[sym],
                     "notes": t["notes"]})
        report.append({"symbol": sym, "target": {k: round(v, 4) for k, v in goal.items()},
                       "achieved": {k: round(achieved[k], 4) for k in TARGET_DIMENSIONS},
                       "max_abs_error": round(max(abs(v) for v in err.values()), 4),
                       "worst": max(err, key=lambda k: abs(err[k]))})
    return rows, report


def write_table(rows, path, force: bool) -> None:
    from visemeface.outputs import atomic_output

    with atomic_output(path, force) as tmp, open(tmp, "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=list(rows[0]), lineterminator="\n")
        w.writeheader()
        for r in rows:
            w.writerow({k: (f"{v:g}" if isinstance(v, float) else v) for k, v in r.items()})


def render_images(folder: Path, force: bool) -> None:
    """Contact sheets of visemes and emotions and seed 002 Fig. 6 (happy /ah/)."""
    from PIL import Image

    from visemeface.cli import main as cli
    from visemeface.commands.sheet import compose_sheet
    from visemeface.muscles.rig import default_rig
    from visemeface.outputs import atomic_output
    from visemeface.postures.library import posed_vertices
    from visemeface.render.renderer import Renderer

    f = ["--force"] if force else []
    if cli(["sheet", "-o", str(folder / "visemes.png"), "--size", "128", *f]) != 0:
        raise SystemExit(2)
    if cli(["sheet", "--emotions", "-o", str(folder / "emotions.png"), "--size", "256", *f]) != 0:
        raise SystemExit(2)
    rig = default_rig()
    r = Renderer(rig.face, size=(320, 320), view="face")
    panels = [("ah", {}), ("ah", {"happiness": 1.0}), ("_", {"happiness": 1.0})]
    images = [r.render(posed_vertices(rig, v, e)) for v, e in panels]
    sheet = compose_sheet(images, ["Viseme /ah/", "Happy /ah/", "Expression 'Happiness'"], columns=3)
    with atomic_output(folder / "happy_ah.png", force) as tmp:
        Image.fromarray(sheet).save(tmp, format="PNG", optimize=True)


def main(argv=None) -> int:
    from visemeface.errors import VisemefaceError
    from visemeface.postures.library import visemes_file

    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("-o", "--output", default=str(visemes_file()), help="CSV to write (default: the shipped table)")
    ap.add_argument("--force", action="store_true", help="overwrite the output")
    ap.add_argument("--images", metavar="DIR", help="also render the contact sheets and Fig. 6 into DIR")
    args = ap.parse_args(argv)
    try:
        rows, report = fit_table()
        for line in report:
            print(json.dumps(line))
        errs = np.array([r["max_abs_error"] for r in report])
        print(json.dumps({"metric": "viseme_fit_max_abs_error", "mean": round(float(errs.mean()), 4),
                          "max": round(float(errs.max()), 4), "worst": report[int(errs.argmax())]["symbol"],
                          "units": "rest mouth widths"}))
        write_table(rows, args.output, args.force)
        if args.images:
            render_images(Path(args.images), args.force)
    except VisemefaceError as exc:
        print(f"fit_visemes: error: {exc}", file=sys.stderr)
        return 2
    return 0


if __name__ == "__main__":
    sys.exit(main())
