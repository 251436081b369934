"""FaceMesh: triangles from quads, normals, files (OBJ/PLY/glTF + landmarks sidecar), errors."""

import json

import numpy as np
import pytest
import trimesh

from visemeface.errors import InputError
from visemeface.face.mesh import FaceMesh, load_face, sidecar_path, split_quads
from visemeface.face.normals import NormalAccumulator, vertex_normals
from visemeface.face.procedural import default_face


@pytest.fixture(scope="module")
def small_face():
    return default_face(1000)


def _quad_sphere(n=24, m=12):
    """A UV sphere of quads (no poles: latitudes -80..80 degrees), unit radius."""
    lat = np.radians(np.linspace(-80, 80, m))
    lon = np.linspace(0, 2 * np.pi, n, endpoint=False)
    la, lo = np.meshgrid(lat, lon, indexing="ij")
    v = np.stack([np.cos(la) * np.cos(lo), np.cos(la) * np.sin(lo), np.sin(la)], -1).reshape(-1, 3)
    idx = np.arange(m * n).reshape(m, n)
    nxt = np.roll(idx, -1, axis=1)
    q = np.stack([idx[:-1], nxt[:-1], nxt[1:], idx[1:]], -1).reshape(-1, 4)
    return v, q


def test_split_quads_keeps_orientation():
    v = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]], float)
    tris = split_quads([[0, 1, 2, 3]])
    n = np.cross(v[tris[:, 1]] - v[tris[:, 0]], v[tris[:, 2]] - v[tris[:, 0]])
    assert np.all(n[:, 2] > 0)                       # counter-clockwise from +z -> +z normals
    assert sorted(np.unique(tris)) == [0, 1, 2, 3]


def test_vertex_normals_of_a_sphere_are_radial():
    v, q = _quad_sphere()
    n = vertex_normals(v, split_quads(q))
    assert np.allclose(np.linalg.norm(n, axis=1), 1.0)
    # outward and within a few degrees of the exact normal (the position itself),
    # except on the open rims where one side is missing
    inner = np.abs(v[:, 2]) < np.sin(np.radians(75))
    assert np.einsum("ij,ij->i", n[inner], v[inner]).min() > np.cos(np.radians(3))


def test_smoothing_groups_keep_a_crease():
    # two faces folded at 90 degrees along the edge (0, 1): one group each
    v = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0], [1, 0, -1], [0, 0, -1]], float)
    q = np.array([[0, 1, 2, 3], [5, 4, 1, 0]])
    tris = split_quads(q)
    plain = NormalAccumulator(tris, 6)(v)
    assert plain[0, 1] < -0.3 and plain[0, 2] > 0.3   # averaged across the fold
    groups = np.array([0, 0, 0, 0, 1, 1])             # (0, 1) belong to the top face's group
    grouped = NormalAccumulator(tris, 6, groups)(v)
    assert np.allclose(grouped[[0, 1]], [0, 0, 1])    # the top face's own normal
    assert np.allclose(grouped[[4, 5]], [0, -1, 0])


def test_triangles_are_quads_then_tris(small_face):
    t = small_face.triangles
    assert len(t) == 2 * len(small_face.quads) + len(small_face.tris)
    assert np.array_equal(t[len(t) - len(small_face.tris):], small_face.tris)


@pytest.mark.parametrize("suffix", [".obj", ".ply", ".glb", ".gltf"])
def test_round_trip(tmp_path, small_face, suffix):
    path = tmp_path / ("face" + suffix)
    mesh_path, side = small_face.save(path)
    assert mesh_path == path and side == tmp_path / "face.landmarks.json" and side.exists()
    back = load_face(path)
    assert np.allclose(back.vertices, small_face.vertices, atol=1e-7)   # float32 in PLY/glTF
    assert np.array_equal(back.quads, small_face.quads)
    assert np.array_equal(back.tris, small_face.tris)
    assert back.landmarks == small_face.landmarks
    assert back.regions.keys() == small_face.regions.keys()
    for k in small_face.regions:
        assert np.array_equal(back.regions[k], small_face.regions[k]), k
    assert np.abs(back.vertex_colors() - small_face.vertex_colors()).max() <= 1 / 255 + 1e-6


