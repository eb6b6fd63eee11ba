"""Whole robots loaded from a file or a string (robot/loading.py, robot/frames.py ``is_branched``): a URDF whose
joints branch gets its whole tree, as the same robot by name does; a serial chain keeps the chain to its tip; and
a goal on a frame only the floating base moves while the joints to it are locked is a LockedJointsError
(goals/binding.py, ``Robot.locked_joints``) naming them and how to free them."""

import numpy as np
import pinocchio as pin
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from urdf_helpers import gripper, joint_xml, robot_xml

import evoik_pin
from evoik_pin.errors import EvoikError, FrameError, LockedJointsError
from evoik_pin.goals import Pose, bind
from evoik_pin.robot import EXAMPLE_ARMS, WHOLE_ROBOTS, bundled_robots_dir, example_robot_data_dir, load_robot
from evoik_pin.robot.frames import deepest_body, is_branched
from evoik_pin.robot.joints import couplings

#: The goal frames of a standing humanoid: both soles and both grippers.
TALOS_GOALS = ("left_sole_link", "right_sole_link", "gripper_left_base_link", "gripper_right_base_link")


def _path(name: str):
    return example_robot_data_dir() / WHOLE_ROBOTS[name].urdf


@pytest.fixture(scope="module")
def talos_file():
    """Talos from its file path (the URDF "talos" names), with a floating base and no tip: the issue's trap."""
    return load_robot(_path("talos"), floating_base=True)


@pytest.mark.parametrize("name, floating", [("talos", True), ("talos_full", True), ("g1", True), ("solo12", True),
                                            ("solo12", False)])
def test_a_whole_robot_file_activates_the_tree_it_does_by_name(name, floating):
    from_file = load_robot(_path(name), floating_base=floating)
    by_name = load_robot(name, floating_base=floating)
    assert from_file.joint_names == by_name.joint_names and from_file.n == by_name.n
    assert from_file.tip == by_name.tip == deepest_body(by_name.full_model)  # the default frame: the same rule
    # every joint of the URDF is an entry of q or follows one (mimic joints)
    model = pin.buildModelFromUrdf(str(_path(name)))
    assert set(from_file.joint_names[6 if floating else 0:]) | set(from_file.mimic_joints) == set(model.names[1:])
    # as a string too: the same text, the same tree
    assert load_robot(from_file.urdf_xml, floating_base=floating).joint_names == by_name.joint_names


def test_the_issue_case_talos_full_had_16_of_38_joints():
    """load_robot(".../talos_full...urdf", floating_base=True) activated one chain towards a gripper finger."""
    robot = load_robot(_path("talos_full"), floating_base=True)
    chain = load_robot(_path("talos_full"), tip=robot.tip, floating_base=True)  # what it was: the deepest link's
    assert chain.n < robot.n
    for frame in ("left_sole_link", "right_sole_link", "arm_left_7_link"):
        assert set(robot.moving_joints(frame)) - set(robot.joint_names[:6]), frame  # joints below the base move it
        assert robot.locked_joints(frame) == []


def test_talos_from_its_file_meets_goals_on_both_soles_and_both_grippers(talos_file):
    robot = talos_file
    by_name = load_robot("talos", floating_base=True)  # the goals of a posture of the whole robot
    q_true = by_name.random_configurations(1, np.random.default_rng(7))[0]
    goals = [Pose(frame, by_name.fk(q_true, frame)) for frame in TALOS_GOALS]
    result = evoik_pin.solve(robot, goals, seed=0)
    assert result.success, result
    for frame, goal in zip(TALOS_GOALS, goals, strict=True):
        reached = robot.fk(result.q, frame)
        assert np.linalg.norm(reached.translation - goal.target.translation) < 1e-6, frame
        assert np.linalg.norm(pin.log3(reached.rotation.T @ goal.target.rotation)) < 1e-6, frame


def test_a_goal_only_the_floating_base_moves_names_the_locked_joints(talos_file):
    q = np.zeros(talos_file.n)
    sole = Pose("right_sole_link", talos_file.fk(q, "right_sole_link"))
    left = load_robot(_path("talos"), tip="gripper_left_base_link", floating_base=True)  # one chain: left arm
    assert left.moving_joints("right_sole_link") == left.joint_names[:6]  # the base moves it, nothing else does
    right_leg = [f"leg_right_{k}_joint" for k in range(1, 7)]
    assert left.locked_joints("right_sole_link") == right_leg
    with pytest.raises(LockedJointsError) as info:
        evoik_pin.solve(left, [Pose("gripper_left_base_link", left.fk(np.zeros(left.n), "gripper_left_base_link")),
                               sole], seed=0)
    message = str(info.value)
    assert all(joint in message for joint in right_leg) and "'right_sole_link'" in message
    assert "tips=['gripper_left_base_link', 'right_sole_link']" in message
    assert "joints=[...]" in message and "tips='all'" in message
    assert isinstance(info.value, FrameError) and isinstance(info.value, EvoikError)
    # following the advice: the chains to both frames free the leg
    both = load_robot(_path("talos"), tips=["gripper_left_base_link", "right_sole_link"], floating_base=True)
    assert set(right_leg) <= set(both.joint_names) and both.locked_joints("right_sole_link") == []
    bind(both, [sole])
    # joints=[...] narrowing a whole tree locks the rest the same way
    arms = load_robot(_path("talos"), floating_base=True,
                      joints=[*left.joint_names[:6], *(j for j in left.joint_names if j.startswith("arm_left"))])
    with pytest.raises(LockedJointsError, match="leg_right_6_joint"):
        bind(arms, [sole])


