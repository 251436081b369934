"""``face --prepare``: a head mesh made elsewhere turned into a face the rig can pose.

From the mesh alone (looking along +z, +y up, in any of metres, centimetres or millimetres):

1. *Landmarks*: the mesh is rendered from the front with the project's renderer, MediaPipe's face detector and
   468-point face mesh (:mod:`visemeface.analysis.landmarks`) find the face in the picture, and the 68
   Multi-PIE points among them (:data:`MEDIAPIPE_68`) are taken back to the mesh: each pixel's visible surface
   point (the renderer's depth buffer), then the nearest vertex. The inner-lip points of the upper lip snap to
   vertices whose normals point down (the upper lip's underside), those of the lower lip to vertices whose
   normals point up, so closed lips that touch still get one seam on each. ``--landmark-indices`` gives the
   68 vertices instead (ICT-FaceKit's README lists its head's).
2. *Units*: the mouth must be 3-8 cm wide; a mesh in centimetres or millimetres is scaled to metres.
3. *Regions*: the lips, seams and lids of :mod:`visemeface.face.multipie`; of the mesh's other pieces, the
   eye-sized ones in the eye openings that are closed or round are the eyeballs, those behind the lips the mouth cavity: the pieces
   above the lips' contact the upper teeth, those below the lower teeth (they turn with the jaw), one across it
   gums and tongue, split by the nearest teeth.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
from scipy.sparse.csgraph import connected_components

from visemeface.errors import InputError
from visemeface.face import multipie

#: The MediaPipe face-mesh vertex (of its canonical 468) at each Multi-PIE 68 point, 0..67.
MEDIAPIPE_68 = (127, 234, 93, 132, 58, 136, 150, 176, 152, 400, 379, 365, 288, 361, 323, 454, 356,
                70, 63, 105, 66, 107, 336, 296, 334, 293, 300,
                168, 197, 5, 4, 75, 97, 2, 326, 305,
                33, 160, 158, 133, 153, 144, 362, 385, 387, 263, 373, 380,
                61, 39, 37, 0, 267, 269, 291, 405, 314, 17, 84, 181,
                78, 82, 13, 312, 308, 317, 14, 87)
#: Inner-lip points of the upper lip and of the lower lip (the corners 60 and 64 belong to neither).
_UPPER_SNAP, _LOWER_SNAP = (61, 62, 63), (65, 66, 67)
#: Largest share of the faces with an edge shared by more than two faces: past it the mesh is no surface to pose.
MAX_NONMANIFOLD = 0.01
RENDER_SIZE = 768
#: A vertex faces the camera when its normal's z is above this.
FRONT_FACING = 0.3
#: Depth of the jaw joints behind the outer eye corners, in mouth widths (the ICT head's: 0.9).
JAW_DEPTH = 0.9


def read_head(path) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray | None]:
    """``(vertices, quads, triangles, vertex colours or None)`` of a mesh file in its own units. An OBJ keeps
    its vertices and quads as written (a reader that splits vertices by texture seams would cut the surface
    apart); other formats are read with trimesh."""
    from visemeface.face.mesh import MESH_SUFFIXES, _read_surface

    path = Path(path)
    if not path.is_file():
        raise InputError("mesh file not found", path)
    if path.suffix.lower() not in MESH_SUFFIXES:
        raise InputError(f"unknown mesh format {path.suffix!r} (use one of {', '.join(MESH_SUFFIXES)})", path)
    if path.suffix.lower() != ".obj":
        V, tris, colours = _read_surface(path)
        return V, np.zeros((0, 4), np.int64), tris, colours
    from visemeface.face.mesh import _obj_text
    from visemeface.retarget.rigs import _read_obj_positions

    _obj_text(path)                          # refuses binary data and files with no vertex lines
    try:
        V, faces, colours = _read_obj_positions(path, colours=True)
    except ValueError:
        raise InputError("not a readable OBJ (a face line with no vertex number)", path) from None
    n = len(V)
    bad = [f for f in faces if len(f) < 3 or min(f) < 0 or max(f) >= n]
    if bad:
        raise InputError(f"a face names vertex {max(bad[0], key=abs) + 1} of {n} (or has under 3 corners)", path)
    quads = np.array([f for f in faces if len(f) == 4], np.int64).reshape(-1, 4)
    tris = np.array([[f[0], f[i], f[i + 1]] for f in faces if len(f) != 4 for i in range(1, len(f) - 1)],
                    np.int64).reshape(-1, 3)
    if not len(quads) + len(tris):
        raise InputError("cannot read mesh: no faces", path)
    return V, quads, tris, colours


def check_surface(V: np.ndarray, quads: np.ndarray, tris: np.ndarray, path) -> None:
    """Refuse a mesh that is no surface: too few faces, or many faces on edges shared by more than two."""
    n_faces = len(quads) + len(tris)
    if n_faces < 200:
        raise InputError(f"{n_faces} faces are too few for a face to pose (a head has thousands)", path)
    e = multipie.face_edges(quads, tris)
    owner = np.concatenate([np.tile(np.arange(len(quads)), 4), len(quads) + np.tile(np.arange(len(tris)), 3)])
    _, inverse, counts = np.unique(np.sort(e, axis=1), axis=0, return_inverse=True, return_counts=True)
    share = len(np.unique(owner[counts[inverse.ravel()] > 2])) / n_faces
    if share > MAX_NONMANIFOLD:
        raise InputError(f"not a manifold surface: {share:.0%} of its faces have an edge shared by more than "
                         "two faces", path)


def detect_68(face, path) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The 68 Multi-PIE vertices of ``face`` (a FaceMesh without landmarks) found in its frontal render:
    ``(indices (68,), pixels (68, 2), the render)``."""
    from scipy.spatial import cKDTree

    from visemeface.analysis.landmarks import FaceModels, available, region_around
    from visemeface.render.renderer import Renderer

    if not available():
        raise InputError("finding the landmarks needs the optional extra (pip install 'visemeface[track]'); "
                         "or give them with --landmark-indices")
    models = FaceModels()
    with Renderer(face, size=RENDER_SIZE) as renderer:
        image = renderer.render()
        found = models.detect(image)
        if not found:
            raise InputError("no face in the mesh's frontal render (the face must look along +z with +y up)",
                             path)
        region = models.region_of(found[0])
        cfg = models.lm_cfg
        for _ in range(2):             # the detector's box, then the box of the landmarks found (tracking's)
            pts, presence = models.landmarks(image, region)
            region = region_around(pts, tuple(cfg["eyes"]), cfg["roi_scale"])
        if presence < cfg["min_presence"]:
            raise InputError(f"no face in the mesh's frontal render (face presence {presence:.2f})", path)
        pixels = pts[list(MEDIAPIPE_68)]
        # pixel centres at integers (OpenCV's) -> the renderer's pixel corners
        surface = renderer.surface_points(pixels + 0.5)
        projected = renderer.project(face.vertices)
    V = face.vertices
    normals = face.vertex_normals()
    if np.mean(normals[:, 2] * (V[:, 2] > np.median(V[:, 2]))) < 0:
        normals = -normals                     # the faces wound inward: the normals made to point out
    off = np.flatnonzero(~np.isfinite(surface[17:]).all(axis=1))
    if len(off):
        raise InputError(f"{len(off)} of the 68 landmarks fall beside the mesh in its frontal render", path)
    tree = cKDTree(V)
    idx = tree.query(np.nan_to_num(surface))[1]
    # a point of the jaw's contour just beside the silhouette: the nearest vertex in the picture facing the camera
    front = np.flatnonzero(normals[:, 2] > FRONT_FACING)
    for k in np.flatnonzero(~np.isfinite(surface[:17]).all(axis=1)):
        idx[k] = front[np.argmin(np.linalg.norm(projected[front] - (pixels[k] + 0.5), axis=1))]
    # closed lips touch below the upper lip's front: each inner-lip point is the vertex of its lip (normals
    # down for the upper, up for the lower) nearest the other lip
    mouth_w = float(np.linalg.norm(V[idx[54]] - V[idx[48]]))
    for group, sign in ((_UPPER_SNAP, -1.0), (_LOWER_SNAP, 1.0)):
        for k in group:
            near = np.array(tree.query_ball_point(V[idx[k]], 0.12 * mouth_w), dtype=np.int64)
            own, other = near[sign * normals[near, 1] > 0.2], near[-sign * normals[near, 1] > 0.2]
            if len(own) and len(other):
                gap = cKDTree(V[other]).query(V[own])[0]
                idx[k] = own[np.argmin(gap + 0.1 * np.linalg.norm(V[own] - V[idx[k]], axis=1))]
    return idx.astype(np.int64), pixels, image


