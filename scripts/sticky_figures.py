"""Figures of the sticky-lip FEM face (issue 8), printed as JSON lines.

    PYTHONPATH=src python scripts/sticky_figures.py              # default face, ~15-25 min on 2 busy cores
    PYTHONPATH=src python scripts/sticky_figures.py --resolution 1500 --only zipper,merge
    PYTHONPATH=src python scripts/sticky_figures.py --only calibration --calibration-tracking 1000

Figures
-------
counts       FEM nodes / hexahedra / saliva elements (seed 000: 6,982 nodes, 3,414 hexahedra)
calibration  per viseme: RMS lip-vertex distance between the FEM equilibrium without glue
             and the kinematic posture, in mouth widths (target <= 5 %)
zipper       sticky (glue 0.08) vs elastic: when and where the lips part; saliva failure
             order at 1 kHz; opening width per 60-fps frame from the mesh and from the
             seed-001 analysis of rendered frames
equilibrium  RMS lip difference sticky vs elastic once open wide (target <= 1 %)
merge        central glue 0.18 at 60 fps: opening count 2 -> 1 and the width jump at the merge (mesh, video)
asymmetry    one-sided activation and one-sided glue: which side opens first
evaporation  the "open" scenario twice with evaporation: jaw at saliva failure, 1st vs 2nd opening
speech       "Bob moves five boats" (closures) and the 3 s example as `speak --physics` runs them, sticky
             and elastic: completes? lip RMS vs the kinematic posture; how far sticky and elastic differ
Pictures go to docs/images/sticky_*.png.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

import numpy as np

from visemeface.face.procedural import default_face
from visemeface.muscles.rig import MuscleRig
from visemeface.physics import drive
from visemeface.physics.face_model import build_fem_face, seam_openings

IMAGES = Path(__file__).resolve().parents[1] / "docs" / "images"


def emit(**kw):
    print(json.dumps(kw, default=lambda o: o.tolist() if hasattr(o, "tolist") else str(o)), flush=True)


def ramp(rig, fps, start=0.02, ramp_s=0.12, hold=0.2, jaw=0.35, extra=None):
    return drive.ramp_track(rig.names, fps, start, ramp_s, hold, jaw, extra)


def run(fem, rig, track, physics="sticky", **settings):
    sim = drive.StickySimulation(fem, rig, track, physics=physics, settings=drive.PhysicsSettings(**settings))
    out = []
    for fr in sim.frames():
        out.append({"i": fr.index, "t": fr.time, "v": fr.vertices, "d": fr.display,
                    "broken": sim.saliva.broken.copy(), **fr.saliva})
    return sim, out


def lip_ids(fem):
    return np.unique(np.concatenate([fem.face.region("upper_lip"), fem.face.region("lower_lip")]))


def fig_counts(fem):
    emit(figure="counts", **fem.counts(), seed_nodes=6982, seed_hexahedra=3414)


def fig_calibration(fem, rig, fps=400, tracking=0.0):
    from visemeface.postures.library import load_visemes
    table = load_visemes()
    lips = lip_ids(fem)
    errs = {}
    diverged = []
    for sym, row in table.iterrows():
        extra = {k: float(v) for k, v in row.items() if k != "jaw" and v != 0}
        tr = ramp(rig, fps, start=0.0, ramp_s=0.08, hold=0.17, jaw=float(row.get("jaw", 0.0)), extra=extra)
        try:
            sim, frames = run(fem, rig, tr, physics="elastic", tracking=tracking)
        except Exception as e:
            diverged.append(sym)
            emit(figure="calibration", viseme=sym, tracking_hz=tracking, error=f"{type(e).__name__}: {str(e)[:160]}")
            continue
        kin = rig.pose(sim.values[-1]) - rig.face.vertices
        got = frames[-1]["v"] - fem.face.vertices
        errs[sym] = float(np.sqrt(np.mean(np.sum((got[lips] - kin[lips]) ** 2, axis=1))) / fem.mouth_width)
        emit(figure="calibration", viseme=sym, tracking_hz=tracking, rms_mouth_widths=round(errs[sym], 5))
    e = np.array(list(errs.values()))
    emit(figure="calibration_summary", tracking_hz=tracking, visemes=len(e), median=round(float(np.median(e)), 5),
         max=round(float(e.max()), 5), worst=max(errs, key=errs.get), target=0.05,
         within_target=int((e <= 0.05).sum()), diverged=diverged)


def mouth_profile(fem, frames, fps, size=512):
    """Seed-001 analysis of the rendered frames: width (mouth widths) and count per frame, and a strip."""
    from visemeface.analysis.openings import OpeningDetector
    from visemeface.analysis.profiles import analyze_frames
    from visemeface.render.renderer import Renderer
    r = Renderer(fem.face, size=(size, size), view="mouth")
    imgs = [r.render(f["d"]) for f in frames]
    prof = analyze_frames(imgs, r.mouth_box(), fps, OpeningDetector(method="seed"))   # the published figures
    return prof, imgs


def fig_zipper(fem, rig):
    lips = lip_ids(fem)
    # 1 kHz: the order in which the saliva fails.
    tr = ramp(rig, 1000)
    res = {p: run(fem, rig, tr, physics=p)[1] for p in ("sticky", "elastic")}
    rest = fem.rest_gaps
    for p, frames in res.items():
        first = {}
        for f in frames:
            for e in np.flatnonzero(f["broken"]):
                first.setdefault(int(e), f["t"])
        part = next(f for f in frames if ((fem.seam_gaps(f["v"]) - rest) / fem.mouth_width).max() > 0.002)
        g = (fem.seam_gaps(part["v"]) - rest) / fem.mouth_width
        spans = [(round(f["t"], 4), round(f["open_span"], 3)) for f in frames if 0 < f["open_span"] < 0.99][:40]
        emit(figure="zipper_1khz", physics=p, first_parting_s=round(part["t"], 4),
             jaw_at_parting=round(float(tr["jaw"].iloc[part["i"]]), 4),
             gap_profile_at_parting=np.round(g / g.max(), 2), seam_s=np.round(fem.seam_s, 2),
             saliva_s=np.round(fem.saliva_s, 2),
             saliva_failure_s=[round(first.get(e, float("nan")), 4) for e in range(len(fem.saliva))],
             open_span_while_growing=spans)
    s, e = res["sticky"][-1]["v"], res["elastic"][-1]["v"]
    emit(figure="equilibrium", rms_sticky_vs_elastic_mouth_widths=round(
        float(np.sqrt(np.mean(np.sum((s[lips] - e[lips]) ** 2, axis=1))) / fem.mouth_width), 6), target=0.01)
    # 60 fps (the seed's camera) on the scenario's slower ramp, with the seed-001
    # analysis of rendered frames.
    tr = ramp(rig, 60, start=0.05, ramp_s=0.35, hold=0.1)
    strips = []
    for p in ("sticky", "elastic"):
        _, frames = run(fem, rig, tr, physics=p)
        prof, imgs = mouth_profile(fem, frames, 60)
        vw = prof["width"].to_numpy()
        first = int(np.argmax(vw > 0)) if (vw > 0).any() else 0
        full = int(np.argmax(vw > 0.9)) if (vw > 0.9).any() else None
        emit(figure="zipper_60fps", physics=p, mesh_open_span=[round(f["open_span"], 3) for f in frames],
             video_width=np.round(vw, 3), video_count=prof["count"].to_numpy(), video_first_open_frame=first,
             video_frames_to_90pct_width=None if full is None else full - first)
        if p == "sticky":
            pick = list(range(max(first - 1, 0), min(first + 6, len(imgs))))
        strips.append(np.concatenate([imgs[i][140:372] for i in pick], axis=1))
    from visemeface.render.export import write_png
    IMAGES.mkdir(parents=True, exist_ok=True)
    write_png(IMAGES / "sticky_zipper.png", np.concatenate(strips, axis=0)[::2, ::2].copy())


def fig_merge(fem, rig):
    """Central glue 0.18 at 60 fps (the seed's camera): two openings, then one; mesh and video."""
    tr = ramp(rig, 60, start=0.05, ramp_s=0.35, hold=0.1)
    strips = []
    for name, kw in (("central glue 0.18", {"glue_profile": "centre=0.18"}), ("uniform glue 0.08", {})):
        _, frames = run(fem, rig, tr, **kw)
        counts = [f["open_count"] for f in frames]
        span = np.array([f["open_span"] for f in frames])
        two = [i for i, c in enumerate(counts) if c == 2]
        merge = two[-1] + 1 if two and two[-1] + 1 < len(counts) else None
        prof, imgs = mouth_profile(fem, frames, 60)
        vw = prof["width"].to_numpy()
        dvw = np.diff(vw)
        emit(figure="merge", case=name, mesh_open_count=counts, mesh_frames_with_two=len(two),
             mesh_merge_frame=merge, mesh_span_jump_at_merge=None if merge is None else round(float(span[merge] - span[merge - 1]), 3),
             video_count=prof["count"].to_numpy(), video_frames_with_two=int((prof["count"].to_numpy() == 2).sum()),
             video_width=np.round(vw, 3), video_width_derivative_max_frame=int(np.argmax(dvw)) + 1,
             video_width_derivative_max=round(float(dvw.max()), 3))
        if two:
            strips.append(np.concatenate([imgs[i][140:372] for i in range(max(two[0] - 2, 0), min(two[0] + 6, len(imgs)))],
                                         axis=1))
    if strips:
        from visemeface.render.export import write_png
        write_png(IMAGES / "sticky_merge.png", strips[0][::2, ::2].copy())


def fig_asymmetry(fem, rig):
    for name, kw, tr in (("one-sided activation (left lower-lip depressor)", {},
                          ramp(rig, 1000, hold=0.0, jaw=0.2, extra={"depressor_labii_inferioris_left": 0.3})),
                         ("one-sided glue (right 0.3, left 0)", {"glue_profile": "right=0.3,left=0"},
                          ramp(rig, 1000, hold=0.0))):
        _, frames = run(fem, rig, tr, **kw)
        first = next((f for f in frames if f["open_count"] > 0), None)
        op = seam_openings(fem, first["v"])["open"] if first else np.zeros(len(fem.seam_s), bool)
        gaps = (fem.seam_gaps(frames[-1]["v"]) - fem.rest_gaps) / fem.mouth_width
        emit(figure="asymmetry", case=name, first_open_s=None if first is None else first["t"],
             open_left_pairs=int(op[fem.seam_s > 0].sum()), open_right_pairs=int(op[fem.seam_s < 0].sum()),
             final_gap_left=round(float(gaps[fem.seam_s > 0].mean()), 4),
             final_gap_right=round(float(gaps[fem.seam_s < 0].mean()), 4))


def fig_evaporation(fem, rig, evaporation=40.0):
    tr = drive.scenario_track("open", rig.names, fps=250)
    for phi in (0.0, evaporation):
        _, frames = run(fem, rig, tr, saliva=drive.SalivaParams(evaporation=phi))
        jaw = tr["jaw"].to_numpy()
        opening = np.flatnonzero(np.diff(np.r_[0, (jaw > 1e-4).astype(int)]) == 1)
        out = []
        for k, start in enumerate(opening):
            end = opening[k + 1] if k + 1 < len(opening) else len(frames)
            seg = frames[start:end]
            b0 = next((f for f in seg if f["broken"].any()), None)
            b1 = next((f for f in seg if f["broken"].all()), None)
            out.append({"opening": k + 1,
                        "jaw_first_failure": None if b0 is None else round(float(jaw[b0["i"]]), 4),
                        "jaw_all_failed": None if b1 is None else round(float(jaw[b1["i"]]), 4),
                        "unzip_ms": None if b0 is None or b1 is None else round(1e3 * (b1["t"] - b0["t"]), 1),
                        "t_first_failure": None if b0 is None else round(b0["t"], 3)})
        emit(figure="evaporation", evaporation_per_s=phi, openings=out)


def fig_speech(fem, rig):
    """Utterances as ``speak --physics sticky|elastic`` runs them: complete? lips vs kinematic, sticky vs elastic."""
    from visemeface.postures.library import load_visemes
    from visemeface.resources import transcripts_path
    from visemeface.speech.timeline import activation_track
    from visemeface.speech.transcripts import read_transcript
    ranges = {n: tuple(r) for n, r in zip(rig.names, rig.ranges)}
    lips = lip_ids(fem)
    for name in ("bob_moves_five_boats.txt", "one_five_zero_zero_six.txt"):
        track = activation_track(read_transcript(transcripts_path(name)), load_visemes(rig=rig), fps=30, ranges=ranges)
        verts = {}
        for physics in ("sticky", "elastic"):
            t0 = time.perf_counter()
            rms, intact, error = [], [], None
            try:
                sim, frames = run(fem, rig, track, physics=physics)
                for f in frames:
                    kin = rig.pose(sim.values[f["i"]]) - rig.face.vertices
                    got = f["v"] - fem.face.vertices
                    rms.append(float(np.sqrt(np.mean(np.sum((got[lips] - kin[lips]) ** 2, axis=1)))))
                    intact.append(1.0 - f["broken_fraction"])
                verts[physics] = np.stack([f["v"][lips] for f in frames])
            except Exception as e:
                error = f"{type(e).__name__}: {str(e)[:160]}"
            wall = time.perf_counter() - t0
            rms = np.array(rms) / fem.mouth_width
            emit(figure="speech", transcript=name, physics=physics, frames=len(track), completed=error is None,
                 error=error, lip_rms_vs_kinematic_max=round(float(rms.max()), 4) if len(rms) else None,
                 lip_rms_vs_kinematic_median=round(float(np.median(rms)), 4) if len(rms) else None,
                 frames_with_saliva_holding=int(np.sum(np.array(intact) > 0)) if intact else None,
                 wall_s=round(wall, 1), s_per_simulated_s=round(wall / max(track.index[-1], 1e-9), 1))
        if len(verts) == 2:
            d = np.sqrt(np.mean(np.sum((verts["sticky"] - verts["elastic"]) ** 2, axis=2), axis=1)) / fem.mouth_width
            emit(figure="speech_sticky_vs_elastic", transcript=name, lip_rms_max=round(float(d.max()), 4),
                 frames_differing_over_1pct=int((d > 0.01).sum()), frames=len(d))


def main(argv=None):
    from visemeface.runtime import configure

    configure()  # as the CLI does: threading layer, OpenMP spin, cache folder
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--resolution", type=int, help="face vertices (default: the default face)")
    ap.add_argument("--calibration-resolution", type=int, default=1500,
                    help="face for the 56-viseme calibration sweep (default 1500: coarse, fast)")
    ap.add_argument("--calibration-tracking", type=float, default=drive.TRACKING_HZ,
                    help="tracking spring (Hz) in the calibration sweep (default %g, the drive's; "
                    "0: dead loads only)" % drive.TRACKING_HZ)
    ap.add_argument("--only", help="comma-separated figures")
    ap.add_argument("--threads", type=int, default=None)
    args = ap.parse_args(argv)
    if args.threads:
        from visemeface.runtime import set_threads
        set_threads(args.threads)
    only = set(args.only.split(",")) if args.only else None
    face = default_face(resolution=args.resolution)
    rig = MuscleRig.from_file(face)
    fem = build_fem_face(face)
    t0 = time.perf_counter()
    for name, fn in (("counts", lambda: fig_counts(fem)), ("zipper", lambda: fig_zipper(fem, rig)),
                     ("merge", lambda: fig_merge(fem, rig)), ("asymmetry", lambda: fig_asymmetry(fem, rig)),
                     ("evaporation", lambda: fig_evaporation(fem, rig)), ("speech", lambda: fig_speech(fem, rig)),
                     ("calibration", lambda: fig_calibration(*_coarse(args.calibration_resolution),
                                                             tracking=args.calibration_tracking))):
        if only is None or name in only:
            try:
                fn()
            except Exception as e:  # a figure that fails is reported, the others still run
                emit(figure=name, error=f"{type(e).__name__}: {str(e)[:300]}")
            print(f"# {name} done at {time.perf_counter() - t0:.0f} s", file=sys.stderr, flush=True)


def _coarse(resolution):
    face = default_face(resolution=resolution)
    return build_fem_face(face), MuscleRig.from_file(face)


if __name__ == "__main__":
    main()
