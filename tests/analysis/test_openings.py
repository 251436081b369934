"""Mouth-opening detector against synthetic frames of known geometry."""

import numpy as np
import pytest

import cv2

from visemeface.analysis.openings import (
    MouthBox, OpeningDetector, detect_openings, median_kernel, median_mask, otsu_threshold, rec601_grey)
from visemeface.analysis.synthetic import Ellipse, mouth_image
from visemeface.errors import InputError

SIZE = (512, 512)
BOX = (56, 156, 400, 200)       # mouth corners at x = 56 and x = 455
W = BOX[2]

CASES = {
    1: [Ellipse(256, 256, 60, 20)],
    2: [Ellipse(180, 256, 40, 14), Ellipse(322, 256, 50, 18)],
    3: [Ellipse(150, 256, 30, 13), Ellipse(250, 258, 40, 20), Ellipse(360, 254, 35, 14)],
}


def _by_area(ellipses):
    return sorted(ellipses, key=lambda e: -e.area)


@pytest.mark.parametrize("n", [1, 2, 3])
@pytest.mark.parametrize("seed", [0, 1])
def test_count_area_width_height_of_known_ellipses(n, seed):
    img = mouth_image(SIZE, BOX, CASES[n], specks=12, noise=10.0, seed=seed)
    op = detect_openings(img, BOX)
    assert op.count == n
    truth = _by_area(CASES[n])
    for i, e in enumerate(truth):
        assert op.area[i] * W * W == pytest.approx(e.area, rel=0.03)
        assert abs(op.width[i] * W - 2 * e.a) <= 2
        assert abs(op.height[i] * W - 2 * e.b) <= 2
    assert op.largest_area == op.area.max()
    assert all(len(c) >= 4 for c in op.contours)


def test_metrics_are_normalised_by_mouth_width():
    """The same mouth at twice the resolution gives the same numbers."""
    small = mouth_image((256, 256), (28, 78, 200, 100), [Ellipse(128, 128, 30, 10)], seed=3)
    big = mouth_image((512, 512), (56, 156, 400, 200), [Ellipse(256, 256, 60, 20)], seed=3)
    a = detect_openings(small, (28, 78, 200, 100))
    b = detect_openings(big, (56, 156, 400, 200))
    assert a.count == b.count == 1
    assert a.largest_area == pytest.approx(b.largest_area, rel=0.05)
    assert a.largest_width == pytest.approx(b.largest_width, abs=2 / 200)
    assert a.largest_height == pytest.approx(b.largest_height, abs=2 / 200)


def test_bright_tongue_inside_does_not_split_the_opening():
    e = Ellipse(256, 256, 70, 24)
    img = mouth_image(SIZE, BOX, [e], tongues=[Ellipse(256, 262, 30, 10)], specks=8, seed=2)
    op = detect_openings(img, BOX)
    assert op.count == 1
    assert op.largest_area * W * W == pytest.approx(e.area, rel=0.03)


def test_teeth_at_the_edge_are_absorbed_only_with_teeth_handling():
    e = Ellipse(256, 256, 70, 24)
    upper_teeth = np.mgrid[:SIZE[0], :SIZE[1]][0] < 256 - 12     # white band under the upper lip
    img = mouth_image(SIZE, BOX, [e], teeth=[upper_teeth], specks=5, seed=3)
    without = detect_openings(img, BOX, method="seed")
    with_teeth = detect_openings(img, BOX, method="seed", teeth=True)
    assert without.count == with_teeth.count == 1
    assert without.largest_area * W * W < 0.9 * e.area            # teeth read as lip
    assert with_teeth.largest_area * W * W == pytest.approx(e.area, rel=0.03)
    assert abs(with_teeth.largest_height * W - 2 * e.b) <= 2


def test_teeth_handling_leaves_a_closed_mouth_closed():
    img = mouth_image(SIZE, BOX, [], seed=5)
    img[240:250, 200:230] = 245             # a white highlight on the lips, no cavity next to it
    assert detect_openings(img, BOX, method="seed", teeth=True).count == 0


def test_lips_method_counts_teeth_and_tongue_between_the_lips():
    """The default method: everything enclosed between the lips is opening, without --teeth."""
    e = Ellipse(256, 256, 70, 24)
    upper_teeth = np.mgrid[:SIZE[0], :SIZE[1]][0] < 256 - 12
    img = mouth_image(SIZE, BOX, [e], teeth=[upper_teeth], tongues=[Ellipse(256, 262, 30, 10)], seed=3)
    op = detect_openings(img, BOX)
    assert op.count == 1
    assert op.largest_area * W * W == pytest.approx(e.area, rel=0.03)
    assert abs(op.largest_height * W - 2 * e.b) <= 2


