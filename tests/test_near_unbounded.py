"""Near-unbounded joints (a mobile base's virtual joints with limits like +-999999): searched within a box around
the target, the robot's nominal limits kept (problem.py's target_box, IKProblem's default box)."""

import numpy as np
import pytest

import evoik_pin as ev
from evoik_pin.problem import NEAR_UNBOUNDED, IKProblem, Target, target_box
from evoik_pin.robot import load_robot

LIMIT = '<limit lower="{lo}" upper="{hi}" effort="1" velocity="1"/>'


def _joint(name, kind, parent, child, axis, lo, hi, xyz="0 0 0"):
    return (f'<joint name="{name}" type="{kind}"><parent link="{parent}"/><child link="{child}"/>'
            f'<origin xyz="{xyz}"/><axis xyz="{axis}"/>{LIMIT.format(lo=lo, hi=hi)}</joint>')


def _arm(base_joints: list[str], big: float = 999999.0) -> str:
    """A mobile base (``base_joints``: "x", "y" prismatic, "yaw" revolute, "fwd" prismatic along its x,
    each limited to +-big) carrying a 3R arm (0.4 m, 0.3 m, 0.1 m tool)."""
    specs = {"x": ("prismatic", "1 0 0"), "y": ("prismatic", "0 1 0"), "yaw": ("revolute", "0 0 1"),
             "fwd": ("prismatic", "1 0 0")}
    links, joints, parent = ['<link name="world"/>'], [], "world"
    for name in base_joints:
        kind, axis = specs[name]
        links.append(f'<link name="{name}_link"/>')
        joints.append(_joint(name, kind, parent, f"{name}_link", axis, -big, big))
        parent = f"{name}_link"
    for k, (axis, xyz) in enumerate([("0 0 1", "0 0 0.2"), ("0 1 0", "0 0 0.1"), ("0 1 0", "0.4 0 0")]):
        links.append(f'<link name="a{k}"/>')
        joints.append(_joint(f"a{k}", "revolute", parent, f"a{k}", axis, -2.5, 2.5, xyz))
        parent = f"a{k}"
    links.append('<link name="tool"/>')
    joints.append(f'<joint name="tool_joint" type="fixed"><parent link="{parent}"/><child link="tool"/>'
                  '<origin xyz="0.3 0 0"/></joint>')
    return f'<robot name="base_arm">{"".join(links)}{"".join(joints)}</robot>'


def _targets(robot, count, seed=0):
    """Targets of configurations drawn within the nominal limits, the near-unbounded ones within +-5e5 of them: the
    API refuses targets beyond MAX_TARGET_NORM (1e6 m) from the base, which two +-999999 m joints can exceed."""
    lower = np.maximum(robot.lower, -5e5)
    upper = np.minimum(robot.upper, 5e5)
    Q = np.random.default_rng(seed).uniform(lower, upper, size=(count, robot.n))
    return Q, [robot.fk(q) for q in Q]


@pytest.mark.parametrize("base", [["x", "y", "yaw"], ["yaw", "fwd"], ["x", "y"]])
def test_far_targets_of_a_mobile_base_are_solved_within_the_nominal_limits(base):
    robot = load_robot(_arm(base))
    assert np.all(np.abs(robot.lower[: len(base)]) == 999999.0)  # the robot keeps its nominal limits
    Q, targets = _targets(robot, 6)
    assert np.abs(Q[:, : len(base)]).max() > 1e5  # targets hundreds of km away
    for i, T in enumerate(targets):
        res = ev.solve(robot, T, seed=i, timeout=None, max_restarts=3)  # a budget the clock does not change
        assert res.success, (i, res.message)
        assert robot.within_bounds(res.q)
        assert np.allclose(robot.fk(res.q).homogeneous, T.homogeneous, atol=1e-5)


def test_the_box_is_around_the_target():
    robot = load_robot(_arm(["x", "y", "yaw"]))
    q = np.array([5000.0, -300.0, 1.0, 0.3, -0.4, 0.5])
    problem = IKProblem(robot, robot.fk(q))
    lo, hi = problem.lower, problem.upper
    assert np.all(lo[:2] < q[:2]) and np.all(q[:2] < hi[:2]) and np.all(hi[:2] - lo[:2] < 10.0)
    assert np.allclose([lo[2], hi[2]], [-np.pi, np.pi])  # one turn of the yaw joint: every heading
    assert np.array_equal(lo[3:], robot.lower[3:]) and np.array_equal(hi[3:], robot.upper[3:])
    assert np.all(robot.lower[:3] == -999999.0)  # the robot's own bounds are untouched


def test_given_bounds_are_used_as_given():
    robot = load_robot(_arm(["x", "y", "yaw"]))
    q = np.array([40.0, 2.0, 0.5, 0.3, -0.4, 0.5])
    lower, upper = robot.lower.copy(), robot.upper.copy()
    lower[:2], upper[:2] = [30.0, -5.0], [50.0, 5.0]
    problem = IKProblem(robot, robot.fk(q), lower=lower, upper=upper)
    assert np.array_equal(problem.lower, lower) and np.array_equal(problem.upper, upper)
    res = ev.solve(robot, robot.fk(q), bounds=(lower, upper), seed=1, timeout=None, max_restarts=3)
    assert res.success and np.all(res.q >= lower) and np.all(res.q <= upper)


