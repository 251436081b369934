"""Viseme/expression tables and expressive blending (visemeface.postures.library)."""

from __future__ import annotations

import math

import numpy as np
import pandas as pd
import pytest

from visemeface.errors import InputError
from visemeface.postures import library as lib
from visemeface.postures.phonemes import CLASSES, DECTALK

# ----------------------------------------------------------------------------- targets


@pytest.fixture(scope="module")
def targets():
    return lib.load_targets()


def test_targets_cover_the_56_dectalk_postures_in_order(targets):
    assert targets.index.tolist() == list(DECTALK)
    assert len(targets) == 56
    assert targets["index"].tolist() == list(range(56))
    assert targets["notes"].str.len().min() > 10


def test_targets_opening_is_upper_raise_plus_lower_drop(targets):
    t = targets
    np.testing.assert_allclose(t.opening_height, t.upper_lip_raise + t.lower_lip_drop, atol=1e-12)


def test_targets_follow_articulatory_phonetics(targets):
    t = targets
    # bilabials closed; silence neutral
    assert (t.loc[["p", "b", "m"], "opening_height"] <= 0).all()  # closed, pressed
    assert (t.loc["_", list(lib.TARGET_DIMENSIONS)] == 0).all()
    # labiodentals: lower lip drawn back onto the upper incisors' edge (which lies 2.5 mm below
    # the rest seam, so the lip's edge goes a little down, not up), upper lip lifted
    assert (t.loc[["f", "v"], "protrusion"] < -0.05).all()
    assert (t.loc[["f", "v"], "upper_lip_raise"] > 0).all()
    # rounded vowels narrower and more protruded than every spread vowel
    rounded, spread = t.loc[["ow", "uw", "w"]], t.loc[["iy", "ih", "ae"]]
    assert rounded.mouth_width.max() < spread.mouth_width.min()
    assert rounded.protrusion.min() > spread.protrusion.max()
    # open vowels have the lowest jaw
    assert t.loc[["aa", "ah", "ae"], "lower_lip_drop"].min() > t.loc[["iy", "uw", "s", "t"], "lower_lip_drop"].max()
    # w is the tightest rounding
    assert t.mouth_width.idxmin() == "w"


def _write(tmp_path, text, name="t.csv"):
    p = tmp_path / name
    p.write_text(text)
    return p


def test_targets_errors_name_file_line_and_column(tmp_path):
    src = lib.targets_file().read_text().splitlines()
    bad = src[:]
    bad[6] = bad[6].replace("0.25", "abc", 1)  # ae's opening height
    p = _write(tmp_path, "\n".join(bad))
    with pytest.raises(InputError, match=r"t\.csv:7: column 'opening_height': 'abc' is not a number"):
        lib.load_targets(p)
    bad = src[:]
    bad[0] = bad[0].replace("mouth_width", "mouth_widht")
    with pytest.raises(InputError, match="did you mean: mouth_width"):
        lib.load_targets(_write(tmp_path, "\n".join(bad)))
    with pytest.raises(InputError, match="missing: jh"):
        lib.load_targets(_write(tmp_path, "\n".join(src[:-1])))
    with pytest.raises(InputError, match="file not found"):
        lib.load_targets(tmp_path / "nope.csv")


# ----------------------------------------------------------------------------- tables on the rig


@pytest.fixture(scope="module")
def rig():
    from visemeface.muscles.rig import default_rig

    return default_rig()


@pytest.fixture(scope="module")
def visemes(rig):
    return lib.load_visemes(rig=rig)


@pytest.fixture(scope="module")
def expressions(rig):
    return lib.load_expressions(rig=rig)


def test_visemes_table_is_56_postures_of_the_12_speech_functions(rig, visemes):
    assert visemes.index.tolist() == list(DECTALK)
    assert visemes.columns.tolist() == list(rig.names)
    # the face's muscles beyond the twelve stay 0; the tongue's and the lip-shaping functions
    # carry data/visemes/articulation.csv
    held = [c for c in rig.names if c.startswith("tongue_") or c in ("lip_rounding", "lower_lip_tuck", "corner_seal")]
    others = [c for c in rig.names if c not in lib.SPEECH_FUNCTIONS and c not in held]
    assert (visemes[others] == 0).all().all()
    assert len(lib.SPEECH_FUNCTIONS) == 12 and len(held) == 8
    assert visemes.loc["th", "tongue_protrusion"] == 1 and visemes.loc["k", "tongue_dorsum_raise"] == 1
    lo, hi = rig.ranges[:, 0], rig.ranges[:, 1]
    assert ((visemes.to_numpy() >= lo) & (visemes.to_numpy() <= hi)).all()
    assert (visemes.loc["_"] == 0).all()
    # left/right symmetric
    for f in lib.SPEECH_FUNCTIONS:
        if f.endswith("_left"):
            np.testing.assert_array_equal(visemes[f], visemes[f.replace("_left", "_right")])


