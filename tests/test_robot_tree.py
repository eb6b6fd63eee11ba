"""robot/tree.py and the compiled tree kinematics (solvers/lm/tree_kinematics.py): the folded tree of a robot's
active joints, frame poses and frame Jacobians, against Pinocchio on every example-robot-data robot with branches
and on random URDF trees (revolute, prismatic, continuous, fixed and mimic joints), with and without a floating
base, and on every arm's chain."""

import numpy as np
import pinocchio as pin
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from kernel_helpers import compiled_frames
from urdf_helpers import gripper, joint_xml, mimic_3r, robot_xml

from evoik_pin.errors import RobotLoadError
from evoik_pin.robot import WHOLE_ROBOTS, list_robots, load_robot
from evoik_pin.robot.frames import find_frame
from evoik_pin.robot.tree import FLOATING_BASE_JOINTS

#: Every example-robot-data robot that loads by name with branches (several limbs, fingers or arms; romeo's and the
#: PR2's hands have mimic joints); a floating base on a few of each kind.
TREES = [name for name in WHOLE_ROBOTS if name not in ("hector", "iris", "finger_edu", "double_pendulum",
                                                       "asr_twodof", "borinot", "hextilt")]
FLOATING = ["talos", "g1", "romeo", "go2", "solo12", "anymal_c", "b1_z1", "baxter"]


def pinocchio_poses(robot, q, frames):
    """(4, 4) poses of ``frames`` in the base frame from Pinocchio's kinematics of the whole URDF (full_model at
    full_configuration: no reduction, no folding, the free-flyer joint for a floating base); the frames of the
    floating base's six joints, which only the robot's own model has, from Pinocchio on that model."""
    model = robot.full_model
    data = model.createData()
    pin.framesForwardKinematics(model, data, robot.full_configuration(q))
    baseMo = robot.base_placement.inverse()
    ids = [find_frame(model, f) for f in frames]
    return [(baseMo * data.oMf[i]).homogeneous if i >= 0 else robot.fk(q, f).homogeneous
            for f, i in zip(frames, ids, strict=True)]


def check_against_pinocchio(robot, rng, count=3, jacobian_frames=None):
    frames = robot.frames
    jac = set(frames if jacobian_frames is None else jacobian_frames)
    for q in robot.random_configurations(count, rng):
        ours = compiled_frames(robot, q, frames)
        for f, (R, p, J), H in zip(frames, ours, pinocchio_poses(robot, q, frames), strict=True):
            assert np.abs(R - H[:3, :3]).max() < 1e-12 and np.abs(p - H[:3, 3]).max() < 1e-12, f
            if f in jac:
                assert np.abs(J - robot.jacobian(q, "world", of=f)).max() < 1e-12, f


# ---------------------------------------------------------------------------------------------- chains
@pytest.mark.parametrize("name", [*list_robots(), "mimic3r", "gripper"])
def test_tree_kinematics_of_a_chain_equal_pinocchio(name, rng):
    # a chain is a tree whose joints each have the previous one as parent
    robot = (load_robot(mimic_3r(), tip="tool") if name == "mimic3r" else load_robot(gripper(), tip="fb_tip")
             if name == "gripper" else load_robot(name))
    m = robot.chain_constants()[2].size
    assert robot.tree.is_chain == (name != "gripper")  # the gripper's driving finger is a branch off the chain
    assert np.array_equal(robot.tree.parent[robot.tree.ancestors(robot.frame_constants()[0])], np.arange(-1, m - 1))
    for q in robot.random_configurations(5, rng):
        ((R, p, J),) = compiled_frames(robot, q, [robot.tip])
        T = robot.fk(q)
        assert np.abs(R - T.rotation).max() < 1e-12 and np.abs(p - T.translation).max() < 1e-12
        assert np.abs(J - robot.jacobian(q, "world")).max() < 1e-12


