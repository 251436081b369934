"""The opening detector and the automatic mouth box on real GRID video, against hand labels.

``data/realdata_labels.csv`` holds labels read by eye from enlarged frames (every 5th frame of
the three clips in ../shared/realdata; see its header). The clips are the GRID corpus's (Cooke,
Barker, Cunningham & Shao, JASA 120:2421, 2006).
"""

from pathlib import Path

import cv2
import numpy as np
import pandas as pd
import pytest

from visemeface.analysis import landmarks
from visemeface.analysis.mouthbox import track_mouth
from visemeface.analysis.openings import OpeningDetector
from visemeface.analysis.video import open_frames

LABELS = Path(__file__).parent / "data" / "realdata_labels.csv"
CLIPS = ("swwp2s", "bbaf2n", "lbax4n")

pytestmark = [pytest.mark.realdata, pytest.mark.slow]


def labels() -> pd.DataFrame:
    return pd.read_csv(LABELS, comment="#")


def measure(realdata: Path, clip: str, detector: OpeningDetector | None = None):
    """Frames, tracked boxes and detections of one clip."""
    frames = list(open_frames(realdata / f"{clip}.mpg").frames())
    boxes = track_mouth(frames, source=clip)
    detector = detector or OpeningDetector()
    return frames, boxes, [detector.detect(f, b) for f, b in zip(frames, boxes)]


def agreement(realdata: Path, detector: OpeningDetector | None = None) -> pd.DataFrame:
    """Labels joined with the detector's open/closed and height (px) per labelled frame."""
    lab = labels()
    rows = []
    for clip in CLIPS:
        _, boxes, found = measure(realdata, clip, detector)
        for r in lab[lab["clip"] == clip].itertuples():
            op = found[r.frame]
            rows.append((clip, r.frame, r.open, r.height_px, int(op.count > 0), op.largest_height * op.mouth_width))
    return pd.DataFrame(rows, columns=["clip", "frame", "open", "height_px", "found", "found_px"])


@pytest.fixture(scope="module")
def table(realdata):
    return agreement(realdata)


def test_open_closed_agreement_with_hand_labels(table):
    agree = (table["open"] == table["found"]).mean()
    assert agree >= 0.95, table[table["open"] != table["found"]].to_string()


def test_opening_height_within_2px_of_hand_labels(table):
    both = table[(table["open"] == 1) & (table["found"] == 1)]
    err = (both["found_px"] - both["height_px"]).abs()
    assert (err <= 2).all(), both[err > 2].to_string()


def test_no_detection_on_the_beard_or_nostrils(realdata):
    """Every opening found lies between the mouth corners and below the nose: inside the padded box."""
    for clip in CLIPS:
        _, boxes, found = measure(realdata, clip)
        for b, op in zip(boxes, found):
            for c in op.contours:
                x, y, w, h = cv2.boundingRect(c)
                assert b.x - 0.1 * b.w <= x and x + w <= b.x + 1.1 * b.w, (clip, b, (x, y, w, h))
                assert y >= b.y - 0.1 * b.w, (clip, b, (x, y, w, h))


#: The mouth in the 100x50 crops of bbaf2n_mouth/ (corners at x = 31 and 70), read by eye.
CROP_BOX = (31, 18, 39, 17)


def test_mouth_crops_count_one_opening_when_open(realdata):
    """bbaf2n_mouth/: the same utterance as crops; 1 opening on open frames, 0 on closed ones."""
    from visemeface.analysis.profiles import analyze_frames

    src = open_frames(realdata / "bbaf2n_mouth", fps=25)
    df = analyze_frames(src.frames(), CROP_BOX, 25)
    lab = labels()
    lab = lab[lab["clip"] == "bbaf2n"]
    counts = df["count"].to_numpy()[lab["frame"].to_numpy()]
    np.testing.assert_array_equal(counts, lab["open"].to_numpy())


