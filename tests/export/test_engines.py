"""The engines' formats (Unity, Godot, Live2D, MMD, Audio2Face, SubRip, WebVTT, Papagayo), each read back by an
independent reader of its documented layout and compared with the ARKit or VRM weights of the same run."""

import json
import re
import struct

import numpy as np
import pytest

from visemeface.cli import main
from visemeface.resources import transcripts_path

from test_retarget import ARKIT

TEXT = "set white with p two soon"
NEW = {"--unity": "a.anim", "--godot": "a.tres", "--live2d": "a.motion3.json", "--mmd": "a.vmd",
       "--audio2face": "a2f.json", "--srt": "a.srt", "--vtt": "a.vtt", "--papagayo": "a.pgo",
       "--vrma": "a.vrma", "--arkit": "k.json", "--vrm": "v.json"}


@pytest.fixture(scope="module")
def run(tmp_path_factory):
    import shutil

    root = tmp_path_factory.mktemp("engines")
    (root / "t.txt").write_text(TEXT + "\n")
    shutil.copy(transcripts_path("set_white_with_p_two_soon.wav"), root / "a.wav")
    args = ["speak", str(root / "t.txt"), "--no-video", "-q", "--audio", str(root / "a.wav")]
    for option, name in NEW.items():
        args += [option, str(root / name)]
    assert main(args) == 0
    return root


def weights(path):
    doc = json.loads(path.read_text())
    return doc["names"], np.array(doc["time"]), np.array(doc["weights"])


# ------------------------------------------------------------------ Unity: PyYAML with Unity's tag

def unity_clip(path):
    yaml = pytest.importorskip("yaml")

    class Loader(yaml.SafeLoader):
        pass

    Loader.add_multi_constructor("tag:unity3d.com,2011:", lambda loader, suffix, node: loader.construct_mapping(
        node, deep=True))
    docs = list(yaml.load_all(path.read_text(encoding="utf-8"), Loader=Loader))
    assert len(docs) == 1
    return docs[0]["AnimationClip"]


def hermite(t, k0, k1):
    """Unity's evaluation of a curve between two keys (cubic Hermite of the values and slopes)."""
    dt = k1["time"] - k0["time"]
    s = (t - k0["time"]) / dt
    h00, h10, h01, h11 = 2 * s**3 - 3 * s**2 + 1, s**3 - 2 * s**2 + s, -2 * s**3 + 3 * s**2, s**3 - s**2
    return h00 * k0["value"] + h10 * dt * k0["outSlope"] + h01 * k1["value"] + h11 * dt * k1["inSlope"]


def test_unity_anim_is_an_animation_clip_of_arkit_blendshape_curves(run):
    clip = unity_clip(run / "a.anim")
    names, times, w = weights(run / "k.json")
    curves = clip["m_FloatCurves"]
    assert [c["attribute"] for c in curves] == [f"blendShape.{n}" for n in ARKIT]
    assert {c["classID"] for c in curves} == {137} and {c["path"] for c in curves} in ({""}, {None})
    assert clip["m_SampleRate"] == 30 and clip["m_EditorCurves"] == curves
    assert clip["m_AnimationClipSettings"]["m_StopTime"] == pytest.approx(times[-1], abs=1e-6)
    k = names.index("jawOpen")
    keys = curves[k]["curve"]["m_Curve"]
    assert 3 < len(keys) <= len(times) and {key["tangentMode"] for key in keys} == {69}
    kt = np.array([key["time"] for key in keys])
    # between keys Unity's Hermite curve is the straight line: it gives every frame's weight (x 100)
    played = []
    for t in times:
        j = min(np.searchsorted(kt, t + 1e-9) - 1, len(keys) - 2)
        played.append(hermite(t, keys[j], keys[j + 1]))
    assert np.allclose(played, 100 * w[:, k], atol=2e-3)
    assert max(played) > 5                                           # the jaw opens


# ------------------------------------------------------------------ Godot: the resource grammar

_VALUE = re.compile(r'^(?P<key>[\w/]+) = (?P<value>.*)$')