def read_indices(path, n_vertices: int) -> np.ndarray:
    """``--landmark-indices``: 68 vertex indices (0-based), a JSON list or numbers separated by spaces or
    commas."""
    import json
    import re

    path = Path(path)
    try:
        text = path.read_text(encoding="utf-8", errors="replace")
    except OSError as exc:
        raise InputError(f"cannot read: {exc.strerror or exc}", path) from None
    try:
        values = json.loads(text)
    except ValueError:
        values = [t for t in re.split(r"[,;\s]+", text.strip()) if t]
    if isinstance(values, dict):
        values = values.get("multi_pie_68", values.get("indices"))
    try:
        idx = [int(v) for v in values if not isinstance(v, bool) and float(v) == int(v)]
    except (TypeError, ValueError, OverflowError):
        raise InputError("expected 68 vertex indices (integers)", path) from None
    if len(idx) != 68 or len(idx) != len(values):
        raise InputError(f"expected 68 vertex indices (integers), got {len(values)} values", path)
    bad = [i for i in idx if not 0 <= i < n_vertices]
    if bad:
        raise InputError(f"vertex index {bad[0]} out of range (mesh has {n_vertices} vertices)", path)
    return np.array(idx, np.int64)


def _pieces(V, quads, tris) -> tuple[np.ndarray, object]:
    """Each vertex's connected piece, and the edge graph of all vertices."""
    graph = multipie.edge_graph(V, quads, tris, np.ones(len(V), bool))
    return connected_components(graph, directed=False)[1], graph


