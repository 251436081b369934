"""The embedded default face: topology, orientation, regions, landmarks, symmetry."""

import numpy as np
import pytest
import scipy.sparse
import scipy.sparse.csgraph
from scipy.spatial import cKDTree

from visemeface.errors import InputError
from visemeface.face.mesh import INTERIOR_LANDMARKS, LANDMARK_NAMES
from visemeface.face.procedural import MOUTH_WIDTH, default_face, mirror_indices


@pytest.fixture(scope="module")
def face():
    return default_face()


def _directed_edges(face):
    q, t = face.quads, face.tris
    return np.concatenate([q[:, [0, 1]], q[:, [1, 2]], q[:, [2, 3]], q[:, [3, 0]],
                           t[:, [0, 1]], t[:, [1, 2]], t[:, [2, 0]]])


def test_default_size_and_resolution_parameter():
    small, big = default_face(1500), default_face(12000)
    face = default_face()
    assert 3000 <= face.n_vertices <= 6000
    assert small.n_vertices < face.n_vertices < big.n_vertices
    parts = ("upper_teeth", "lower_teeth", "upper_gum", "lower_gum", "tongue")
    for f, target in [(small, 1500), (face, 4500), (big, 12000)]:
        # the resolution counts the skin, eyes and cavity walls; the interior adds a fixed ~500
        interior = sum(len(f.regions[k]) for k in parts)
        assert 0.7 * target < f.n_vertices - interior < 1.35 * target
        # every resolution keeps the same named parts and the mouth width
        assert set(f.landmarks) == set(LANDMARK_NAMES + INTERIOR_LANDMARKS)
        lm = f.landmarks
        width = f.vertices[lm["mouth_corner_left"], 0] - f.vertices[lm["mouth_corner_right"], 0]
        assert width == pytest.approx(MOUTH_WIDTH, abs=1e-12)


def test_deterministic():
    a, b = default_face(), default_face()
    assert np.array_equal(a.vertices, b.vertices)
    assert np.array_equal(a.quads, b.quads) and np.array_equal(a.tris, b.tris)
    assert np.array_equal(a.colors, b.colors)
    assert a.landmarks == b.landmarks
    assert a.regions.keys() == b.regions.keys()
    assert all(np.array_equal(a.regions[k], b.regions[k]) for k in a.regions)


def test_bad_parameters_are_input_errors():
    with pytest.raises(InputError, match="resolution"):
        default_face(10)
    with pytest.raises(InputError, match="rest_gap"):
        default_face(rest_gap=-0.001)


def test_manifold_and_consistently_oriented(face):
    e = _directed_edges(face)
    # each directed edge once: neighbouring faces traverse a shared edge in opposite directions
    assert len(np.unique(e, axis=0)) == len(e)
    _, counts = np.unique(np.sort(e, axis=1), axis=0, return_counts=True)
    assert counts.max() <= 2
    # every vertex is used by some face
    assert np.array_equal(np.unique(np.concatenate([face.quads.ravel(), face.tris.ravel()])),
                          np.arange(face.n_vertices))


def test_normals_point_outward(face):
    n = face.vertex_normals()
    lm = face.landmarks
    for name in ["nose_tip", "chin", "upper_lip_top", "lower_lip_bottom", "nasion",
                 "eye_centre_left", "eye_centre_right", "brow_inner_left"]:
        assert n[lm[name], 2] > 0.5, name
    assert n[lm["cheek_left"], 0] > 0.2 and n[lm["cheek_right"], 0] < -0.2
    # the skin faces away from the head's inside: away from a point well behind the face
    inside = np.array([0.0, 0.03, -0.09])
    skin = np.setdiff1d(np.arange(face.n_vertices),
                        np.concatenate([face.regions["mouth_cavity"], face.regions["eyes"]]))
    outward = np.einsum("ij,ij->i", n[skin], face.vertices[skin] - inside) > 0
    assert outward.mean() > 0.97


def test_open_boundaries_only_at_seam_eyes_and_rim(face):
    be = face.boundary_edges()
    bv = np.unique(be)
    allowed = np.concatenate([face.regions[k] for k in
                              ("eyes", "boundary", "mouth_cavity", "lip_seam_upper", "lip_seam_lower")])
    assert np.setdiff1d(bv, allowed).size == 0
    # loops: the outer rim, two eyelid openings, two eyeball rims, the two cavity sides,
    # the two gum strips and the tongue (the teeth are closed)
    n = face.n_vertices
    g = scipy.sparse.coo_matrix((np.ones(len(be)), (be[:, 0], be[:, 1])), shape=(n, n))
    _, label = scipy.sparse.csgraph.connected_components(g, directed=False)
    assert len(np.unique(label[bv])) == 10
    # the rim is one loop holding every boundary-region vertex
    rim = face.regions["boundary"]
    assert len(np.unique(label[rim])) == 1