def godot_resource(text):
    """Godot's text resource grammar: a ``[gd_resource ...]`` heading, ``[resource]``, then ``key = value``
    lines whose values are numbers, strings, ``NodePath("...")``, packed arrays ``Type( n, ... )``, lists
    and (multi-line) dictionaries."""
    lines = text.split("\n")
    head = re.fullmatch(r'\[gd_resource type="(\w+)" format=(\d+)\]', lines[0])
    assert head and lines[1] == "" and lines[2] == "[resource]"
    props, i = {}, 3
    while i < len(lines) and lines[i]:
        m = _VALUE.match(lines[i])
        assert m, lines[i]
        value = m["value"]
        if value == "{":
            j = lines.index("}", i)
            value = "{" + " ".join(lines[i + 1:j]) + "}"
            i = j
        props[m["key"]] = _variant(value)
        i += 1
    return head[1], int(head[2]), props


def _variant(value):
    value = value.strip()
    packed = re.fullmatch(r"(PackedFloat32Array|PoolRealArray)\((.*)\)", value)
    if packed:
        return np.array([float(x) for x in packed[2].split(",") if x.strip()])
    node = re.fullmatch(r'NodePath\("(.*)"\)', value)
    if node:
        return ("NodePath", node[1])
    if value.startswith("{"):
        inner = re.sub(r"(PackedFloat32Array|PoolRealArray)\(([^)]*)\)", r"[\2]", value[1:-1])
        return {k: np.array(v) if isinstance(v, list) else v for k, v in json.loads("{" + inner + "}").items()}
    return json.loads(value.replace("true", "true").replace("false", "false"))


def test_godot4_tres_holds_one_blend_shape_track_per_arkit_weight(run):
    kind, fmt, props = godot_resource((run / "a.tres").read_text())
    names, times, w = weights(run / "k.json")
    assert (kind, fmt) == ("Animation", 3)
    assert props["step"] == pytest.approx(1 / 30, rel=1e-5) and props["length"] == pytest.approx(3.0, abs=1e-3)
    for k, name in enumerate(ARKIT):
        assert props[f"tracks/{k}/type"] == "blend_shape" and props[f"tracks/{k}/path"] == ("NodePath", f".:{name}")
        keys = props[f"tracks/{k}/keys"].reshape(-1, 3)          # Godot's (time, transition, value) triplets
        assert np.allclose(keys[:, 0], times, atol=1e-5) and np.all(keys[:, 1] == 1)
        assert np.allclose(keys[:, 2], w[:, k], atol=1e-5)
    assert f"tracks/{len(ARKIT)}/type" not in props


def test_godot3_tres_holds_value_tracks_of_blend_shapes(tmp_path):
    from visemeface.export.godot import tres_text

    t = np.arange(4) / 30
    kind, fmt, props = godot_resource(tres_text(["jawOpen", "mouthClose"], t, [[0, 1], [.5, 1], [1, 0], [.25, 0]],
                                                30, version="3"))
    assert (kind, fmt) == ("Animation", 2)
    assert props["tracks/0/type"] == "value" and props["tracks/0/path"] == ("NodePath", ".:blend_shapes/jawOpen")
    keys = props["tracks/0/keys"]
    assert np.allclose(keys["times"], t, atol=1e-6) and np.allclose(keys["values"], [0, .5, 1, .25])
    assert keys["update"] == 0 and np.all(keys["transitions"] == 1)


# ------------------------------------------------------------------ Live2D, Audio2Face: JSON layouts