def test_frames_the_base_alone_should_move_stay_goals(talos_file):
    left = load_robot(_path("talos"), tip="gripper_left_base_link", floating_base=True)
    base = Pose("base_link", left.fk(np.zeros(left.n), "base_link"))  # only fixed joints between the root and it
    assert left.moving_joints("base_link") == left.joint_names[:6] and left.locked_joints("base_link") == []
    bind(left, [base])
    # joints the caller fixed at values (Robot.locked, solve's locked=) are placed on purpose: the base may carry them
    leg = {f"leg_right_{k}_joint": 0.0 for k in range(1, 7)}
    standing = talos_file.locked(leg)
    assert standing.locked_joints("right_sole_link") == list(leg)
    bind(standing, [Pose("right_sole_link", talos_file.fk(np.zeros(talos_file.n), "right_sole_link"))])


def test_without_a_floating_base_the_locked_branch_is_the_old_frame_error():
    left = load_robot(_path("talos"), tip="gripper_left_base_link")
    with pytest.raises(FrameError, match="no active joint of talos_reduced moves frame 'right_sole_link'") as info:
        bind(left, [Pose("right_sole_link", left.fk(np.zeros(left.n), "right_sole_link"))])
    assert not isinstance(info.value, LockedJointsError)


def test_serial_chain_files_keep_the_chain_to_their_tip():
    puma = load_robot(bundled_robots_dir() / "puma3r.urdf")  # README: any URDF file; default tip its deepest link
    assert puma.tip == deepest_body(puma.full_model) and puma.tips == (puma.tip,)
    assert puma.joint_names == load_robot("puma3r").joint_names
    ur5 = example_robot_data_dir() / EXAMPLE_ARMS["ur5"].urdf
    assert load_robot(ur5, tip="tool0").joint_names == load_robot("ur5").joint_names
    # a gripper whose second finger mimics the first is a chain: the deepest fingertip's, the driver folded in
    panda = load_robot(example_robot_data_dir() / EXAMPLE_ARMS["panda"].urdf)
    assert panda.tip in ("panda_leftfinger", "panda_rightfinger") and panda.n == 8
    assert not is_branched(panda.full_model, couplings(panda.full_model, {"panda_finger_joint2":
                                                                              ("panda_finger_joint1", 1.0, 0.0)}))
    g = load_robot(gripper())
    assert g.joint_names == ["wrist", "finger_a"] and g.mimic_joints == {"finger_b": ("finger_a", -0.5, 0.01)}


def test_a_tip_given_still_picks_one_chain_of_a_tree():
    arm = load_robot(_path("talos"), tip="arm_left_7_link")
    assert arm.joint_names == load_robot("talos", tip="arm_left_7_link").joint_names and arm.n == 9


def test_fingers_moving_on_their_own_are_branches():
    def hand(mimic):
        return robot_xml("hand", ["base", "palm", "fa", "fb"], [
            joint_xml("wrist", "revolute", "base", "palm", xyz="0 0 0.1"),
            joint_xml("finger_a", "prismatic", "palm", "fa", xyz="0 0.02 0.05", axis="0 1 0", lo=0, hi=0.04),
            joint_xml("finger_b", "prismatic", "palm", "fb", xyz="0 -0.02 0.05", axis="0 -1 0", lo=0, hi=0.04,
                      mimic=("finger_a", 1.0, 0.0) if mimic else None)])
    assert load_robot(hand(mimic=False)).joint_names == ["wrist", "finger_a", "finger_b"]  # both fingers free
    assert load_robot(hand(mimic=True)).joint_names == ["wrist", "finger_a"]


@st.composite
def _trees(draw):
    """A random URDF tree: link i > 0 hangs from an earlier link by a revolute, prismatic or fixed joint."""
    count = draw(st.integers(2, 9))
    parents = [draw(st.integers(0, i - 1)) for i in range(1, count)]
    kinds = [draw(st.sampled_from(["revolute", "revolute", "prismatic", "fixed"])) for _ in parents]
    if all(k == "fixed" for k in kinds):
        kinds[draw(st.integers(0, len(kinds) - 1))] = "revolute"
    joints = [joint_xml(f"j{i + 1}", kind, f"l{p}", f"l{i + 1}", xyz="0.1 0 0.05")
              for i, (p, kind) in enumerate(zip(parents, kinds, strict=True))]
    return robot_xml("tree", [f"l{i}" for i in range(count)], joints), kinds


@settings(max_examples=60, deadline=None, database=None)
@given(_trees())
def test_property_without_a_tip_a_urdf_gets_every_joint_and_a_tree_is_one_no_chain_covers(tree):
    xml, kinds = tree
    robot = load_robot(xml)
    movable = [f"j{i + 1}" for i, kind in enumerate(kinds) if kind != "fixed"]
    assert sorted(robot.joint_names) == sorted(movable)  # a chain to the deepest link, or the whole tree
    model = robot.full_model
    chain = {model.names[j] for j in model.supports[model.frames[model.getFrameId(robot.tip)].parentJoint][1:]}
    assert is_branched(model, {}) == (chain != set(movable))  # branched: no chain to one link holds every joint