def test_lips_method_ignores_the_seam_of_closed_lips():
    img = mouth_image(SIZE, BOX, [Ellipse(256, 256, 150, 3)], noise=6.0, seed=4)      # 6 px high dark seam
    assert detect_openings(img, BOX).count == 0
    assert detect_openings(img, BOX, min_height=0).count == 1


def test_lips_method_ignores_a_blob_narrower_than_an_opening():
    """A blob taller than 0.05 w but narrower (MPEG's chroma at a mouth corner: 3 x 6 px on a 106 px mouth)
    is no opening; the same blob widened past 0.05 w is one."""
    narrow = mouth_image(SIZE, BOX, [Ellipse(400, 256, 8, 16)], noise=6.0, seed=5)     # 17 px wide, 33 high
    assert detect_openings(narrow, BOX).count == 0                                     # under 0.05 w = 20 px
    assert detect_openings(narrow, BOX, min_height=0).count == 1
    assert detect_openings(mouth_image(SIZE, BOX, [Ellipse(400, 256, 14, 16)], noise=6.0, seed=5), BOX).count == 1


def test_convex_hull_fills_a_notch():
    e = Ellipse(256, 256, 70, 24)
    img = mouth_image(SIZE, BOX, [e], teeth=[Ellipse(256, 232, 20, 12)], seed=4)
    plain = detect_openings(img, BOX, method="seed")
    hull = detect_openings(img, BOX, method="seed", hull=True)
    assert plain.largest_area * W * W < 0.95 * e.area
    assert hull.largest_area * W * W == pytest.approx(e.area, rel=0.03)
    assert hull.largest_area >= plain.largest_area


@pytest.mark.parametrize("threshold", ["otsu", 80.0])
def test_closed_mouth_gives_count_zero(threshold):
    img = mouth_image(SIZE, BOX, [], noise=8.0, seed=6)
    op = detect_openings(img, BOX, threshold=threshold)
    assert op.count == 0
    assert (op.largest_area, op.largest_width, op.largest_height) == (0.0, 0.0, 0.0)


def test_uniform_noise_is_not_an_opening():
    rng = np.random.default_rng(0)
    img = np.clip(rng.normal(120, 20, (128, 128, 3)), 0, 255).astype(np.uint8)
    assert detect_openings(img, (0, 0, 128, 128), method="seed").count == 0


def test_fixed_threshold_matches_otsu_on_clean_contrast():
    img = mouth_image(SIZE, BOX, CASES[2], seed=7)
    a = detect_openings(img, BOX)
    b = detect_openings(img, BOX, threshold=70)
    np.testing.assert_allclose(a.area, b.area, rtol=0.01)


def test_min_area_drops_specks_only():
    small = Ellipse(150, 256, 4, 4)                # ~50 px = 3.1e-4 w^2
    img = mouth_image(SIZE, BOX, [Ellipse(300, 256, 40, 15), small], noise=3.0, seed=8)
    assert detect_openings(img, BOX).count == 1                  # default 5e-4 w^2 = 80 px
    assert detect_openings(img, BOX, min_area=1e-4, min_height=0).count == 2


def test_otsu_three_levels_lands_on_the_darkest():
    rng = np.random.default_rng(1)
    values = np.concatenate([rng.normal(200, 5, 5000), rng.normal(110, 5, 3000), rng.normal(25, 5, 300)])
    hist = np.bincount(np.clip(values, 0, 255).astype(int), minlength=256)
    t = otsu_threshold(hist)
    assert 40 < t < 95
    two = np.concatenate([rng.normal(200, 5, 5000), rng.normal(120, 5, 3000)])   # skin and lips only
    assert otsu_threshold(np.bincount(two.astype(int), minlength=256)) is None


@pytest.mark.parametrize("k", [3, 5, 7, 11, 15])
def test_median_mask_is_median_then_threshold(k):
    """Threshold decomposition: the majority vote equals OpenCV's median blur, borders included."""
    rng = np.random.default_rng(k)
    for grey in (rng.integers(0, 256, (61, 83), dtype=np.uint8),
                 cv2.GaussianBlur(rng.integers(0, 256, (61, 83), dtype=np.uint8), (0, 0), 2.0)):
        for t in (40, 100, 127, 128, 200):
            np.testing.assert_array_equal(median_mask(grey <= t, k), cv2.medianBlur(grey, k) <= t)


def test_large_mouth_uses_the_large_kernel():
    """At ~800 px (kernel 11) a 4 px dark speck on the lips is blurred away, a real opening is kept."""
    box = (100, 100, 800, 400)
    e = Ellipse(500, 300, 120, 40)
    img = mouth_image((600, 1000), box, [e, Ellipse(300, 300, 4, 4)], noise=4.0, seed=11)
    op = detect_openings(img, box, min_area=0)
    assert op.count == 1
    assert op.largest_area * 800 ** 2 == pytest.approx(e.area, rel=0.03)