def test_visemes_reach_their_lip_targets(rig, visemes, targets):
    """The fitted activations reproduce the lip-shape targets on the rig (within 0.1 mouth width)."""
    from visemeface.muscles.measure import LipGauge

    gauge = LipGauge(rig.face)
    for sym in ["p", "f", "ow", "w", "ae", "aa", "sh", "r", "ao", "iy"]:
        got = gauge.changes(rig.pose(visemes.loc[sym].to_numpy()))
        for k in lib.TARGET_DIMENSIONS:
            assert abs(got[k] - targets.loc[sym, k]) < 0.1, (sym, k, got[k], targets.loc[sym, k])
    closed = gauge.measure(rig.pose(visemes.loc["m"].to_numpy()))
    assert closed["lips_closed"]


def test_expressions_seven_emotions_facs_and_one_sided_contempt(rig, expressions):
    assert set(lib.EMOTIONS) <= set(expressions.index)
    assert expressions.columns.tolist() == list(rig.names)
    info = lib.expression_info()
    assert info.loc["happiness", "action_units"].count("AU12") == 1
    assert expressions.loc["happiness", "zygomatic_major_left"] > 0.5
    assert expressions.loc["surprise", "jaw"] > 0 and expressions.loc["sadness", "depressor_anguli_oris_left"] > 0
    # the lids: surprise widens (AU5), happiness narrows from below (AU6), anger tightens (AU7)
    assert expressions.loc["surprise", "upper_lid_raise_left"] > 0.5
    assert expressions.loc["happiness", "lower_lid_raise_left"] > 0.5
    assert expressions.loc["anger", "lower_lid_raise_left"] > 0.5
    for e in expressions.index:
        row = expressions.loc[e]
        left = row[[c for c in row.index if c.endswith("_left")]].to_numpy()
        right = row[[c.replace("_left", "_right") for c in row.index if c.endswith("_left")]].to_numpy()
        if e == "contempt":
            assert left.sum() > 0 and right.sum() == 0
        else:
            np.testing.assert_array_equal(left, right)


def _table_text(path):
    return path.read_text().splitlines()


def test_activation_table_errors_name_file_line_column(tmp_path, rig):
    src = _table_text(lib.expressions_file())
    bad = src[:]
    bad[0] = bad[0].replace("zygomatic_major_left", "zygomatic_majr_left", 1)
    with pytest.raises(InputError, match=r"e\.csv:1: column 'zygomatic_majr_left' is not a function of the rig "
                                         r"\(did you mean: zygomatic_major_left"):
        lib.load_expressions(_write(tmp_path, "\n".join(bad), "e.csv"), rig=rig)
    bad = src[:]
    bad[2] = bad[2].replace("sadness,0,", "sadness,7,", 1)
    with pytest.raises(InputError, match=r"e\.csv:3: column 'zygomatic_major_left': 7 is outside the range \[0, 1\]"):
        lib.load_expressions(_write(tmp_path, "\n".join(bad), "e.csv"), rig=rig)
    bad = src[:]
    bad[2] = bad[2].replace("sadness,0,", "sadness,nan,", 1)
    with pytest.raises(InputError, match=r"e\.csv:3: .*not a finite number"):
        lib.load_expressions(_write(tmp_path, "\n".join(bad), "e.csv"), rig=rig)
    with pytest.raises(InputError, match="emotions missing: disgust"):
        lib.load_expressions(_write(tmp_path, "\n".join(src[:-1]), "e.csv"), rig=rig)
    vis = _table_text(lib.visemes_file())
    with pytest.raises(InputError, match=r"v\.csv:58: symbol 'jh' appears twice"):
        lib.load_visemes(_write(tmp_path, "\n".join(vis + vis[-1:]), "v.csv"), rig=rig)
    with pytest.raises(InputError, match=r"postures missing: jh"):
        lib.load_visemes(_write(tmp_path, "\n".join(vis[:-1]), "v.csv"), rig=rig)


# ----------------------------------------------------------------------------- blending


