"""Vectorized objectives: each equals the same quantity computed row by row with robot.fk / Pinocchio."""

import numpy as np
import pinocchio as pin
import pytest

from evoik_pin import lie
from evoik_pin.errors import OptionError
from evoik_pin.objectives import (
    JointLimitMargin,
    ManipulabilityCost,
    MaxJointDisplacement,
    OrientationError,
    PopulationKinematics,
    PoseDistance,
    PoseError,
    PositionError,
    RPYPoseError,
    WeightedJointDisplacement,
    default_objective,
)
from evoik_pin.problem import Target
from evoik_pin.robot import load_robot


@pytest.fixture(scope="module")
def arm():
    return load_robot("redundant7r")


@pytest.fixture(scope="module")
def population(arm):
    return arm.random_configurations(25, np.random.default_rng(3))


@pytest.fixture(scope="module")
def pose_target(arm):
    return Target.coerce(arm.fk(arm.random_configurations(1, np.random.default_rng(4))[0]))


def _wrap(a):
    return (a + np.pi) % (2 * np.pi) - np.pi


def test_position_error_matches_fk_row_by_row(arm, population):
    target = Target(position=[0.3, -0.2, 0.7])
    values = PositionError(target)(population, robot=arm)
    expected = [np.linalg.norm(arm.fk(q).translation - target.position) for q in population]
    assert values.shape == (len(population),)
    assert np.allclose(values, expected, rtol=0, atol=1e-13)


def test_orientation_and_pose_error_match_log3(arm, population, pose_target):
    rot = OrientationError(pose_target)(population, robot=arm)
    expected_rot = [np.linalg.norm(pin.log3(pose_target.rotation.T @ arm.fk(q).rotation)) for q in population]
    assert np.allclose(rot, expected_rot, atol=1e-10)
    pose = PoseError(pose_target, position_weight=2.0, orientation_weight=0.25)(population, robot=arm)
    expected_pos = [np.linalg.norm(arm.fk(q).translation - pose_target.position) for q in population]
    assert np.allclose(pose, 2.0 * np.asarray(expected_pos) + 0.25 * np.asarray(expected_rot), atol=1e-10)
    distance = PoseDistance(pose_target, orientation_weight=0.25)(population, robot=arm)
    assert np.allclose(distance, np.hypot(expected_pos, 0.25 * np.asarray(expected_rot)), atol=1e-10)


def test_rotation_angle_is_accurate_near_zero_and_near_pi(arm):
    q = np.full(arm.n, 0.1)
    T = arm.fk(q)
    for angle in (1e-9, 1e-4, 1.0, np.pi - 1e-6):
        R_target = T.rotation @ pin.exp3(np.array([0.0, angle, 0.0]))
        value = OrientationError(Target(position=T.translation, rotation=R_target))(q[None], robot=arm)[0]
        assert value == pytest.approx(angle, rel=1e-6, abs=1e-15)


def test_rpy_pose_error_of_paper_004_matches_row_by_row(arm, population, pose_target):
    obj = RPYPoseError(pose_target)  # sigma = 0.3, epsilon = 0.7 as in paper 004
    values = obj(population, robot=arm)
    rpy_t = pin.rpy.matrixToRpy(pose_target.rotation)
    expected = []
    for q in population:
        T = arm.fk(q)
        d = _wrap(pin.rpy.matrixToRpy(T.rotation) - rpy_t)
        expected.append(0.3 * np.linalg.norm(T.translation - pose_target.position) + 0.7 * np.linalg.norm(d))
    assert np.allclose(values, expected, atol=1e-10)
    R = np.array([arm.fk(q).rotation for q in population])
    assert np.allclose(lie.rpy(R), [pin.rpy.matrixToRpy(r) for r in R], atol=1e-10)


def test_joint_displacement_terms(arm, population):
    q_ref = np.linspace(-0.3, 0.3, arm.n)
    gains = np.arange(1.0, arm.n + 1.0)
    max_disp = MaxJointDisplacement(q_ref)(population, robot=arm)
    weighted = WeightedJointDisplacement(q_ref, gains)(population, robot=arm)
    for i, q in enumerate(population):
        assert max_disp[i] == pytest.approx(max(abs(q[k] - q_ref[k]) for k in range(arm.n)))
        assert weighted[i] == pytest.approx(np.sqrt(sum(gains[k] * (q[k] - q_ref[k]) ** 2 for k in range(arm.n))))
    with pytest.raises(OptionError, match="gains"):
        WeightedJointDisplacement(q_ref, -gains)
    with pytest.raises(OptionError, match="gains"):
        WeightedJointDisplacement(q_ref, gains[:3])


