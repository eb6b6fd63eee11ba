"""Mimic joints (robot/robot.py, robot/urdf_checks.py): one entry of q per independent degree of freedom,
the coupled joints in FK, batch FK, Jacobians (chain rule), the compiled chain and LM kernel, bounds, and the
URDFs whose couplings cannot hold."""

import warnings

import numpy as np
import pytest
from kernel_helpers import compiled_frames
from urdf_helpers import gripper, joint_xml, mimic_3r, robot_xml, yourdfpy_pose

import evoik_pin as ev
from evoik_pin.errors import FrameError, RobotLoadError, RobotLoadWarning
from evoik_pin.problem import IKProblem, Target
from evoik_pin.robot import load_robot
from evoik_pin.solvers.lm import LevenbergMarquardt, solve_pairs
from evoik_pin.solvers.lm.reference import ReferenceLM

ARMS = {
    "3r": (mimic_3r(), "tool"),  # j3 = 2 j2 + 0.1 on the chain
    "gripper": (gripper(), "fb_tip"),  # finger_b = -0.5 finger_a + 0.01, finger_a off the chain
    "gripper_sorted": (gripper("z_driver", "a_follower"), "fb_tip"),  # the follower comes first in joint order
    "panda_finger": ("panda", "panda_rightfinger"),  # panda_finger_joint2 mimics panda_finger_joint1
}


@pytest.fixture(scope="module", params=list(ARMS))
def arm(request):
    source, tip = ARMS[request.param]
    return load_robot(source, tip=tip)


def test_one_entry_per_independent_joint():
    robot = load_robot(mimic_3r(), tip="tool")
    assert robot.n == 2 and robot.joint_names == ["j1", "j2"]
    assert robot.mimic_joints == {"j3": ("j2", 2.0, 0.1)}
    assert robot.model.nv == 3  # the physical chain keeps j3
    g = load_robot(gripper(), tip="fb_tip")
    assert g.joint_names == ["wrist", "finger_a"] and g.mimic_joints == {"finger_b": ("finger_a", -0.5, 0.01)}
    assert list(g.revolute) == [True, False]


def test_fk_equals_yourdfpy(arm, rng):
    for q in arm.random_configurations(10, rng):
        T = arm.fk(q).homogeneous
        assert np.abs(T - yourdfpy_pose(arm, q)).max() < 1e-9


def test_coupled_value_reaches_pinocchio():
    robot = load_robot(mimic_3r(), tip="tool")
    q = np.array([0.3, -0.4])
    x = robot.to_pinocchio(q)
    assert np.allclose(x, [0.3, -0.4, 2 * -0.4 + 0.1])
    assert np.allclose(robot.from_pinocchio(x), q)
    full = robot.full_configuration(q)
    assert np.allclose(full, x)


def test_batches_and_jacobians_include_the_coupling(arm, rng):
    Q = arm.random_configurations(12, rng)
    P, R = arm.fk_batch(Q)
    p2, R2, J = arm.fk_jacobian_batch(Q)
    assert np.abs(arm.positions_batch(Q) - P).max() < 1e-12
    eps = 1e-6
    for i, q in enumerate(Q):
        T = arm.fk(q)
        assert np.abs(P[i] - T.translation).max() < 1e-12 and np.abs(R[i] - T.rotation).max() < 1e-12
        Jw = arm.jacobian(q, "world")
        assert Jw.shape == (6, arm.n) and np.abs(J[i] - Jw).max() < 1e-12
        fd = np.empty((3, arm.n))
        for k in range(arm.n):
            dq = np.zeros(arm.n)
            dq[k] = eps
            fd[:, k] = (arm.fk(q + dq).translation - arm.fk(q - dq).translation) / (2 * eps)
        assert np.abs(Jw[:3] - fd).max() < 1e-7
        Jl = arm.jacobian_local_unchecked(q)
        assert np.abs(Jl - arm.jacobian(q, "local")).max() < 1e-12


def test_compiled_chain_with_coupling(arm, rng):
    FR, Fp, rev = arm.chain_constants()
    index, scale, offset = arm.chain_coupling()
    m = FR.shape[0] - 1
    assert index.dtype == np.int64 and index.shape == scale.shape == offset.shape == rev.shape == (m,)
    for q in arm.random_configurations(5, rng):
        ((R, p, J),) = compiled_frames(arm, q, [arm.tip])
        T = arm.fk(q)
        assert np.abs(R - T.rotation).max() < 1e-12 and np.abs(p - T.translation).max() < 1e-12
        assert np.abs(J - arm.jacobian(q, "world")).max() < 1e-12


