"""Headless renderer: framing, dark open mouth, projections, determinism, camera geometry."""

import json

import cv2
import numpy as np
import pytest

from visemeface.errors import InputError
from visemeface.face.procedural import default_face
from visemeface.render.renderer import BACKGROUND, Renderer, save_png

SIZE = 160


@pytest.fixture(scope="module")
def face():
    return default_face(2500)


@pytest.fixture(scope="module")
def front(face):
    r = Renderer(face, size=SIZE, view="face")
    yield r
    r.release()


@pytest.fixture(scope="module")
def mouth(face):
    r = Renderer(face, size=SIZE, view="mouth")
    yield r
    r.release()


def _foreground(img):
    bg = np.array(BACKGROUND) * 255
    return np.abs(img.astype(float) - bg).sum(axis=2) > 30


def _lum(img):
    return img.astype(float) @ np.array([0.299, 0.587, 0.114])


def _opened(face, drop=0.010):
    """Lower lip and chin moved down (more at the centre line): the seam opens."""
    v = face.vertices.copy()
    jaw = face.regions["jaw"]
    w = np.exp(-(np.linalg.norm(v[jaw, :2], axis=1) / 0.05) ** 2)
    v[jaw, 1] -= drop * w
    return v


def test_face_in_frame(front):
    img = front.render()
    assert img.shape == (SIZE, SIZE, 3) and img.dtype == np.uint8
    fg = _foreground(img)
    rows, cols = np.nonzero(fg)
    # inside the frame with a margin, and big
    assert rows.min() > 0 and cols.min() > 0 and rows.max() < SIZE - 1 and cols.max() < SIZE - 1
    assert rows.max() - rows.min() > 0.8 * SIZE
    assert cols.max() - cols.min() > 0.45 * SIZE
    # left-right balanced in the front view
    assert abs(cols.mean() - SIZE / 2) < 0.03 * SIZE
    # the background really is dark and the face is skin coloured
    assert _lum(img[~fg]).max() < 30
    skin = img[fg].astype(float).mean(0)
    assert skin[0] > skin[1] > skin[2] and skin[0] > 120


def test_landmarks_project_onto_the_face(face, front):
    img = front.render()
    fg = _foreground(img)
    lm = face.landmarks
    for name in ("nose_tip", "chin", "cheek_left", "brow_inner_right", "mouth_corner_left"):
        u, v = front.project(face.vertices[lm[name]])[0]
        assert fg[int(v), int(u)], name
    # an eye: dark pupil with white sclera beside it
    u, v = (int(c) for c in front.project(face.vertices[lm["eye_centre_left"]])[0])
    lum = _lum(img)
    assert lum[v, u] < 60
    assert lum[v, u - 8:u + 9].max() > 150
    # image orientation: the subject's left (+x) on the viewer's right, up is up
    (ul, vl), (ur, vr) = front.project(face.vertices[[lm["eye_centre_left"], lm["eye_centre_right"]]])
    assert ul > ur
    assert front.project(face.vertices[lm["chin"]])[0, 1] > front.project(face.vertices[lm["nasion"]])[0, 1]


def test_repeated_renders_identical(face, front):
    buffers = (front.vbo.glo, front.ibo.glo, front.cbo.glo)
    a = front.render()
    front.render(_opened(face))
    b = front.render()
    assert np.array_equal(a, b)
    assert (front.vbo.glo, front.ibo.glo, front.cbo.glo) == buffers   # rewritten, never rebuilt
    with Renderer(face, size=SIZE, view="face") as other:
        assert np.array_equal(other.render(), a)


def test_dark_mouth_when_lower_lip_moves_down(face, mouth):
    x, y, w, h = mouth.mouth_box()
    closed = mouth.render()
    opened = mouth.render(_opened(face))
    roi = (slice(y - h, y + 2 * h), slice(x, x + w))
    dark_closed = (_lum(closed[roi]) < 40).sum()
    dark_open = (_lum(opened[roi]) < 40).sum()
    assert dark_closed < 0.01 * w * 3 * h
    assert dark_open > 0.08 * w * 3 * h
    # the dark pixels lie between the mouth corners, below the upper lip's rest line
    rows, cols = np.nonzero(_lum(opened) < 40)
    assert x <= cols.min() and cols.max() <= x + w
    u_mid, v_mid = mouth.project(face.vertices[face.landmarks["upper_lip_mid"]])[0]
    assert np.median(rows) > v_mid - 1