def test_blend_is_weighted_sum_then_clamp(rig, visemes, expressions):
    lo, hi = rig.ranges[:, 0], rig.ranges[:, 1]
    v, e1, e2 = visemes.loc["ah"].to_numpy(), expressions.loc["happiness"].to_numpy(), expressions.loc["surprise"].to_numpy()
    a = lib.blend("ah", {"happiness": 0.5, "surprise": 0.25}, w_viseme=0.8, rig=rig)
    assert a.index.tolist() == list(rig.names)
    np.testing.assert_allclose(a.to_numpy(), np.clip(0.8 * v + 0.5 * e1 + 0.25 * e2, lo, hi))
    # the pure expression: silence viseme carries no activation
    np.testing.assert_allclose(lib.blend("_", {"anger": 1.0}, rig=rig).to_numpy(), expressions.loc["anger"].to_numpy())
    # viseme alone, default weight
    np.testing.assert_allclose(lib.blend("ow", rig=rig).to_numpy(), visemes.loc["ow"].to_numpy())
    # weights 0 leave the neutral face
    assert (lib.blend("aa", {"fear": 0}, w_viseme=0, rig=rig) == 0).all()


def test_blend_clamps_to_the_rig_ranges(rig, visemes):
    hi = rig.ranges[:, 1]
    a = lib.blend("ah", {"happiness": 3.0}, rig=rig)
    j = rig.names.index("zygomatic_major_left")
    assert a.iloc[j] == hi[j]  # 3·1.0 summed with the viseme, clamped to the top of the range
    assert (a.to_numpy() <= hi).all() and (a.to_numpy() >= rig.ranges[:, 0]).all()
    big = lib.blend("aa", {}, w_viseme=10, rig=rig)
    np.testing.assert_allclose(big.to_numpy(), np.clip(10 * visemes.loc["aa"].to_numpy(), rig.ranges[:, 0], hi))


@pytest.mark.parametrize("call, message", [
    (lambda r: lib.blend("ahh", {}, rig=r), r"unknown viseme 'ahh' \(did you mean: ah"),
    (lambda r: lib.blend("ah", {"hapiness": 1}, rig=r), r"unknown emotion 'hapiness' \(did you mean: happiness"),
    (lambda r: lib.blend("ah", {"happiness": -0.1}, rig=r), "weight of 'happiness' must not be negative"),
    (lambda r: lib.blend("ah", {"happiness": float("nan")}, rig=r), "weight of 'happiness' must be finite"),
    (lambda r: lib.blend("ah", {"happiness": "x"}, rig=r), "must be a number"),
    (lambda r: lib.blend("ah", {}, w_viseme=-1, rig=r), "weight of 'viseme' must not be negative"),
    (lambda r: lib.blend("ah", {}, w_viseme=math.inf, rig=r), "must be finite"),
])
def test_blend_bad_input(rig, call, message):
    with pytest.raises(InputError, match=message):
        call(rig)


def test_posed_vertices_is_the_rig_pose_of_the_blend(rig):
    v = lib.posed_vertices(rig, "ah", {"happiness": 0.6})
    np.testing.assert_allclose(v, rig.pose(lib.blend("ah", {"happiness": 0.6}, rig=rig).to_numpy()))
    assert v.shape == rig.rest.shape
    # seed 002 Fig. 6: the happy /ah/ raises the corners above the plain /ah/ by as much as the smile
    # alone raises them at rest (the visemes leave zygomatic major to the emotions, so nothing is clamped)
    from visemeface.muscles.measure import LipGauge

    g = LipGauge(rig.face)

    def corners(viseme, emotions):
        return g.changes(lib.posed_vertices(rig, viseme, emotions))["corner_height"]

    smile = corners("_", {"happiness": 1.0})
    assert smile > 0.05
    assert corners("ah", {"happiness": 1.0}) - corners("ah", {}) == pytest.approx(smile, rel=0.05)


def test_parse_weights():
    assert lib.parse_weights(["happiness=0.6", "fear"]) == {"happiness": 0.6, "fear": 1.0}
    assert lib.parse_weights("anger=0.2, sadness=0.3") == {"anger": 0.2, "sadness": 0.3}
    assert lib.parse_weights(None) == {}
    # a mapping gives its weights, not its names at weight 1 (a dict of 0.3 was read as 1)
    assert lib.parse_weights({"happiness": 0.3}) == {"happiness": 0.3}
    assert lib.parse_weights(pd.Series({"anger": 0.5})) == {"anger": 0.5}
    with pytest.raises(InputError, match="negative"):
        lib.parse_weights({"anger": -1})
    # blend takes every form: a dict, a Series (it raised pandas' "ambiguous"), a list, a string
    smile = [float(lib.blend("ah", e)["zygomatic_major_left"])
             for e in ({"happiness": 0.6}, pd.Series({"happiness": 0.6}), ["happiness=0.6"], "happiness=0.6")]
    assert smile == [pytest.approx(0.6)] * 4
    for bad, msg in [("anger=-1", "negative"), ("anger=nan", "finite"), ("=2", "NAME=WEIGHT"), ("anger=x", "number")]:
        with pytest.raises(InputError, match=msg):
            lib.parse_weights(bad)


