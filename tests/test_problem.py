"""Targets and IK problems: accepted target forms, bad input, evaluation, tolerances and the Pro box."""

import numpy as np
import pinocchio as pin
import pytest

from evoik_pin.errors import BoundsError, ConfigurationError, OptionError, TargetError
from evoik_pin.objectives import PositionError
from evoik_pin.problem import DEFAULT_PRO_DELTA, IKProblem, Target
from evoik_pin.robot import load_robot


@pytest.fixture(scope="module")
def arm():
    return load_robot("redundant7r")


def test_target_forms():
    p = np.array([0.3, 0.1, 0.6])
    R = pin.rpy.rpyToMatrix(0.1, -0.2, 0.3)
    assert Target.coerce(p).rotation is None
    assert Target.coerce([0.3, 0.1, 0.6]).position.tolist() == p.tolist()
    from_se3 = Target.coerce(pin.SE3(R, p))
    assert np.allclose(from_se3.rotation, R) and np.allclose(from_se3.position, p)
    H = np.eye(4)
    H[:3, :3], H[:3, 3] = R, p
    from_h = Target.coerce(H)
    assert np.allclose(from_h.rotation, R) and np.allclose(from_h.position, p)
    explicit = Target(position=p, rotation=R)
    assert Target.coerce(explicit) is explicit and explicit.has_orientation
    assert np.allclose(Target.from_rpy(p, [0.1, -0.2, 0.3]).rotation, R)
    assert np.allclose(explicit.se3().homogeneous, H)


def test_planar_target_forms():
    t = Target.planar_target(0.2, 0.1)
    assert t.planar and not t.has_orientation and t.position.shape == (2,)
    ty = Target.planar_target(0.2, 0.1, yaw=0.5)
    assert ty.has_orientation and ty.yaw == 0.5
    assert np.allclose(ty.se3().translation, [0.2, 0.1, 0.0])
    assert np.allclose(pin.rpy.matrixToRpy(ty.se3().rotation), [0, 0, 0.5])


@pytest.mark.parametrize("bad, match", [
    ([0.1, 0.2], "3-vector"),
    ([0.1, 0.2, 0.3, 0.4], "3-vector"),
    (np.eye(3), "3-vector"),
    ("abc", "3-vector"),
    ([0.1, np.nan, 0.3], "NaN or inf"),
    ([0.1, np.inf, 0.3], "NaN or inf"),
])
def test_bad_targets_are_clear_errors(bad, match):
    with pytest.raises(TargetError, match=match):
        Target.coerce(bad)


def test_bad_rotations_and_yaw():
    with pytest.raises(TargetError, match="not a rotation matrix"):
        Target(position=[0, 0, 0], rotation=2 * np.eye(3))
    with pytest.raises(TargetError, match="3 x 3"):
        Target(position=[0, 0, 0], rotation=np.eye(2))
    with pytest.raises(TargetError, match="NaN or inf"):
        Target(position=[0, 0, 0], rotation=np.full((3, 3), np.nan))
    with pytest.raises(TargetError, match="planar"):
        Target(position=[0, 0, 0], yaw=0.3)
    with pytest.raises(TargetError, match="finite"):
        Target.planar_target(0.1, 0.1, yaw=np.inf)
    with pytest.raises(TargetError, match="yaw angle"):
        Target(position=[0.1, 0.1], rotation=np.eye(3), planar=True)


def test_evaluate_matches_fk_and_counts(arm):
    rng = np.random.default_rng(11)
    q_goal = arm.random_configurations(1, rng)[0]
    problem = IKProblem(arm, arm.fk(q_goal), tolerance=1e-6, orientation_weight=0.5)
    Q = arm.random_configurations(12, rng)
    ev = problem.evaluate(Q)
    assert problem.evaluations == 12
    T_goal = arm.fk(q_goal)
    for i, q in enumerate(Q):
        T = arm.fk(q)
        pos = np.linalg.norm(T.translation - T_goal.translation)
        rot = np.linalg.norm(pin.log3(T_goal.rotation.T @ T.rotation))
        assert ev.position_error[i] == pytest.approx(pos, abs=1e-13)
        assert ev.orientation_error[i] == pytest.approx(rot, abs=1e-10)
        assert ev.cost[i] == pytest.approx(pos + 0.5 * rot, abs=1e-10)
    assert np.allclose(problem.cost(Q), ev.cost)
    assert problem.evaluations == 24
    exact = problem.evaluate(q_goal[None])
    assert problem.succeeded(exact.position_error, exact.orientation_error).all()
    assert not problem.succeeded(ev.position_error, ev.orientation_error).any()


