"""Teeth and tongue in renders: /aa/ shows upper teeth over the tongue, /m/ shows no teeth."""

import numpy as np
import pytest

from visemeface.postures.library import posed_vertices
from visemeface.render.mouth_pixels import interior_features, teeth_pixels, tongue_pixels
from visemeface.render.renderer import Renderer


@pytest.fixture(scope="module")
def mouth_view(rig):
    r = Renderer(rig.face, size=192, view="mouth")
    yield r
    r.release()


def test_aa_shows_upper_teeth_above_the_tongue(rig, mouth_view):
    v = posed_vertices(rig, "aa", {})
    img = mouth_view.render(v)
    f = interior_features(mouth_view, img, v)
    assert f["opening"] > 500
    # teeth: bright pale pixels, mostly in the upper half of the opening
    assert f["teeth_upper"] > 0.04 * f["opening"]
    assert f["teeth_upper"] > 2 * f["teeth_lower"]
    # tongue: red pixels in the lower half, hardly any in the upper
    assert f["tongue_lower"] > 0.08 * f["opening"]
    assert f["tongue_lower"] > 3 * f["tongue_upper"]


def test_closed_lips_show_no_teeth(rig, mouth_view):
    v = posed_vertices(rig, "m", {})
    img = mouth_view.render(v)
    x, y, w, h = mouth_view.mouth_box()
    box = img[y - h // 2: y + h + h // 2, x: x + w]
    assert teeth_pixels(box).sum() == 0
    f = interior_features(mouth_view, img, v)
    assert f["teeth_upper"] + f["teeth_lower"] == 0


def test_the_pixel_classes_do_not_overlap_on_the_face(rig, mouth_view):
    img = mouth_view.render()
    # skin is neither teeth nor tongue: a rest face has no teeth pixels and the red ones are the lips
    assert teeth_pixels(img).mean() < 0.002
    red = tongue_pixels(img)
    lips = np.concatenate([rig.face.region("upper_lip"), rig.face.region("lower_lip")])
    uv = np.round(mouth_view.project(rig.face.vertices[lips])).astype(int)
    assert red[uv[:, 1].clip(0, 191), uv[:, 0].clip(0, 191)].mean() > 0.5
