"""Retargeting vocabularies: the recipes as data, the bounded least-squares fit, the issue's poses."""

import numpy as np
import pytest

from visemeface.errors import InputError
from visemeface.postures.library import PostureLibrary
from visemeface.postures.phonemes import DECTALK
from visemeface.retarget import OCULUS, ShapeFit, moving_vertices, vocabulary
from visemeface.retarget.recipes import RecipeResolver, parse_recipe, phoneme_classes, side_weights

#: ARKit's 52 blendshapes in Live Link Face's column order.
ARKIT = ("eyeBlinkLeft eyeLookDownLeft eyeLookInLeft eyeLookOutLeft eyeLookUpLeft eyeSquintLeft eyeWideLeft "
         "eyeBlinkRight eyeLookDownRight eyeLookInRight eyeLookOutRight eyeLookUpRight eyeSquintRight eyeWideRight "
         "jawForward jawRight jawLeft jawOpen mouthClose mouthFunnel mouthPucker mouthRight mouthLeft "
         "mouthSmileLeft mouthSmileRight mouthFrownLeft mouthFrownRight mouthDimpleLeft mouthDimpleRight "
         "mouthStretchLeft mouthStretchRight mouthRollLower mouthRollUpper mouthShrugLower mouthShrugUpper "
         "mouthPressLeft mouthPressRight mouthLowerDownLeft mouthLowerDownRight mouthUpperUpLeft mouthUpperUpRight "
         "browDownLeft browDownRight browInnerUp browOuterUpLeft browOuterUpRight cheekPuff cheekSquintLeft "
         "cheekSquintRight noseSneerLeft noseSneerRight tongueOut").split()


@pytest.fixture(scope="module")
def lib(rig):
    return PostureLibrary(rig)


@pytest.fixture(scope="module")
def fits(rig, lib):
    return {name: ShapeFit(vocabulary(name, rig, lib), moving_vertices(rig)) for name in ("arkit", "vrm", "oculus")}


def weights_of(fit, rig, a):
    w, r = fit.frame(rig.displacement(np.asarray(a, dtype=float)))
    return dict(zip(fit.vocab.names, w)), r


def test_vocabularies_hold_the_clients_names(fits):
    assert fits["arkit"].vocab.names == ARKIT
    assert fits["oculus"].vocab.names == list(OCULUS) and len(OCULUS) == 15
    assert fits["vrm"].vocab.names[:5] == ["aa", "ih", "ou", "ee", "oh"]
    made = dict(zip(ARKIT, fits["arkit"].vocab.made))
    assert made["jawOpen"] and made["mouthSmileLeft"] and made["eyeBlinkLeft"] and made["eyeLookInLeft"]
    assert not made["tongueOut"] and not made["cheekPuff"]
    # what the rig cannot make has a zero shape; what it can make moves the face
    shapes = fits["arkit"].vocab.shapes
    assert np.all(np.abs(shapes[~fits["arkit"].vocab.made]) == 0)
    assert np.all(np.abs(shapes[fits["arkit"].vocab.made]).max(axis=(1, 2)) > 1e-4)


def test_every_dectalk_symbol_has_a_class():
    table = phoneme_classes()
    assert set(table) == set(DECTALK)
    assert {o for o, _ in table.values()} == set(OCULUS)
    assert {r for _, r in table.values()} == set("ABCDEFGHX")


@pytest.mark.parametrize("viseme,names,least", [
    ("aa", ["jawOpen"], 0.5),
    ("uw", ["mouthPucker", "mouthFunnel"], 0.4),
    ("m", ["mouthPressLeft", "mouthPressRight"], 0.3),
])
def test_arkit_weights_of_the_issues_visemes(rig, lib, fits, viseme, names, least):
    w, r = weights_of(fits["arkit"], rig, lib.blend(viseme).to_numpy())
    assert max(w[n] for n in names) > least, {k: round(v, 2) for k, v in w.items() if v > 0.05}
    assert r < 2e-4       # residual RMS over the face surface below 0.2 mm (/aa/ 0.10 mm: its tongue is not fitted)
    assert all(0.0 <= v <= 1.0 for v in w.values())
    assert w["eyeBlinkLeft"] < 1e-9 and w["tongueOut"] == 0          # speech does not blink


def test_arkit_smiles_for_happiness_and_is_sided(rig, lib, fits):
    w, _ = weights_of(fits["arkit"], rig, lib.blend("_", {"happiness": 1.0}).to_numpy())
    assert w["mouthSmileLeft"] > 0.4 and w["mouthSmileRight"] > 0.4
    contempt, _ = weights_of(fits["arkit"], rig, lib.blend("_", {"contempt": 1.0}).to_numpy())
    assert contempt["mouthSmileLeft"] > 0.5 > 0.05 > contempt["mouthSmileRight"]   # one-sided, subject's left


def test_the_fit_recovers_weights_it_was_given(rig, fits):
    fit = fits["arkit"]
    rng = np.random.default_rng(3)
    truth = np.zeros(len(ARKIT))
    chosen = rng.choice(fit.made, 6, replace=False)
    truth[chosen] = rng.uniform(0.2, 0.8, 6)
    d = fit.play(truth)[0]
    w, r = fit.frame(d)
    size = np.sqrt((d ** 2).sum() / fit.n_measured)
    # mouthFunnel = 0.7 pucker + 0.2 jaw is nearly mouthPucker/jawOpen's sum: the ridge may trade a few
    # hundredths between such twins; the motion they play is the one given
    assert np.abs(w - truth).max() < 0.05 and r < 0.005 * size


def test_viseme_weights_are_a_partition_of_one(rig, lib, fits):
    for sym in ("_", "aa", "f", "m", "uw"):   # (a fricative like s is fitted as a spread vowel plus FF)
        w, r = weights_of(fits["oculus"], rig, lib.blend(sym).to_numpy())
        assert abs(sum(w.values()) - 1.0) < 5e-3 and min(w.values()) >= 0
        assert max(w, key=w.get) == phoneme_classes()[sym][0], (sym, w)


def test_sided_halves_add_up_to_the_whole(rig):
    left, right = side_weights(rig, "left"), side_weights(rig, "right")
    assert np.allclose(left + right, 1.0)
    x = rig.face.vertices[:, 0]
    assert left[x > 0.02].min() == 1.0 and left[x < -0.02].max() == 0.0


def test_bad_recipes_are_refused(rig):
    with pytest.raises(InputError, match="bad recipe term"):
        parse_recipe("AU12L=x")
    with pytest.raises(InputError, match="unknown recipe term 'AU99'"):
        RecipeResolver(rig).sum(parse_recipe("AU99"))
    with pytest.raises(InputError, match="unknown vocabulary"):
        vocabulary("arkitt", rig)