def test_rig_defaults_travel_with_the_face_and_a_hand_written_sidecar_gets_a_meshs(tmp_path, small_face):
    """A saved face keeps its own rig defaults (the procedural face none: it poses the same saved and
    loaded); a sidecar written by hand, without them, gets a mesh's (the mouth corners as one piece)."""
    from visemeface.face.mesh import MESH_RIG_DEFAULTS

    small_face.rig_defaults = {"jaw": {"neck_fade_deg": 30.0}}
    small_face.save(tmp_path / "a.obj")
    assert load_face(tmp_path / "a.obj").rig_defaults == {"jaw": {"neck_fade_deg": 30.0}}
    small_face.rig_defaults = {}
    small_face.save(tmp_path / "b.obj")
    assert load_face(tmp_path / "b.obj").rig_defaults == {}
    side = tmp_path / "b.landmarks.json"
    data = json.loads(side.read_text())
    del data["rig_defaults"]
    side.write_text(json.dumps(data))
    assert load_face(tmp_path / "b.obj").rig_defaults == MESH_RIG_DEFAULTS


def test_save_refuses_overwrite_without_force(tmp_path, small_face):
    path = tmp_path / "f.ply"
    small_face.save(path)
    before = path.read_bytes()
    moved = FaceMesh(small_face.vertices + 0.01, small_face.quads, small_face.tris,
                     small_face.regions, small_face.landmarks, small_face.colors)
    with pytest.raises(InputError, match="exists"):
        moved.save(path)
    assert path.read_bytes() == before
    moved.save(path, force=True)
    assert np.allclose(load_face(path).vertices, moved.vertices, atol=1e-7)


def test_one_face_saves_in_two_formats_beside_one_landmarks_file(tmp_path, small_face):
    small_face.save(tmp_path / "head.obj")
    side = (tmp_path / "head.landmarks.json").read_bytes()
    small_face.save(tmp_path / "head.glb")                     # the same landmarks: no clash
    assert (tmp_path / "head.landmarks.json").read_bytes() == side
    other = FaceMesh(small_face.vertices, small_face.quads, small_face.tris, small_face.regions,
                     {k: v for k, v in list(small_face.landmarks.items())[1:]}, small_face.colors)
    with pytest.raises(InputError, match="exists"):           # other landmarks: --force or another name
        other.save(tmp_path / "head.ply")
    assert not (tmp_path / "head.ply").exists()


def test_save_unknown_format(tmp_path, small_face):
    with pytest.raises(InputError, match="unknown mesh format"):
        small_face.save(tmp_path / "face.stl")


def test_users_mesh_with_coordinate_landmarks(tmp_path):
    sphere = trimesh.creation.icosphere(subdivisions=2, radius=0.08)
    path = tmp_path / "head.obj"
    sphere.export(path)
    target = sphere.vertices[17] + [0.001, -0.0005, 0.0]      # near vertex 17, not on it
    (tmp_path / "head.landmarks.json").write_text(json.dumps({
        "landmarks": {"nose_tip": target.tolist(), "chin": 5},
        "regions": {"jaw": [1, 2, 3]},
    }))
    face = load_face(path)
    assert face.n_vertices == len(sphere.vertices)
    assert face.landmarks == {"nose_tip": 17, "chin": 5}
    assert face.quads.shape == (0, 4) and len(face.tris) == len(sphere.faces)
    assert np.array_equal(face.regions["jaw"], [1, 2, 3])
    assert face.vertex_colors().shape == (face.n_vertices, 3)


