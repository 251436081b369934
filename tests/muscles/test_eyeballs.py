"""Rigid eyeballs (rig-file ``[gaze] rigid``): on the ICT head each eyeball turns whole and exactly, as one
rotation obeying Listing's law (Helmholtz 1867), inside the rig's one product; the default face keeps its
linearised turn."""

from __future__ import annotations

import numpy as np
import pytest

from visemeface.errors import InputError


@pytest.fixture(scope="module")
def ict_rig():
    from visemeface.face.ict import ict_face
    from visemeface.muscles.rig import MuscleRig

    return MuscleRig.from_file(ict_face())


def _rotation(axis_angle: np.ndarray) -> np.ndarray:
    """The rotation matrix of a rotation vector (Rodrigues)."""
    theta = np.linalg.norm(axis_angle)
    if theta == 0:
        return np.eye(3)
    k = axis_angle / theta
    K = np.array([[0, -k[2], k[1]], [k[2], 0, -k[0]], [-k[1], k[0], 0]])
    return np.eye(3) + np.sin(theta) * K + (1 - np.cos(theta)) * K @ K


def _turns(rig, side):
    return [m for m in rig.muscles if m.kind == "turn" and m.name.endswith(side)]


@pytest.mark.parametrize("h,v", [(1.0, 0.0), (0.0, -1.0), (0.7, 0.6), (-1.0, 1.0)])
def test_each_ict_eyeball_turns_as_one_exact_rotation_for_any_gaze(ict_rig, h, v):
    pose = ict_rig.pose({"eye_turn_horizontal_left": h, "eye_turn_horizontal_right": h,
                         "eye_turn_vertical_left": v, "eye_turn_vertical_right": v})
    for side in ("left", "right"):
        turns = _turns(ict_rig, side)
        assert len(turns) == 2 and all(m.rigid for m in turns)
        ball = turns[0].mask & turns[1].mask
        # the turns are about one centre, the eyeball's sphere (ICT's is 12 mm across)
        np.testing.assert_allclose(turns[0].centre, turns[1].centre)
        omega = sum(a * m.k * m.axis / np.linalg.norm(m.axis) for a, m in zip((h, v), turns))
        R = _rotation(omega)
        c = turns[0].centre
        want = (ict_rig.rest[ball] - c) @ R.T + c
        err = np.linalg.norm(pose[ball] - want, axis=1).max()
        assert err < 1e-6, err                               # float32 product: below a micrometre
        # the linearised turn it replaces is far off at these angles
        linear = ict_rig.rest[ball] + np.cross(omega, ict_rig.rest[ball] - c)
        assert np.linalg.norm(linear - want, axis=1).max() > 100 * err
        # a rotation keeps every distance from the centre
        np.testing.assert_allclose(np.linalg.norm(pose[ball] - c, axis=1),
                                   np.linalg.norm(ict_rig.rest[ball] - c, axis=1), atol=1e-6)


def test_the_lids_still_follow_a_rigid_vertical_gaze(ict_rig):
    up = ict_rig.pose({"eye_turn_vertical_left": 1.0})
    m = next(m for m in ict_rig.muscles if m.name == "eye_turn_vertical_left")
    lid = m.lids > 0.5
    assert lid.any() and not (lid & m.mask).any()
    rise = (up - ict_rig.rest)[lid, 1]
    assert rise.max() > 2e-3                                   # the upper lid rises millimetres with the eye


def test_the_default_face_keeps_its_linearised_turn():
    """Its eyeballs are flattened caps, not spheres: no rigid turns, the gaze linear in the activation."""
    from visemeface.muscles.rig import default_rig

    rig = default_rig()
    assert not rig._eyes and not any(m.rigid for m in rig.muscles)
    half = rig.pose({"eye_turn_horizontal_left": 0.5}) - rig.rest
    full = rig.pose({"eye_turn_horizontal_left": 1.0}) - rig.rest
    np.testing.assert_allclose(full, 2 * half, atol=1e-8)


def test_a_gaze_table_that_is_not_true_or_false_is_refused_by_name(tmp_path):
    from visemeface.muscles.rig import MuscleRig, default_rig
    from visemeface.resources import data_path

    p = tmp_path / "rig.toml"
    p.write_text(data_path("rig", "default.toml").read_text() + '\n[gaze]\nrigid = "yes"\n')
    with pytest.raises(InputError, match=r"gaze.*rigid.*expected true or false"):
        MuscleRig.from_file(default_rig().face, p)
