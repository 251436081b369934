"""The default opening measure (method 'mesh'): bounded by the face mesh's lip contours, decided by
evidence relative to the speaker's own lips, so the same for any skin and lip colour."""

from __future__ import annotations

import cv2
import numpy as np
import pytest

from visemeface.analysis.openings import MouthBox, OpeningDetector

SIZE = (160, 200)
CX, CY, HALF_W = 100, 80, 40          # mouth centre and half width (px): an 80 px mouth


def contour(half_w: float, top: float, bottom: float) -> np.ndarray:
    """20 points in the face mesh's order: corner, lower edge (left to right), corner, upper edge back."""
    xs = np.linspace(-half_w, half_w, 11)
    shape = np.sqrt(np.clip(1 - (xs / half_w) ** 2, 0, 1))
    lower = np.stack([CX + xs, CY + bottom * shape], 1)
    upper = np.stack([CX + xs[::-1], CY - top * shape[::-1]], 1)
    return np.vstack([lower, upper[1:-1]])


def mouth(skin, lip, gap: float = 0.0, teeth: bool = False, glued: float = 0.0, moustache: bool = False,
          grey: bool = False):
    """An RGB mouth: skin, lips (a ring), a dark cavity ``gap`` px tall (0: closed, a shaded seam),
    optional upper teeth, lips glued over ``glued`` px at the centre, a dark moustache above."""
    img = np.empty(SIZE + (3,), np.uint8)
    img[:] = skin
    cv2.ellipse(img, (CX, CY), (HALF_W, 16), 0, 0, 360, lip, -1)
    if gap > 0:
        cv2.ellipse(img, (CX, CY), (HALF_W - 6, int(gap // 2)), 0, 0, 360, (int(lip[0] * 0.2), 8, 10), -1)
        if teeth:
            cv2.rectangle(img, (CX - 14, CY - int(gap // 2)), (CX + 14, CY - int(gap // 2) + 3), (235, 232, 220), -1)
        if glued:
            cv2.rectangle(img, (CX - int(glued // 2), CY - 8), (CX + int(glued // 2), CY + 8), lip, -1)
    else:
        cv2.line(img, (CX - HALF_W + 4, CY), (CX + HALF_W - 4, CY), tuple(int(c * 0.75) for c in lip), 2)
    if moustache:
        cv2.ellipse(img, (CX, CY - 24), (HALF_W, 7), 0, 0, 360, (30, 22, 18), -1)
    img = cv2.GaussianBlur(img, (0, 0), 1.0)
    if grey:
        img = np.repeat(cv2.cvtColor(img, cv2.COLOR_RGB2GRAY)[..., None], 3, axis=2)
    return img


def box_with_mesh(gap: float) -> MouthBox:
    # the mesh's inner contour sits a little inside the visible opening, as on real video
    lips = np.vstack([contour(HALF_W, 16, 16), contour(HALF_W - 6, max(0.3, gap / 2 - 1.5), max(0.3, gap / 2 - 1.5))])
    return MouthBox(CX - HALF_W, CY - 16, 2 * HALF_W, 32, lips=lips)


TONES = {  # skin, lip (RGB): light, medium, dark (lips near the skin's own tone), very dark
    "light": ((235, 200, 180), (200, 110, 115)),
    "medium": ((200, 150, 115), (170, 95, 90)),
    "dark": ((95, 65, 48), (80, 48, 45)),
    "very dark": ((60, 40, 30), (52, 32, 30)),
}


@pytest.mark.parametrize("tone", TONES)
def test_open_and_closed_the_same_for_every_skin_tone(tone):
    skin, lip = TONES[tone]
    det = OpeningDetector()
    closed = det.detect(mouth(skin, lip), box_with_mesh(0))
    assert closed.count == 0, tone
    for gap, teeth in ((10, False), (16, True)):
        op = det.detect(mouth(skin, lip, gap, teeth), box_with_mesh(gap))
        assert op.count == 1, (tone, gap)
        assert abs(op.largest_height * op.mouth_width - (gap + 1)) <= 3, (tone, gap, op.largest_height * 80)   # 0.04 w


def test_grey_video_and_a_moustache_do_not_change_the_answer():
    skin, lip = TONES["dark"]
    det = OpeningDetector()
    for kw in ({"grey": True}, {"moustache": True}, {"grey": True, "moustache": True}):
        assert det.detect(mouth(skin, lip, **kw), box_with_mesh(0)).count == 0, kw
        op = det.detect(mouth(skin, lip, 12, True, **kw), box_with_mesh(12))
        assert op.count == 1, kw
        x, y, w, h = cv2.boundingRect(op.contours[0])
        assert y >= CY - 16, (kw, y)                  # nothing above the upper lip: not the moustache


def test_two_openings_with_a_glued_centre_count_two():
    skin, lip = TONES["very dark"]
    op = OpeningDetector().detect(mouth(skin, lip, 10, glued=8), box_with_mesh(10))
    assert op.count == 2


def test_without_a_mesh_the_bound_comes_from_the_lips_by_colour():
    skin, lip = TONES["light"]
    box = MouthBox(CX - HALF_W, CY - 16, 2 * HALF_W, 32)
    det = OpeningDetector()
    assert det.detect(mouth(skin, lip), box).count == 0
    assert det.detect(mouth(skin, lip, 12, True), box).count == 1


def test_lips_just_parted_measure_the_gap_not_the_highlight_beside_it():
    # A mouth at its own resolution (no resampling), lips parted by a 2 px black gap over the centre
    # fifth, a white highlight along the lower lip's edge across half the mouth (a render's or a wet
    # lip's): the opening is the gap. (Read as teeth, the highlight made it 0.5 of the mouth wide.)
    s = 4
    img = np.empty((SIZE[0] * s, SIZE[1] * s, 3), np.uint8)
    skin, lip = TONES["light"]
    img[:] = skin
    cx, cy, hw = CX * s, CY * s, HALF_W * s
    cv2.ellipse(img, (cx, cy), (hw, 16 * s), 0, 0, 360, lip, -1)
    cv2.line(img, (cx - hw + 16, cy), (cx + hw - 16, cy), tuple(int(c * 0.75) for c in lip), 2)
    cv2.line(img, (cx - hw // 2, cy + 3), (cx + hw // 2, cy + 3), (250, 235, 230), 2)     # the highlight
    cv2.rectangle(img, (cx - 16, cy - 1), (cx + 16, cy), (8, 6, 8), -1)                  # the gap, 32 px
    lips = (box_with_mesh(0).lips - (CX, CY)) * s + (cx, cy)
    op = OpeningDetector().detect(img, MouthBox(cx - hw, cy - 16 * s, 2 * hw, 32 * s, lips=lips))
    assert op.count == 1
    assert abs(op.largest_width * op.mouth_width - 33) <= 4, op.largest_width * op.mouth_width


def _hair_over_upper_lip(img: np.ndarray, alpha: float = 0.6) -> np.ndarray:
    """Dark brown hair over the upper lip's vermilion (its outer half), in vertical streaks."""
    out = img.astype(np.float32)
    rows = slice(CY - 17, CY - 9)
    cols = np.arange(CX - HALF_W + 6, CX + HALF_W - 6)
    streak = np.where(cols % 3 == 0, 1.0, 0.7)[None, :, None] * alpha
    out[rows, cols] = out[rows, cols] * (1 - streak) + np.array([38.0, 28.0, 22.0]) * streak
    return np.round(out).astype(np.uint8)


@pytest.mark.parametrize("tone", ["light", "medium"])
def test_hair_over_the_upper_lip_changes_neither_closed_nor_open(tone):
    # the upper lip's own colour is then mostly hair's: compared with it the bare lip below the hair reads
    # unlike lip too, joins the opening to the bound's edge, and the open mouth is dropped as hair. Lips
    # are one tissue, so the lower lip's colour is used instead
    skin, lip = TONES[tone]
    det = OpeningDetector()
    assert det.detect(_hair_over_upper_lip(mouth(skin, lip)), box_with_mesh(0)).count == 0, tone
    op = det.detect(_hair_over_upper_lip(mouth(skin, lip, 12, True)), box_with_mesh(12))
    assert op.count == 1 and abs(op.largest_height * op.mouth_width - 13) <= 3, (tone, op.largest_height * 80)