def label(V: np.ndarray, quads: np.ndarray, tris: np.ndarray, lm68: np.ndarray, path,
          silhouette: bool = False) -> tuple[dict, dict]:
    """Regions and landmarks of a head in metres from its 68 Multi-PIE vertices (see the module notes);
    ``silhouette``: the jaw's contour among them was found in a picture."""
    piece, graph = _pieces(V, quads, tris)
    main = piece[lm68[48]]
    if piece[lm68[54]] != main:
        raise InputError("the two mouth corners lie on separate pieces of the mesh", path)
    surface = piece == main
    for a, b in ((48, 54), (60, 64), (36, 39), (42, 45), (27, 8)):
        if abs(V[lm68[a], 0] - V[lm68[b], 0]) + abs(V[lm68[a], 1] - V[lm68[b], 1]) < 1e-9:
            raise InputError(f"Multi-PIE landmarks {a} and {b} lie on one spot (vertices {lm68[a]}, {lm68[b]})",
                             path)
    try:
        regions = multipie.lip_regions(V, graph, surface, lm68, exclusive=True)
    except ValueError as exc:
        raise InputError(f"cannot trace the lips: {exc}", path) from None
    if not (len(regions["lip_seam_upper"]) and len(regions["lip_seam_lower"])):
        raise InputError("cannot trace the lips: no seam between the inner-lip landmarks", path)
    regions.update(multipie.lid_regions(V, surface, lm68))
    landmarks = multipie.named_landmarks(V, np.flatnonzero(surface), lm68)
    width = float(np.linalg.norm(V[lm68[54]] - V[lm68[48]]))
    if silhouette:
        # the contour found in a picture is the silhouette, on a head far behind the face's own contour (the
        # ears): the jaw joints at its height and width, JAW_DEPTH mouth widths behind the outer eye corners
        for side, (a, b), eye in (("right", (1, 2), 36), ("left", (15, 14), 45)):
            target = (V[lm68[a]] + V[lm68[b]]) / 2
            target[2] = V[lm68[eye], 2] - JAW_DEPTH * width
            cand = np.flatnonzero(surface)
            landmarks[f"jaw_joint_{side}"] = int(cand[np.argmin(np.linalg.norm(V[cand] - target, axis=1))])
    others = [np.flatnonzero(piece == k) for k in np.unique(piece) if k != main]
    edges = np.sort(multipie.face_edges(quads, tris), axis=1)
    rim, counts = np.unique(edges, axis=0, return_counts=True)
    open_v = np.zeros(len(V), bool)
    open_v[rim[counts == 1].ravel()] = True
    eyeballs = []
    for side, (outer, inner, *_rest) in zip(("right", "left"), multipie.EYES):
        c0, c1 = V[lm68[outer]], V[lm68[inner]]
        centre, eye_w = (c0 + c1) / 2, float(np.linalg.norm(c1 - c0))
        # an eyeball: a piece about the eye's size in its opening, closed or round (not a lash card or a tear
        # film, which are open and flat), with the small pieces inside it (a pupil)
        at_eye = [p for p in others if np.linalg.norm(V[p, :2].mean(axis=0) - centre[:2]) < 0.5 * eye_w]
        ball = [p for p in at_eye if 0.5 * eye_w < np.ptp(V[p], axis=0).max() < 2.0 * eye_w
                and (not open_v[p].any() or np.ptp(V[p], axis=0).min() >= 0.45 * np.ptp(V[p], axis=0).max())]
        if ball:
            lo, hi = np.min([V[p].min(axis=0) for p in ball], axis=0), np.max([V[p].max(axis=0) for p in ball], axis=0)
            ball += [p for p in at_eye if np.ptp(V[p], axis=0).max() < 0.3 * eye_w
                     and (V[p] >= lo).all() and (V[p] <= hi).all()]
            ball_v = np.concatenate(ball)
            eyeballs.append(ball_v)
            landmarks[f"eye_centre_{side}"] = int(ball_v[np.argmax(V[ball_v, 2])])
        else:                                    # no eyeball: the surface in the eye's opening
            cand = np.flatnonzero(surface)
            landmarks[f"eye_centre_{side}"] = int(cand[np.argmin(np.linalg.norm(V[cand] - centre, axis=1))])
    if eyeballs:
        regions["eyeballs"] = regions["eyes"] = np.concatenate(eyeballs)
    mid = V[lm68[[48, 54]]].mean(axis=0)
    lip_z = V[np.concatenate([regions["lip_seam_upper"], regions["lip_seam_lower"]]), 2].max()
    inside = [p for p in others if abs(V[p, 0].mean() - mid[0]) < 0.8 * width
              and abs(V[p, 1].mean() - mid[1]) < 0.8 * width and lip_z - 2.0 * width < V[p, 2].mean() < lip_z]
    if inside:
        regions["mouth_cavity"] = np.concatenate(inside)
        # pieces above the lips' contact are fixed to the skull, those below turn with the jaw, and one across
        # it (gums and tongue) is split by the nearest of those (visemeface.face.multipie.mouth_interior)
        seam_y = V[np.concatenate([regions["lip_seam_upper"], regions["lip_seam_lower"]]), 1].mean()
        across = [V[p, 1].min() < seam_y - 0.25 * width and V[p, 1].max() > seam_y + 0.25 * width for p in inside]
        upper = [p for p, a in zip(inside, across) if not a and V[p, 1].mean() > seam_y]
        lower = [p for p, a in zip(inside, across) if not a and V[p, 1].mean() <= seam_y]
        soft = [p for p, a in zip(inside, across) if a]
        if upper and lower:
            interior, found = multipie.mouth_interior(V, np.concatenate(upper), np.concatenate(lower),
                                                      np.concatenate(soft or [np.zeros(0, np.int64)]), width)
            regions.update({k: v for k, v in interior.items() if len(v)})
            landmarks.update(found)
    return regions, landmarks


