"""Whole robots (robot/robot.py, robot/catalog.py, robot/loading.py): every example-robot-data robot by name, the
active joints of several tips (their union) or of the whole tree, a floating base (its six entries, bounds, the
free-flyer configuration), frames by name with suggestions, fk / jacobian of any frame, and bad input."""

import numpy as np
import pinocchio as pin
import pytest
from urdf_helpers import joint_xml, robot_xml

from evoik_pin.cli import main
from evoik_pin.errors import BoundsError, ConfigurationError, FrameError, RobotLoadError
from evoik_pin.robot import WHOLE_ROBOTS, example_robot_data_dir, list_robots, load_robot
from evoik_pin.robot.frames import find_frame
from evoik_pin.robot.tree import FLOATING_BASE_JOINTS

#: Robots without joints of their own: only a floating base moves them.
FLYING = {"hector", "iris"}


@pytest.mark.parametrize("name", list(WHOLE_ROBOTS))
def test_every_whole_robot_loads_by_name(name, rng):
    path = example_robot_data_dir() / WHOLE_ROBOTS[name].urdf
    model = pin.buildModelFromUrdf(str(path))
    if name in FLYING:
        with pytest.raises(RobotLoadError, match="no movable joint"):
            load_robot(name)
    else:
        robot = load_robot(name)
        # the whole tree: every 1-DOF joint but the mimic ones is an entry of q, in the model's order
        mimics = set(robot.mimic_joints)
        expected = [model.names[j] for j in range(1, model.njoints)
                    if model.joints[j].nv == 1 and model.names[j] not in mimics]
        assert robot.joint_names == expected and robot.tips == (robot.tip,)
        assert robot.model.njoints == model.njoints and not robot.floating_base
        q = robot.random_configurations(1, rng)[0]
        assert robot.full_configuration(q).shape == (model.nq,)
    robot = load_robot(name, floating_base=True)
    assert robot.joint_names[:6] == list(FLOATING_BASE_JOINTS) and robot.floating_base
    assert robot.full_model.nq == model.nq + 7
    if WHOLE_ROBOTS[name].srdf is not None:
        assert robot.srdf is not None and robot.srdf.endswith(".srdf")


def test_list_robots_says_what_each_is(capsys):
    arms = list_robots()
    assert "talos" not in arms and "panda" in arms  # the arms alone, as before
    everything = list_robots(whole=True)
    assert everything[: len(arms)] == arms and {"talos", "g1", "go2", "baxter", "allegro_right"} <= set(everything)
    what = list_robots(whole=True, describe=True)
    assert set(what) == set(everything) and "humanoid" in what["talos"] and "tip panda_hand_tcp" in what["panda"]
    assert main(["robots"]) == 0
    out = capsys.readouterr().out
    assert "talos" in out and "whole robots" in out


def test_tips_make_the_union_of_their_chains(rng):
    baxter = load_robot("baxter", tips=["left_gripper", "right_gripper"])
    assert baxter.n == 14 and baxter.tip == "left_gripper" and baxter.tips == ("left_gripper", "right_gripper")
    assert baxter.joint_names[:7] == [f"left_{j}" for j in ("s0", "s1", "e0", "e1", "w0", "w1", "w2")]
    left = load_robot("baxter", tip="left_gripper")
    assert left.joint_names == baxter.joint_names[:7]
    q = baxter.random_configurations(1, rng)[0]
    # the left chain alone gives the same left gripper pose; the right one is moved by the other seven entries
    assert np.abs(left.fk(q[:7]).homogeneous - baxter.fk(q, "left_gripper").homogeneous).max() < 1e-12
    assert baxter.moving_joints("right_gripper") == baxter.joint_names[7:]
    assert baxter.moving_joints("torso") == []
    J = baxter.jacobian(q, of="right_gripper")
    assert J.shape == (6, 14) and not J[:, :7].any()
    # the PR2's torso lift is shared by both arms
    pr2 = load_robot("pr2", tips=["l_gripper_tool_frame", "r_gripper_tool_frame"])
    assert pr2.joint_names[0] == "torso_lift_joint" and pr2.n == 15
    assert "torso_lift_joint" in pr2.moving_joints("l_gripper_tool_frame")
    assert "torso_lift_joint" in pr2.moving_joints("r_gripper_tool_frame")


def test_whole_robot_narrowed_by_tip_or_joints():
    talos = load_robot("talos", tip="arm_left_7_link")
    assert talos.n == 9 and talos.joint_names[:2] == ["torso_1_joint", "torso_2_joint"]
    legs = load_robot("talos", joints=[f"leg_left_{k}_joint" for k in range(1, 7)])
    assert legs.n == 6 and legs.model.njoints - 1 == 6


