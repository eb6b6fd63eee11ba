"""robot/robot.py (Robot) on every bundled and example arm: FK against an independent parser, batches,
Jacobians, manipulability, continuous joints, sub-chains, the placements the viewer draws, and bad input."""

import numpy as np
import pinocchio as pin
import pytest
import yourdfpy

from evoik_pin.errors import (
    BoundsError,
    ConfigurationError,
    FrameError,
    RobotLoadError,
)
from evoik_pin.robot import BUNDLED_ROBOTS, EXAMPLE_ARMS, load_robot

ALL = list(BUNDLED_ROBOTS) + list(EXAMPLE_ARMS)


@pytest.fixture(scope="module", params=ALL)
def robot(request):
    return load_robot(request.param)


def test_attributes(robot):
    assert robot.n == len(robot.joint_names) == robot.lower.size == robot.upper.size
    assert np.all(np.isfinite(robot.lower)) and np.all(robot.lower < robot.upper)
    assert robot.urdf_path is not None and robot.urdf_path.is_file()
    assert robot.model.nv == robot.n


def test_fk_equals_yourdfpy(robot, rng):
    urdf = yourdfpy.URDF.load(str(robot.urdf_path), build_scene_graph=True, load_meshes=False,
                              build_collision_scene_graph=False, load_collision_meshes=False)
    base = robot.base
    for q in robot.random_configurations(25, rng):
        cfg = {name: 0.0 for name in urdf.actuated_joint_names}
        full = robot.full_configuration(q)
        for name in urdf.actuated_joint_names:  # locked joints at the values Pinocchio locked them at
            jm = robot.full_model.joints[robot.full_model.getJointId(name)]
            cfg[name] = (np.arctan2(full[jm.idx_q + 1], full[jm.idx_q]) if jm.nq == 2 else full[jm.idx_q])
        urdf.update_cfg(cfg)
        ref = urdf.get_transform(robot.tip, base)
        T = robot.fk(q)
        assert np.abs(T.translation - ref[:3, 3]).max() < 1e-9
        assert np.abs(T.rotation - ref[:3, :3]).max() < 1e-9


def test_fk_batch_equals_fk(robot, rng):
    Q = robot.random_configurations(40, rng)
    P, R = robot.fk_batch(Q)
    assert P.shape == (40, 3) and R.shape == (40, 3, 3)
    assert np.abs(robot.positions_batch(Q) - P).max() < 1e-12
    for i, q in enumerate(Q):
        T = robot.fk(q)
        assert np.abs(T.translation - P[i]).max() < 1e-12
        assert np.abs(T.rotation - R[i]).max() < 1e-12


def test_jacobian_equals_finite_differences(robot, rng):
    h = 1e-7
    for q in robot.random_configurations(5, rng):
        J = robot.jacobian(q, "world")
        T0 = robot.fk(q)
        for k in range(robot.n):
            dq = np.zeros(robot.n)
            dq[k] = h
            Tp, Tm = robot.fk(q + dq), robot.fk(q - dq)
            assert np.abs((Tp.translation - Tm.translation) / (2 * h) - J[:3, k]).max() < 1e-6
            # angular velocity in base axes: log of R(q+h) R(q-h)^T / 2h
            w = pin.log3(Tp.rotation @ Tm.rotation.T) / (2 * h)
            assert np.abs(w - J[3:, k]).max() < 1e-6
        Jl = robot.jacobian(q, "local")
        R = T0.rotation
        assert np.abs(R @ Jl[:3] - J[:3]).max() < 1e-9 and np.abs(R @ Jl[3:] - J[3:]).max() < 1e-9
        assert np.abs(robot.jacobian_batch(q[None])[0] - J).max() < 1e-12


def test_manipulability(robot, rng):
    Q = robot.random_configurations(5, rng)
    batch = robot.manipulability_batch(Q, "full")
    for i, q in enumerate(Q):
        J = robot.jacobian(q)
        for rows, sel in [("translation", [0, 1, 2]), ("full", list(range(6))), ([0, 1, 5], [0, 1, 5])]:
            # Yoshikawa's measure: sqrt(det(J J^T)) with no fewer joints than rows; with fewer joints (a 4- or
            # 5-joint arm's full rows) the product of the singular values, not J J^T's zero
            Js = J[sel]
            ref = (np.sqrt(max(np.linalg.det(Js @ Js.T), 0.0)) if len(sel) <= robot.n
                   else float(np.prod(np.linalg.svd(Js, compute_uv=False))))
            assert robot.manipulability(q, rows=rows) == pytest.approx(ref, rel=1e-7, abs=1e-15)
        assert batch[i] == pytest.approx(robot.manipulability(q, "full"), rel=1e-7, abs=1e-12)


