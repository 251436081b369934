"""``face --prepare``'s refusals: one line, exit 2, nothing written."""

import json

import numpy as np
import pytest

from visemeface.cli import main


@pytest.fixture(scope="module")
def ours(tmp_path_factory):
    """The default face as a bare OBJ (no landmarks file) and its mouth corners."""
    from visemeface.face.procedural import default_face

    root = tmp_path_factory.mktemp("ours")
    face = default_face(1500)
    face.save(root / "ours.obj")
    (root / "ours.landmarks.json").unlink()
    return root / "ours.obj", face


def _refused(capsys, argv, folder, *words):
    before = sorted(p.name for p in folder.iterdir())
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert err.startswith("visemeface: ") and err.count("\n") == 1, err
    for w in words:
        assert w in err, err
    assert sorted(p.name for p in folder.iterdir()) == before


def _indices(tmp_path, face, **override):
    idx = [0] * 68
    idx[48], idx[54] = face.landmarks["mouth_corner_right"], face.landmarks["mouth_corner_left"]
    for k, v in override.items():
        idx[int(k[1:])] = v
    path = tmp_path / "idx.json"
    path.write_text(json.dumps(idx))
    return path


def test_a_mouth_five_metres_wide_is_refused(ours, tmp_path, capsys):
    # 500 units: 5 m in centimetres, 50 cm in millimetres, no unit a mouth is measured in
    mesh, face = ours
    big = tmp_path / "big.obj"
    lines = [f"v {x * 1e4:.6f} {y * 1e4:.6f} {z * 1e4:.6f}" for x, y, z in face.vertices]
    lines += ["f " + " ".join(str(i + 1) for i in t) for t in face.triangles]
    big.write_text("\n".join(lines) + "\n")
    idx = _indices(tmp_path, face)
    _refused(capsys, ["face", "--prepare", str(big), "--landmark-indices", str(idx), "-o", str(tmp_path / "h.obj")],
             tmp_path, "mouth is 500 file units wide", "units")


def test_landmark_indices_out_of_range_or_too_few(ours, tmp_path, capsys):
    mesh, face = ours
    out = str(tmp_path / "h.obj")
    idx = _indices(tmp_path, face, i30=face.n_vertices)
    _refused(capsys, ["face", "--prepare", str(mesh), "--landmark-indices", str(idx), "-o", out], tmp_path,
             f"vertex index {face.n_vertices} out of range")
    idx = _indices(tmp_path, face)                           # all the others on vertex 0
    _refused(capsys, ["face", "--prepare", str(mesh), "--landmark-indices", str(idx), "-o", out], tmp_path,
             "lie on one spot")
    idx.write_text("1 2 3")
    _refused(capsys, ["face", "--prepare", str(mesh), "--landmark-indices", str(idx), "-o", out], tmp_path,
             "expected 68 vertex indices")


def test_a_non_manifold_mess_is_refused(tmp_path, capsys):
    fan = tmp_path / "fan.obj"               # 300 triangles all on one edge
    rng = np.random.default_rng(1)
    lines = ["v 0 0 0", "v 0 1 0"] + [f"v {x:.3f} {y:.3f} {z:.3f}" for x, y, z in rng.normal(size=(300, 3))]
    lines += [f"f 1 2 {k + 3}" for k in range(300)]
    fan.write_text("\n".join(lines) + "\n")
    _refused(capsys, ["face", "--prepare", str(fan), "-o", str(tmp_path / "h.obj")], tmp_path, "not a manifold")
    junk = tmp_path / "junk.obj"
    junk.write_bytes(b"\0\1\2 binary")
    _refused(capsys, ["face", "--prepare", str(junk), "-o", str(tmp_path / "h.obj")], tmp_path, "not a valid OBJ")


def test_a_mesh_with_no_face_is_refused(tmp_path, capsys):
    import trimesh

    ball = tmp_path / "ball.obj"
    trimesh.creation.icosphere(subdivisions=3, radius=0.1).export(ball)
    _refused(capsys, ["face", "--prepare", str(ball), "-o", str(tmp_path / "h.obj")], tmp_path, "no face")


def test_outputs_are_not_overwritten_and_options_are_checked(ours, tmp_path, capsys):
    mesh, _ = ours
    out = tmp_path / "h.obj"
    out.write_text("keep me")
    _refused(capsys, ["face", "--prepare", str(mesh), "-o", str(out)], tmp_path, "exists", "--force")
    assert out.read_text() == "keep me"
    _refused(capsys, ["face", "--prepare", str(mesh), "-o", str(tmp_path / "h.png")], tmp_path, "must end in")
    _refused(capsys, ["face", "--prepare", str(mesh)], tmp_path, "needs -o")
    _refused(capsys, ["face", "-o", str(tmp_path / "f.png"), "--sheet", str(tmp_path / "s.png")], tmp_path,
             "--sheet needs --prepare")
    _refused(capsys, ["face", "--prepare", str(mesh), "-o", str(tmp_path / "g.obj"), "--export",
                      str(tmp_path / "e.obj")], tmp_path, "--export does not go with --prepare")