def test_automatic_box_covers_both_mouth_corners(realdata):
    """The issue's acceptance: on each real clip the automatic box covers both hand-read corners,
    and its edges are not absurdly far from them (within a third of the natural mouth width)."""
    if not landmarks.available():
        pytest.skip("the automatic box from landmarks needs the optional extra visemeface[track]")
    corners = pd.read_csv(LABELS.with_name("realdata_corners.csv"), comment="#")
    for clip in CLIPS:
        boxes = track_mouth(list(open_frames(realdata / f"{clip}.mpg").frames()), source=clip)
        assert len({b.mouth_width for b in boxes}) == 1          # one normalising width for the clip
        for r in corners[corners["clip"] == clip].itertuples():
            b = boxes[r.frame]
            inside = np.array([r.left_x - b.x, b.x + b.w - 1 - r.right_x])    # > 0: corner inside the box
            assert (inside >= 1).all(), (clip, r.frame, b, inside)
            assert (inside <= b.mouth_width / 3).all(), (clip, r.frame, b, inside)


def test_automatic_box_covers_the_tracked_corners_on_every_frame(realdata):
    """Every frame: the box covers the face-mesh corners of that frame (the box is per frame)."""
    if not landmarks.available():
        pytest.skip("the automatic box from landmarks needs the optional extra visemeface[track]")
    mouth = landmarks.settings()["mouth"]
    for clip in CLIPS:
        frames = list(open_frames(realdata / f"{clip}.mpg").frames())
        tracker = landmarks.FaceTracker()
        pts = [tracker(f) for f in frames]
        assert all(p is not None for p in pts), clip
        boxes = track_mouth(frames, source=clip)
        for p, b in zip(pts, boxes):
            xs = p[mouth["corners"], 0]
            assert b.x + 1 <= xs.min() and xs.max() <= b.x + b.w - 2, (clip, b, xs)


def test_colour_box_edges_near_the_mouth_corners(realdata):
    """The colour fallback (no landmark model): box edges within 5 px (about 0.13 w) of the corners.

    It does not always cover them: on bbaf2n the right corner lies up to 5 px beyond the box (MPEG-1's
    4:2:0 chroma loses the lip colour before the corner); the detector analyses box + 0.1 w each side.
    """
    corners = pd.read_csv(LABELS.with_name("realdata_corners.csv"), comment="#")
    off = []
    for clip in CLIPS:
        boxes = track_mouth(list(open_frames(realdata / f"{clip}.mpg").frames()), source=clip, method="colour")
        for r in corners[corners["clip"] == clip].itertuples():
            b = boxes[r.frame]
            off += [b.x - r.left_x, b.x + b.w - 1 - r.right_x]
    assert np.abs(off).max() <= 5, off


def test_real_releases_grow_over_frames_and_taper(realdata):
    """How real openings grow (the figure the sticky lips are compared with, issue 16): at 25 fps an
    opening that lasts 4+ frames reaches 90 % of its width over 2-4 frames (80-160 ms), not in the
    frame it appears, and its height rises fast, then tapers (power-law exponent below 1)."""
    from visemeface.analysis.profiles import opening_onsets, profile_from_openings
    f90, expo = [], []
    for clip in CLIPS:
        _, _, found = measure(realdata, clip)
        o = opening_onsets(profile_from_openings(found, 25.0, clip))
        o = o[o["frames"] >= 4]
        f90 += o["frames_to_90pct"].tolist()
        expo += o["height_exponent"].dropna().tolist()
    assert len(f90) >= 6 and np.median(f90) >= 2 and max(f90) >= 3, f90
    assert len(expo) >= 2 and max(expo) < 1, expo