def test_planar_manipulability_of_vehicle_arm():
    """Paper 003: the 3 x 5 task Jacobian (x, y, yaw)."""
    robot = load_robot("vehicle_arm")
    q = np.array([0.3, -0.2, 0.4, 0.9, -0.5])
    J = robot.jacobian(q)[[0, 1, 5]]
    assert J.shape == (3, 5)
    assert robot.manipulability(q, rows="planar") == pytest.approx(np.sqrt(np.linalg.det(J @ J.T)))


def test_continuous_joints_map_both_ways(rng):
    robot = load_robot("kinova")
    assert robot.continuous.any() and robot.model.nq > robot.n
    assert np.allclose(robot.lower[robot.continuous], -np.pi) and np.allclose(robot.upper[robot.continuous], np.pi)
    for q in robot.random_configurations(20, rng):
        q_pin = robot.to_pinocchio(q)
        assert q_pin.shape == (robot.model.nq,)
        assert np.allclose(robot.from_pinocchio(q_pin), q)
    # a continuous joint at +pi and -pi is the same configuration
    q = np.zeros(robot.n)
    k = int(np.nonzero(robot.continuous)[0][0])
    qa, qb = q.copy(), q.copy()
    qa[k], qb[k] = np.pi - 1e-9, -np.pi + 1e-9
    assert np.allclose(robot.fk(qa).translation, robot.fk(qb).translation, atol=1e-8)


def test_fingers_are_locked():
    robot = load_robot("panda")
    assert robot.n == 7 and all("finger" not in j for j in robot.joint_names)
    assert robot.full_model.nq == 9


def test_sub_chain_with_base_and_tip(rng):
    full = load_robot("panda", tip="panda_link8")
    sub = load_robot("panda", base="panda_link2", tip="panda_link8")
    assert sub.n == 5 and sub.joint_names == [f"panda_joint{i}" for i in range(3, 8)]
    q = full.random_configurations(1, rng)[0]
    # base pose from the full chain at the locked value of joints 1-2 (0 and 0, inside the limits)
    q[:2] = 0.0
    oMb = full.fk(np.r_[q[:2], np.zeros(5)]) if False else None  # noqa: F841 - kept explicit below
    T_full = full.fk(q)
    pin_model = full.model
    data = pin_model.createData()
    pin.framesForwardKinematics(pin_model, data, full.to_pinocchio(q))
    oMbase = data.oMf[pin_model.getFrameId("panda_link2")]
    expected = oMbase.inverse() * T_full
    assert np.allclose(sub.fk(q[2:]).homogeneous, expected.homogeneous, atol=1e-12)
    P, R = sub.fk_batch(q[None, 2:])
    assert np.allclose(P[0], expected.translation, atol=1e-12)
    J = sub.jacobian(q[2:])
    h = 1e-7
    dq = np.zeros(5)
    dq[0] = h
    fd = (sub.fk(q[2:] + dq).translation - sub.fk(q[2:] - dq).translation) / (2 * h)
    assert np.allclose(fd, J[:3, 0], atol=1e-6)


def test_joint_subset_and_bounds_override():
    robot = load_robot("redundant7r", joints=["joint1", "joint2", "joint4"])
    assert robot.n == 3 and robot.joint_names == ["joint1", "joint2", "joint4"]
    r = load_robot("planar2r", bounds=([-1, -1], [1, 1]))
    assert np.allclose(r.lower, -1) and np.allclose(r.upper, 1)


# ---------------------------------------------------------------------------- placements for the viewer
def test_joint_axes_are_the_jacobian_columns(robot, rng):
    """Joint k's axis, turned into the base frame, is its angular (revolute) or linear (prismatic) column."""
    assert robot.joint_axes.shape == (robot.n, 3)
    assert np.allclose(np.linalg.norm(robot.joint_axes, axis=1), 1.0)
    data = robot.model.createData()
    Rt = robot.base_placement.rotation.T
    for q in robot.random_configurations(3, rng):
        pin.forwardKinematics(robot.model, data, robot.to_pinocchio(q))
        J = robot.jacobian(q, "world")
        for k in range(robot.n):
            axis = Rt @ data.oMi[k + 1].rotation @ robot.joint_axes[k]
            assert np.allclose(J[3:, k] if robot.revolute[k] else J[:3, k], axis, atol=1e-12)