# ---------------------------------------------------------------------------------------------- trees
@pytest.mark.parametrize("name, floating", [(name, False) for name in TREES] + [(name, True) for name in FLOATING])
def test_tree_kinematics_equal_pinocchio_on_example_robot_trees(name, floating, rng):
    robot = load_robot(name, floating_base=floating)
    assert not robot.tree.is_chain
    assert (robot.joint_names[:6] == list(FLOATING_BASE_JOINTS)) == floating
    # every frame's pose; the Jacobians of a sample of frames (Pinocchio's costs more than the whole check)
    sample = robot.frames[:: max(1, len(robot.frames) // 12)]
    check_against_pinocchio(robot, rng, count=2, jacobian_frames=sample)


@pytest.mark.parametrize("name", ["talos", "pr2", "allegro_right"])
def test_population_kinematics_of_any_frame(name, rng):
    robot = load_robot(name, floating_base=name == "talos")
    frames = [f for f in robot.frames if robot.moving_joints(f)][::7][:6]
    Q = robot.random_configurations(6, rng)
    P, R = robot.fk_batch(Q, frames=frames)
    assert P.shape == (6, len(frames), 3) and R.shape == (6, len(frames), 3, 3)
    for i, q in enumerate(Q):
        for g, f in enumerate(frames):
            H = robot.fk(q, frame=f).homogeneous
            assert np.abs(P[i, g] - H[:3, 3]).max() < 1e-12 and np.abs(R[i, g] - H[:3, :3]).max() < 1e-12
    f = frames[-1]
    p1, R1 = robot.fk_batch(Q, frames=f)
    assert np.array_equal(p1, P[:, -1]) and np.array_equal(R1, R[:, -1])
    assert np.abs(robot.positions_batch(Q, frame=f) - P[:, -1]).max() < 1e-12
    J = robot.jacobian_batch(Q, frame=f)
    for i, q in enumerate(Q):
        assert np.abs(J[i] - robot.jacobian(q, of=f)).max() < 1e-12


def test_a_floating_base_is_the_free_flyer_of_pinocchio(rng):
    # the first six entries of q: the root link's position (m) and yaw, pitch, roll (rad), R = Rz Ry Rx; in
    # full_configuration, Pinocchio's free-flyer numbers: position and unit quaternion (x, y, z, w)
    robot = load_robot("go2", floating_base=True)
    ff = pin.buildModelFromUrdf(str(robot.urdf_path), pin.JointModelFreeFlyer())
    assert [ff.names[j] for j in range(ff.njoints)] == [robot.full_model.names[j] for j in range(ff.njoints)]
    for q in robot.random_configurations(4, rng):
        full = robot.full_configuration(q)
        assert full.shape == (ff.nq,) and np.allclose(full[:3], q[:3])
        assert abs(np.linalg.norm(full[3:7]) - 1) < 1e-12 and full[6] >= 0
        R = pin.Quaternion(full[6], *full[3:6]).toRotationMatrix()
        assert np.allclose(R, pin.rpy.rpyToMatrix(q[5], q[4], q[3]), atol=1e-12)
        data = ff.createData()
        pin.framesForwardKinematics(ff, data, full)
        for f in ("base", "FL_foot", "RR_calf"):
            assert np.allclose(data.oMf[ff.getFrameId(f)].homogeneous, robot.fk(q, f).homogeneous, atol=1e-12)
    lo, hi = robot.lower[:6], robot.upper[:6]
    assert np.allclose(lo, [-1, -1, -1, -np.pi, -np.pi / 2, -np.pi]) and np.allclose(hi, -lo)


# ---------------------------------------------------------------------------------------------- random trees
@st.composite
def random_trees(draw):
    """URDF of a random tree: 1-9 joints, each child of a random earlier link, revolute / continuous / prismatic /
    fixed, random origins and axes, some mimicking an earlier movable joint."""
    count = draw(st.integers(1, 9))
    links = ["root"]
    joints, movable = [], []
    for i in range(count):
        parent = draw(st.sampled_from(links))
        kind = draw(st.sampled_from(["revolute", "continuous", "prismatic", "fixed"]))
        xyz = " ".join(f"{v:.6g}" for v in draw(st.lists(st.floats(-0.4, 0.4), min_size=3, max_size=3)))
        rpy = " ".join(f"{v:.6g}" for v in draw(st.lists(st.floats(-3.1, 3.1), min_size=3, max_size=3)))
        axis = np.array(draw(st.lists(st.floats(-1, 1), min_size=3, max_size=3)))
        if np.linalg.norm(axis) < 0.1:
            axis = np.array([0.0, 0.0, 1.0])
        axis = " ".join(f"{v:.6g}" for v in axis)
        mimic = None
        if kind != "fixed" and movable and draw(st.integers(0, 3)) == 0:
            mimic = (draw(st.sampled_from(movable)), draw(st.floats(-2, 2)), draw(st.floats(-0.3, 0.3)))
        lo, hi = (-0.5, 0.5) if kind == "prismatic" else (-3.0, 3.0)
        if mimic is not None:
            lo, hi = -50.0, 50.0  # the coupling, not the mimic joint's limits, is tested
        child = f"l{i}"
        joints.append(joint_xml(f"j{i}", kind, parent, child, xyz=xyz, rpy=rpy, axis=axis, lo=lo, hi=hi,
                                mimic=mimic))
        links.append(child)
        if kind != "fixed" and mimic is None:
            movable.append(f"j{i}")
    if not movable:
        joints.append(joint_xml("jm", "revolute", "root", "lm", xyz="0 0 0.1"))
        links.append("lm")
    return robot_xml("tree", links, joints)


@settings(max_examples=80, deadline=None, database=None, suppress_health_check=[HealthCheck.too_slow])
@given(xml=random_trees(), floating=st.booleans(), seed=st.integers(0, 2**16), data=st.data())
def test_random_trees_equal_pinocchio(xml, floating, seed, data):
    # the whole tree, or the chains to a few links (their union: mimic drivers off them still in q)
    links = [f"l{i}" for i in range(xml.count("<joint "))] if "lm" not in xml else ["lm"]
    tips = data.draw(st.one_of(st.just("all"), st.lists(st.sampled_from(links), min_size=1, max_size=3, unique=True)))
    try:
        robot = load_robot(xml, tips=tips, floating_base=floating)
    except RobotLoadError as exc:  # chains of fixed joints only
        assert "no movable joint" in str(exc) and tips != "all" and not floating
        return
    check_against_pinocchio(robot, np.random.default_rng(seed), count=2)