def test_no_degenerate_quads(face):
    v = face.vertices[face.quads]
    edges = np.linalg.norm(np.roll(v, -1, axis=1) - v, axis=2)
    assert edges.min() > 1e-4                         # 0.1 mm
    n1 = np.cross(v[:, 1] - v[:, 0], v[:, 2] - v[:, 0])
    n2 = np.cross(v[:, 2] - v[:, 0], v[:, 3] - v[:, 0])
    assert 0.5 * np.linalg.norm(n1, axis=1).min() > 1e-8   # 0.01 mm^2
    assert 0.5 * np.linalg.norm(n2, axis=1).min() > 1e-8
    # not folded: the two halves of a quad face the same way
    cos = np.einsum("ij,ij->i", n1, n2) / np.linalg.norm(n1, axis=1) / np.linalg.norm(n2, axis=1)
    assert cos.min() > 0.0


def test_units_axes_origin(face):
    v, lm = face.vertices, face.landmarks
    cl, cr = v[lm["mouth_corner_left"]], v[lm["mouth_corner_right"]]
    assert np.allclose(0.5 * (cl + cr), 0.0, atol=1e-12)
    assert cl[0] > 0 > cr[0]                           # +x is the subject's left
    assert v[lm["eye_centre_left"], 0] > 0 and v[lm["brow_outer_left"], 0] > 0
    y = {k: v[lm[k], 1] for k in lm}
    assert y["brow_inner_left"] > y["eye_centre_left"] > y["nose_tip"] > y["upper_lip_top"] > 0
    assert 0 > y["lower_lip_bottom"] > y["chin"]
    # a human-sized face: 0.1 m to 0.16 m wide, mouth ~ 0.05 m
    width = v[:, 0].max() - v[:, 0].min()
    assert 0.10 < width < 0.16
    assert 0.055 < v[lm["eye_centre_left"], 0] - v[lm["eye_centre_right"], 0] < 0.070


def test_nose_tip_is_most_forward(face):
    assert face.landmarks["nose_tip"] == int(np.argmax(face.vertices[:, 2]))


def test_lip_seam_pairs_and_corners(face):
    up, lo = face.regions["lip_seam_upper"], face.regions["lip_seam_lower"]
    v, lm = face.vertices, face.landmarks
    assert len(up) == len(lo) >= 5
    # ordered by x (and sorted, as every region), corners shared at both ends
    assert np.all(np.diff(v[up, 0]) > 0) and np.all(np.diff(v[lo, 0]) > 0)
    assert up[0] == lo[0] == lm["mouth_corner_right"] and up[-1] == lo[-1] == lm["mouth_corner_left"]
    assert np.all(up[1:-1] != lo[1:-1])               # the slit: distinct vertices inside
    # the corners are the seam's extreme x
    seam = np.union1d(up, lo)
    assert v[seam, 0].max() == v[lm["mouth_corner_left"], 0]
    assert v[seam, 0].min() == v[lm["mouth_corner_right"], 0]
    # closed at rest by default: pairs coincide
    assert np.abs(v[up] - v[lo]).max() < 1e-12
    assert lm["upper_lip_mid"] in up and lm["lower_lip_mid"] in lo


def test_rest_gap_opens_the_seam():
    f = default_face(rest_gap=0.002)
    up, lo = f.regions["lip_seam_upper"], f.regions["lip_seam_lower"]
    gap = f.vertices[up, 1] - f.vertices[lo, 1]
    assert gap.max() == pytest.approx(0.002, rel=0.05)       # at the centre
    assert np.all(gap[1:-1] > 0) and gap[0] == gap[-1] == 0  # tapering to the corners


def test_upper_lip_above_lower(face):
    v = face.vertices
    up, lo = face.regions["upper_lip"], face.regions["lower_lip"]
    assert np.intersect1d(up, lo).size == 2            # only the two corners
    assert v[up, 1].min() >= -1e-12 and v[lo, 1].max() <= 1e-12
    assert v[up, 1].mean() > 0.003 and v[lo, 1].mean() < -0.003
    # the vermilion spans the mouth width
    assert v[up, 0].min() == pytest.approx(-0.025, abs=2e-4)
    assert v[lo, 0].max() == pytest.approx(0.025, abs=2e-4)


