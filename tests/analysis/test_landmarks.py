"""Face detection and face-mesh landmarks (MediaPipe's models run by ai-edge-litert, extra ``track``)."""

from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from visemeface.analysis import landmarks
from visemeface.analysis.landmarks import Region, decode, iou, region_around, ssd_anchors, weighted_nms
from visemeface.errors import InputError
from visemeface.resources import data_path

CORNERS = Path(__file__).parent / "data" / "realdata_corners.csv"

needs_model = pytest.mark.skipif(not landmarks.available(), reason="needs the optional extra visemeface[track]")


def test_anchors_match_blazeface_short_range():
    cfg = landmarks.settings()["detector"]
    a = ssd_anchors(cfg["size"], cfg["strides"], cfg["anchors_per_layer"])
    assert a.shape == (896, 2)                        # 16x16 cells x 2 + 8x8 cells x 6
    np.testing.assert_allclose(a[:2], [[0.5 / 16, 0.5 / 16]] * 2)
    np.testing.assert_allclose(a[512:518], [[0.5 / 8, 0.5 / 8]] * 6)
    np.testing.assert_allclose(a[-1], [7.5 / 8, 7.5 / 8])


def test_decode_offsets_anchor_and_nothing_below_the_score():
    anchors = np.array([[0.25, 0.5], [0.75, 0.5]])
    raw = np.zeros((2, 16))
    raw[0, :4] = [12.8, -12.8, 25.6, 51.2]            # centre +0.1,-0.1; size 0.2 x 0.4
    raw[0, 4:6] = [6.4, 0.0]
    scores, boxes, kps = decode(raw, np.array([3.0, -3.0]), anchors, 128, 0.5)
    assert scores.shape == (1,) and scores[0] == pytest.approx(1 / (1 + np.exp(-3)))
    np.testing.assert_allclose(boxes[0], [0.25, 0.2, 0.45, 0.6])
    assert kps.shape == (1, 6, 2)
    np.testing.assert_allclose(kps[0, 0], [0.3, 0.5])
    scores, boxes, kps = decode(raw, np.array([-5.0, -5.0]), anchors, 128, 0.5)
    assert scores.size == 0 and boxes.shape == (0, 4) and kps.shape == (0, 6, 2)


def test_weighted_nms_merges_overlapping_boxes_by_score():
    boxes = np.array([[0, 0, 10, 10], [1, 0, 11, 10], [50, 50, 60, 60]], float)
    kps = np.zeros((3, 1, 2))
    out = weighted_nms(np.array([0.9, 0.3, 0.8]), boxes, kps, 0.3)
    assert len(out) == 2 and out[0][0] == 0.9
    np.testing.assert_allclose(out[0][1], [0.25, 0, 10.25, 10])        # (0.9 * 0 + 0.3 * 1) / 1.2
    np.testing.assert_allclose(out[1][1], boxes[2])
    assert iou(boxes[0], boxes[:1])[0] == pytest.approx(1.0)


def test_region_maps_crop_pixels_to_the_rotated_square():
    r = Region(100.0, 50.0, 40.0, np.pi / 2)
    m = r.to_frame(4)
    centre = m @ np.array([1.5, 1.5, 1.0])             # the crop's centre
    np.testing.assert_allclose(centre, [100, 50])
    right = m @ np.array([3.5, 1.5, 1.0])              # +u turned by 90 degrees: +y in the frame (y down)
    np.testing.assert_allclose(right, [100, 70])
    pts = np.array([[0, 0], [10, 10], [20, 0], [3, 2]], float)
    reg = region_around(pts, (0, 2), 1.5)
    assert (reg.x, reg.y, reg.size, reg.angle) == (10, 5, 30, 0)


def test_models_ship_as_package_data():
    for name in ("face_detection_short_range.tflite", "face_landmark.tflite", "NOTICE.md", "LICENSE-mediapipe"):
        assert data_path("models", name).is_file(), name


@needs_model
def test_blank_frame_has_no_face():
    frame = np.full((288, 360, 3), (200, 120, 40), np.uint8)
    models = landmarks.FaceModels()
    assert models.detect(frame) == []
    assert landmarks.FaceTracker(models)(frame) is None


@needs_model
@pytest.mark.realdata
def test_mesh_corners_near_hand_read_corners(realdata):
    """Mesh points 61 and 291 against the hand-read corners of 30 GRID frames: median error <= 2 px,
    none beyond 8 px (lbax4n's right corner runs on along the lip line up to 7 px past a reading)."""
    from visemeface.analysis.video import open_frames

    corners = pd.read_csv(CORNERS, comment="#")
    models = landmarks.FaceModels()
    idx = landmarks.settings()["mouth"]["corners"]
    err = []
    for clip in ("swwp2s", "bbaf2n", "lbax4n"):
        frames = list(open_frames(realdata / f"{clip}.mpg").frames())
        found = models.detect(frames[0])
        assert len(found) == 1 and found[0].score > 0.8
        tracker = landmarks.FaceTracker(models)
        pts = [tracker(f) for f in frames]
        for r in corners[corners["clip"] == clip].itertuples():
            err += list(pts[r.frame][idx, 0] - [r.left_x, r.right_x])
    err = np.abs(err)
    assert np.median(err) <= 2 and err.max() <= 8, err.round(1)