def test_mouth_box_spans_the_corners(face, mouth, front):
    for r in (mouth, front):
        x, y, w, h = r.mouth_box()
        corners = r.project(face.vertices[[face.landmarks["mouth_corner_right"],
                                           face.landmarks["mouth_corner_left"]]])
        assert abs(x - corners[0, 0]) <= 1 and abs(x + w - corners[1, 0]) <= 1
        assert 0 <= x and x + w <= SIZE and 0 <= y and y + h <= SIZE
    # the mouth view magnifies: the mouth spans most of the frame
    assert 0.5 * SIZE < mouth.mouth_box()[2] < 0.8 * SIZE
    assert front.mouth_box()[2] < 0.4 * SIZE


def test_camera_info_is_a_sidecar(mouth):
    info = json.loads(json.dumps(mouth.camera_info()))
    assert info["mouth_box"] == list(mouth.mouth_box())
    assert info["size"] == [SIZE, SIZE]
    assert info["mouth_width_px"] == pytest.approx(mouth.mouth_box()[2], abs=1)
    # the stored matrices reproduce the projection
    mvp = np.array(info["projection_matrix"]) @ np.array(info["view_matrix"])
    assert np.allclose(mvp, mouth.mvp)


def test_orthographic_differs_from_perspective(face, front):
    with Renderer(face, size=SIZE, view="face", projection="orthographic") as ortho:
        a, b = front.render(), ortho.render()
        assert not np.array_equal(a, b)
        assert _foreground(b).sum() > 0.3 * SIZE * SIZE
        # perspective: nearer points spread more from the image centre than in orthographic
        lm = face.landmarks
        pts = face.vertices[[lm["nose_tip"], lm["jaw_joint_left"]]]
        d_persp = np.diff(front.project(pts)[:, 0])[0]
        d_ortho = np.diff(ortho.project(pts)[:, 0])[0]
        assert abs(d_persp - d_ortho) > 0.5


def test_three_quarter_view_turns_the_head(face):
    with Renderer(face, size=SIZE, view="three-quarter") as r:
        img = r.render()
        assert _foreground(img).sum() > 0.25 * SIZE * SIZE
        lm = face.landmarks
        nose_u = r.project(face.vertices[lm["nose_tip"]])[0, 0]
        eyes_u = r.project(face.vertices[[lm["eye_centre_left"], lm["eye_centre_right"]]])[:, 0]
        # seen from the subject's left, the nose points to the viewer's left of the eyes' midpoint
        assert nose_u < eyes_u.mean() - 0.03 * SIZE


def test_bad_arguments(face, front):
    with pytest.raises(InputError, match="multiple of 16"):
        Renderer(face, size=100)
    with pytest.raises(InputError, match="did you mean"):
        Renderer(face, size=SIZE, view="mouht")
    with pytest.raises(InputError, match="projection"):
        Renderer(face, size=SIZE, projection="fisheye")
    with pytest.raises(InputError, match="shape"):
        front.render(face.vertices[:-1])
    with pytest.raises(InputError, match="NaN"):
        front.render(np.full_like(face.vertices, np.nan))


def test_a_closed_renderer_says_so(face):
    with Renderer(face, size=(32, 32)) as r:
        r.render()
    with pytest.raises(RuntimeError, match="closed"):
        r.render()


def test_save_png_round_trip(tmp_path, front):
    img = front.render()
    path = tmp_path / "f.png"
    save_png(path, img)
    back = cv2.imread(str(path))[:, :, ::-1]
    assert np.array_equal(back, img)
    with pytest.raises(InputError, match="exists"):
        save_png(path, img)
    save_png(path, np.zeros_like(img), force=True)
    assert cv2.imread(str(path)).max() == 0
    with pytest.raises(InputError, match="must end in .png"):      # PNG bytes under another name: refused
        save_png(tmp_path / "f.jpg", img)