def prepare(path, indices=None, say=print):
    """The face of the mesh at ``path`` (metres) and its 68 Multi-PIE vertices; ``indices``: a
    ``--landmark-indices`` file (else they are found in the render). Prints what it found through ``say``."""
    from visemeface.face.mesh import MESH_RIG_DEFAULTS, FaceMesh
    from visemeface.retarget.rigs import _units

    V, quads, tris, colours = read_head(path)
    check_surface(V, quads, tris, path)
    if indices is not None:
        lm68 = read_indices(indices, len(V))
        say(f"landmarks: the 68 vertices of {indices}")
    else:
        lm68, _, _ = detect_68(FaceMesh(V, quads, tris), path)
        say("landmarks: 68 found in the frontal render (MediaPipe face mesh)")
    width = float(np.linalg.norm(V[lm68[54]] - V[lm68[48]]))
    try:
        scale = _units(V, lm68[54], lm68[48], path)
    except InputError:
        raise InputError(f"the mouth is {width:.4g} file units wide: not 3-8 cm in metres, centimetres or "
                         "millimetres (check the mesh's units)", path) from None
    unit = {1.0: "metres", 0.01: "centimetres", 0.001: "millimetres"}[scale]
    say(f"units: {unit} (mouth {width:.4g} units wide = {width * scale * 100:.1f} cm)"
        + ("" if scale == 1.0 else f"; scaled by {scale:g} to metres"))
    V = V * scale
    regions, landmarks = label(V, quads, tris, lm68, path, silhouette=indices is None)
    face = FaceMesh(V, quads, tris, regions, landmarks, colours,         # the mesh's own colours, if it has them
                    rig_defaults=MESH_RIG_DEFAULTS)
    say("regions: " + ", ".join(f"{k} {len(v)}" for k, v in face.regions.items() if k != "eyes"))
    return face, lm68