def test_live2d_motion3_counts_and_mouth_curves(run):
    from visemeface.export.live2d import parameters

    doc = json.loads((run / "a.motion3.json").read_text())
    names, times, w = weights(run / "k.json")
    meta, curves = doc["Meta"], doc["Curves"]
    assert doc["Version"] == 3 and meta["Fps"] == 30 and meta["CurveCount"] == len(curves) == 2
    assert [c["Id"] for c in curves] == ["ParamMouthOpenY", "ParamMouthForm"]
    segments = points = 0
    for c in curves:                      # Cubism's reading of Segments: a first point, then typed segments
        s, i, pts = c["Segments"], 2, [tuple(c["Segments"][:2])]
        while i < len(s):
            assert s[i] == 0                                           # linear
            pts.append((s[i + 1], s[i + 2]))
            i += 3
            segments += 1
        points += len(pts)
        c["points"] = np.array(pts)
    assert (meta["TotalSegmentCount"], meta["TotalPointCount"]) == (segments, points)
    assert times[-1] <= meta["Duration"] < times[-1] + 1 / 30          # the utterance's end
    for c, (pid, terms, low, high) in zip(curves, parameters()):
        want = np.clip(sum(x * w[:, names.index(n)] for n, x in terms), low, high)
        assert np.allclose(c["points"][:, 0], times, atol=1e-4) and np.allclose(c["points"][:, 1], want, atol=2e-4)
    assert curves[0]["points"][:, 1].max() > 0.05


def test_audio2face_json_is_the_arkit_weights_in_a2fs_layout(run):
    doc = json.loads((run / "a2f.json").read_text())
    names, times, w = weights(run / "k.json")
    assert doc["exportFps"] == 30 and doc["facsNames"] == ARKIT and doc["numPoses"] == 52
    assert doc["numFrames"] == len(times) == len(doc["weightMat"]) and doc["trackPath"].endswith("a.wav")
    assert np.allclose(doc["weightMat"], w, atol=1e-6)


# ------------------------------------------------------------------ MMD: VMD's binary layout

def read_vmd(data):
    """A VMD reader of the documented layout (header, model name, bone frames, morph frames)."""
    assert data[:30].rstrip(b"\0") == b"Vocaloid Motion Data 0002"
    model = data[30:50].rstrip(b"\0").decode("shift_jis")
    pos = 50
    (bones,) = struct.unpack_from("<I", data, pos)
    pos += 4 + 111 * bones
    (n,) = struct.unpack_from("<I", data, pos)
    pos += 4
    frames = []
    for _ in range(n):
        name, frame, weight = struct.unpack_from("<15sIf", data, pos)
        frames.append((name.split(b"\0")[0].decode("shift_jis"), frame, weight))
        pos += 23
    rest = struct.unpack_from("<4I", data, pos)
    assert pos + 16 == len(data)
    return model, frames, rest


def test_mmd_vmd_holds_vowel_morph_frames_at_30_fps(run):
    model, frames, rest = read_vmd((run / "a.vmd").read_bytes())
    names, times, w = weights(run / "v.json")
    assert model == "" and rest == (0, 0, 0, 0)
    morphs = {m for m, _, _ in frames}
    assert morphs == {"あ", "い", "う", "え", "お", "まばたき"}
    for morph, vrm in (("あ", "aa"), ("お", "oh"), ("まばたき", "blink")):
        f = np.array([fr for m, fr, _ in frames if m == morph])
        v = np.array([x for m, _, x in frames if m == morph])
        assert np.array_equal(f, np.arange(len(f))) and f[-1] == int(times[-1] * 30 + 1e-6)
        assert np.allclose(v, np.interp(f / 30, times, w[:, names.index(vrm)]), atol=1e-5)
    assert max(x for m, _, x in frames if m == "あ") > 0.1


# ------------------------------------------------------------------ VRMA: pygltflib and the extension's layout

def test_vrma_animates_each_preset_expression_node_by_its_translation_x(run):
    pygltflib = pytest.importorskip("pygltflib")
    g = pygltflib.GLTF2().load_binary(str(run / "a.vrma"))
    names, times, w = weights(run / "v.json")
    blob = g.binary_blob()

    def accessor(i):
        a = g.accessors[i]
        view = g.bufferViews[a.bufferView]
        n = a.count * {"SCALAR": 1, "VEC3": 3}[a.type]
        return np.frombuffer(blob, "<f4", n, (view.byteOffset or 0) + (a.byteOffset or 0))

    ext = g.extensions["VRMC_vrm_animation"]
    assert "VRMC_vrm_animation" in g.extensionsUsed and ext["specVersion"] == "1.0" and not g.meshes
    preset = ext["expressions"]["preset"]
    assert set(preset) == set(names) >= {"aa", "ih", "ou", "ee", "oh", "blink", "happy"}
    (anim,) = g.animations
    by_node = {c.target.node: anim.samplers[c.sampler] for c in anim.channels if c.target.path == "translation"}
    for name in ("aa", "oh", "blink"):
        s = by_node[preset[name]["node"]]
        t, xyz = accessor(s.input), accessor(s.output).reshape(-1, 3)
        assert s.interpolation == "LINEAR" and np.allclose(t, times, atol=1e-6)
        assert np.allclose(xyz[:, 0], w[:, names.index(name)], atol=1e-6) and not xyz[:, 1:].any()
    assert accessor(by_node[preset["aa"]["node"]].output).max() > 0.1