def test_kernel_runs_equal_the_python_loop_on_mimic_chains(arm):
    rng = np.random.default_rng(5)
    same = converged = 0
    for _ in range(15):
        qt, q0 = arm.random_configurations(2, rng)
        problem = IKProblem(arm, Target(arm.fk(qt).translation))
        a = LevenbergMarquardt(problem).run(q0, 40)
        b = ReferenceLM(problem).run(q0, 40)
        same += a.iterations == b.iterations and np.allclose(a.q, b.q, atol=1e-8)
        converged += a.converged
        assert a.converged == b.converged and arm.within_bounds(a.q)
    assert same >= 13 and converged >= 5
    out = solve_pairs(arm, arm.random_configurations(4, rng), [Target(arm.fk(q).translation) for q in
                                                             arm.random_configurations(4, rng)],
                      arm.lower, arm.upper, 1e-9, 1e-9)
    assert out.q.shape == (4, arm.n)


def test_solve_keeps_the_coupling(arm):
    rng = np.random.default_rng(11)
    for q in arm.random_configurations(3, rng):
        T = arm.fk(q)
        r = ev.solve(arm, T, seed=0, timeout=None, max_restarts=20)
        assert r.success and arm.within_bounds(r.q, 1e-12)
        assert np.abs(yourdfpy_pose(arm, r.q) - T.homogeneous).max() < 1e-5


def test_bounds_keep_every_mimic_joint_inside_its_limits():
    robot = load_robot(mimic_3r(lower3=-1.0, upper3=2.0), tip="tool")
    # j2 in [-2, 2] and j3 = 2 j2 + 0.1 in [-1, 2]  ->  j2 in [-0.55, 0.95]
    assert np.allclose(robot.lower, [-3, -0.55]) and np.allclose(robot.upper, [3, 0.95])
    g = load_robot(gripper(), tip="fb_tip")  # finger_b = -0.5 finger_a + 0.01 in [-0.03, 0.05]: finger_a <= 0.08
    assert np.allclose(g.lower, [-3, 0.0]) and np.allclose(g.upper, [3, 0.04])
    with pytest.raises(RobotLoadError, match="no value of 'j2'.*limits"):
        load_robot(mimic_3r(offset=10.0), tip="tool")


def test_continuous_and_mixed_mimic_joints(rng):
    xml = robot_xml("mixed", ["b", "l1", "l2", "l3", "t"], [
        joint_xml("c1", "continuous", "b", "l1", axis="0 0 1"),
        joint_xml("r2", "revolute", "l1", "l2", xyz="0.3 0 0", axis="0 1 0", mimic=("c1", 0.5, 0.2)),
        joint_xml("c3", "continuous", "l2", "l3", xyz="0.2 0 0", axis="1 0 0", mimic=("c1", -1.0, 0.0)),
        joint_xml("p4", "prismatic", "l3", "t", xyz="0.1 0 0", axis="1 0 0", lo=0, hi=0.2, mimic=("c1", 0.05, 0.1)),
    ])
    robot = load_robot(xml)
    assert robot.n == 1 and robot.continuous.tolist() == [True]
    for q in robot.random_configurations(6, rng):
        assert np.abs(robot.fk(q).homogeneous - yourdfpy_pose(robot, q)).max() < 1e-9
        assert np.abs(robot.positions_batch(q[None])[0] - robot.fk(q).translation).max() < 1e-12


def test_mimic_of_a_mimic_is_resolved_to_its_driver():
    xml = robot_xml("cascade", ["b", "l1", "l2", "l3", "t"], [
        joint_xml("j1", "revolute", "b", "l1", axis="0 0 1"),
        joint_xml("j2", "revolute", "l1", "l2", xyz="0.3 0 0", axis="0 1 0", mimic=("j1", 2.0, 0.1), lo=-9, hi=9),
        joint_xml("j3", "revolute", "l2", "l3", xyz="0.2 0 0", axis="0 1 0", mimic=("j2", 0.5, -0.3), lo=-9, hi=9),
        joint_xml("jt", "fixed", "l3", "t", xyz="0.1 0 0"),
    ])
    robot = load_robot(xml)
    assert robot.joint_names == ["j1"]
    assert robot.mimic_joints["j3"] == pytest.approx(("j1", 1.0, 0.5 * 0.1 - 0.3))
    assert np.allclose(robot.to_pinocchio([0.4]), [0.4, 0.9, 0.5 * 0.9 - 0.3])


