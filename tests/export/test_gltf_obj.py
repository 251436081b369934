"""glTF colours and extras, ARKit-named morph targets, OBJ normals and materials, the preview command."""

import json
import struct

import numpy as np
import pytest

from visemeface.cli import main
from visemeface.export.gltf import srgb_to_linear

from test_retarget import ARKIT


def read_glb(path):
    data = path.read_bytes()
    n = struct.unpack_from("<I", data, 12)[0]
    doc = json.loads(data[20:20 + n])
    binary = data[20 + n + 8:]

    def accessor(i):
        acc = doc["accessors"][i]
        view = doc["bufferViews"][acc["bufferView"]]
        width = {"SCALAR": 1, "VEC3": 3, "VEC4": 4}[acc["type"]]
        dtype = {5126: "<f4", 5123: "<u2", 5125: "<u4"}[acc["componentType"]]
        arr = np.frombuffer(binary, dtype, acc["count"] * width, view["byteOffset"])
        return arr.reshape(acc["count"], width) if width > 1 else arr

    return doc, accessor


def test_srgb_to_linear():
    assert np.allclose(srgb_to_linear([0.0, 0.04045, 1.0]), [0.0, 0.04045 / 12.92, 1.0])
    assert srgb_to_linear(0.86) == pytest.approx(0.7106, abs=1e-4)


def test_glb_colours_are_linear_and_extras_tell_the_rate(exported, default_face):
    doc, accessor = read_glb(exported / "a.glb")
    colours = accessor(doc["meshes"][0]["primitives"][0]["attributes"]["COLOR_0"])
    cheek = default_face.landmarks["cheek_left"]
    assert colours[cheek, 0] == pytest.approx(0.70, abs=0.02)          # not the display value 0.86
    assert doc["materials"][0]["pbrMetallicRoughness"]["metallicFactor"] == 0
    extras = doc["asset"]["extras"]
    assert extras["fps"] == 30 and extras["source"].endswith("t.txt") and extras["shapes"] == "muscles"
    times = accessor(doc["animations"][0]["samplers"][0]["input"])
    assert extras["keyframes"] == len(times) == extras["frames"] + 1 and extras["heldLastKey"]
    assert np.allclose(times[:-1], np.arange(extras["frames"]) / 30, atol=1e-6)
    assert doc["scenes"][0]["extras"] == extras


def test_gltf_shapes_arkit_names_the_morph_targets(arkit_glb):
    doc, accessor = read_glb(arkit_glb)
    assert doc["meshes"][0]["extras"]["targetNames"] == ARKIT and doc["asset"]["extras"]["shapes"] == "arkit"
    w = accessor(doc["animations"][0]["samplers"][0]["output"]).reshape(-1, 52)
    assert w.min() >= 0 and w.max() <= 1 and w[:, ARKIT.index("jawOpen")].max() > 0.1


def test_obj_frames_have_unit_normals_and_materials(exported, default_face):
    folder = exported / "objd"
    mtl = (folder / "face.mtl").read_text()
    defined = {line.split()[1] for line in mtl.splitlines() if line.startswith("newmtl")}
    assert defined == {"skin", "lip", "eye", "cavity"}
    text = (folder / "frame_000010.obj").read_text()
    assert "mtllib face.mtl" in text
    vn = np.array([line.split()[1:] for line in text.splitlines() if line.startswith("vn ")], float)
    assert len(vn) == default_face.n_vertices and np.allclose(np.linalg.norm(vn, axis=1), 1, atol=1e-4)
    used = {line.split()[1] for line in text.splitlines() if line.startswith("usemtl")}
    assert used == defined
    faces = [line for line in text.splitlines() if line.startswith("f ")]
    assert len(faces) == len(default_face.triangles) and all("//" in f for f in faces[:10])


def test_preview_command(exported, tmp_path, capsys):
    out = tmp_path / "p.html"
    assert main(["preview", str(exported / "a.glb"), "--audio", str(exported / "a.wav"), "-o", str(out)]) == 0
    page = out.read_text()
    assert "data:audio/wav;base64," in page and 'id="glb"' in page and "http://" not in page.split("<script>")[0]
    assert main(["preview", str(exported / "a.glb"), "-o", str(out)]) == 2
    assert "output exists" in capsys.readouterr().err
    y = str(tmp_path / "y.html")
    for args, message in [([str(exported / "t.txt"), "-o", y], "not a readable binary glTF"),
                          ([str(exported / "a.glb"), "--audio", str(exported / "t.txt"), "-o", y],
                           "a browser cannot play"),
                          ([str(exported / "a.glb"), "-o", str(tmp_path / "x.htm")], "must end in .html")]:
        assert main(["preview", *args]) == 2
        assert message in capsys.readouterr().err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["p.html"]


def test_preview_of_a_still_mesh_says_so(tmp_path, capsys):
    assert main(["face", "--export", str(tmp_path / "head.glb"), "-q"]) == 0
    assert main(["preview", str(tmp_path / "head.glb"), "-o", str(tmp_path / "head.html")]) == 0
    assert "a still mesh: the glb has no animation" in capsys.readouterr().out


def test_preview_without_a_path_goes_beside_the_video(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "s.txt").write_text("hi\n")
    assert main(["speak", "s.txt", "--size", "32", "--msaa", "0", "-q", "-o", "take.mp4", "--preview"]) == 0
    assert (tmp_path / "take.mp4").is_file() and not (tmp_path / "s.html").exists()
    assert "VF3" in (tmp_path / "take.html").read_text()