@needs_model
@pytest.mark.realdata
def test_tracker_redetects_after_a_blank_frame(realdata):
    from visemeface.analysis.video import open_frames

    frames = list(open_frames(realdata / "bbaf2n.mpg").frames())[:3]
    tracker = landmarks.FaceTracker()
    assert tracker(frames[0]) is not None
    assert tracker(np.zeros_like(frames[1])) is None and tracker.region is None
    pts = tracker(frames[2])
    assert pts is not None and pts.shape == (468, 2)


def test_unknown_box_method_is_an_input_error():
    from visemeface.analysis.mouthbox import track_mouth

    with pytest.raises(InputError, match="landmarks"):
        track_mouth([np.zeros((8, 8, 3), np.uint8)], method="haar")


def test_natural_width_from_closed_frames():
    from visemeface.analysis.mouthbox import natural_width

    corners = np.array([[[0, 0], [w, 0]] for w in (40, 40, 40, 50, 50)], float)
    assert natural_width(corners, np.array([0, 1, 1, 10, 12.0])) == 40     # open, spread frames left out
    assert natural_width(corners, np.full(5, 10.0)) == 40                 # none closed: the clip median


def test_without_the_extra_the_box_comes_from_colour(monkeypatch):
    """No interpreter installed: track_mouth falls back to the colour box (its own no-face error)."""
    from visemeface.analysis import mouthbox

    called = []
    monkeypatch.setattr(landmarks, "available", lambda: False)
    monkeypatch.setattr(mouthbox, "colour_boxes", lambda frames, source="": called.append(source) or [])
    mouthbox.track_mouth([np.zeros((8, 8, 3), np.uint8)], source="clip")
    assert called == ["clip"]


def test_mouth_box_keeps_the_natural_width_apart():
    from visemeface.analysis.openings import MouthBox

    assert MouthBox(1, 2, 50, 20, natural_w=40).mouth_width == 40
    assert MouthBox.of((1, 2, 50, 20)).mouth_width == 50
    # the pad is in natural widths: 0.1 x 40 = 4 px left of x = 10
    assert MouthBox(10, 10, 50, 20, natural_w=40).region((0.1, 0, 0, 0), 100, 100)[0] == 6


@needs_model
@pytest.mark.realdata
def test_face_turned_in_the_frame_is_an_input_error(realdata):
    """A real clip turned 90 degrees: the mesh still finds the face, but widths along the rows would be
    the mouth's heights; a one-line InputError instead of a silently swapped profile (upright passes)."""
    import cv2

    from visemeface.analysis.mouthbox import landmark_boxes
    from visemeface.analysis.video import open_frames

    frames = list(open_frames(realdata / "swwp2s.mpg").frames())[:4]
    assert len(landmark_boxes(frames, "clip")) == 4
    turned = [np.ascontiguousarray(cv2.rotate(f, cv2.ROTATE_90_CLOCKWISE)) for f in frames]
    with pytest.raises(InputError, match=r"clip: the face is turned \+9\d degrees"):
        landmark_boxes(turned, "clip")


@needs_model
@pytest.mark.realdata
def test_frames_without_a_face_are_marked_not_found(realdata):
    """The face leaves after frame 4 (black frames): those boxes are held from frame 4 and flagged
    ``found=False`` (analyze warns), the frames tracked or between two tracked faces are found."""
    from visemeface.analysis.mouthbox import landmark_boxes
    from visemeface.analysis.video import open_frames

    frames = list(open_frames(realdata / "swwp2s.mpg").frames())[:10]
    frames[5:] = [np.zeros_like(f) for f in frames[5:]]
    boxes = landmark_boxes(frames, "clip", every=2)
    # frame 5 lies between frame 4 (face) and 6 (none): counted found; 6-9 have no face near them
    assert [b.found for b in boxes] == [True] * 6 + [False] * 4
    assert boxes[9].w == boxes[4].w


def test_colour_box_marks_frames_without_a_face(monkeypatch):
    from visemeface.analysis import mouthbox

    lips = (10.0, 30.0, 20.0, 26.0)
    frames = [np.full((64, 64, 3), v, np.uint8) for v in (0, 1, 0)]      # frame 1: no lips, no face
    monkeypatch.setattr(mouthbox, "find_face", lambda frame, min_face: (None, (0, 0, 8, 8)))
    monkeypatch.setattr(mouthbox, "find_lips", lambda frame, min_face, face: None if frame[0, 0, 0] else lips)
    monkeypatch.setattr(mouthbox, "lip_extent", lambda frame, red: None)
    boxes = mouthbox.colour_boxes(frames, refine_every=99)
    assert [b.found for b in boxes] == [True, False, True]
