"""The exports in the clients that read them: headless Chromium (the preview page), Blender (glb, OBJ +
PC2), the Khronos glTF validator. Each skips with its reason where the client is not installed
(``apt-get install chromium blender python3-numpy``; ``npm install -g gltf-validator``)."""

import json
import shutil
import subprocess
from pathlib import Path

import numpy as np
import pytest

from test_gltf_obj import read_glb
from test_retarget import ARKIT

pytestmark = pytest.mark.slow
HERE = Path(__file__).resolve().parent


def _chromium():
    for name in ("chromium", "chromium-browser", "google-chrome"):
        if shutil.which(name):
            return shutil.which(name)
    pytest.skip("no Chromium (apt-get install chromium)")


def test_preview_plays_in_headless_chromium(exported):
    chromium = _chromium()
    url = (exported / "p.html").as_uri() + "#t=1"
    cmd = [chromium, "--headless=new", "--no-sandbox", "--disable-gpu", "--use-angle=swiftshader",
           "--enable-unsafe-swiftshader", "--virtual-time-budget=8000", "--window-size=640,520", "--dump-dom", url]
    out = subprocess.run(cmd, capture_output=True, text=True, timeout=120)
    start = out.stdout.find('<pre id="status">')
    assert start >= 0, out.stderr[-2000:]
    status = json.loads(out.stdout[start + len('<pre id="status">'):out.stdout.index("</pre>", start)])
    assert status["ready"] and status["errors"] == [] and status["time"] == 1
    assert "Uncaught" not in out.stderr
    # the morph weights three.js plays at t = 1 s are the glb's keyframes interpolated there
    doc, accessor = read_glb(exported / "a.glb")
    times = accessor(doc["animations"][0]["samplers"][0]["input"])
    w = accessor(doc["animations"][0]["samplers"][0]["output"]).reshape(len(times), -1)
    names = doc["meshes"][0]["extras"]["targetNames"]
    k = names.index("orbicularis_oris")
    assert status["weights"]["orbicularis_oris"] == pytest.approx(np.interp(1.0, times, w[:, k]), abs=1e-4)
    assert max(status["weights"].values()) > 0.1
    r, g, b = status["pixel"]                                   # the centre of the face: lit skin
    assert r > g > b and r > 120


def test_blender_imports_the_glb_and_the_pc2_steps_are_exact(exported, arkit_glb, tmp_path):
    blender = shutil.which("blender")
    if blender is None:
        pytest.skip("no Blender (apt-get install blender python3-numpy, or pip bpy)")
    out = tmp_path / "blender.json"
    run = subprocess.run([blender, "-b", "--factory-startup", "--python", str(HERE / "blender_checks.py"), "--",
                          str(arkit_glb), str(exported / "objd"), str(exported / "a.pc2"), str(exported / "a.glb"),
                          str(out)],
                         capture_output=True, text=True, timeout=300)
    if not out.exists() and "No module named 'numpy'" in run.stdout + run.stderr:
        pytest.skip("Blender's glTF importer needs numpy (apt-get install python3-numpy)")
    assert out.exists(), (run.stdout + run.stderr)[-3000:]
    res = json.loads(out.read_text())
    doc, _ = read_glb(arkit_glb)
    frames = doc["asset"]["extras"]["frames"]
    assert res["scene_fps"] == pytest.approx(30)
    assert res["shape_keys"][1:] == ARKIT                                # "Basis", then the ARKit names
    keys = np.array(res["key_frames"])
    assert np.allclose(keys[:frames], np.arange(frames), atol=1e-4)     # one key a scene frame
    assert len(keys) == frames + 1                                      # and the held last pose
    assert all(e is not None and e <= 0.01 for e in res["pc2_error_mm"].values()), res["pc2_error_mm"]
    assert {"skin", "lip", "eye", "cavity"} <= set(res["obj_materials"])
    # spoken from a recording, the face hangs from the animated head node; Blender turns it frame by
    # frame as the glb's keys say (glTF's y up is Blender's z: (w, x, y, z) -> (w, x, -z, y))
    doc, accessor = read_glb(exported / "a.glb")
    head = next(i for i, n in enumerate(doc["nodes"]) if n.get("name") == "head")
    channel = next(c for c in doc["animations"][0]["channels"] if c["target"] == {"node": head, "path": "rotation"})
    sampler = doc["animations"][0]["samplers"][channel["sampler"]]
    x, y, z, w = accessor(sampler["output"]).reshape(-1, 4).T
    want = np.stack([w, x, -z, y], axis=1)[:len(res["head_rotations"])]
    got = np.array(res["head_rotations"])
    assert res["face_parent"] == "head" and len(got) == doc["asset"]["extras"]["frames"]
    assert np.abs(np.sum(got * want, axis=1)).min() > 1 - 1e-6          # the same rotation at every frame
    turn = np.degrees(2 * np.arccos(np.clip(np.abs(got[:, 0]), 0, 1)))
    assert 0.3 < turn.max() < 5                                           # it moves, by a natural amount


def _validator():
    node = shutil.which("node")
    if node is None:
        pytest.skip("no node (the Khronos glTF validator runs on node)")
    root = subprocess.run(["npm", "root", "-g"], capture_output=True, text=True).stdout.strip()
    if not (Path(root) / "gltf-validator").is_dir():
        pytest.skip("no Khronos glTF validator (npm install -g gltf-validator)")
    return node, root


def test_khronos_validator_finds_no_error(exported, arkit_glb):
    node, root = _validator()
    script = ("const v = require(process.argv[1] + '/gltf-validator'); const fs = require('fs');"
              "v.validateBytes(new Uint8Array(fs.readFileSync(process.argv[2])))"
              ".then(r => console.log(JSON.stringify(r.issues))).catch(e => { console.error(e); process.exit(1); });")
    for glb in (exported / "a.glb", arkit_glb):
        out = subprocess.run([node, "-e", script, root, str(glb)], capture_output=True, text=True, timeout=120)
        assert out.returncode == 0, out.stderr
        issues = json.loads(out.stdout)
        assert issues["numErrors"] == issues["numWarnings"] == issues["numInfos"] == 0, issues["messages"][:5]
