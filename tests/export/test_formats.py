"""Rhubarb, Live Link and the weight files: the formats as their documentation shows them."""

import csv
import json
import xml.etree.ElementTree as ET

import numpy as np
import pandas as pd
import pytest

from visemeface.cli import main
from visemeface.export.retarget import live_link_timecode
from visemeface.export.rhubarb import dat_text, json_text, tsv_text, xml_text
from visemeface.retarget.classes import mouth_cues

from test_retarget import ARKIT

#: Rhubarb's README: a person saying 'Hi' (TSV, XML and JSON of the same recording).
HI = [(0.00, 0.05, "X"), (0.05, 0.27, "D"), (0.27, 0.31, "C"), (0.31, 0.43, "B"), (0.43, 0.47, "X")]
HI_SOUND = "C:\\Users\\Daniel\\Desktop\\av\\hi\\hi.wav"
HI_TSV = "0.00\tX\n0.05\tD\n0.27\tC\n0.31\tB\n0.43\tX\n0.47\tX\n"
HI_XML = """<?xml version="1.0" encoding="utf-8"?>
<rhubarbResult>
  <metadata>
    <soundFile>C:\\Users\\Daniel\\Desktop\\av\\hi\\hi.wav</soundFile>
    <duration>0.47</duration>
  </metadata>
  <mouthCues>
    <mouthCue start="0.00" end="0.05">X</mouthCue>
    <mouthCue start="0.05" end="0.27">D</mouthCue>
    <mouthCue start="0.27" end="0.31">C</mouthCue>
    <mouthCue start="0.31" end="0.43">B</mouthCue>
    <mouthCue start="0.43" end="0.47">X</mouthCue>
  </mouthCues>
</rhubarbResult>
"""
HI_JSON = """{
  "metadata": {
    "soundFile": "C:\\\\Users\\\\Daniel\\\\Desktop\\\\av\\\\hi\\\\hi.wav",
    "duration": 0.47
  },
  "mouthCues": [
    { "start": 0.00, "end": 0.05, "value": "X" },
    { "start": 0.05, "end": 0.27, "value": "D" },
    { "start": 0.27, "end": 0.31, "value": "C" },
    { "start": 0.31, "end": 0.43, "value": "B" },
    { "start": 0.43, "end": 0.47, "value": "X" }
  ]
}
"""


def test_rhubarb_writers_reproduce_rhubarbs_documented_example():
    assert tsv_text(HI, 0.47) == HI_TSV
    assert xml_text(HI, 0.47, HI_SOUND) == HI_XML
    assert json_text(HI, 0.47, HI_SOUND) == HI_JSON
    doc = json.loads(json_text(HI, 0.47, HI_SOUND))
    assert [(c["start"], c["end"], c["value"]) for c in doc["mouthCues"]] == HI
    root = ET.fromstring(xml_text(HI, 0.47, HI_SOUND))
    assert [(float(c.get("start")), float(c.get("end")), c.text) for c in root.iter("mouthCue")] == HI


def test_dat_frames_count_from_one_at_the_dat_rate():
    assert dat_text(HI) == "MohoSwitch1\n1 X\n2 D\n7 C\n8 B\n11 X\n"        # 1 + int(24 t)
    assert dat_text(HI, fps=100, preston_blair=True) == "MohoSwitch1\n1 rest\n6 AI\n28 E\n32 etc\n44 rest\n"
    # two cues on one frame: the later one is shown
    assert dat_text([(0.0, 0.01, "X"), (0.01, 0.5, "A")], fps=24) == "MohoSwitch1\n1 A\n"


def test_mouth_cues_merge_neighbours_and_cover_the_utterance():
    seg = pd.DataFrame({"start": [0.0, 0.1, 0.2, 0.255, 0.4], "end": [0.1, 0.2, 0.255, 0.4, 0.6],
                        "phoneme": ["_", "m", "b", "aa", "_"]})
    assert mouth_cues(seg) == [(0.0, 0.1, "X"), (0.1, 0.25, "A"), (0.25, 0.4, "D"), (0.4, 0.6, "X")]


def test_live_link_timecode():
    assert live_link_timecode(0.0, 30) == "00:00:00:00.000"
    assert live_link_timecode(1.5, 30) == "00:00:01:15.000"
    assert live_link_timecode(3661.25, 24) == "01:01:01:06.000"
    assert live_link_timecode(0.01, 60) == "00:00:00:00.600"


def test_live_link_csv_has_its_exact_header_and_a_row_a_frame(exported):
    with open(exported / "ll.csv", newline="") as fh:
        rows = list(csv.reader(fh))
    head = rows[0]
    rot = ["HeadYaw", "HeadPitch", "HeadRoll", "LeftEyeYaw", "LeftEyePitch", "LeftEyeRoll",
           "RightEyeYaw", "RightEyePitch", "RightEyeRoll"]
    assert head == ["Timecode", "BlendShapeCount"] + [n[0].upper() + n[1:] for n in ARKIT] + rot
    assert head[2:5] == ["EyeBlinkLeft", "EyeLookDownLeft", "EyeLookInLeft"]
    frames = len(pd.read_csv(exported / "t.csv", comment="#"))
    assert len(rows) - 1 == frames
    assert rows[1][0] == "00:00:00:00.000" and rows[31][0] == "00:00:01:00.000"
    for r in rows[1:]:
        assert r[1] == "61" and all(0.0 <= float(x) <= 1.0 for x in r[2:54]) and set(r[57:]) == {"0"}
    # the head moves with the speech (normalised: 1 = 90 degrees), within natural ranges; the eyes' columns stay 0
    head_deg = np.array([[float(x) for x in r[54:57]] for r in rows[1:]]) * 90
    assert np.abs(head_deg).max(axis=0).tolist() <= [4.0, 5.0, 3.0] and np.abs(head_deg[:, 1]).max() > 0.5
    jaw = [float(r[head.index("JawOpen")]) for r in rows[1:]]
    assert max(jaw) > 0.1     # "white" opens the jaw (ARKit's jawOpen 1 is fully open: 33 mm on the ICT rig)