def test_symmetric_about_x0(face):
    m = mirror_indices(face.vertices, tol=1e-9)
    assert np.abs(face.vertices[m] * [-1, 1, 1] - face.vertices).max() <= 1e-9
    v, lm = face.vertices, face.landmarks
    for name in lm:
        if name.endswith("_left"):
            a, b = v[lm[name]], v[lm[name.replace("_left", "_right")]]
            assert np.allclose(a * [-1, 1, 1], b, atol=1e-9), name
    # regions are mirror-symmetric as point sets
    for name, idx in face.regions.items():
        tree = cKDTree(v[idx])
        d, _ = tree.query(v[idx] * [-1, 1, 1])
        assert d.max() <= 1e-9, name


def test_lower_face_is_all_quads(face):
    # extra triangles exist only on the eyes (pupil fans), above the nose
    tri_vertices = np.unique(face.tris)
    assert np.isin(tri_vertices, face.regions["eyes"]).all()
    assert face.vertices[tri_vertices, 1].min() > face.vertices[face.landmarks["nose_tip"], 1]


def test_regions_where_they_claim(face):
    v, r, lm = face.vertices, face.regions, face.landmarks
    jaw = r["jaw"]
    assert np.isin(r["lower_lip"], np.append(jaw, [lm["mouth_corner_left"], lm["mouth_corner_right"]])).all()
    assert lm["chin"] in jaw and lm["lower_lip_mid"] in jaw
    assert not np.isin(r["upper_lip"], jaw).any() and lm["upper_lip_mid"] not in jaw
    assert np.intersect1d(jaw, r["fixed"]).size == 0
    assert v[r["fixed"], 1].min() > 0                  # the skull part is above the mouth
    assert v[r["brow"], 1].min() > v[lm["eye_centre_left"], 1] - 0.01
    assert lm["nose_tip"] in r["nose"]
    assert np.isin([lm["cheek_left"], lm["cheek_right"]], r["cheek"]).all()
    for name, idx in r.items():
        assert np.array_equal(idx, np.unique(idx)), name
        assert len(idx) > 0, name


def test_colours_dark_cavity_red_lips(face):
    c = face.vertex_colors()
    assert c.shape == (face.n_vertices, 3) and c.dtype == np.float32
    lum = c @ np.array([0.299, 0.587, 0.114])
    walls = face.regions["cavity_wall"]
    assert lum[walls].max() < 0.2
    # shaded dark toward the back: the deepest wall vertices are the darkest
    z = face.vertices[walls, 2]
    back, front = walls[z < np.quantile(z, 0.2)], walls[z > np.quantile(z, 0.8)]
    assert lum[back].max() < 0.05 < lum[front].mean()
    teeth = np.concatenate([face.regions["upper_teeth"], face.regions["lower_teeth"]])
    assert lum[teeth].min() > 0.6 and (c[teeth].max(1) - c[teeth].min(1)).max() < 0.15   # bright, pale
    tongue = c[face.regions["tongue"]]
    assert (tongue[:, 0] > 1.4 * tongue[:, 1]).all()                                     # red, not grey
    lip = c[face.regions["lower_lip"]].mean(0)
    skin = c[face.landmarks["cheek_left"]]
    assert lip[0] / lip[1] > 1.25 * skin[0] / skin[1]   # redder than the skin


def test_teeth_and_tongue_sit_inside_the_mouth(face):
    v, r, lm = face.vertices, face.regions, face.landmarks
    seam_z = v[lm["upper_lip_mid"], 2]
    for name in ("upper_teeth", "lower_teeth", "upper_gum", "lower_gum", "tongue"):
        p = v[r[name]]
        assert p[:, 2].max() < seam_z - 0.005, name          # behind the lips' front by 5 mm or more
        assert np.abs(p[:, 0]).max() < 0.03, name            # inside the cheeks
    up, lo = v[lm["upper_incisor_edge"]], v[lm["lower_incisor_edge"]]
    # a normal bite: upper incisors 1-3 mm below the seam, overlapping the lower ones by 2 mm, in front
    assert -0.003 <= up[1] <= -0.001 and lo[1] - up[1] == pytest.approx(0.002, abs=1e-4)
    assert up[2] > lo[2]
    # the tongue lies behind the lower incisors and below their edge
    tip = v[lm["tongue_tip"]]
    assert tip[2] < lo[2] - 0.002 and tip[1] < lo[1]
    # each crown is a closed box: 14 faces... 6 quads per tooth, 10 teeth per arch
    assert len(r["upper_teeth"]) == len(r["lower_teeth"]) == 10 * 8