def test_fk_and_jacobian_of_any_frame_equal_pinocchio(rng):
    robot = load_robot("talos", floating_base=True)
    model = pin.buildModelFromUrdf(str(robot.urdf_path), pin.JointModelFreeFlyer())
    data = model.createData()
    for q in robot.random_configurations(3, rng):
        pin.framesForwardKinematics(model, data, robot.full_configuration(q))
        for f in ("left_sole_link", "arm_right_7_joint", "gripper_left_base_link", "base_link"):
            assert np.abs(robot.fk(q, frame=f).homogeneous - data.oMf[find_frame(model, f)].homogeneous).max() < 1e-12
        # the Jacobian in q's coordinates: finite differences of fk (the base's yaw-pitch-roll included)
        J = robot.jacobian(q, "world", of="left_sole_link")
        h = 1e-6
        for k in range(robot.n):
            dq = np.zeros(robot.n)
            dq[k] = h
            Tp, Tm = robot.fk(q + dq, "left_sole_link"), robot.fk(q - dq, "left_sole_link")
            assert np.abs((Tp.translation - Tm.translation) / (2 * h) - J[:3, k]).max() < 1e-7
            assert np.abs(pin.log3(Tp.rotation @ Tm.rotation.T) / (2 * h) - J[3:, k]).max() < 1e-7
        Jl = robot.jacobian(q, "local", of="left_sole_link")
        R = robot.fk(q, "left_sole_link").rotation
        assert np.abs(R @ Jl[:3] - J[:3]).max() < 1e-12


def test_the_tip_stays_the_default_frame(rng):
    panda = load_robot("panda")
    q = panda.random_configurations(1, rng)[0]
    assert panda.fk(q) == panda.fk(q, frame="panda_hand_tcp")
    assert np.array_equal(panda.jacobian(q), panda.jacobian(q, of="panda_hand_tcp"))
    assert "panda_link3" in panda.frames and "universe" not in panda.frames
    # a frame off the chain, where the model locked it (the fingers)
    assert panda.moving_joints("panda_leftfinger") == panda.joint_names


def test_floating_base_bounds_and_base_box():
    robot = load_robot("go2", floating_base=True, base_box=0.25)
    assert np.allclose(robot.lower[:3], -0.25) and np.allclose(robot.upper[:3], 0.25)
    robot = load_robot("go2", floating_base=True, base_box=([0, -1, 0.2], [2, 1, 0.5]))
    assert np.allclose(robot.lower[:3], [0, -1, 0.2]) and np.allclose(robot.upper[:3], [2, 1, 0.5])
    lower, upper = robot.lower.copy(), robot.upper.copy()
    upper[2] = 0.8
    robot.set_bounds(lower, upper)
    assert robot.upper[2] == 0.8
    with pytest.raises(BoundsError, match="floating_base=True"):
        load_robot("go2", base_box=0.5)
    with pytest.raises(BoundsError, match="base_box"):
        load_robot("go2", floating_base=True, base_box="wide")
    with pytest.raises(BoundsError, match="inverted"):
        load_robot("go2", floating_base=True, base_box=([0, 0, 0], [-1, 1, 1]))


def test_bad_frames_and_floating_bases():
    robot = load_robot("baxter")
    q = np.zeros(robot.n)
    with pytest.raises(FrameError, match=r"no frame 'left_grip' \(closest: left_gripper"):
        robot.fk(q, frame="left_grip")
    with pytest.raises(FrameError, match="closest: left_gripper"):
        robot.jacobian(q, of="left_grip")
    with pytest.raises(ConfigurationError, match="'world' or 'local'"):
        robot.jacobian(q, "left_gripper")
    with pytest.raises(FrameError, match=r"unknown tip frame 'right_grip' \(closest: right_gripper"):
        load_robot("baxter", tips=["left_gripper", "right_grip"])
    with pytest.raises(FrameError, match="non-empty list"):
        load_robot("baxter", tips=[])
    with pytest.raises(FrameError, match="list of frame names"):
        load_robot("baxter", tips="left_gripper")
    with pytest.raises(FrameError, match="no base frame can be chosen"):
        load_robot("talos", base="torso_2_link", floating_base=True)
    free = robot_xml("free", ["world", "base", "l1"], [
        '<joint name="free" type="floating"><parent link="world"/><child link="base"/></joint>',
        joint_xml("j1", "revolute", "base", "l1")])
    with pytest.raises(RobotLoadError, match="root already moves.*'free'"):
        load_robot(free, base="base", tip="l1", floating_base=True)