def test_weight_files_parse_back(exported):
    doc = json.loads((exported / "a.json").read_text())
    assert doc["names"] == ARKIT and doc["vocabulary"] == "arkit" and doc["fps"] == 30
    assert len(doc["weights"]) == len(doc["time"]) == len(pd.read_csv(exported / "t.csv", comment="#"))
    oc = pd.read_csv(exported / "o.csv")
    assert list(oc.columns[2:]) == "sil PP FF TH DD kk CH SS nn RR aa E ih oh ou".split()
    assert (oc.iloc[:, 2:].sum(axis=1) - 1).abs().max() < 5e-3
    vrm = pd.read_csv(exported / "v.csv")
    assert {"aa", "ih", "ou", "ee", "oh", "blink", "happy", "surprised"} <= set(vrm.columns)
    assert vrm["blink"].between(0, 1).all() and (vrm["blink"] < 0.05).mean() > 0.8   # blinks are brief
    assert vrm[["aa", "oh", "ou"]].to_numpy().max() > 0.3


def test_oculus_visemes_say_what_is_spoken_whatever_the_face_does(tmp_path):
    """Meta's visemes are the speech's classes, with a character's expressions driven beside them: fitted to
    the whole face, a smile at rest read as FF 0.81. From speak they are the speech's own pose's."""
    (tmp_path / "t.txt").write_text("0.00 0.30 _\n0.30 0.50 aa\n0.50 0.80 _\n")
    for name, extra in (("plain", []), ("happy", ["--emotion", "happiness=1"])):
        assert main(["speak", str(tmp_path / "t.txt"), "--no-video", "-q", "--oculus", str(tmp_path / f"{name}.csv"),
                     *extra]) == 0
    plain, happy = (pd.read_csv(tmp_path / f"{n}.csv") for n in ("plain", "happy"))
    pd.testing.assert_frame_equal(plain, happy)
    assert happy.loc[0, "sil"] > 0.9 and happy.loc[0, "FF"] == 0
    assert happy.loc[12, "aa"] == happy.iloc[12, 2:].max() > 0.7           # 0.40 s: the /aa/


def test_rhubarb_json_of_a_run(exported):
    doc = json.loads((exported / "r.json").read_text())
    cues = doc["mouthCues"]
    assert cues[0]["start"] == 0 and cues[-1]["end"] == doc["metadata"]["duration"]
    assert all(a["end"] == b["start"] for a, b in zip(cues, cues[1:]))
    assert all(a["value"] != b["value"] for a, b in zip(cues, cues[1:]))
    assert {c["value"] for c in cues} <= set("ABCDEFGHX") and doc["metadata"]["soundFile"].endswith("a.wav")


@pytest.mark.parametrize("extra,message", [
    (["--rhubarb", "r.txt"], "must end in .tsv or .json or .xml or .dat"),
    (["--rhubarb", "r.dat", "--dat-fps", "0"], "--dat-fps: must be a frame rate"),
    (["--livelink", "l.json"], "must end in .csv"),
    (["--gltf", "g.glb", "--gltf-shapes", "arkitt"], "invalid choice"),
])
def test_bad_export_options_are_refused_before_work(tmp_path, capsys, monkeypatch, extra, message):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "s.txt").write_text("hi\n")
    assert main(["speak", "s.txt", "--no-video", "-q"] + extra) == 2
    err = capsys.readouterr().err
    assert message in err and err.count("\n") == 1
    assert sorted(p.name for p in tmp_path.iterdir()) == ["s.txt"]


def test_library_misuse_is_refused_before_anything_is_written(tmp_path):
    """From Python as from the command line: a misspelt sink setting, a measures output without physics,
    an emotion weight past 1 given as a dict, text that is not a str."""
    from visemeface.animate import animate
    from visemeface.errors import InputError
    from visemeface.export import SINKS
    from visemeface.speech.g2p import text_to_utterance

    with pytest.raises(InputError, match="no setting 'shapes'.*did you mean: gltf_shapes"):
        SINKS["gltf"](tmp_path / "a.glb", shapes="arkit")
    utt = text_to_utterance("mama")
    with pytest.raises(InputError, match="measures writes a simulation's figures"):
        animate(utt, [SINKS["measures"](tmp_path / "m.csv")])
    with pytest.raises(InputError, match="not in 0..1"):
        animate(utt, [SINKS["track"](tmp_path / "t.csv")], emotions={"happiness": 5})
    with pytest.raises(InputError, match="must be a str"):
        text_to_utterance(None)
    with pytest.raises(InputError, match="animate takes an Utterance .* got str"):   # text, not an Utterance
        animate("mama", [SINKS["track"](tmp_path / "t.csv")])
    assert list(tmp_path.iterdir()) == []
    from visemeface.retarget.classes import mouth_cues
    with pytest.raises(InputError, match="mouth cues need DECtalk phones; 'AA1' is none .did you mean: aa"):
        mouth_cues(pd.DataFrame({"start": [0.0], "end": [0.2], "phoneme": ["AA1"]}))    # was a KeyError
    # bare timed Segments are an utterance too
    animate(utt.segments, [SINKS["track"](tmp_path / "t.csv")], show_progress=False)
    assert (tmp_path / "t.csv").is_file()