def test_the_threshold_and_bounded_robots():
    below = load_robot(_arm(["x"], big=NEAR_UNBOUNDED * 0.999))
    target = Target.coerce(below.fk(np.zeros(below.n)))
    lo, hi = target_box(below, target, below.lower, below.upper)
    assert np.array_equal(lo, below.lower) and np.array_equal(hi, below.upper)  # not near-unbounded: kept
    at = load_robot(_arm(["x"], big=NEAR_UNBOUNDED))
    lo, hi = target_box(at, target, at.lower, at.upper)
    assert hi[0] - lo[0] < 10.0
    panda = load_robot("panda")
    problem = IKProblem(panda, panda.fk(np.zeros(7) + 0.1))
    assert np.array_equal(problem.lower, panda.lower) and np.array_equal(problem.upper, panda.upper)


def test_a_target_box_outside_one_sided_limits_stays_inside_them():
    robot = load_robot(_arm(["x"]).replace('lower="-999999.0"', 'lower="0"', 1))
    target = Target.coerce(robot.fk(np.array([0.0, 0.1, 0.2, 0.3])))
    far_behind = Target(position=target.position - [5000.0, 0, 0], rotation=target.rotation)
    lo, hi = target_box(robot, far_behind, robot.lower, robot.upper)
    assert lo[0] == hi[0] == 0.0  # the nearest the joint's limits allow


def test_a_mimic_finger_off_the_tip_chain_does_not_break_the_box():
    """A mobile base carrying an arm whose gripper's second finger mimics the first, the tip on the first (rtb-data's
    frankie_arm_hand: the tree has one physical joint more than the base->tip chain): target_box read the tree's
    joint ranges against the chain's joints and raised a broadcasting ValueError on the first solve."""
    arm = _arm(["x", "y"])
    fingers = (
        '<link name="fa"/><link name="fb"/>'
        '<joint name="fa_joint" type="prismatic"><parent link="tool"/><child link="fa"/><origin xyz="0 0.02 0"/>'
        '<axis xyz="0 1 0"/><limit lower="0" upper="0.04" effort="1" velocity="1"/></joint>'
        '<joint name="fb_joint" type="prismatic"><parent link="tool"/><child link="fb"/><origin xyz="0 -0.02 0"/>'
        '<axis xyz="0 -1 0"/><limit lower="0" upper="0.04" effort="1" velocity="1"/><mimic joint="fa_joint"/></joint>')
    robot = load_robot(arm.replace("</robot>", fingers + "</robot>"), tip="fa")
    assert robot.n == 6  # x, y, the 3R arm and the driving finger; the mimic finger follows it
    Q, targets = _targets(robot, 3, seed=4)
    for i, T in enumerate(targets):
        lower, upper = target_box(robot, Target.coerce(T), robot.lower, robot.upper)
        assert np.all(lower <= upper) and np.all(robot.lower <= lower) and np.all(upper <= robot.upper)
        res = ev.solve(robot, T, seed=i, timeout=None, max_restarts=3)
        assert res.success, (i, res.message)
        assert np.allclose(robot.fk(res.q).homogeneous, T.homogeneous, atol=1e-5)


@pytest.mark.parametrize("base", [["x", "y", "yaw"], ["yaw", "fwd"], ["x", "y"]])
def test_random_configurations_are_ones_the_library_solves_for(base):
    """rtb-data's ridgeback: random_configurations drew the base's +-999999 m joints anywhere in their range, so
    solve(robot, robot.fk(q)) of the library's own random configuration was refused as out of reach (1.16e6 m)."""
    robot = load_robot(_arm(base))
    lower, upper = robot.sampling_box()
    assert np.all(robot.lower <= lower) and np.all(upper <= robot.upper)
    assert np.abs(np.concatenate([lower, upper])).max() < 10.0  # reach 1.0 m: +-(2 R + 0.1) m, one turn
    Q = robot.random_configurations(8, np.random.default_rng(3))
    assert np.all((lower <= Q) & (Q <= upper))
    for i, q in enumerate(Q):
        T = robot.fk(q)
        res = ev.solve(robot, T, seed=i)
        assert res.success, (i, res.message)
        assert np.allclose(robot.fk(res.q).homogeneous, T.homogeneous, atol=1e-5)


def test_bounded_robots_draw_from_their_bounds_as_before():
    robot = load_robot("ur5")
    lower, upper = robot.sampling_box()
    assert np.array_equal(lower, robot.lower) and np.array_equal(upper, robot.upper)
    expected = np.random.default_rng(7).uniform(robot.lower, robot.upper, size=(4, robot.n))
    assert np.array_equal(robot.random_configurations(4, np.random.default_rng(7)), expected)
