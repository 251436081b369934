"""Skin-tone presets of the default face (``--skin``): only colours change, darker to the end."""

import cv2
import numpy as np
import pytest

from visemeface.errors import InputError
from visemeface.face.colouring import default_skin, skin_tone, skin_tones
from visemeface.face.procedural import default_face


def _lightness(rgb) -> float:
    return float(cv2.cvtColor(np.float32(rgb).reshape(1, 1, 3), cv2.COLOR_RGB2LAB)[0, 0, 0])


def test_presets_span_the_fitzpatrick_range_light_to_dark():
    tones = skin_tones()
    assert list(tones) == ["I", "II", "III", "IV", "V", "VI"] and default_skin() == "III"
    skin = [_lightness(s) for s, _ in tones.values()]
    assert np.all(np.diff(skin) < 0) and skin[0] >= 80 and skin[-1] <= 30
    for s, lip in tones.values():                # lips darker and redder than their skin
        assert _lightness(lip) < _lightness(s) and lip[0] - lip[1] > s[0] - s[1]


def test_skin_changes_only_colours_and_the_default_is_the_original_face():
    base, dark = default_face(), default_face(skin="VI")
    np.testing.assert_array_equal(base.vertices, dark.vertices)
    np.testing.assert_allclose(default_face(skin="III").colors, base.colors)
    lips = base.regions["upper_lip"]
    assert dark.colors[lips].mean() < 0.5 * base.colors[lips].mean()
    interior = base.regions["upper_teeth"]                      # teeth keep their colour
    np.testing.assert_allclose(dark.colors[interior], base.colors[interior])


def test_unknown_preset_is_an_input_error_naming_the_choices():
    with pytest.raises(InputError, match="I, II, III, IV, V, VI"):
        skin_tone("VII")
    assert skin_tone("vi")[0].tolist() == skin_tones()["VI"][0].tolist()


def test_face_command_renders_the_darker_skin(tmp_path):
    from visemeface.cli import main

    out = {}
    for skin in ("I", "VI"):
        path = tmp_path / f"{skin}.png"
        assert main(["face", "-o", str(path), "--skin", skin, "--size", "64", "-q"]) == 0
        out[skin] = cv2.imread(str(path)).astype(float)
    centre = np.s_[20:44, 20:44]                       # the face's middle, not the background
    assert out["VI"][centre].mean() < 0.5 * out["I"][centre].mean()
