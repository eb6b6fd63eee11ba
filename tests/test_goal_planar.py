"""The Planar goal: (x, y) in the base plane and optionally the heading; what a planar tip Target becomes."""

import numpy as np
import pytest

import evoik_pin as ek
from evoik_pin.errors import OptionError, TargetError
from evoik_pin.goals import Planar, Pose, Position
from evoik_pin.io.goals_file import load_goals, save_goals
from evoik_pin.problem import IKProblem, Target


@pytest.fixture(scope="module")
def vehicle_arm():
    return ek.load_robot("vehicle_arm")


def test_planar_goal_checks_its_numbers():
    g = Planar("tip", 0.2, -0.1, yaw=0.5, weight=2.0)
    assert g.target.tolist() == [0.2, -0.1, 0.5] and g.yaw == 0.5 and g.has_orientation
    assert Planar("tip", 0.2, -0.1).yaw is None and not Planar("tip", 0.2, -0.1).has_orientation
    with pytest.raises(TargetError, match="Planar on 'tip' takes finite numbers"):
        Planar("tip", np.nan, 0.0)
    with pytest.raises(TargetError, match="Planar on 'tip' takes finite numbers"):
        Planar("tip", 0.0, "y")
    with pytest.raises(OptionError, match="weight"):
        Planar("tip", 0.0, 0.0, weight=0.0)


def test_planar_errors_are_in_the_plane_and_the_wrapped_heading():
    import pinocchio as pin

    T = pin.SE3(pin.rpy.rpyToMatrix(0.0, 0.0, 3.1), np.array([1.0, 2.0, 0.7]))  # height is free
    pos, rot = Planar("tip", 1.3, 2.4, yaw=-3.1).errors(T)
    assert pos == pytest.approx(0.5) and rot == pytest.approx(2 * np.pi - 6.2)
    assert Planar("tip", 1.0, 2.0).errors(T) == (0.0, None)


def test_a_planar_tip_target_is_its_planar_goal(vehicle_arm):
    """The same answer, bit for bit, from Target.planar_target and [Planar(tip, ...)] (one problem form), and both
    meet the goal by the robot's own kinematics."""
    rng = np.random.default_rng(0)
    for q in vehicle_arm.random_configurations(3, rng):
        T = vehicle_arm.fk(q)
        yaw = float(np.arctan2(T.rotation[1, 0], T.rotation[0, 0]))
        x, y = T.translation[:2]
        a = ek.solve(vehicle_arm, Target.planar_target(x, y, yaw), seed=1)
        b = ek.solve(vehicle_arm, [Planar(vehicle_arm.tip, x, y, yaw)], seed=1)
        assert a.success and b.success
        assert np.array_equal(a.q, b.q)
        assert a.goal_errors is None and b.goal_errors == [(b.position_error, b.orientation_error)]
        pos, rot = Planar(vehicle_arm.tip, x, y, yaw).errors(vehicle_arm.fk(b.q))
        assert pos <= 1e-6 and rot <= 1e-6


def test_a_tip_targets_problem_holds_its_tip_goal(vehicle_arm):
    panda = ek.load_robot("panda")
    T = panda.fk(np.full(panda.n, 0.3))
    for target, kind in ((T, Pose), (T.translation.copy(), Position), (Target.planar_target(0.3, 0.2), Planar)):
        robot = vehicle_arm if kind is Planar else panda
        problem = IKProblem(robot, target, tolerance=1e-5, rotation_tolerance=1e-4)
        (goal,) = problem.goals
        assert type(goal) is kind and goal.frame == robot.tip
        assert (goal.tolerance, goal.rotation_tolerance, goal.weight) == (1e-5, 1e-4, 1.0)
        stack, pt, Rt = problem.goal_stack()
        assert stack is IKProblem(robot, target, tolerance=1e-5, rotation_tolerance=1e-4).goal_stack()[0]
        assert np.array_equal(pt[0], goal.encode()[0]) and np.array_equal(Rt[0], goal.encode()[1])
        assert problem.chosen(np.zeros(robot.n)) is None  # a tip target reports no goal-set choice


def test_planar_goals_file_round_trip(tmp_path, vehicle_arm):
    goals = [Planar(vehicle_arm.tip, 0.4, -0.2, yaw=0.25, tolerance=1e-5), Planar(vehicle_arm.tip, 0.4, -0.2)]
    for g in goals:
        path = tmp_path / "planar.yaml"
        save_goals([g], path)
        (back,) = load_goals(path)
        assert type(back) is Planar and back.target.tolist() == g.target.tolist() and back.yaw == g.yaw
        assert back.tolerance == g.tolerance


def test_planar_goals_on_any_frame_and_beside_a_position(vehicle_arm):
    """A Planar goal on a frame other than the tip, and one beside a Position on the same frame (its (x, y, yaw) is
    no point to clash with the position's): solved, and met by the robot's own kinematics."""
    rng = np.random.default_rng(3)
    for i, q in enumerate(vehicle_arm.random_configurations(5, rng)):
        for frame in ("link4", vehicle_arm.tip):
            T = vehicle_arm.fk(q, frame)
            planar = Planar(frame, *T.translation[:2], yaw=float(np.arctan2(T.rotation[1, 0], T.rotation[0, 0])))
            goals = [planar, Position(vehicle_arm.tip, vehicle_arm.fk(q).translation)]
            r = ek.solve(vehicle_arm, goals, seed=i, timeout=None, max_restarts=3)
            assert r.success
            pos, rot = planar.errors(vehicle_arm.fk(r.q, frame))
            assert pos <= 1e-6 and rot <= 1e-6
            assert np.linalg.norm(vehicle_arm.fk(r.q).translation - goals[1].target) <= 1e-6