def test_manipulability_terms_match_robot_manipulability(arm, population):
    Y = np.array([arm.manipulability(q, "translation") for q in population])
    assert np.allclose(ManipulabilityCost("translation", "value")(population, robot=arm), Y, atol=1e-12)
    assert np.allclose(ManipulabilityCost("translation", "inverse")(population, robot=arm), 1 / (Y + 1), atol=1e-12)
    assert np.allclose(ManipulabilityCost("translation", "negative")(population, robot=arm), -Y, atol=1e-12)
    Y_full = np.array([arm.manipulability(q, "full") for q in population])
    assert np.allclose(ManipulabilityCost("full", "value")(population, robot=arm), Y_full, atol=1e-12)
    with pytest.raises(OptionError, match="form"):
        ManipulabilityCost(form="squared")


def test_joint_limit_margin(arm, population):
    obj = JointLimitMargin(arm.lower, arm.upper)
    values = obj(population, robot=arm)
    for i, q in enumerate(population):
        half = (arm.upper - arm.lower) / 2
        margin = min(min(q[k] - arm.lower[k], arm.upper[k] - q[k]) / half[k] for k in range(arm.n))
        assert values[i] == pytest.approx(1 - margin)
    mid = (arm.lower + arm.upper) / 2
    assert obj(mid[None], robot=arm)[0] == pytest.approx(0.0)
    assert obj(arm.lower[None], robot=arm)[0] == pytest.approx(1.0)


def test_weighted_sums_compose(arm, population, pose_target):
    pos, rot = PositionError(pose_target), OrientationError(pose_target)
    q_ref = np.zeros(arm.n)
    combo = 2.0 * pos + rot * 0.5 + 3 * MaxJointDisplacement(q_ref)
    kin = PopulationKinematics(arm, population)
    expected = 2.0 * pos(population, kin) + 0.5 * rot(population, kin) + 3 * MaxJointDisplacement(q_ref)(
        population, kin)
    assert np.allclose(combo(population, kin), expected, rtol=0, atol=1e-15)
    assert "PositionError" in repr(combo) and "MaxJointDisplacement" in repr(combo)
    with pytest.raises(TypeError):
        pos + 1.0  # noqa: B018 - adding a number is not a composition


def test_planar_targets_use_xy_and_wrapped_yaw():
    arm = load_robot("planar2r")
    Q = arm.random_configurations(20, np.random.default_rng(5))
    target = Target.planar_target(0.2, 0.15, yaw=3.1)
    kin = PopulationKinematics(arm, Q)
    pos = PositionError(target)(Q, kin)
    rot = OrientationError(target)(Q, kin)
    for i, q in enumerate(Q):
        T = arm.fk(q)
        assert pos[i] == pytest.approx(np.linalg.norm(T.translation[:2] - [0.2, 0.15]), abs=1e-13)
        yaw = np.arctan2(T.rotation[1, 0], T.rotation[0, 0])
        assert rot[i] == pytest.approx(abs(_wrap(yaw - 3.1)), abs=1e-12)
        assert rot[i] <= np.pi


def test_default_objective_and_bad_use(arm, population, pose_target):
    position_only = Target(position=[0.1, 0.2, 0.3])
    assert np.allclose(default_objective(position_only)(population, robot=arm),
                       PositionError(position_only)(population, robot=arm))
    assert np.allclose(default_objective(pose_target, 0.5)(population, robot=arm),
                       PoseError(pose_target, 1.0, 0.5)(population, robot=arm))
    euclidean = default_objective(pose_target, 0.5, "euclidean")
    assert isinstance(euclidean, PoseDistance) and euclidean.orientation_weight == 0.5
    assert isinstance(default_objective(position_only, 0.5, "euclidean"), PositionError)
    with pytest.raises(OptionError, match="pose_metric 'l1' is not one of .*'sum', 'euclidean'"):
        default_objective(pose_target, 1.0, "l1")
    with pytest.raises(OptionError, match="rotation"):
        PoseDistance(position_only)
    with pytest.raises(OptionError, match="rotation"):
        OrientationError(position_only)
    with pytest.raises(OptionError, match="pose target"):
        RPYPoseError(position_only)
    with pytest.raises(OptionError, match="kin"):
        PositionError(position_only)(population)
