"""`visemeface convert`: every readable format into every writable one keeps the timing within one frame;
cue formats round-trip exactly; bad input is one line, exit 2, nothing written."""

import json
import shutil
import struct

import numpy as np
import pandas as pd
import pytest

from visemeface.cli import main
from visemeface.resources import transcripts_path

from test_engines import TEXT, godot_resource, read_pgo, read_vmd, unity_clip

FPS = 30.0
#: The readable inputs, made by one speak run (the Rhubarb and Papagayo ones by their writers).
SOURCES = ["r.tsv", "r.json", "r.xml", "r.dat", "a.pgo", "k.csv", "k.json", "v.json", "o.csv", "ll.csv",
           "a2f.json", "tr.csv", "m.glb", "k.glb"]
#: Every output convert writes: (file name, --to where the suffix is shared).
TARGETS = [("o.pc2", None), ("o.glb", None), ("track.csv", "track"), ("arkit.csv", "arkit"),
           ("ll.csv", "livelink"), ("vrm.json", "vrm"), ("oculus.csv", "oculus"), ("o.tsv", None),
           ("rh.json", "rhubarb"), ("o.xml", None), ("o.dat", None), ("o.html", None), ("o.anim", None),
           ("o.tres", None), ("o.motion3.json", None), ("o.vmd", None), ("a2f.json", "audio2face"),
           ("o.srt", None), ("o.vtt", None), ("o.pgo", None), ("o.vrma", None)]


@pytest.fixture(scope="module")
def sources(tmp_path_factory):
    from visemeface.export.rhubarb import dat_text, json_text, xml_text

    root = tmp_path_factory.mktemp("sources")
    (root / "t.txt").write_text(TEXT + "\n")
    shutil.copy(transcripts_path("set_white_with_p_two_soon.wav"), root / "a.wav")
    outs = {"--rhubarb": "r.tsv", "--papagayo": "a.pgo", "--arkit": "k.csv", "--vrm": "v.json", "--oculus": "o.csv",
            "--livelink": "ll.csv", "--audio2face": "a2f.json", "--track": "tr.csv", "--gltf": "m.glb"}
    args = ["speak", str(root / "t.txt"), "--no-video", "-q", "--audio", str(root / "a.wav"), "--no-blink"]
    assert main(args + [x for o, n in outs.items() for x in (o, str(root / n))]) == 0
    assert main(["convert", str(root / "k.csv"), str(root / "k.json"), "--to", "arkit", "-q"]) == 0
    assert main(args + ["--gltf", str(root / "k.glb"), "--gltf-shapes", "arkit"]) == 0
    lines = [ln.split("\t") for ln in (root / "r.tsv").read_text().split("\n") if ln]
    cues = [(float(a), float(b), s) for (a, s), (b, _) in zip(lines, lines[1:])]
    end = float(lines[-1][0])
    (root / "r.json").write_text(json_text(cues, end))
    (root / "r.xml").write_text(xml_text(cues, end))
    (root / "r.dat").write_text(dat_text(cues, 30.0))
    return root


def convert(src, out, *more):
    return main(["convert", str(src), str(out), "-q", "--force", *more])


def dat_args(path):
    return ["--dat-fps", "30"] if str(path).endswith(".dat") else []


def read_pc2(path):
    head = struct.Struct("<12siiffi")
    magic, _, n, _, _, frames = head.unpack_from(path.read_bytes())
    assert magic == b"POINTCACHE2\0"
    return np.frombuffer(path.read_bytes()[head.size:], "<f4").reshape(frames, n, 3)


@pytest.fixture(scope="module")
def lips(rig):
    return rig.face.landmarks["upper_lip_mid"], rig.face.landmarks["lower_lip_mid"]


def opening(path, lips, tmp_path, more=()):
    """The lip gap per frame at 30 fps of a readable take (convert it to a point cache)."""
    pc2 = tmp_path / f"{path.name}.pc2"
    assert convert(path, pc2, "--fps", "30", *more) == 0
    v = read_pc2(pc2)
    return v[:, lips[0], 1] - v[:, lips[1], 1]


def lag(a, b, most: int = 6) -> int:
    """The shift (frames) of ``b`` against ``a`` that correlates them best."""
    n = min(len(a), len(b))
    a, b = (np.asarray(x[:n], float) for x in (a, b))
    a, b = (a - a.mean()) / (a.std() + 1e-12), (b - b.mean()) / (b.std() + 1e-12)
    score = {k: float(np.mean(a[max(0, -k):n - max(0, k)] * b[max(0, k):n - max(0, -k)]))
             for k in range(-most, most + 1)}
    return max(score, key=score.get)