def test_analyze_source_takes_a_path_as_it_takes_a_frame_source(realdata):
    """From Python a clip's path is enough (it raised AttributeError: 'str' has no 'frames')."""
    from visemeface.analysis.profiles import analyze_source

    by_path, boxes = analyze_source(str(realdata / "bbaf2n.mpg"))
    by_source, _ = analyze_source(open_frames(realdata / "bbaf2n.mpg"))
    assert len(by_path) == 75 and len(boxes) == 75
    pd.testing.assert_frame_equal(by_path, by_source)


def test_mirrored_clips_agree_with_the_hand_labels(realdata):
    """The default method on the left-right mirrored clips (scripts/analysis_fairness.py's 'mirrored'
    group; its other groups -- darkened skin, moustache, grey, low contrast -- are measured there)."""
    rows = _fairness_rows(realdata, "mirrored")
    assert (rows["open"] == rows["found"]).mean() >= 0.95, rows.to_string()
    both = rows[(rows["open"] == 1) & (rows["found"] == 1)]
    # the originals hold +-2 px; mirrored, the resampling grid falls differently: 2.12 px measured
    assert ((both["found_px"] - both["height_px"]).abs() <= 2.25).all(), both.to_string()
    assert rows["outside"].sum() == 0


def _fairness_rows(realdata, kind):
    import sys
    import tempfile

    sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "scripts"))
    import analysis_fairness as af

    cache = Path(tempfile.gettempdir()) / "visemeface_fairness"
    return pd.DataFrame(af.real_rows(realdata, [kind], OpeningDetector(), cache, CLIPS))


def test_a_moustache_over_the_upper_lip_neither_opens_nor_closes_the_mouth(realdata):
    """A dark moustache drawn over the upper lip's edge (scripts/analysis_fairness.py's 'moustache' group):
    the upper lip's colour is then the hair's, and compared with it the bare lip reads as teeth; compared
    with the lower lip's colour (lips are one tissue) 41 of the 45 labelled frames agree (35 before)."""
    rows = _fairness_rows(realdata, "moustache")
    assert (rows["open"] == rows["found"]).mean() >= 0.9, rows[rows["open"] != rows["found"]].to_string()
    assert rows["outside"].sum() == 0


def test_an_upper_lip_lifted_off_the_teeth_reads_open(realdata):
    """swwp2s's /eh/ (frame 16) and /iy/ (frame 35, hand label 8 px open): the teeth show from the lifted
    upper lip down, past the bound the face mesh gives, and end in the halo, enclosed by lip."""
    frames = list(open_frames(realdata / "swwp2s.mpg").frames())
    boxes = track_mouth(frames, source="swwp2s")
    det = OpeningDetector()
    for k in (16, 35):
        op = det.detect(frames[k], boxes[k])
        assert op.count >= 1 and op.largest_height * op.mouth_width >= 6, (k, op.largest_height * op.mouth_width)


def test_darkened_copy_lowers_the_skin_by_40_lightness_units_and_spares_the_teeth(realdata):
    """The 'dark' group of scripts/analysis_fairness.py is what it says: skin L* down by >= 40."""
    from visemeface.analysis import augment

    frames = list(open_frames(realdata / "swwp2s.mpg").frames())[:1]
    pts = landmarks.FaceTracker()(frames[0]) if landmarks.available() else None
    if pts is None:
        pytest.skip("needs the face mesh (visemeface[track])")
    f = augment.darkening_factor(frames[0], pts)
    dark = augment.darken_skin(frames[0], pts, f)
    outer = pts[landmarks.settings()["mouth"]["outer"]]
    lips = augment._poly(frames[0].shape, outer).astype(bool)
    ring = cv2.dilate(lips.view(np.uint8), np.ones((25, 25), np.uint8)).astype(bool) & ~lips
    drop = np.median(augment._lightness(frames[0])[ring]) - np.median(augment._lightness(dark)[ring])
    assert drop >= 40, drop
    assert augment.grey(frames[0]).std(axis=2).max() == 0
    np.testing.assert_array_equal(augment.mirror(augment.mirror(frames[0])), frames[0])
