"""Lip and tongue shapes of the viseme table on the default rig (issue 13's acceptance figures).

Where the numbers come from: the ratios and distances are the issue's acceptance figures;
the rig's lip-shaping functions (lip_rounding, corner_seal, lower_lip_tuck) and the
targets of uw, w, f, v were set so the default face reaches them (docs: data/rig/default.toml,
data/visemes/articulation.csv).
"""

import numpy as np
import pytest

from visemeface.muscles.measure import inner_opening, lip_dimensions
from visemeface.postures.library import posed_vertices


@pytest.fixture(scope="module")
def shapes(rig):
    out = {}
    for v in ("uw", "w", "aa", "f", "v", "th", "dh", "m", "iy"):
        p = posed_vertices(rig, v, {})
        out[v] = (p, inner_opening(rig.face, p), lip_dimensions(rig.face, p))
    return out


@pytest.mark.parametrize("v", ["uw", "w"])
def test_rounded_visemes_are_a_small_protruded_oval(shapes, v):
    _, o, d = shapes[v]
    assert 0.003 < o["height"] and o["aspect"] <= 2.5        # was about 10: a corner-to-corner slit
    assert d["protrusion"] >= 0.004


def test_open_vowel_is_an_oval_not_a_slit_to_the_corners(shapes):
    _, o, d = shapes["aa"]
    assert o["width"] <= 0.8 * d["mouth_width"]
    assert o["height"] > 0.012


@pytest.mark.parametrize("v", ["f", "v"])
def test_labiodentals_put_the_lower_lip_on_the_upper_incisors(rig, shapes, v):
    # the incisors rest on the lower lip: its top covers their edge (above it by at most the edge's depth
    # below the rest seam, 2.5 mm) and lies just in front of it (touching: within 1 mm), so of the teeth
    # only the upper incisors show, above the lower lip
    p = shapes[v][0]
    lm = rig.face.landmarks
    up = p[lm["lower_lip_mid"], 1] - p[lm["upper_incisor_edge"], 1]
    ahead = p[lm["lower_lip_mid"], 2] - p[lm["upper_incisor_edge"], 2]
    assert 0.0005 <= up <= 0.0025 and 0.0 <= ahead <= 0.001, (up, ahead)


@pytest.mark.parametrize("v", ["th", "dh"])
def test_dentals_put_the_tongue_tip_in_front_of_the_lower_incisors(rig, shapes, v):
    p = shapes[v][0]
    lm = rig.face.landmarks
    assert p[lm["tongue_tip"], 2] > p[lm["lower_incisor_edge"], 2] + 0.002


def test_closed_and_spread_shapes(shapes):
    assert shapes["m"][1]["width"] == 0                       # bilabial: closed all along
    assert shapes["iy"][1]["aspect"] > 5                      # spread: a long thin opening
