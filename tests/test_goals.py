"""evoik_pin.goals: Pose and Position goals (their checks), goal lists bound to a robot (frames, clashes), IKProblem
over a goal list (population errors and cost), and memetic solving whole robots: every goal met by Pinocchio's
forward kinematics of the answer, within the joint limits, each goal's errors in Result.goal_errors."""

import numpy as np
import pinocchio as pin
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import evoik_pin as ek
from evoik_pin.errors import FrameError, MethodError, OptionError, TargetError
from evoik_pin.goals import Pose, Position, bind
from evoik_pin.problem import IKProblem
from evoik_pin.robot.frames import find_frame

TALOS_FRAMES = ["left_sole_link", "right_sole_link", "arm_left_7_link", "arm_right_7_link"]


@pytest.fixture(scope="module")
def talos():
    return ek.load_robot("talos", floating_base=True)


def _check_answer(robot, goals, result):
    """Every goal met by Pinocchio's kinematics of the whole URDF at the answer (full_configuration), q in bounds."""
    model = robot.full_model
    data = model.createData()
    pin.framesForwardKinematics(model, data, robot.full_configuration(result.q))
    assert robot.within_bounds(result.q)
    for goal, (pos, rot) in zip(goals, result.goal_errors, strict=True):
        T = data.oMf[find_frame(model, goal.frame)]
        pt, Rt = goal.encode()
        assert np.linalg.norm(T.translation - pt) <= goal.tolerance and pos <= goal.tolerance
        if goal.has_orientation:
            assert np.linalg.norm(pin.log3(Rt.T @ T.rotation)) <= goal.rotation_tolerance and rot is not None
        else:
            assert rot is None


# ---------------------------------------------------------------------------------------------- goals
def test_goals_check_their_inputs():
    T = pin.SE3.Random()
    g = Pose("hand", T, weight=2, tolerance=1e-5)
    assert g.rotation_tolerance == 1e-5 and g.weight == 2.0 and g.has_orientation
    assert np.allclose(Pose("hand", T.homogeneous).target.homogeneous, T.homogeneous)
    assert "Pose('hand'" in repr(g) and "Position('hand', [1.0, 2.0, 3.0]" in repr(Position("hand", [1, 2, 3]))
    with pytest.raises(TargetError, match="a 3-vector is a position"):
        Pose("hand", [1.0, 2.0, 3.0])
    with pytest.raises(TargetError, match="Pose on 'hand'.*NaN"):
        Pose("hand", np.full((4, 4), np.nan))
    with pytest.raises(TargetError, match="not a rotation matrix"):
        Pose("hand", 2 * np.eye(4) - np.diag([0, 0, 0, 1.0]))
    with pytest.raises(TargetError, match="takes a 3-vector"):
        Position("hand", T)
    with pytest.raises(TargetError, match=r"shape \(2,\)"):
        Position("hand", [1.0, 2.0])
    with pytest.raises(TargetError, match="NaN"):
        Position("hand", [1.0, np.nan, 0.0])
    for bad in (0, -1, np.nan, "heavy"):
        with pytest.raises(OptionError, match="weight of the goal on 'hand'"):
            Position("hand", [0, 0, 0], weight=bad)
    with pytest.raises(OptionError, match="tolerances.*>= 0"):
        Pose("hand", T, tolerance=-1e-6)
    with pytest.raises(OptionError, match="rotation_tolerance"):
        Pose("hand", T, rotation_tolerance=np.inf)
    with pytest.raises(FrameError, match="frame name"):
        Position(3, [0, 0, 0])


def test_goal_lists_bound_to_a_robot():
    baxter = ek.load_robot("baxter", tips=["left_gripper"])
    q = np.zeros(baxter.n)
    T = baxter.fk(q, "left_gripper")
    goals, stack, pt, Rt = bind(baxter, (Pose("left_gripper", T), Position("left_wrist", [0.5, 0.2, 0.3])))
    assert len(goals) == 2 and stack.rows == 9 and pt.shape == (2, 3) and Rt.shape == (2, 3, 3)
    with pytest.raises(TargetError, match="goal list is empty"):
        bind(baxter, [])
    with pytest.raises(TargetError, match="goal 1 is a ndarray"):
        bind(baxter, [Pose("left_gripper", T), np.zeros(3)])
    with pytest.raises(FrameError, match=r"no frame 'left_grip' \(closest: left_gripper"):
        bind(baxter, [Pose("left_grip", T)])
    with pytest.raises(FrameError, match="no active joint of baxter moves frame 'right_gripper'"):
        bind(baxter, [Pose("right_gripper", T)])
    with pytest.raises(TargetError, match="frame 'left_gripper' has two goals with different targets"):
        bind(baxter, [Pose("left_gripper", T), Position("left_gripper", T.translation + 0.01)])
    bind(baxter, [Pose("left_gripper", T), Position("left_gripper", T.translation)])  # the same target: fine