def curves_signal(path, lips, tmp_path):
    """The opening of a write-only output, through its own reader: ARKit curves played, or its mouth parameter."""
    from visemeface.convert.take import weights_take

    name = path.name
    if name.endswith(".anim"):
        curves = unity_clip(path)["m_FloatCurves"]
        names = [c["attribute"].split(".", 1)[1] for c in curves]
        t = np.arange(0, max(k["time"] for c in curves for k in c["curve"]["m_Curve"]) + 1e-6, 1 / FPS)
        w = np.column_stack([np.interp(t, [k["time"] for k in c["curve"]["m_Curve"]],
                                       [k["value"] / 100 for k in c["curve"]["m_Curve"]]) for c in curves])
    elif name.endswith(".tres"):
        _, _, props = godot_resource(path.read_text())
        tracks = sorted({int(k.split("/")[1]) for k in props if k.startswith("tracks/")})
        names = [props[f"tracks/{i}/path"][1].split(":")[1] for i in tracks]
        keys = [props[f"tracks/{i}/keys"].reshape(-1, 3) for i in tracks]
        t, w = keys[0][:, 0], np.column_stack([k[:, 2] for k in keys])
    elif name.endswith(".vrma"):
        from visemeface.convert.gltf import read_glb

        doc, accessor = read_glb(path)
        preset = doc["extensions"]["VRMC_vrm_animation"]["expressions"]["preset"]
        samplers = {c["target"]["node"]: doc["animations"][0]["samplers"][c["sampler"]]
                    for c in doc["animations"][0]["channels"]}
        names = list(preset)
        t = accessor(samplers[preset[names[0]]["node"]]["input"])
        w = np.column_stack([accessor(samplers[preset[n]["node"]]["output"]).reshape(-1, 3)[:, 0] for n in names])
    elif name.endswith(".motion3.json"):
        seg = json.loads(path.read_text())["Curves"][0]["Segments"]
        return np.array(seg[1::3])
    else:
        _, frames, _ = read_vmd(path.read_bytes())
        n = max(f for _, f, _ in frames) + 1
        return sum(np.array([x for m, _, x in frames if m == v]) for v in "あいうえお")[:n]
    take = weights_take(path, names, t, w, "test", fps=FPS)
    out = tmp_path / "played.json"
    from visemeface.export.retarget import write_weights

    write_weights(out, take.vocabulary, names, take.times, take.weights, FPS, force=True)
    return opening(out, lips, tmp_path)


@pytest.mark.slow
@pytest.mark.parametrize("source", SOURCES)
def test_every_pair_keeps_the_timing_within_one_frame(sources, source, lips, tmp_path):
    src = sources / source
    reference = opening(src, lips, tmp_path, dat_args(src))
    assert np.ptp(reference) > 1e-3                                    # the mouth moves
    with_words = source == "a.pgo"
    lags = {}
    for name, to in TARGETS:
        out = tmp_path / name
        args = (["--to", to] if to else []) + dat_args(src) + dat_args(out) + ["--fps", "30"]   # as the reference
        status = convert(src, out, *args)
        if name.endswith((".srt", ".vtt", ".pgo")) and not with_words:
            assert status == 2 and not out.exists(), (source, name)   # the take has no words: refused
            continue
        assert status == 0 and out.exists(), (source, name)
        if name.endswith((".srt", ".vtt", ".pgo")):
            _check_words(src, out)
            continue
        if name.endswith(".html"):
            continue                                                   # the page embeds the glb read below
        readable = not name.endswith((".anim", ".tres", ".motion3.json", ".vmd", ".pc2", ".vrma"))
        if name.endswith(".pc2"):
            v = read_pc2(out)
            signal = v[:, lips[0], 1] - v[:, lips[1], 1]
        else:
            signal = opening(out, lips, tmp_path, dat_args(out)) if readable else curves_signal(out, lips, tmp_path)
        lags[name] = lag(reference, signal)
        if (readable or name.endswith(".pc2")) and not name.endswith(".dat") and not source.endswith(".dat"):
            assert abs(len(signal) - len(reference)) <= 1, (source, name, len(signal), len(reference))
    print(json.dumps({"source": source, "lag_frames": lags}))          # shown with pytest -s
    assert {n: k for n, k in lags.items() if abs(k) > 1} == {}, source


@pytest.mark.slow
def test_an_arkit_take_refitted_onto_oculus_visemes_shuts_the_lips_on_its_bilabials_only(sources, lips, tmp_path):
    # ARKit weights are played with ARKit's meaning (fitted on the reference ARKit rig's pose), a motion no
    # mixture of our visemes makes exactly: fitted onto them, its lips' press outweighed the jaw's opening,
    # and the strongest class was PP over most of the speech (the cue output's lips shut for 1.5 s)
    src, out = sources / "k.csv", tmp_path / "oculus.csv"
    reference = opening(src, lips, tmp_path)
    assert convert(src, out, "--to", "oculus", "--fps", "30") == 0
    got = opening(out, lips, tmp_path)
    assert abs(lag(reference, got)) <= 1
    n = min(len(reference), len(got))
    assert np.corrcoef(reference[:n], got[:n])[0, 1] >= 0.8
    weights = pd.read_csv(out)
    pp = np.flatnonzero(weights.iloc[:, 2:].to_numpy().argmax(axis=1) == list(weights.columns[2:]).index("PP"))
    shut = np.flatnonzero(reference <= 0.0)
    assert len(pp) and all(np.abs(shut - k).min() <= 1 for k in pp), (pp, shut)


