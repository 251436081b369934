"""Experiment (issue 16): tether the lips at the mouth corners and measure the film's load along the seam.

    PYTHONPATH=src NUMBA_NUM_THREADS=1 python scripts/corner_tether.py                  # default face
    PYTHONPATH=src NUMBA_NUM_THREADS=1 python scripts/corner_tether.py --resolution 1500
    PYTHONPATH=src NUMBA_NUM_THREADS=1 python scripts/corner_tether.py --tether 1 --zipper

On the FEM face the upper and lower lips share only the mouth-corner vertex; between it and the
last seam pair they are separate tissue (the regapped seam is a 1 mm slit up to the corner).
``--tether k`` welds the ``k`` outermost seam pairs on each side into one vertex (the default
face's lips are closed at rest, so each pair is one point there) before the face is extruded:
the tissue is continuous through the lips' depth there, a commissure ``k`` seam pairs long. The
film then runs from the last unwelded pair into the welded vertex (wedges, as
``film_corners`` does into the corner).

Measured on the seed's opening (jaw eased 0 -> 0.35 from 0.05 s to 0.40 s, held), per film slab,
folded onto |s| (0 centre, 1 corner; the two sides averaged):

* ``gap``: elastic (no glue): the lips' skin-side gap beyond the rest gap, mm;
* ``stretch``: glue 10 (never breaks): the film's stretch sqrt(C_yy) - 1, %.

at the frames where the jaw first reaches 0.2 and 0.35. ``--zipper``: also the seed's glued
opening (glue 0.08, the cohesive film with rupture time, as tests/physics/test_zipper.py) with
the tether and without: first opening place and frames from first opening to full width.
``--crack``: the film's stretch ahead of a central opening of half-length a (|s| < a unglued, the
rest unbreakable), and the jaw at which that tip reaches glue 0.08's breaking stretch.

As a pytest plugin it runs the physics tests on the tethered face, the film into the weld:

    TETHER=1 PYTHONPATH=src:scripts python -m pytest -p corner_tether tests/physics/test_sticky.py -k "centre_first or merge"
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import numpy as np

from visemeface.face.mesh import FaceMesh
from visemeface.face.procedural import default_face
from visemeface.muscles.rig import MuscleRig
from visemeface.physics import drive
from visemeface.physics.face_model import _saliva_hexes, build_fem_face, seam_pairs
from visemeface.physics.glue import GLUE
from visemeface.physics.saliva import RUPTURE_TIME, SalivaParams

BINS = np.array([0.0, 0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 0.7, 0.8, 0.9, 0.97])


def weld_corner_pairs(face: FaceMesh, k: int):
    """A copy of ``face`` with the ``k`` outermost seam pairs per side welded (lower vertex into the upper).

    Returns the face and the welded (upper) vertex nearest the centre on each side (right, left).
    """
    pairs = seam_pairs(face)
    if not 0 < 2 * k < len(pairs) - 1:
        raise SystemExit(f"--tether {k}: the face has {len(pairs)} seam pairs")
    weld = np.concatenate([pairs[:k], pairs[len(pairs) - k:]])
    v = face.vertices.copy()
    remap = np.arange(face.n_vertices)
    remap[weld[:, 1]] = weld[:, 0]
    v[weld[:, 0]] = 0.5 * (v[weld[:, 0]] + v[weld[:, 1]])
    regions = dict(face.regions)
    lower = np.setdiff1d(regions["lip_seam_lower"], weld[:, 1])
    regions["lip_seam_lower"] = np.union1d(lower, weld[:, 0])
    for name, idx in face.regions.items():           # the lower vertex is on no quad now: out of every region
        if name != "lip_seam_lower":
            regions[name] = np.union1d(np.setdiff1d(idx, weld[:, 1]), weld[np.isin(weld[:, 1], idx), 0])
    welded = FaceMesh(v, remap[face.quads], remap[face.tris] if len(face.tris) else face.tris, regions,
                      dict(face.landmarks), face.colors)
    return welded, (int(pairs[k - 1, 0]), int(pairs[len(pairs) - k, 0]))


def tethered_fem(face: FaceMesh, k: int):
    """The FEM face with ``k`` pairs welded per side and film wedges from the last free pair into the weld."""
    welded, (right, left) = weld_corner_pairs(face, k)
    fem = build_fem_face(welded)
    S = fem.n_surface
    node_of = np.full(welded.n_vertices, -1, dtype=np.int64)
    node_of[fem.surface_vertices] = np.arange(S)
    L = len(fem.saliva) // (len(fem.seam_pairs) - 1)
    axis = welded.landmark_position("mouth_corner_left") - welded.landmark_position("mouth_corner_right")
    axis /= np.linalg.norm(axis)
    origin = 0.5 * (welded.landmark_position("mouth_corner_left") + welded.landmark_position("mouth_corner_right"))
    s_of = {c: float((fem.face.vertices[c] - origin) @ axis / (0.5 * fem.mouth_width)) for c in (right, left)}
    p = fem.seam_pairs
    hexes = [_saliva_hexes(node_of[[right, p[0, 0]]], node_of[[right, p[0, 1]]], S, L),
             _saliva_hexes(node_of[[p[-1, 0], left]], node_of[[p[-1, 1], left]], S, L)]
    ends = [np.tile([s_of[right], fem.seam_s[0]], (L, 1)), np.tile([fem.seam_s[-1], s_of[left]], (L, 1))]
    fem.corner_hexes, fem.corner_s = np.concatenate(hexes), np.concatenate(ends)
    return fem


def folded(s, values):
    """``values`` at the slabs nearest each |s| of BINS, left and right averaged (NaN: no slab within 0.05)."""
    out = []
    for b in BINS:
        r, l_ = np.argmin(np.abs(s + b)), np.argmin(np.abs(s - b))
        near = abs(abs(s[r]) - b) <= 0.05 and abs(s[l_] - b) <= 0.05
        out.append(0.5 * (values[r] + values[l_]) if near else np.nan)
    return np.array(out)


def profiles(fem, rig, fps: float, film_corners: bool, lip_bone: str = "muscle"):
    """Elastic gap (mm) and unbreakable-film stretch (%) per slab at jaw 0.2 and 0.35."""
    track = drive.ramp_track(rig.names, fps, 0.05, 0.35, 0.3, 0.35)
    jaw = track["jaw"].to_numpy()
    at = {"0.20": int(np.flatnonzero(jaw >= 0.2)[0]), "0.35": int(np.flatnonzero(jaw >= 0.35 - 1e-9)[0]),
          "0.35+0.3s": len(jaw) - 1}
    out = {}
    for physics, glue in (("elastic", 0.0), ("sticky", 10.0)):
        settings = drive.PhysicsSettings(film_corners=film_corners, glue=glue, lip_bone=lip_bone)
        sim = drive.StickySimulation(fem, rig, track, physics=physics, settings=settings)
        for fr in sim.frames():
            for j, k in at.items():
                if fr.index != k:
                    continue
                if physics == "elastic":
                    out[("gap_mm", j)] = (sim.film.front_gaps(fr.displacement) - sim.film.rest_gap) * 1e3
                else:
                    out[("stretch_pct", j)] = (np.sqrt(np.minimum(sim.film.stretch(fr.displacement), 1e6)) - 1) * 100
        s = sim.film.s
    return s, out


def print_profiles(label, s, out):
    print(f"# {label}: |s| = " + " ".join(f"{b:5.2f}" for b in BINS))
    for (what, jaw), v in sorted(out.items()):
        f = folded(s, v)
        mid = np.abs(s) <= 0.8
        print(f"{what:>11} jaw {jaw:>9}: " + " ".join(f"{x:5.2f}" for x in f)
              + f" | peak |s|={abs(s[np.argmax(v)]):.2f} max/centre={v.max() / f[0]:.3f}"
              + f" middle-80% {v[mid].min():.2f}..{v[mid].max():.2f}", flush=True)


def crack(fem, rig, fps: float, film_corners: bool, label: str, jaw: float = 0.5):
    """The film's load ahead of a central opening: slabs with |s| < a unglued, the rest unbreakable (glue 10).

    Per half-length a: the largest stretch of the glued film (at its tip) at jaw 0.2 and 0.35, and the
    jaw at which that tip first reaches glue 0.08's breaking stretch (the seed's film breaks there): a
    zipper that waits for the jaw needs that jaw to rise with a; flat or falling, it cascades.
    """
    track = drive.ramp_track(rig.names, fps, 0.05, 0.35 * jaw / 0.35, 0.0, jaw)
    jaws = track["jaw"].to_numpy()
    z = 100 * (np.sqrt(1.0 + GLUE) - 1.0)
    print(f"# crack {label}: a = |s| of the open centre; tip stretch % at jaw 0.2 / 0.35 (peak where); "
          f"jaw at which the tip reaches {z:.2f} % (glue {GLUE})", flush=True)
    nodes = np.sort(fem.seam_s[fem.seam_s > 1e-9])[:-1]      # the seam pairs inside the film's ends
    mids = 0.5 * (np.r_[0.0, nodes[:-1]] + nodes)
    for a in np.r_[0.0, np.sort(np.r_[nodes, mids])]:
        a = round(float(a), 3)
        settings = drive.PhysicsSettings(film_corners=film_corners, glue=10.0,
                                         glue_profile=f"{-a}..{a}=0" if a > 0 else None)
        sim = drive.StickySimulation(fem, rig, track, physics="sticky", settings=settings)
        glued = sim.film.glue > 0
        row, reach = {}, None
        for fr in sim.frames():
            st = (np.sqrt(np.minimum(sim.film.stretch(fr.displacement), 1e6)) - 1) * 100
            tip = float(st[glued].max())
            for j in (0.2, 0.35):
                if j not in row and jaws[fr.index] >= j - 1e-9:
                    row[j] = (tip, float(abs(sim.film.s[glued][np.argmax(st[glued])])))
            if reach is None and tip >= z:
                reach = float(jaws[fr.index])
        edge = "pair" if np.isclose(nodes, a, atol=2e-3).any() else "mid-hex" if a > 0 else "intact"
        print(f"  a={a:.3f} ({edge:>7}): jaw 0.2 {row[0.2][0]:.2f} (|s|={row[0.2][1]:.2f})  jaw 0.35 {row[0.35][0]:.2f} "
              f"(|s|={row[0.35][1]:.2f})  tip reaches {z:.2f} % at jaw {reach if reach is None else round(reach, 3)}",
              flush=True)


def zipper(fem, rig, fps: float, label: str, film_corners: bool, rupture_time: float, jaw: float = 0.35,
           glue_profile=None):
    """The seed's glued opening (glue 0.08, jaw eased up over 0.35 s, held 0.75 s; sticky_figures' zipper run)."""
    sys.path.insert(0, str(Path(__file__).resolve().parent))
    from sticky_figures import zipper_measures
    track = drive.ramp_track(rig.names, fps, 0.05, 0.35, 0.75, jaw)
    settings = drive.PhysicsSettings(film_corners=film_corners, saliva=SalivaParams(rupture_time=rupture_time),
                                     glue_profile=glue_profile)
    sim = drive.StickySimulation(fem, rig, track, physics="sticky", settings=settings)
    frames = []
    for fr in sim.frames():
        op = sim.film.front_gaps(fr.displacement) - sim.film.rest_gap
        frames.append({"gap": op / fem.mouth_width, **fr.saliva})
    m = zipper_measures(sim, frames, fps)
    m["frames_first_to_full"] = int(round(m.get("first_to_full_s", 0) * fps)) if m.get("opens") else None
    m["broken_at_first_open"] = frames[m["first_open_frame"]]["broken_fraction"] if m.get("opens") else None
    m["frames_with_two_openings"] = sum(f["film_open_count"] == 2 for f in frames)
    print(f"# zipper {label}, jaw {jaw}, film_corners={film_corners}, rupture_time={rupture_time}, "
          f"glue_profile={glue_profile}: "
          + json.dumps(m, default=lambda o: o.tolist()), flush=True)


def pytest_configure(config):
    """As a pytest plugin (``-p corner_tether``, scripts/ on the path): every default FEM face is built with
    ``$TETHER`` pairs welded per side (0: main's face) and the film runs into the corners (or the weld)."""
    import os
    from dataclasses import dataclass

    from visemeface.physics import face_model, simulation
    k, build = int(os.environ.get("TETHER", "1")), face_model.build_fem_face

    def tethered(face, *a, **kw):
        return build(face, *a, **kw) if (a or kw or not k) else tethered_fem(face, k)

    @dataclass(frozen=True)
    class FilmIntoCorners(simulation.PhysicsSettings):
        film_corners: bool = True

    face_model.build_fem_face, drive.PhysicsSettings = tethered, FilmIntoCorners


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--resolution", type=int, default=None)
    ap.add_argument("--tether", default="0,1", help="comma-separated pairs welded per side (0: main's face)")
    ap.add_argument("--fps", type=float, default=60.0)
    ap.add_argument("--zipper", action="store_true")
    ap.add_argument("--no-profiles", action="store_true")
    ap.add_argument("--lip-bone", choices=("muscle", "free"), default="muscle", help="profiles: the lips' deep layer")
    ap.add_argument("--crack", action="store_true", help="the film's tip stretch ahead of a central opening")
    ap.add_argument("--jaw", type=float, default=0.35, help="zipper: jaw activation at the top")
    ap.add_argument("--glue-profile", default=None, help="zipper: e.g. centre=0.18 (seed 001's central glue)")
    ap.add_argument("--rupture-time", type=float, default=0.0,
                    help=f"zipper: saliva rupture time, s (0: the seed's brittle film; {RUPTURE_TIME}: test_zipper's)")
    args = ap.parse_args()
    from visemeface.runtime import set_threads
    set_threads(1)
    face = default_face(resolution=args.resolution)
    rig = MuscleRig.from_file(face)
    for k in (int(x) for x in args.tether.split(",")):
        fem = build_fem_face(face) if k == 0 else tethered_fem(face, k)
        variants = ((False, "main, film ends at last pair"), (True, "main, film into corners")) if k == 0 \
            else ((True, f"tether {k} pair(s)/side, film into the weld"),)
        if not args.no_profiles:
            for corners, label in variants:
                s, out = profiles(fem, rig, args.fps, corners, args.lip_bone)
                print_profiles(f"res {args.resolution or 'default'} lip bone {args.lip_bone}, {label}", s, out)
        for corners, label in variants:
            if args.crack:
                crack(fem, rig, args.fps, corners, f"res {args.resolution or 'default'} {label}")
            if args.zipper:
                zipper(fem, rig, args.fps, f"res {args.resolution or 'default'} tether {k}", corners,
                       args.rupture_time, args.jaw, args.glue_profile)


if __name__ == "__main__":
    main()