def test_a_list_bound_again_packs_its_new_targets_and_keeps_every_check():
    """A list with the goals of one bound before (new targets: an IKSolver's calls) gets the same stack and its own
    targets; the checks that read the targets (a frame's two goals clashing) still run, and the others still refuse
    what they refused."""
    baxter = ek.load_robot("baxter", tips=["left_gripper"])
    Ts = [baxter.fk(q, "left_gripper") for q in baxter.random_configurations(3, np.random.default_rng(5))]
    bound = [bind(baxter, [Pose("left_gripper", T), Position("left_wrist", T.translation)]) for T in Ts]
    assert all(b[1] is bound[0][1] for b in bound)
    for (_, _, pt, Rt), T in zip(bound, Ts, strict=True):
        assert np.array_equal(pt, [T.translation, T.translation]) and np.array_equal(Rt[0], T.rotation)
    same_frame = [bind(baxter, [Pose("left_gripper", T), Position("left_gripper", T.translation)]) for T in Ts]
    assert same_frame[1][1] is same_frame[0][1]
    with pytest.raises(TargetError, match="frame 'left_gripper' has two goals with different targets"):
        bind(baxter, [Pose("left_gripper", Ts[0]), Position("left_gripper", Ts[0].translation + 0.01)])
    with pytest.raises(FrameError, match=r"no frame 'left_grip' \(closest: left_gripper"):
        bind(baxter, [Pose("left_grip", Ts[0])])
    with pytest.raises(FrameError, match="no active joint of baxter moves frame 'right_gripper'"):
        bind(baxter, [Pose("right_gripper", Ts[0])])
    other = ek.load_robot("baxter", tips=["right_gripper"])  # another robot: its own checks and stack
    with pytest.raises(FrameError, match="no active joint of baxter moves frame 'left_gripper'"):
        bind(other, [Pose("left_gripper", Ts[0]), Position("left_wrist", Ts[0].translation)])


@settings(max_examples=60, deadline=None)
@given(st.lists(st.tuples(st.one_of(st.none(), st.floats(0, 10)), st.one_of(st.none(), st.floats(0, 4)),
                          st.floats(0.1, 5)), min_size=1, max_size=5), st.floats(0, 2))
def test_property_goal_summary_is_the_population_formulas(errors, orientation_weight):
    """goal_summary (plain floats) gives what the population's formulas give for one row: the largest position
    error, the largest angle (None when no goal has one) and _goal_cost's weighted sum."""
    baxter = _baxter_left()
    T = baxter.fk(np.zeros(baxter.n), "left_gripper")
    goals = [Pose("left_gripper", T, weight=w) if r is not None else Position("left_gripper", T.translation, weight=w)
             for _, r, w in errors]
    problem = IKProblem(baxter, goals, orientation_weight=orientation_weight)
    pairs = [(p, r) for p, r, _ in errors]
    pos, rot, cost = problem.goal_summary(pairs)
    P = np.array([[p or 0.0 for p, _ in pairs]])
    R = np.array([[r or 0.0 for _, r in pairs]])
    assert pos == P.max()
    assert rot == (None if all(r is None for _, r in pairs) else max(r for _, r in pairs if r is not None))
    assert cost == pytest.approx(float(problem._goal_cost(P, R)[0]), rel=1e-14, abs=1e-300)


_BAXTER: list = []


def _baxter_left():
    if not _BAXTER:
        _BAXTER.append(ek.load_robot("baxter", tips=["left_gripper"]))
    return _BAXTER[0]


