"""detect_contacts / ground_height: a foot is in contact when near the floor and slow."""

import numpy as np
import pytest

from evoik_pin.errors import MotionError
from evoik_pin.motion import Motion, detect_contacts, ground_height


def two_feet(fps=30.0):
    """Left foot planted for frames 0-9, lifted and swinging forward at 2 m/s for 10-19; right foot always planted
    on a floor at z = 0.3 m (a stage), ankles 0.08 m above it."""
    n = 20
    left = np.zeros((n, 3))
    left[:, 2] = 0.38
    swing = np.arange(10, 20)
    left[swing, 0] = 2.0 * (swing - 9) / fps
    left[swing, 2] = 0.38 + 0.15 * np.sin(np.pi * (swing - 9) / 11)
    right = np.tile([0.0, -0.2, 0.38], (n, 1))
    return Motion(np.stack([left, right], axis=1), ["LeftFoot", "RightFoot"], fps)


def test_planted_and_swinging_frames():
    c = detect_contacts(two_feet())
    assert set(c) == {"LeftFoot", "RightFoot"}
    assert c["RightFoot"].dtype == bool and c["RightFoot"].all()
    # frame 9 is the last planted one, but its central-difference speed already sees the swing start
    np.testing.assert_array_equal(c["LeftFoot"], np.arange(20) < 9)


def test_floor_is_found_under_a_raised_stage():
    assert ground_height(two_feet()) == pytest.approx(0.38)


def test_thresholds_decide():
    assert detect_contacts(two_feet(), height=1.0, speed=100.0)["LeftFoot"].all()
    p = two_feet().positions.copy()
    p[:, 1, 0] = 0.5 * np.arange(20) / 30.0  # the right foot slides at 0.5 m/s ...
    p[:, 1, 2] += 0.04  # ... 4 cm above the floor (the left foot, planted at first, keeps the floor estimate)
    m = Motion(p, ["LeftFoot", "RightFoot"], 30.0)
    assert detect_contacts(m)["RightFoot"].all()  # defaults: within 5 cm, slower than 0.7 m/s
    assert not detect_contacts(m, speed=0.4)["RightFoot"].any()
    assert not detect_contacts(m, height=0.03)["RightFoot"].any()


def test_one_frame_motion_has_speed_zero():
    m = Motion(np.zeros((1, 2, 3)), ["LeftFoot", "RightFoot"], 30)
    assert all(v.tolist() == [True] for v in detect_contacts(m).values())


def test_given_feet_and_smpl_defaults():
    p = np.zeros((3, 3, 3))
    m = Motion(p, ["pelvis", "left_ankle", "right_ankle"], 30)
    assert set(detect_contacts(m)) == {"left_ankle", "right_ankle"}
    assert set(detect_contacts(m, feet="left_ankle")) == {"left_ankle"}


@pytest.mark.parametrize(("kwargs", "message"), [
    ({"height": 0}, "height threshold"), ({"height": -0.1}, "height threshold"),
    ({"speed": float("nan")}, "speed threshold"), ({"speed": "slow"}, "speed threshold"),
    ({"feet": ["LeftFot"]}, "closest: \\['LeftFoot'\\]"), ({"feet": []}, "at least one foot"),
])
def test_bad_arguments(kwargs, message):
    with pytest.raises(MotionError, match=message):
        detect_contacts(two_feet(), **kwargs)


def test_no_default_feet():
    m = Motion(np.zeros((2, 1, 3)), ["hand"], 30)
    with pytest.raises(MotionError, match="feet="):
        detect_contacts(m)