# ------------------------------------------------------------------ captions: the srt and webvtt-py readers

def seconds(clock):
    h, m, x = clock.split(":")
    return 3600 * int(h) + 60 * int(m) + float(x)


def test_srt_and_vtt_captions_read_back_with_their_libraries(run):
    srt = pytest.importorskip("srt")
    webvtt = pytest.importorskip("webvtt")
    subs = list(srt.parse((run / "a.srt").read_text()))
    assert " ".join(s.content for s in subs) == TEXT
    cues = list(webvtt.read(str(run / "a.vtt")))
    assert len(cues) == len(subs)
    for s, c in zip(subs, cues):
        start, end = seconds(c.start), seconds(c.end)
        assert start == pytest.approx(s.start.total_seconds(), abs=1e-3)
        assert end == pytest.approx(s.end.total_seconds(), abs=1e-3)
        assert c.text == s.content                                  # the word timestamps stripped
        stamps = [seconds(x) for x in re.findall(r"<(\d\d:\d\d:\d\d\.\d{3})>", c.raw_text)]
        assert len(stamps) == len(s.content.split()) - 1
        assert all(start < a < end for a in stamps) and stamps == sorted(stamps)


def test_captions_break_at_pauses_and_length():
    from visemeface.export.captions import MAX_CHARS, caption_groups

    words = [(0.0, 0.2, "one"), (0.2, 0.4, "two"), (1.0, 1.2, "three")]
    assert [[w for _, _, w in g] for g in caption_groups(words)] == [["one", "two"], ["three"]]
    long = [(i * 0.2, i * 0.2 + 0.2, "word") for i in range(30)]
    assert all(len(" ".join(w for _, _, w in g)) <= MAX_CHARS for g in caption_groups(long))