def test_a_problem_over_goals(talos):
    rng = np.random.default_rng(2)
    qt = talos.random_configurations(1, rng)[0]
    goals = [Pose(f, talos.fk(qt, f), weight=w) for f, w in zip(TALOS_FRAMES[:3], (1.0, 2.0, 1.0), strict=True)]
    goals.append(Position(TALOS_FRAMES[3], talos.fk(qt, TALOS_FRAMES[3]).translation))
    problem = IKProblem(talos, goals, orientation_weight=0.5)
    assert problem.target is None and problem.goals == goals
    Q = np.vstack([qt, talos.random_configurations(5, rng)])
    ev = problem.evaluate(Q)
    assert ev.cost[0] == pytest.approx(0.0, abs=1e-12) and (ev.cost[1:] > 0).all()
    for i, q in enumerate(Q):  # the population's errors are the one-configuration ones
        errors = problem.goal_errors(q)
        assert ev.position_error[i] == pytest.approx(max(e[0] for e in errors), abs=1e-12)
        assert ev.orientation_error[i] == pytest.approx(max(e[1] for e in errors[:3]), abs=1e-9)
        expected = sum(g.weight * (p + 0.5 * (r or 0.0)) for g, (p, r) in zip(goals, errors, strict=True))
        assert ev.cost[i] == pytest.approx(expected, rel=1e-9, abs=1e-12)
        assert problem.assess(q)[2] == pytest.approx(expected, rel=1e-9, abs=1e-12)
    assert np.array_equal(problem.cost(Q), ev.cost)
    with pytest.raises(OptionError, match="own cost"):
        IKProblem(talos, goals, objective=problem.cost)


# ---------------------------------------------------------------------------------------------- solving
@pytest.mark.parametrize("name, build", [
    ("talos", "floating"), ("baxter", "grippers"), ("allegro_right", "fingertips"), ("go2", "floating")])
def test_memetic_meets_every_goal_of_whole_robots(name, build):
    robot = ek.load_robot(name, floating_base=build == "floating")
    rng = np.random.default_rng(5)
    for i, qt in enumerate(robot.random_configurations(4, rng)):
        if name == "talos":
            goals = [Pose(f, robot.fk(qt, f)) for f in TALOS_FRAMES[:3]] + [
                Position(TALOS_FRAMES[3], robot.fk(qt, TALOS_FRAMES[3]).translation)]
        elif name == "baxter":
            goals = [Pose(f, robot.fk(qt, f)) for f in ("left_gripper", "right_gripper")]
        elif name == "allegro_right":
            goals = [Position(f"link_{k}.0_tip", robot.fk(qt, f"link_{k}.0_tip").translation) for k in (3, 7, 11, 15)]
        else:  # go2: the base's pose and four feet
            goals = [Pose("base", robot.fk(qt, "base"))] + [
                Position(f, robot.fk(qt, f).translation) for f in ("FL_foot", "FR_foot", "RL_foot", "RR_foot")]
        result = ek.solve(robot, goals, seed=i, timeout=None, max_restarts=20)
        assert result.success, (name, result.message)
        _check_answer(robot, goals, result)


def test_goals_that_cannot_all_be_met_give_the_best_compromise(talos):
    q = np.zeros(talos.n)
    T = talos.fk(q, "left_sole_link")
    far = pin.SE3(T.rotation, T.translation + np.array([0.0, 0.0, 5.0]))  # 5 m above: out of the base box's reach
    goals = [Pose("left_sole_link", far), Position("right_sole_link", talos.fk(q, "right_sole_link").translation)]
    result = ek.solve(talos, goals, seed=0, timeout=None, max_restarts=1)
    assert not result.success and "goals not met: left_sole_link" in result.message
    assert len(result.goal_errors) == 2 and result.goal_errors[0][0] > 1.0
    assert talos.within_bounds(result.q)


def test_goal_lists_go_to_goal_methods(talos):
    goals = [Position("left_sole_link", talos.fk(np.zeros(talos.n), "left_sole_link").translation)]
    with pytest.raises(MethodError, match="goal lists are solved by 'memetic'"):
        ek.solve(talos, goals, method="algebraic")  # the closed forms: one target (every other method takes goal lists)
    with pytest.raises(TargetError, match="empty"):
        ek.solve(talos, [])


def test_a_single_target_is_the_tip_goal(rng):
    panda = ek.load_robot("panda")
    T = panda.fk(panda.random_configurations(1, rng)[0])
    a = ek.solve(panda, T, seed=3)
    b = ek.solve(panda, [Pose(panda.tip, T)], seed=3)
    assert a.success and b.success and np.array_equal(a.q, b.q)
    assert a.goal_errors is None and b.goal_errors == [(b.position_error, b.orientation_error)]