def _check_words(src, out):
    from visemeface.convert import read_take

    words = read_take(src).utterance.words
    if out.suffix == ".pgo":
        _, fps, _, back = read_pgo(out.read_text())
        got = [(a / fps, w) for *_, w, a, _, _ in back]
    else:
        import re

        stamps = re.findall(r"(\d\d):(\d\d):(\d\d)[,.](\d{3}) -->", out.read_text())
        got = [(3600 * int(h) + 60 * int(m) + int(s) + int(ms) / 1000, None) for h, m, s, ms in stamps]
        words = words.iloc[[0]]
    for (t, w), (_, row) in zip(got, words.iterrows()):
        assert abs(t - row["start"]) <= 1 / 24 + 1e-6 and w in (None, row["word"])


def test_mouth_cues_round_trip_exactly_through_every_cue_format(sources, tmp_path):
    a = sources / "r.tsv"
    for name in ("b.json", "c.xml", "d.pgo", "e.tsv"):
        b = tmp_path / name
        assert convert(a, b, *(["--to", "rhubarb"] if name.endswith(".json") else [])) == (0 if name != "d.pgo" else 2)
        if b.exists():
            a = b
    assert (tmp_path / "e.tsv").read_text() == (sources / "r.tsv").read_text()
    assert convert(sources / "r.dat", tmp_path / "f.dat", "--dat-fps", "30") == 0
    assert (tmp_path / "f.dat").read_text() == (sources / "r.dat").read_text()


def test_arkit_weights_survive_live_link_and_audio2face(sources, tmp_path):
    from visemeface.convert import read_take

    assert convert(sources / "k.csv", tmp_path / "ll.csv", "--to", "livelink") == 0
    assert convert(tmp_path / "ll.csv", tmp_path / "a2f.json", "--to", "audio2face") == 0
    first, back = read_take(sources / "k.csv"), read_take(tmp_path / "a2f.json")
    assert back.names == first.names and back.fps == 30 and len(back.times) == len(first.times)
    k = first.names.index("jawOpen")
    assert np.abs(back.weights - first.weights).max() <= 2e-5    # passed through (re-sampled from 6-decimal times)
    assert first.weights[:, k].max() > 0.05


def test_a_papagayo_project_gives_captions_of_its_words(sources, tmp_path):
    srt = pytest.importorskip("srt")
    assert convert(sources / "a.pgo", tmp_path / "a.srt") == 0
    assert " ".join(s.content for s in srt.parse((tmp_path / "a.srt").read_text())) == TEXT


BAD = {"x.tsv": "0.00\tX\n0.30\tQ\n0.50\tX\n", "x.json": '{"mouthCues": [{"start": 0}]}', "y.json": "[1, 2]",
       "x.xml": "<other/>", "x.dat": "Switch\n1 A\n", "x.pgo": "lipsync version 1\nsnd\nx\n",
       "x.csv": "frame,time,notAShape\n0,0.0,0.5\n", "y.csv": "frame,time,jawOpen\n0,0.0,nan\n",
       "z.csv": "Timecode,BlendShapeCount,JawOpen\n00:00:00:bad,1,0.5\n", "x.glb": "not a glb",
       "x.wav": "RIFF", "x.pc2": "POINTCACHE2"}


@pytest.mark.parametrize("name", sorted(BAD))
def test_a_bad_take_is_one_line_exit_2_and_nothing_written(tmp_path, capsys, name):
    (tmp_path / name).write_text(BAD[name])
    assert convert(tmp_path / name, tmp_path / "out.anim") == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("visemeface: error:"), err
    assert sorted(p.name for p in tmp_path.iterdir()) == [name]


@pytest.mark.parametrize("out,more,says", [("o.csv", [], "say which with --to"), ("o.png", [], "convert writes"),
                                          ("o.anim", ["--tres-godot", "3"], "setting of the godot output"),
                                          ("r.tsv", [], "overwrite")])
def test_a_bad_output_is_refused_before_reading(sources, tmp_path, capsys, out, more, says):
    target = sources / "r.tsv" if out == "r.tsv" else tmp_path / out
    assert main(["convert", str(sources / "r.tsv"), str(target), "-q", *more]) == 2
    assert says in capsys.readouterr().err
    assert not (tmp_path / out).exists()


def test_a_suffix_several_formats_write_is_the_inputs_own_format(sources, tmp_path):
    # .json is Rhubarb's, ARKit's, VRM's, Oculus's and Audio2Face's: a Rhubarb take stays Rhubarb, an
    # ARKit take ARKit; a take of neither needs --to
    assert convert(sources / "r.tsv", tmp_path / "r.json") == 0
    assert "mouthCues" in json.loads((tmp_path / "r.json").read_text())
    assert convert(sources / "k.csv", tmp_path / "k.json") == 0
    assert json.loads((tmp_path / "k.json").read_text())["vocabulary"] == "arkit"
    assert convert(sources / "tr.csv", tmp_path / "t.json") == 2 and not (tmp_path / "t.json").exists()