def test_rec601_weights():
    img = np.zeros((1, 3, 3), np.uint8)
    img[0, 0, 0] = img[0, 1, 1] = img[0, 2, 2] = 200
    np.testing.assert_array_equal(rec601_grey(img)[0], np.rint(200 * np.array([0.299, 0.587, 0.114])))


def test_median_kernel_scales_with_mouth_width():
    assert median_kernel(800) == 11
    ks = [median_kernel(w) for w in range(10, 3000, 7)]
    assert all(k % 2 == 1 and k >= 3 for k in ks)
    assert ks == sorted(ks)
    assert median_kernel(100) == 3


@pytest.mark.parametrize("box", [(-1, 0, 50, 50), (0, 0, 600, 50), (500, 500, 20, 20)])
def test_box_outside_the_frame(box):
    img = np.zeros((512, 512, 3), np.uint8)
    with pytest.raises(InputError, match="outside"):
        detect_openings(img, box)


@pytest.mark.parametrize("box", [("a", 1, 2, 3), (1, 2, 3), (0, 0, 2, 2), (0, 0, float("nan"), 5)])
def test_bad_box_values(box):
    with pytest.raises(InputError, match="mouth box"):
        MouthBox.of(box)


@pytest.mark.parametrize("bad", [dict(threshold="auto"), dict(threshold=300), dict(min_area=2)])
def test_bad_settings(bad):
    with pytest.raises(InputError):
        OpeningDetector(**bad)


def test_pad_keeps_a_dropped_jaw_in_view():
    """A box on the rest lips (as the renderer writes it) must not cut off an opening jaw."""
    box = (56, 156, 400, 100)                               # bottom edge at y = 256
    e = Ellipse(256, 236, 70, 40)                           # reaches down to y = 276
    img = mouth_image(SIZE, BOX, [e], seed=9)
    full = detect_openings(img, box)
    cut = detect_openings(img, box, pad=0)
    assert abs(full.largest_height * W - 2 * e.b) <= 2
    assert full.largest_area * W * W == pytest.approx(e.area, rel=0.03)
    assert cut.largest_height * W <= 256 - 196 + 1          # only the rows inside the box
    with pytest.raises(InputError, match="pad"):
        OpeningDetector(pad=(0.1, -1, 0, 0))


def test_rendered_face_closed_then_opening():
    """The project's own renderer: a closed mouth has no opening; the jaw opens one that grows."""
    from visemeface.muscles.rig import default_rig
    from visemeface.render.renderer import Renderer

    rig = default_rig()
    with Renderer(rig.face, size=(256, 256), view="mouth") as renderer:
        box = renderer.mouth_box()
        found = [detect_openings(renderer.render(rig.pose({"jaw": j})), box) for j in (0.0, 0.5, 1.0)]
    assert [f.count for f in found] == [0, 1, 1]
    assert 0 < found[1].largest_height < found[2].largest_height
    assert 0 < found[1].largest_area < found[2].largest_area
    assert found[2].largest_width > 0.6                     # the opening spans most of the mouth


@pytest.mark.parametrize("method,hull,teeth", [("lips", False, False), ("seed", False, False),
                                               ("seed", True, True)])
def test_translation_and_mirror_invariance(method, hull, teeth):
    """Moving the frame content with the box, or mirroring both, changes no metric."""
    img = mouth_image((400, 400), (50, 150, 300, 100),
                      [Ellipse(130, 200, 30, 12), Ellipse(220, 202, 45, 18)], specks=6, seed=12)
    box = (50, 150, 300, 100)
    ref = detect_openings(img, box, hull=hull, teeth=teeth, method=method)
    moved = np.zeros((460, 430, 3), np.uint8)
    moved[37:437, 21:421] = img
    shifted = detect_openings(moved, (71, 187, 300, 100), hull=hull, teeth=teeth, method=method)
    mirrored = detect_openings(img[:, ::-1], (400 - 50 - 300, 150, 300, 100), hull=hull, teeth=teeth, method=method)
    assert ref.count == shifted.count == mirrored.count == 2
    for other in (shifted, mirrored):
        np.testing.assert_array_equal(other.area, ref.area)
        np.testing.assert_array_equal(other.width, ref.width)
        np.testing.assert_array_equal(other.height, ref.height)
    np.testing.assert_array_equal(shifted.contours[0] - [21, 37], ref.contours[0])


@pytest.mark.parametrize("frame", [np.zeros((64, 64, 3)), np.zeros((64, 64), np.uint8), np.zeros((64, 64, 4), np.uint8)])
def test_a_frame_that_is_not_rgb_uint8_is_refused(frame):
    """Floats in 0..1 would threshold as black (a shut mouth, silently); grey or RGBA crash in OpenCV."""
    with pytest.raises(InputError, match="RGB uint8"):
        OpeningDetector().detect(frame, (8, 24, 48, 16))