def test_joints_subset_names_drivers_and_locks_their_followers():
    robot = load_robot(mimic_3r(), tip="tool", joints=["j1"])  # j2 locked at 0, so j3 sits at 0.1
    assert robot.joint_names == ["j1"] and robot.mimic_joints == {}
    q = np.array([0.2])
    assert np.abs(robot.fk(q).homogeneous - load_robot(mimic_3r(), tip="tool").fk([0.2, 0.0]).homogeneous).max() < 1e-12
    with pytest.raises(FrameError, match="'j3' mimics 'j2'"):
        load_robot(mimic_3r(), tip="tool", joints=["j1", "j3"])


def test_a_mimic_following_a_joint_above_the_base_is_locked():
    xml = mimic_3r().replace('<joint name="jt" type="fixed"><parent link="l3"/><child link="tool"/>',
                             '<joint name="j4" type="revolute"><parent link="l3"/><child link="tool"/>'
                             '<axis xyz="0 0 1"/><limit lower="-1" upper="1" effort="1" velocity="1"/>')
    full = load_robot(xml, tip="tool")
    robot = load_robot(xml, base="l2", tip="tool")  # j2 is above the base, locked at 0: j3 = 2 * 0 + 0.1
    assert full.joint_names == ["j1", "j2", "j4"] and robot.joint_names == ["j4"] and robot.mimic_joints == {}
    base = full.fk([0.0, 0.0, 0.0]).homogeneous @ np.linalg.inv(robot.fk([0.0]).homogeneous)  # l2 in the root
    for v in (-0.5, 0.7):
        assert np.allclose(robot.fk([v]).homogeneous, yourdfpy_pose(robot, [v]), atol=1e-9)
        assert np.allclose(base @ robot.fk([v]).homogeneous, full.fk([0.0, 0.0, v]).homogeneous, atol=1e-12)
    with pytest.raises(RobotLoadError, match="no movable joint"):
        load_robot(mimic_3r(), base="l2", tip="tool")  # only j3 on that chain, and it is constant


def test_broken_mimic_tags():
    with pytest.warns(RobotLoadWarning, match="mimics 'nope', which is no joint of the file"):
        robot = load_robot(mimic_3r().replace('mimic joint="j2"', 'mimic joint="nope"'), tip="tool")
    assert robot.n == 3  # j3 loads as an independent joint
    with pytest.warns(RobotLoadWarning, match="a fixed joint"):
        load_robot(mimic_3r().replace('mimic joint="j2"', 'mimic joint="jt"'), tip="tool")
    with pytest.raises(RobotLoadError, match="mimics itself"):
        load_robot(mimic_3r().replace('mimic joint="j2"', 'mimic joint="j3"'), tip="tool")
    with pytest.raises(RobotLoadError, match="multiplier of joint 'j3'"):
        load_robot(mimic_3r(multiplier="x"), tip="tool")
    cycle = robot_xml("cycle", ["b", "l1", "l2"], [
        joint_xml("j1", "revolute", "b", "l1", mimic=("j2", 1, 0)),
        joint_xml("j2", "revolute", "l1", "l2", mimic=("j1", 1, 0)),
    ])
    with pytest.raises(RobotLoadError, match="mimic joints form a cycle: j1 -> j2 -> j1"):
        load_robot(cycle)
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # a mimic on a fixed joint means nothing: no warning
        load_robot(mimic_3r().replace('<origin xyz="0.1 0 0.02"', '<mimic joint="j1"/><origin xyz="0.1 0 0.02"'),
                   tip="tool")


@pytest.mark.parametrize("make", [mimic_3r, gripper])
def test_skeleton_of_a_mimic_chain_without_visuals(make):
    # a chain with a mimic joint on it has more physical joints than entries of q: the skeleton (drawn for URDFs
    # without <visual>) iterates the physical ones, with their travel
    from evoik_pin.viz import skeleton_model

    robot = load_robot(make(), tip="tool" if make is mimic_3r else "fb_tip")
    geom = skeleton_model(robot)
    revolute, axes, lower, upper = robot.chain_joints()
    assert len(revolute) == robot.model.njoints - 1 > robot.n or make is gripper
    names = {o.name for o in geom.geometryObjects}
    assert {f"skeleton_{robot.model.names[j]}" for j in range(1, robot.model.njoints)} <= names
    assert ("skeleton_rail_finger_b" in names) == (make is gripper)
    assert (lower <= upper).all()