def test_captions_without_words_are_refused(tmp_path, capsys):
    (tmp_path / "t.txt").write_text("0.00 0.05 _\n0.05 0.25 aa\n0.25 0.30 _\n")
    assert main(["speak", str(tmp_path / "t.txt"), "--no-video", "-q", "--srt", str(tmp_path / "a.srt")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "needs the utterance's words" in err[0]
    assert sorted(p.name for p in tmp_path.iterdir()) == ["t.txt"]


# ------------------------------------------------------------------ Papagayo: its loader's reading

def read_pgo(text):
    """Papagayo's reading of a project (LipsyncDoc.Open): header, voices, phrases, words, phonemes."""
    lines = iter(text.split("\n"))
    assert next(lines) == "lipsync version 1"
    sound, fps, duration, voices = next(lines), int(next(lines)), int(next(lines)), int(next(lines))
    out = []
    for _ in range(voices):
        name, _text, n_phrases = next(lines).strip(), next(lines).strip(), int(next(lines))
        for _ in range(n_phrases):
            phrase, start, end, n_words = next(lines).strip(), int(next(lines)), int(next(lines)), int(next(lines))
            for _ in range(n_words):
                word, a, b, n = next(lines).split()
                phonemes = [tuple(next(lines).split()) for _ in range(int(n))]
                out.append((phrase, start, end, word, int(a), int(b), [(int(f), p) for f, p in phonemes]))
    return sound, fps, duration, out


def test_papagayo_pgo_reads_back_as_words_with_preston_blair_shapes(run):
    sound, fps, duration, words = read_pgo((run / "a.pgo").read_text())
    assert fps == 24 and duration == 72 and sound.endswith("a.wav")
    assert " ".join(w[3] for w in words) == TEXT
    shapes = {"AI", "E", "etc", "FV", "L", "MBP", "O", "rest", "U", "WQ"}
    previous_end = -1
    for phrase, start, end, word, a, b, phonemes in words:
        assert start <= a <= b <= end and a > previous_end
        previous_end = b
        assert phonemes and all(a <= f <= b for f, _ in phonemes) and {p for _, p in phonemes} <= shapes
    p = next(w for w in words if w[3] == "p")
    assert p[6][0] == (p[4], "MBP")                           # /p/ opens on the lips pressed


# ------------------------------------------------------------------ Godot itself (headless Godot 3 from Debian)

@pytest.mark.slow
def test_godot3_plays_the_tres_as_the_weights(run, tmp_path):
    import shutil
    import subprocess
    from pathlib import Path

    godot = shutil.which("godot3-server") or shutil.which("godot3")
    if godot is None:
        pytest.skip("no headless Godot 3 (apt-get install godot3-server)")
    names, times, w = weights(run / "k.json")
    assert main(["speak", str(run / "t.txt"), "--no-video", "-q", "--audio", str(run / "a.wav"),
                 "--godot", str(tmp_path / "g3.tres"), "--tres-godot", "3"]) == 0
    (tmp_path / "project.godot").write_text("")
    shutil.copy(Path(__file__).with_name("godot_checks.gd"), tmp_path / "godot_checks.gd")
    at = [0.0, 0.61, 1.005, 1.4, times[-1]]                       # on frames and between them
    env = {"PATH": "/usr/bin:/bin", "HOME": str(tmp_path), "VF_TRES": str(tmp_path / "g3.tres"),
           "VF_OUT": str(tmp_path / "out.json"), "VF_TIMES": json.dumps(at)}
    run_ = subprocess.run([godot, "--path", str(tmp_path), "-s", "godot_checks.gd"], env=env, capture_output=True,
                          text=True, timeout=120)
    assert (tmp_path / "out.json").exists(), (run_.stdout + run_.stderr)[-3000:]
    out = json.loads((tmp_path / "out.json").read_text())
    assert out["tracks"] == 52 and out["paths"] == [f".:blend_shapes/{n}" for n in ARKIT]
    assert out["keys"] == [len(times)] * 52 and out["step"] == pytest.approx(1 / 30, rel=1e-4)
    want = np.array([[np.interp(t, times, w[:, k]) for k in range(52)] for t in at])
    assert np.allclose(out["played"], want, atol=1e-4)
    assert max(row[ARKIT.index("jawOpen")] for row in out["played"]) > 0.05


# ------------------------------------------------------------------ Blender reads the VRMA (glTF importer)

@pytest.mark.slow
def test_blender_imports_the_vrma_and_plays_each_expression_as_its_weight(run, tmp_path):
    import shutil
    import subprocess
    from pathlib import Path

    blender = shutil.which("blender")
    if blender is None:
        pytest.skip("no Blender (apt-get install blender python3-numpy, or pip bpy)")
    out = tmp_path / "vrma.json"
    done = subprocess.run([blender, "-b", "--factory-startup", "--python", str(Path(__file__).with_name("blender_vrma.py")), "--",
                           str(run / "a.vrma"), str(out)], capture_output=True, text=True, timeout=300)
    if not out.exists() and "No module named 'numpy'" in done.stdout + done.stderr:
        pytest.skip("Blender's glTF importer needs numpy (apt-get install python3-numpy)")
    assert out.exists(), (done.stdout + done.stderr)[-3000:]
    keys = json.loads(out.read_text())["x_keys"]
    names, times, w = weights(run / "v.json")
    for name in ("aa", "ih", "ou", "ee", "oh", "blink"):
        t, x = np.array(keys[f"expression_{name}"]).T
        assert np.allclose(t, times, atol=1e-4), name                   # the keys at the weights' times
        assert np.allclose(x, w[:, names.index(name)], atol=1e-5), name  # the node's X is the weight
    assert max(max(v for _, v in keys[f"expression_{n}"]) for n in ("aa", "oh")) > 0.1