def test_base_placement(rng):
    assert load_robot("ur5").base_placement.isIdentity()
    robot = load_robot("panda", base="panda_link2", tip="panda_link8")
    data = robot.model.createData()
    pin.framesForwardKinematics(robot.model, data, pin.neutral(robot.model))
    oMbase = robot.base_placement
    assert np.allclose(oMbase.homogeneous, data.oMf[robot.model.getFrameId("panda_link2")].homogeneous, atol=0)
    oMbase.translation[:] = 1.0  # a copy: the robot's own placement stays
    assert not np.allclose(robot.base_placement.translation, 1.0)
    for q in robot.random_configurations(3, rng):
        pin.framesForwardKinematics(robot.model, data, robot.to_pinocchio(q))
        tip = robot.base_placement.inverse() * data.oMf[robot.model.getFrameId("panda_link8")]
        assert np.allclose(tip.homogeneous, robot.fk(q).homogeneous, atol=1e-12)


@pytest.mark.parametrize("name, kwargs", [("ax18", {}), ("vehicle_arm", {}), ("kinova", {}),
                                          ("panda", {"base": "panda_link2", "tip": "panda_link8"})])


def test_geometry_placements(name, kwargs, rng):
    robot = load_robot(name, **kwargs)
    geom = robot.visual_model
    data = robot.model.createData()
    for q in robot.random_configurations(3, rng):
        placements = robot.geometry_placements(geom, q)
        assert len(placements) == geom.ngeoms
        pin.forwardKinematics(robot.model, data, robot.to_pinocchio(q))
        for g, M in zip(geom.geometryObjects, placements, strict=True):
            assert np.allclose(M.homogeneous, (data.oMi[g.parentJoint] * g.placement).homogeneous, atol=1e-12)
    if name == "ax18":  # its tip sphere sits on the tip frame
        (tool,) = [M for g, M in zip(geom.geometryObjects, placements, strict=True) if g.name == "tool_0"]
        assert np.allclose(tool.translation, robot.fk(q).translation, atol=1e-12)
    with pytest.raises(ConfigurationError, match=rf"expected \({robot.n},\)"):
        robot.geometry_placements(geom, np.zeros(robot.n + 1))


# ---------------------------------------------------------------------------- bad input
def test_unknown_frames_listed():
    with pytest.raises(FrameError, match="unknown tip frame 'hand'.*panda_link7"):
        load_robot("panda", tip="hand")
    with pytest.raises(FrameError, match="unknown base frame"):
        load_robot("panda", base="nowhere")


def test_tip_not_downstream_of_base():
    with pytest.raises(FrameError, match="not downstream"):
        load_robot("panda", base="panda_link5", tip="panda_link3")
    with pytest.raises(FrameError, match="not downstream"):
        load_robot("panda", base="panda_leftfinger", tip="panda_rightfinger")


def test_chain_without_joints():
    with pytest.raises(RobotLoadError, match="no movable joint"):
        load_robot("panda", base="panda_link8", tip="panda_hand")


def test_bad_joint_vectors():
    robot = load_robot("ur5")
    with pytest.raises(ConfigurationError, match=r"expected \(6,\)"):
        robot.fk(np.zeros(5))
    with pytest.raises(ConfigurationError, match="NaN or inf"):
        robot.fk([0, 0, np.nan, 0, 0, 0])
    with pytest.raises(ConfigurationError, match="NaN or inf"):
        robot.jacobian([0, 0, np.inf, 0, 0, 0])
    with pytest.raises(ConfigurationError, match=r"\(N, 6\)"):
        robot.fk_batch(np.zeros((3, 4)))
    with pytest.raises(ConfigurationError, match="'world' or 'local'"):
        robot.jacobian(np.zeros(6), frame="tool")
    with pytest.raises(ConfigurationError, match="rows"):
        robot.manipulability(np.zeros(6), rows="planarr")


def test_bad_bounds_leave_robot_unchanged():
    robot = load_robot("planar2r")
    before = robot.lower.copy(), robot.upper.copy()
    with pytest.raises(BoundsError, match="inverted"):
        robot.set_bounds([0, 1], [1, 0])
    with pytest.raises(BoundsError, match="2 values"):
        robot.set_bounds([0], [1])
    with pytest.raises(BoundsError, match="finite"):
        robot.set_bounds([0, -np.inf], [1, 1])
    assert np.array_equal(robot.lower, before[0]) and np.array_equal(robot.upper, before[1])
    with pytest.raises(BoundsError, match="inverted"):
        load_robot("planar2r", bounds=([1, 1], [0, 0]))