def test_viseme_table_is_up_to_date_with_targets_and_rig(rig, visemes, load_script):
    """visemes.csv poses the lips as well as a fresh fit of targets.csv on the current rig.

    Fails when targets.csv or the rig changed without rerunning
    ``PYTHONPATH=src python scripts/fit_visemes.py --force``.
    """
    from visemeface.muscles.measure import LipGauge

    fv = load_script("fit_visemes")
    rows, report = fv.fit_table(rig)
    gauge = LipGauge(rig.face)
    stale = []
    for row, rep in zip(rows, report):
        got = gauge.changes(rig.pose(visemes.loc[row["symbol"]].to_numpy()))
        worst = max(abs(got[k] - rep["achieved"][k]) for k in lib.TARGET_DIMENSIONS)
        if worst > 0.01:
            stale.append(f"{row['symbol']} ({worst:.3f})")
    assert not stale, "visemes.csv is stale, rerun scripts/fit_visemes.py --force: " + ", ".join(stale)


def test_keep_contact_closes_a_surprised_bilabial_with_the_jaw_only(rig):
    from visemeface.muscles.measure import LipGauge

    g = LipGauge(rig.face)
    plain = lib.blend("m", {"surprise": 1.0}, rig=rig)
    kept = lib.blend("m", {"surprise": 1.0}, rig=rig, keep_contact=True)
    assert not g.measure(rig.pose(plain.to_numpy()))["lips_closed"]  # seed 002's linear blend opens the lips
    assert g.measure(rig.pose(kept.to_numpy()))["lips_closed"]
    assert g.changes(rig.pose(kept.to_numpy()))["opening_height"] <= g.changes(lib.posed_vertices(rig, "m"))["opening_height"] + 1e-3
    changed = plain.index[plain.to_numpy() != kept.to_numpy()].tolist()
    assert changed == ["jaw"] and kept["jaw"] < plain["jaw"]
    # postures without lip contact, or without an emotion, are the plain blend
    pd.testing.assert_series_equal(lib.blend("aa", {"surprise": 1.0}, rig=rig, keep_contact=True),
                                   lib.blend("aa", {"surprise": 1.0}, rig=rig))
    pd.testing.assert_series_equal(lib.blend("p", {}, rig=rig, keep_contact=True), lib.blend("p", {}, rig=rig))
    np.testing.assert_allclose(lib.posed_vertices(rig, "m", {"surprise": 1.0}, keep_contact=True),
                               rig.pose(kept.to_numpy()))


def test_empty_table_file_is_a_one_line_error(tmp_path):
    p = tmp_path / "empty.csv"
    p.write_bytes(b"")
    with pytest.raises(InputError, match="not a readable CSV"):
        lib.load_visemes(p)


def test_viseme_names_are_case_insensitive_and_suggested():
    assert lib.blend("AA").equals(lib.blend("aa"))
    with pytest.raises(InputError, match=r"unknown viseme 'AX2' \(did you mean: ax"):
        lib.blend("AX2")


def test_blend_reads_emotions_as_the_command_line_does_and_any_case():
    a = lib.blend("ah", {"happiness": 0.6})
    assert lib.blend("AH", "Happiness=0.6").equals(a) and lib.blend("ah", {"HAPPINESS": 0.6}).equals(a)


def test_a_track_given_to_pose_says_which_call_takes_a_track():
    from visemeface.muscles.rig import default_rig

    rig = default_rig()
    track = pd.DataFrame({"jaw": [0.1, 0.2]}, index=[0.0, 0.1])
    with pytest.raises(InputError, match=r"use rig.poses\(track\)"):
        rig.pose(track)
    assert rig.poses(track).shape == (2, rig.face.n_vertices, 3)


def test_activation_track_wants_the_viseme_table_not_its_values():
    from visemeface.speech.timeline import activation_track

    seg = pd.DataFrame({"start": [0.0], "end": [0.2], "phoneme": ["_"]})
    with pytest.raises(InputError, match="visemes must be a DataFrame"):
        activation_track(seg, lib.load_visemes().values)
