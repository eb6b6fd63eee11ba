"""A retargeted clip leaves at rest the joints no mapped frame depends on and whose URDF gives no speed (Romeo's
hands: velocity="0"), and only those: G1's wrists past the mapped hand frames keep their freedom."""

import numpy as np

import evoik_pin as ek
from evoik_pin.motion import load_clip, mapping_preset
from evoik_pin.robot.velocity_limits import without_urdf_speed


def test_romeos_hands_stay_at_rest_through_a_walk():
    romeo = ek.load_robot("romeo", floating_base=True)
    idle = without_urdf_speed(romeo)
    assert [j for j, x in zip(romeo.joint_names, idle, strict=True) if x] == ["LHand", "RHand"]
    clip = ek.retarget(romeo, load_clip("walk"), mapping="cmu")
    assert np.ptp(clip.q[:, idle], axis=0).max() == 0.0  # they moved at 2.5 rad/s before
    assert np.ptp(clip.q[:, ~idle][:, 6:], axis=0).max() > 0.1  # the rest of the body does walk


def test_only_joints_without_a_urdf_speed_are_held():
    g1 = ek.load_robot("g1", floating_base=True)
    moving = set().union(*(g1.moving_joints(f) for f in mapping_preset("cmu", "g1")))
    assert "left_wrist_yaw_joint" not in moving  # past the mapped hand frame, yet with a URDF speed: free
    assert not without_urdf_speed(g1).any()