def test_euclidean_pose_metric_combines_the_errors_as_a_norm(arm, rng):
    target = arm.fk(arm.random_configurations(1, rng)[0])
    Q = arm.random_configurations(12, rng)
    ev = IKProblem(arm, target, orientation_weight=0.3, pose_metric="euclidean").evaluate(Q)
    assert np.allclose(ev.cost, np.hypot(ev.position_error, 0.3 * ev.orientation_error), rtol=0, atol=1e-15)
    summed = IKProblem(arm, target, orientation_weight=0.3).evaluate(Q)
    assert np.allclose(summed.cost, summed.position_error + 0.3 * summed.orientation_error, rtol=0, atol=1e-15)


def test_position_only_problem_and_tolerances(arm):
    problem = IKProblem(arm, [0.3, 0.2, 0.6], tolerance=1e-3)
    assert problem.rotation_tolerance == 1e-3
    ev = problem.evaluate(np.zeros((2, arm.n)))
    assert ev.orientation_error is None
    assert np.allclose(ev.cost, ev.position_error)
    assert problem.succeeded(np.array([5e-4, 2e-3])).tolist() == [True, False]
    strict_rot = IKProblem(arm, pin.SE3.Identity(), tolerance=1e-3, rotation_tolerance=1e-6)
    assert strict_rot.succeeded(1e-4, 1e-3) == np.False_


@pytest.mark.parametrize("kwargs, error, match", [
    (dict(tolerance=-1.0), OptionError, "tolerance"),
    (dict(tolerance=np.nan), OptionError, "tolerance"),
    (dict(rotation_tolerance=-1e-3), OptionError, "rotation_tolerance"),
    (dict(orientation_weight=-2.0), OptionError, "orientation_weight"),
    (dict(pose_metric="max"), OptionError, "pose_metric 'max' is not one of"),
    (dict(pose_metric="max", objective=PositionError(Target(position=[0.3, 0.2, 0.6]))), OptionError, "pose_metric"),
    (dict(q0=np.zeros(3)), ConfigurationError, "q0"),
    (dict(q0=np.full(7, np.nan)), ConfigurationError, "NaN"),
    (dict(lower=np.zeros(3), upper=np.ones(3)), BoundsError, "7 values"),
    (dict(lower=np.ones(7), upper=np.zeros(7)), BoundsError, "inverted"),
    (dict(lower=np.full(7, -np.inf), upper=np.ones(7)), BoundsError, "finite"),
])
def test_bad_problem_options(arm, kwargs, error, match):
    with pytest.raises(error, match=match):
        IKProblem(arm, [0.3, 0.2, 0.6], **kwargs)


def test_pro_box(arm):
    problem = IKProblem(arm, [0.3, 0.2, 0.6], tolerance=1e-8)
    problem.evaluate(np.zeros((3, arm.n)))
    q_prev = arm.lower + 0.001  # near the lower limits: the box is cut by the bounds
    q_prev[3] = 0.2
    pro = problem.with_pro_box(q_prev)
    assert np.allclose(pro.lower, np.maximum(arm.lower, q_prev - DEFAULT_PRO_DELTA))
    assert np.allclose(pro.upper, np.minimum(arm.upper, q_prev + DEFAULT_PRO_DELTA))
    assert pro.lower[3] == pytest.approx(0.2 - np.pi / 100) and pro.upper[3] == pytest.approx(0.2 + np.pi / 100)
    assert np.allclose(pro.q0, q_prev) and pro.evaluations == 0 and pro.tolerance == 1e-8
    assert problem.evaluations == 3 and np.allclose(problem.lower, arm.lower)  # original unchanged
    narrow = problem.with_pro_box(np.zeros(arm.n), delta=0.01)
    assert np.allclose(narrow.upper - narrow.lower, 0.02)
    with pytest.raises(OptionError, match="delta"):
        problem.with_pro_box(q_prev, delta=0.0)
    with pytest.raises(ConfigurationError):
        problem.with_pro_box(np.zeros(2))


def test_a_4x4_target_must_be_a_homogeneous_pose():
    import evoik_pin as ev
    from evoik_pin.errors import TargetError

    T = np.eye(4)
    T[:3, 3] = [0.3, 0.1, 0.4]
    assert np.array_equal(Target.coerce(T).position, [0.3, 0.1, 0.4])
    bad = T.copy()
    bad[3] = [0.0, 0.0, 0.0, 2.0]  # a scaled homogeneous matrix: not a pose
    with pytest.raises(TargetError, match="bottom row"):
        Target.coerce(bad)
    bad[3] = [0.1, 0.0, 0.0, 1.0]  # a projective row
    with pytest.raises(TargetError, match="bottom row"):
        ev.solve("panda", bad)
    H = np.stack([T, bad])
    with pytest.raises(TargetError, match="target 1: the bottom row"):
        Target.from_poses(H)
    assert len(Target.from_poses(np.stack([T, T]))) == 2