def lip_stretch(face) -> float:
    """Torn lips, measured: the largest stretch (posed / rest edge length) of a lip triangle more than 0.1
    mouth widths from either corner, over every viseme alone and with each emotion at full weight (1: none;
    a torn lip: over 3)."""
    from visemeface.muscles.rig import MuscleRig
    from visemeface.postures.library import PostureLibrary

    lib = PostureLibrary(MuscleRig.from_file(face, None))
    T, V, L = face.triangles, face.vertices, face.landmarks
    lip = np.zeros(len(V), bool)
    lip[np.concatenate([face.regions["upper_lip"], face.regions["lower_lip"]])] = True
    corners = V[[L["mouth_corner_left"], L["mouth_corner_right"]]]
    width = np.linalg.norm(corners[0] - corners[1])
    near = np.min(np.linalg.norm(V[T].mean(axis=1)[:, None] - corners[None], axis=2), axis=1) / width
    T = T[lip[T].any(axis=1) & (near > 0.1)]

    def edges(P):
        return np.stack([np.linalg.norm(P[T[:, i]] - P[T[:, (i + 1) % 3]], axis=1) for i in range(3)], axis=1)

    rest = np.maximum(edges(V), 1e-12)
    worst = 0.0
    for viseme in lib.visemes.index:
        for emotion in [None, *lib.expressions.index]:
            P = lib.posed_vertices(viseme, {emotion: 1.0} if emotion else None)
            worst = max(worst, float((edges(P) / rest).max()))
    return worst


def check_sheet(face, lm68: np.ndarray, size: int = RENDER_SIZE) -> np.ndarray:
    """A frontal render of ``face`` with its regions tinted, its 68 landmarks and its lip seams drawn."""
    import cv2

    from visemeface.render.renderer import Renderer

    c = face.vertex_colors().astype(np.float64)
    for name, tint in (("upper_lids", (0.35, 0.55, 0.9)), ("lower_lids", (0.35, 0.85, 0.55))):
        if name in face.regions:
            c[face.regions[name]] = tint
    for name, tint in (("upper_lip", (0.95, 0.3, 0.3)), ("lower_lip", (0.95, 0.7, 0.2))):
        c[face.regions[name]] = tint
    from dataclasses import replace

    shown = replace(face, colors=c)
    with Renderer(shown, size=size) as renderer:
        image = np.ascontiguousarray(renderer.render())
        for name, colour in (("lip_seam_upper", (255, 255, 255)), ("lip_seam_lower", (40, 40, 40))):
            for u, v in renderer.project(face.vertices[face.regions[name]]):
                cv2.circle(image, (int(u), int(v)), 1, colour, -1, cv2.LINE_AA)
        for k, (u, v) in enumerate(renderer.project(face.vertices[lm68])):
            cv2.circle(image, (int(u), int(v)), 3, (40, 255, 255), -1, cv2.LINE_AA)
            if k % 4 == 0:
                cv2.putText(image, str(k), (int(u) + 4, int(v) - 3), cv2.FONT_HERSHEY_SIMPLEX, 0.3, (255, 255, 0),
                            1, cv2.LINE_AA)
    return image