def test_explicit_landmarks_path(tmp_path, small_face):
    small_face.save(tmp_path / "a.ply")
    (tmp_path / "a.landmarks.json").rename(tmp_path / "marks.json")
    with pytest.raises(InputError, match="landmarks file not found"):
        load_face(tmp_path / "a.ply")
    face = load_face(tmp_path / "a.ply", tmp_path / "marks.json")
    assert face.landmarks == small_face.landmarks


def test_missing_mesh(tmp_path):
    with pytest.raises(InputError) as exc:
        load_face(tmp_path / "nope.obj")
    assert "nope.obj" in str(exc.value) and "not found" in str(exc.value)


def test_corrupt_mesh(tmp_path):
    path = tmp_path / "broken.ply"
    path.write_bytes(b"ply\nformat binary_little_endian 1.0\nelement vertex 99\nend_header\n\x00\x01")
    sidecar_path(path).write_text('{"landmarks": {}}')
    with pytest.raises(InputError) as exc:
        load_face(path)
    assert "broken.ply" in str(exc.value) and "cannot read mesh" in str(exc.value)
    assert "\n" not in str(exc.value)


@pytest.mark.parametrize("text, message", [
    ('{"landmarks": {"chin": 3,}\n}', "not valid JSON"),
    ('[1, 2]', "JSON object"),
    ('{"landmarks": {"chin": 999999}}', "'chin': vertex index 999999 out of range"),
    ('{"landmarks": {"chin": "here"}}', "'chin': expected a vertex index"),
    ('{"landmarks": {}, "regions": {"jaw": [0, -4]}}', "region 'jaw'"),
    ('{"landmarks": {}, "n_vertices": 12}', "mesh of 12 vertices"),
    ('{"landmarks": {}, "rig_defaults": {"modiolus": 0.2}}', "'rig_defaults' must map rig-file tables"),
])
def test_bad_sidecar(tmp_path, small_face, text, message):
    small_face.save(tmp_path / "f.ply")
    side = tmp_path / "f.landmarks.json"
    side.write_text(text)
    with pytest.raises(InputError) as exc:
        load_face(tmp_path / "f.ply")
    assert message in str(exc.value)
    assert str(side) in str(exc.value)


def test_bad_json_names_the_line(tmp_path, small_face):
    small_face.save(tmp_path / "f.ply")
    (tmp_path / "f.landmarks.json").write_text('{\n "landmarks": {\n  "chin": 3,\n }\n}')
    with pytest.raises(InputError) as exc:
        load_face(tmp_path / "f.ply")
    assert exc.value.line == 4


def test_colours_from_regions_when_the_mesh_has_none():
    v, q = _quad_sphere(8, 5)
    face = FaceMesh(v, q, regions={"lower_lip": [0, 1], "mouth_cavity": [2, 3], "eyes": [4]})
    c = face.vertex_colors()
    lum = c @ np.array([0.299, 0.587, 0.114])
    assert lum[[2, 3]].max() < 0.1                      # dark cavity
    assert c[0, 0] / c[0, 1] > 1.2 * c[10, 0] / c[10, 1]  # lips redder than skin
    assert lum[4] > lum[10]                            # pale eye


def test_landmarks_path_that_is_a_folder_is_a_one_line_error(tmp_path):
    from visemeface.errors import InputError
    from visemeface.face.mesh import load_face
    from visemeface.face.procedural import default_face

    face = default_face(resolution=1500)
    face.save(tmp_path / "m.obj")
    with pytest.raises(InputError, match="cannot read"):
        load_face(tmp_path / "m.obj", landmarks_path=tmp_path)


def test_the_face_command_exports_one_face_in_two_formats(tmp_path, monkeypatch, capsys):
    from visemeface.cli import main

    monkeypatch.chdir(tmp_path)
    assert main(["face", "--export", "head.obj"]) == 0
    assert main(["face", "--export", "head.glb"]) == 0          # the same landmarks beside both
    assert main(["face", "--resolution", "1500", "--export", "head.ply"]) == 2    # other landmarks: refused
    assert "head.landmarks.json: output exists" in capsys.readouterr().err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["head.glb", "head.landmarks.json", "head.obj"]
