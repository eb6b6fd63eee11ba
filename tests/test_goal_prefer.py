"""Goal sets, prefer=, preferences and locking (issue 23): behaviour, judged by Pinocchio's kinematics."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import evoik_pin as ev
from evoik_pin.errors import BoundsError, ConfigurationError, FrameError, MethodError, OptionError, TargetError
from evoik_pin.goals import (
    CenterOfMass,
    Direction,
    JointLimitMargin,
    LookAt,
    Manipulability,
    MinimalDisplacement,
    Pose,
    Position,
    Posture,
    RelativePose,
)
from evoik_pin.goals.preferences import turn_difference
from evoik_pin.solvers.lm import wrapping_joints
from evoik_pin.solvers.search.prefer import nearest_turn


@pytest.fixture(scope="module")
def panda():
    robot = ev.load_robot("panda")
    ev.prepare(robot)
    return robot


@pytest.fixture(scope="module")
def ur5():
    return ev.load_robot("ur5")


def _pin_pose(robot, q, frame=None):
    """The frame's pose by Pinocchio directly (the reference)."""
    data = robot.model.createData()
    pin.framesForwardKinematics(robot.model, data, robot.to_pinocchio(q))
    return data.oMf[robot.model.getFrameId(frame or robot.tip)]


def _far(T, k):
    return pin.SE3(T.rotation, T.translation + np.array([1.5 + 0.1 * k, 0.0, 0.0]))


# ---------------------------------------------------------------------- goal sets
def test_goal_set_forms_and_errors():
    T = np.eye(4)
    g = Pose("f", [T, pin.SE3.Identity()])
    assert len(g.alternatives) == 2 and g.alternatives[1].target == pin.SE3.Identity()
    assert len(Pose("f", np.stack([T, T, T])).alternatives) == 3
    assert Pose("f", T.tolist()).alternatives is None  # a nested (4, 4) list is one pose
    assert len(Position("f", [[0, 0, 1], [0, 1, 0]]).alternatives) == 2
    assert Position("f", [0, 0, 1]).alternatives is None
    with pytest.raises(TargetError, match="goal set with no poses"):
        Pose("f", [])
    with pytest.raises(TargetError, match="goal set with no points"):
        Position("f", np.zeros((0, 3)))
    bad = np.eye(4)
    bad[3] = 1.0
    with pytest.raises(TargetError, match="member 1 of the goal set"):
        Pose("f", [T, bad])


def test_goal_set_finds_the_reachable_member(panda):
    rng = np.random.default_rng(3)
    for i in range(5):
        q = panda.random_configurations(1, rng)[0]
        T = panda.fk(q)
        members = [_far(T, k) for k in range(4)] + [T] + [_far(T, 9)]
        r = ev.solve(panda, [Pose(panda.tip, members)], seed=i)
        assert r.success, r.message
        assert r.chosen == [4]
        M = _pin_pose(panda, r.q)
        assert np.linalg.norm(M.translation - T.translation) <= 1e-6
        assert np.linalg.norm(pin.log3(T.rotation.T @ M.rotation)) <= 1e-6


def test_chosen_is_none_for_single_targets(panda):
    q = np.zeros(panda.n)
    r = ev.solve(panda, [Pose(panda.tip, panda.fk(q))], seed=0)
    assert r.success and r.chosen == [None]
    assert ev.solve(panda, panda.fk(q), seed=0).chosen is None


def test_goal_set_positions_and_mixed_goals(panda):
    q = np.full(panda.n, 0.3)
    p = panda.fk(q).translation
    r = ev.solve(panda, [Position(panda.tip, [p + [2, 0, 0], p])], seed=0)
    assert r.success and r.chosen == [1]


def test_goal_set_evolutionary_violation_is_the_min(panda):
    q = np.full(panda.n, 0.2)
    T = panda.fk(q)
    problem, _ = ev.make_problem(panda, [Pose(panda.tip, [_far(T, 0), T])])
    ev_set = problem.evaluate(q[None])
    assert ev_set.position_error[0] <= 1e-12 and ev_set.orientation_error[0] <= 1e-6
    single, _ = ev.make_problem(panda, [Pose(panda.tip, _far(T, 0))])
    assert single.evaluate(q[None]).position_error[0] > 1.0
    r = ev.solve(panda, [Pose(panda.tip, [_far(T, 0), T], tolerance=1e-3)], method="de", seed=0, q0=q)
    assert r.chosen == [1]


# ---------------------------------------------------------------------- prefer
def test_prefer_checks(panda):
    T = panda.fk(np.zeros(panda.n))
    with pytest.raises(OptionError, match="prefer"):
        ev.solve(panda, T, prefer="closest")
    with pytest.raises(OptionError, match="q0"):
        ev.solve(panda, T, prefer="nearest")
    with pytest.raises(MethodError, match="memetic"):
        ev.solve(panda, T, prefer="nearest", q0=np.zeros(panda.n), method="de")


def test_prefer_nearest_is_no_farther_than_first(panda):
    rng = np.random.default_rng(5)
    for i in range(6):
        q, q0 = panda.random_configurations(2, rng)
        T = panda.fk(q)
        first = ev.solve(panda, T, q0=q0, seed=i, timeout=None, max_restarts=2)
        near = ev.solve(panda, T, q0=q0, prefer="nearest", seed=i, timeout=0.005)
        assert near.success, near.message
        M = _pin_pose(panda, near.q)
        assert np.linalg.norm(M.translation - T.translation) <= 1e-6
        assert panda.within_bounds(near.q)
        assert np.linalg.norm(near.q - q0) <= np.linalg.norm(first.q - q0) + 1e-9


def test_prefer_manipulability_beats_first(panda):
    rng = np.random.default_rng(6)
    for i in range(4):
        q = panda.random_configurations(1, rng)[0]
        T = panda.fk(q)
        first = ev.solve(panda, T, seed=i)
        best = ev.solve(panda, T, prefer="manipulability", seed=i, timeout=0.005)
        assert best.success, best.message
        assert panda.manipulability(best.q, "full") >= panda.manipulability(first.q, "full") * (1 - 1e-9)


@settings(max_examples=30, deadline=None)
@given(st.lists(st.floats(-30, 30), min_size=6, max_size=6), st.lists(st.floats(-6, 6), min_size=6, max_size=6))
def test_nearest_turn_same_pose_within_limits_and_no_farther(q, q0):
    robot = ev.load_robot("ur5")
    lo, hi = robot.lower, robot.upper
    wrap = wrapping_joints(robot, lo, hi)
    q = np.clip(np.array(q), lo, hi)
    q0 = np.array(q0)
    out = nearest_turn(q, q0, lo, hi, wrap)
    assert np.all(out >= lo) and np.all(out <= hi)
    k = (out - q) / (2 * np.pi)
    assert np.allclose(k, np.round(k), atol=1e-9)
    assert np.all(np.abs(out - q0) <= np.abs(q - q0) + 1e-12)


@pytest.mark.parametrize("name", ["ur5", "pr2_left"])
def test_turned_rows_are_nearest_turn_bit_for_bit(name):
    """The compiled nearest turns of prefer's hot path (turned_rows) are nearest_turn's numbers exactly, on UR5 (every
    joint a full turn, +-2 pi) and on PR2's arm (two continuous joints among bounded ones), rows far and near q0, on
    a bound and half a turn away."""
    from evoik_pin.solvers.search.descent import turned_rows

    if name == "pr2_left":
        from evoik_pin.robot import example_robot_data_dir

        robot = ev.load_robot(str(example_robot_data_dir() / "pr2_description/urdf/pr2.urdf"), base="torso_lift_link",
                              tip="l_gripper_tool_frame")
    else:
        robot = ev.load_robot(name)
    lo, hi = robot.lower, robot.upper
    wrap = wrapping_joints(robot, lo, hi)
    assert wrap.any()
    rng = np.random.default_rng(3)
    for _ in range(20):
        q0 = robot.random_configurations(1, rng)[0]
        near = np.clip(q0 + rng.normal(0, 0.1, (10, robot.n)), lo, hi)
        Q = np.concatenate([robot.random_configurations(30, rng), near, np.tile(lo, (2, 1)), np.tile(hi, (2, 1)),
                            np.clip(q0 + np.pi, lo, hi)[None]])
        out = turned_rows(Q, q0, lo, hi, wrap)
        assert np.array_equal(out, nearest_turn(Q, q0, lo, hi, wrap))
        assert np.array_equal(out, np.array([nearest_turn(q, q0, lo, hi, wrap) for q in Q]))


@settings(max_examples=40, deadline=None)
@given(st.integers(0, 2**32 - 1), st.integers(0, 30), st.lists(st.integers(0, 12), min_size=1, max_size=4))
def test_table_starts_follow_nearest_first(seed, k, sizes):
    """prefer's table starts (answer_choice._TableStarts, ranked once in arrays) come in nearest_first's order, taken a
    batch at a time or one by one, with ties and entries at inf among the distances."""
    from evoik_pin.solvers.search.answer_choice import _TableStarts
    from evoik_pin.solvers.search.seed_table import nearest_first

    rng = np.random.default_rng(seed)
    d = rng.integers(0, 8, size=40).astype(float)  # ties
    d[rng.random(40) < 0.3] = np.inf
    Q = np.arange(40.0)[:, None]
    k_finite = min(k, int(np.isfinite(d).sum()))
    expected = [float(i) for i in nearest_first(d, k_finite)]
    starts, got = _TableStarts(Q, d, k), []
    for size in sizes:
        got += starts.take(size)[:, 0].tolist()
    got += [q[0] for q in starts]
    assert got == expected
    one_by_one = _TableStarts(Q, d, k)
    assert [q[0] for q in one_by_one] == expected


# ---------------------------------------------------------------------- preferences
def test_preferences_keep_goals_and_lower_their_cost(panda):
    rng = np.random.default_rng(7)
    mid = (panda.lower + panda.upper) / 2
    for i in range(4):
        T = panda.fk(panda.random_configurations(1, rng)[0])
        plain = ev.solve(panda, [Pose(panda.tip, T)], seed=i)
        pref = ev.solve(panda, [Pose(panda.tip, T), Posture(mid, 1.0)], seed=i)
        assert pref.success, pref.message
        M = _pin_pose(panda, pref.q)
        assert np.linalg.norm(M.translation - T.translation) <= 1e-6
        assert np.linalg.norm(pin.log3(T.rotation.T @ M.rotation)) <= 1e-6
        assert np.linalg.norm(pref.q - mid) <= np.linalg.norm(plain.q - mid) + 1e-9


def _posture_cost(q, q_ref, wrap):
    d = turn_difference(q, q_ref, wrap)
    return 0.5 * float(d @ d)


def test_posture_refines_along_a_free_axis(ur5):
    """UR5 on a pose with its z rotation free (``free="rz"``): 5 rows on 6 joints leave a turn about the tool's z
    axis, along which Posture moves the answer (the refinement once took the goal's six rows for a full pose and
    left every answer where it was)."""
    rng = np.random.default_rng(3)
    q_ref = (ur5.lower + ur5.upper) / 2
    wrap = wrapping_joints(ur5, ur5.lower, ur5.upper)
    for i in range(3):
        T = ur5.fk(ur5.random_configurations(1, rng)[0])
        goal = Pose(ur5.tip, T, free="rz")
        plain = ev.solve(ur5, [goal], seed=i, timeout=None, max_restarts=2)
        pref = ev.solve(ur5, [goal, Posture(q_ref, 1.0)], seed=i, timeout=None, max_restarts=2)
        assert plain.success and pref.success, pref.message
        M = _pin_pose(ur5, pref.q)
        assert np.linalg.norm(M.translation - T.translation) <= 1e-6
        assert np.arccos(np.clip(M.rotation[:, 2] @ T.rotation[:, 2], -1, 1)) <= 1e-6
        assert _posture_cost(pref.q, q_ref, wrap) < _posture_cost(plain.q, q_ref, wrap) - 1e-3


def test_posture_refines_inside_a_tolerance_band(ur5):
    """A +-2 mm / +-5 degree band on UR5 (6 joints, 6 rows): inside the band no row binds, so Posture moves the
    answer (the refinement once counted six rows on six joints and stopped), which stays inside the band."""
    rng = np.random.default_rng(4)
    half = np.array([0.002] * 3 + [np.radians(5)] * 3)
    q_ref = (ur5.lower + ur5.upper) / 2
    wrap = wrapping_joints(ur5, ur5.lower, ur5.upper)
    for i in range(3):
        T = ur5.fk(ur5.random_configurations(1, rng)[0])
        goal = Pose(ur5.tip, T, tolerance=half)
        plain = ev.solve(ur5, [goal], seed=i, timeout=None, max_restarts=2)
        pref = ev.solve(ur5, [goal, Posture(q_ref, 1.0)], seed=i, timeout=None, max_restarts=2)
        assert plain.success and pref.success, pref.message
        M = _pin_pose(ur5, pref.q)
        v = np.concatenate([T.rotation.T @ (M.translation - T.translation), pin.log3(T.rotation.T @ M.rotation)])
        assert (np.abs(v) <= half * (1 + 1e-9)).all(), v / half
        assert _posture_cost(pref.q, q_ref, wrap) < _posture_cost(plain.q, q_ref, wrap) - 1e-4


@pytest.mark.parametrize(("make", "free"), [
    (lambda r, q, T: [Pose(r.tip, T, free="rz")], 2),
    (lambda r, q, T: [Position(r.tip, T.translation), LookAt(r.tip, [0, 0, 1], T.act(np.array([0, 0, 0.4])))], 2),
    (lambda r, q, T: [Direction(r.tip, [0, 0, 1], T.rotation[:, 2])], 5),
    (lambda r, q, T: [RelativePose("panda_link1", r.tip, r.fk(q, "panda_link1").actInv(T))], 1),
    (lambda r, q, T: [CenterOfMass(point=r.fk(q, "panda_link4").translation, axes="xy")], 5),
], ids=["free axis", "position + LookAt", "Direction", "RelativePose", "CenterOfMass"])
def test_refine_steps_where_every_goal_kind_stays_met(panda, make, free):
    """The null space refine steps in is that of every goal kind's own error: moving an answer 1e-4 along any of
    its directions changes no goal's error by more than second order, and it has the dimension the goals leave
    (7 joints less the rows that bind: a free axis 5, a position 3 and a gaze 2, a direction 2, a relative pose of
    the six joints after link1 6, a CoM over a point 2)."""
    from evoik_pin.solvers.lm import LevenbergMarquardt
    from evoik_pin.solvers.search.prefer import _null_basis, _task_jacobian

    q_true = np.array([0.3, -0.4, 0.2, -1.9, 0.1, 1.6, 0.4])
    T = panda.fk(q_true)
    goals = make(panda, q_true, T)
    r = ev.solve(panda, goals, q0=q_true + 0.05, seed=0, timeout=None, max_restarts=2)
    assert r.success, r.message
    problem, _ = ev.make_problem(panda, goals)
    N = _null_basis(_task_jacobian(problem, r.q, LevenbergMarquardt(problem)))
    assert N.shape[0] == free
    h = 1e-4
    for v in N:
        for sign in (-1.0, 1.0):
            errors = problem.goal_errors(r.q + sign * h * v)
            assert max(max(p or 0.0, a or 0.0) for p, a in errors) < 20 * h * h, errors


def test_preferences_never_step_into_collision(panda):
    """A ball where Posture's refinement would take Panda's elbow (link4's origin in the answer refined without a
    scene): with the scene, the refined answer stays out of it, says so truthfully, and is no worse for Posture than
    the plain answer (the refinement once walked into the ball and kept the search's stale collision_free=True:
    a colliding answer reported as a success)."""
    from evoik_pin.scene import Scene

    mid = (panda.lower + panda.upper) / 2
    rng = np.random.default_rng(5)
    T = [panda.fk(panda.random_configurations(1, rng)[0]) for _ in range(5)][-1]
    options = {"seed": 4, "timeout": None, "max_restarts": 2}
    free = ev.solve(panda, [Pose(panda.tip, T), Posture(mid)], **options)
    scene = Scene(panda).add_sphere("ball", 0.04, pin.SE3(np.eye(3), panda.fk(free.q, "panda_link4").translation))
    assert scene.in_collision(free.q, 0.0)  # the ball is where the refinement goes
    plain = ev.solve(panda, [Pose(panda.tip, T)], scene=scene, **options)
    pref = ev.solve(panda, [Pose(panda.tip, T), Posture(mid)], scene=scene, **options)
    assert plain.success and not scene.in_collision(plain.q, 0.0)
    assert pref.success, pref.message
    assert not scene.in_collision(pref.q, 0.0)
    assert pref.collision_free is True
    M = _pin_pose(panda, pref.q)
    assert np.linalg.norm(M.translation - T.translation) <= 1e-6
    assert 0.5 * np.sum((pref.q - mid) ** 2) <= 0.5 * np.sum((plain.q - mid) ** 2) + 1e-12


def test_joint_limit_margin_and_posture_by_name(panda):
    T = panda.fk(np.full(panda.n, 0.1))
    # a budget of restarts, not of wall-clock time: the verdict must not depend on the machine's load
    r = ev.solve(panda, [Pose(panda.tip, T), JointLimitMargin(0.1), Posture({"panda_joint1": 0.5}, 0.5)], seed=0,
                 timeout=None, max_restarts=20)
    assert r.success, r.message


def test_minimal_displacement_and_manipulability_preferences(panda):
    rng = np.random.default_rng(8)
    q, q0 = panda.random_configurations(2, rng)
    T = panda.fk(q)
    r = ev.solve(panda, [Pose(panda.tip, T), MinimalDisplacement()], q0=q0, seed=0)
    assert r.success
    r2 = ev.solve(panda, [Pose(panda.tip, T), Manipulability()], seed=0)
    assert r2.success
    r3 = ev.solve(panda, [Pose(panda.tip, T), Posture(np.zeros(panda.n))], method="de", seed=0, q0=q,
                  max_generations=5)
    assert r3.success, r3.message


def test_preference_errors(panda):
    T = panda.fk(np.zeros(panda.n))
    with pytest.raises(OptionError, match="margin"):
        JointLimitMargin(-0.1)
    with pytest.raises(OptionError, match="weight"):
        Posture(np.zeros(7), 0.0)
    with pytest.raises(FrameError, match="nope"):
        ev.solve(panda, [Pose(panda.tip, T), Posture({"nope": 0.0})])
    with pytest.raises(ConfigurationError, match="Posture"):
        ev.solve(panda, [Pose(panda.tip, T), Posture(np.zeros(3))])
    with pytest.raises(OptionError, match="q0"):
        ev.solve(panda, [Pose(panda.tip, T), MinimalDisplacement()])
    with pytest.raises(TargetError, match="preferences only"):
        ev.solve(panda, [Posture(np.zeros(7))])


# ---------------------------------------------------------------------- locking
def test_locked_robot_kinematics_match_pinocchio(panda):
    locked = panda.locked({"panda_joint1": 0.4, "panda_joint4": -1.2})
    assert locked.n == panda.n - 2
    assert locked.joint_names == [j for j in panda.joint_names if j not in ("panda_joint1", "panda_joint4")]
    rng = np.random.default_rng(9)
    for q in locked.random_configurations(5, rng):
        full = np.insert(np.insert(q, 0, 0.4), 3, -1.2)
        assert np.allclose(locked.fk(q).homogeneous, panda.fk(full).homogeneous, atol=1e-12)
        assert np.allclose(locked.full_configuration(q), panda.full_configuration(full), atol=1e-12)
        J_fd = np.empty((3, locked.n))
        for k in range(locked.n):
            dq = np.zeros(locked.n)
            dq[k] = 1e-7
            J_fd[:, k] = (locked.fk(q + dq).translation - locked.fk(q - dq).translation) / 2e-7
        assert np.allclose(locked.jacobian(q)[:3], J_fd, atol=1e-6)
    again = locked.locked({"panda_joint2": 0.1})
    assert again.n == panda.n - 3 and np.allclose(
        again.fk(np.zeros(4)).homogeneous, panda.fk([0.4, 0.1, 0, -1.2, 0, 0, 0]).homogeneous)


def test_locked_errors(panda):
    with pytest.raises(FrameError, match="panda_joint9"):
        panda.locked({"panda_joint9": 0.0})
    with pytest.raises(BoundsError, match=r"panda_joint4.*limits"):
        panda.locked({"panda_joint4": 1.0})
    with pytest.raises(OptionError):
        panda.locked([("panda_joint1", 0.0)])


def test_solve_locked_returns_the_full_layout(panda):
    rng = np.random.default_rng(10)
    q = panda.random_configurations(1, rng)[0]
    q[2] = 0.25
    T = panda.fk(q)
    r = ev.solve(panda, T, locked={"panda_joint3": 0.25}, seed=0, q0=np.zeros(panda.n))
    assert r.success, r.message
    assert r.q.shape == (panda.n,) and r.q[2] == 0.25
    M = _pin_pose(panda, r.q)
    assert np.linalg.norm(M.translation - T.translation) <= 1e-6
    r2 = ev.solve(panda, [Pose(panda.tip, T)], locked={"panda_joint3": 0.25}, prefer="nearest", q0=q, seed=0)
    assert r2.success and r2.q[2] == 0.25


# ---------------------------------------------------------------------- goals files and the command line
def test_goals_file_round_trip_of_sets_and_preferences(tmp_path, panda):
    from evoik_pin.errors import GoalsFileError
    from evoik_pin.io.goals_file import load_goals, save_goals

    T = panda.fk(np.full(panda.n, 0.3))
    goals = [Pose(panda.tip, [_far(T, 0), T]), Posture({"panda_joint1": 0.2}, 0.5), JointLimitMargin(0.1),
             Manipulability(), MinimalDisplacement(2.0), Posture(np.zeros(panda.n))]
    for suffix in (".yaml", ".json"):
        path = save_goals(goals, tmp_path / f"g{suffix}")
        back = load_goals(path)
        assert [type(g) for g in back] == [type(g) for g in goals]
        assert np.array_equal(back[0].member_targets[0], goals[0].member_targets[0])
        assert np.array_equal(back[0].member_targets[1], goals[0].member_targets[1])
        assert back[1].q_ref == {"panda_joint1": 0.2} and back[1].weight == 0.5
        assert back[2].margin == 0.1 and back[4].weight == 2.0
        # a budget of restarts, not of wall-clock time: the verdict must not depend on the machine's load
        r = ev.solve(panda, back, q0=np.zeros(panda.n), seed=0, timeout=None, max_restarts=20)
        assert r.success and r.chosen == [1], r.message
    bad = tmp_path / "bad.yaml"
    bad.write_text("goals:\n  - {frame: panda_hand_tcp, kind: position, targets: []}\n")
    with pytest.raises(GoalsFileError, match="non-empty list of targets"):
        load_goals(bad)
    bad.write_text("goals:\n  - {kind: posture}\n")
    with pytest.raises(GoalsFileError, match="q_ref"):
        load_goals(bad)


def test_cli_prefer_and_locked(tmp_path):
    import json
    import subprocess
    import sys

    out = subprocess.run([sys.executable, "-m", "evoik_pin.cli", "solve", "panda", "--xyz", "0.4", "0.1", "0.5",
                          "--rpy", "180", "0", "0", "--prefer", "nearest", "--q0", "0", "0", "0", "-90", "0", "90",
                          "45", "--locked", "panda_joint3=10", "--json"], capture_output=True, text=True)
    assert out.returncode == 0, out.stderr
    info = json.loads(out.stdout)
    assert info["success"] and abs(info["q_deg"][2] - 10.0) < 1e-9
    bad = subprocess.run([sys.executable, "-m", "evoik_pin.cli", "solve", "panda", "--xyz", "0.4", "0.1", "0.5",
                          "--locked", "panda_joint9=1"], capture_output=True, text=True)
    assert bad.returncode == 2 and "panda_joint9" in bad.stderr


def test_bench_script_runs_small():
    """scripts/bench_goal_kinds_prefer.py's run(args) makes its section (3 targets a part)."""
    import argparse
    import importlib.util
    from pathlib import Path

    pytest.importorskip("pytracik")
    path = Path(__file__).resolve().parents[1] / "scripts" / "bench_goal_kinds_prefer.py"
    spec = importlib.util.spec_from_file_location("bench_goal_kinds_prefer", path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    text = module.run(argparse.Namespace(n=3, seed=0, verbose=False, prefer_timeout=None))
    assert "nearest vs Distance" in text and "10 grasps, 7 unreachable" in text and "JointLimitMargin" in text


def test_preferences_bench_runs_small(monkeypatch):
    """scripts/bench_goal_kinds_preferences.py on two UR5 free="rz" problems, the fixed budget: the three ways
    interleaved, each answer judged by the benchmark's geometry, no problem lost, Posture's distance lowered."""
    import importlib
    from pathlib import Path

    monkeypatch.syspath_prepend(str(Path(__file__).resolve().parents[1] / "scripts"))
    module = importlib.import_module("bench_goal_kinds_preferences")
    bench = module.axes_benches(2, 23)[0]
    module.run_bench(bench, {"fixed": {"timeout": None, "max_restarts": 2}}, lambda msg: None)
    rows = bench.rows["fixed"]
    assert [[r[0] for r in rows[w]] for w in module.WAYS] == [[True, True]] * 3
    plain, posture = ([module.posture_distance(r[2], bench.q_ref, bench.wrap) for r in rows[w]]
                      for w in module.WAYS[:2])
    assert all(b < a for a, b in zip(plain, posture, strict=True)), (plain, posture)
    line = module.report_rows(bench)[0]
    assert line.startswith("| UR5 `free=\"rz\"` | fixed | 2 | 100.0 / 100.0 / 100.0 | -0 +0 / -0 +0 |")
    assert line.endswith("| - (no joint with limits) |")


def test_jacobian_world_unchecked_equals_jacobian():
    for robot in (ev.load_robot("panda"), ev.load_robot("panda", base="panda_link1")):
        rng = np.random.default_rng(11)
        for q in robot.random_configurations(3, rng):
            for frame in (None, robot.frames[-3]):
                fid = None if frame is None else robot.frame_id(frame)
                assert np.allclose(robot.jacobian_world_unchecked(q, fid), robot.jacobian(q, "world", of=frame),
                                   atol=1e-12)


# ---------------------------------------------------------------------- the compiled null-space descent
def _answers(robot, problem, rng, k):
    """k LM answers of the problem (every goal met) from uniform random starts."""
    from evoik_pin.solvers.lm import LevenbergMarquardt

    lm = LevenbergMarquardt(problem)
    out = []
    while len(out) < k:
        run = lm.run(rng.uniform(robot.lower, robot.upper), 100)
        if run.converged:
            out.append(run.q)
    return lm, np.array(out)


@settings(max_examples=12, deadline=None)
@given(st.integers(0, 2**32 - 1), st.sampled_from(["nearest", "manipulability"]))
def test_descent_never_worsens_the_criterion_and_keeps_the_goals(panda, seed, prefer):
    from evoik_pin.solvers.lm.nullspace import MODE_MANIPULABILITY, MODE_NEAREST, nullspace_kernel

    rng = np.random.default_rng(seed)
    q_target, q0 = panda.random_configurations(2, rng)
    T = panda.fk(q_target)
    problem = ev.make_problem(panda, T, q0=q0)[0]
    lm, Q = _answers(panda, problem, rng, 3)
    mode = MODE_NEAREST if prefer == "nearest" else MODE_MANIPULABILITY
    Q_out, f = np.empty_like(Q), np.empty(Q.shape[0])
    nullspace_kernel()["descend_batch"](Q, q0, mode, *lm._args, 30, 4, 0.5, Q_out, f)

    def criterion(q):  # the reference: NumPy distance, Pinocchio's Jacobian
        if prefer == "nearest":
            return float(np.sum((q - q0) ** 2))
        J = panda.jacobian(q, "world")
        return -float(np.sqrt(max(np.linalg.det(J @ J.T), 0.0)))

    for q_in, q_out, f_out in zip(Q, Q_out, f, strict=True):
        assert criterion(q_out) <= criterion(q_in) + 1e-12
        assert f_out == pytest.approx(criterion(q_out), rel=1e-9, abs=1e-12)
        assert panda.within_bounds(q_out)
        M = _pin_pose(panda, q_out)
        assert np.linalg.norm(M.translation - T.translation) <= 1e-6
        assert np.linalg.norm(pin.log3(T.rotation.T @ M.rotation)) <= 1e-6


@pytest.mark.parametrize("prefer", ["nearest", "manipulability"])
def test_descent_then_best_is_the_trial_then_a_round_of_its_best(panda, prefer):
    """descend_batch_then_best (prefer's trial and its best answer's first round in one call) gives exactly what the
    two calls give: every answer descended, then the one of least criterion descended on from where it ended."""
    from evoik_pin.solvers.lm.nullspace import MODE_MANIPULABILITY, MODE_NEAREST, nullspace_kernel

    kernels = nullspace_kernel()
    mode = MODE_NEAREST if prefer == "nearest" else MODE_MANIPULABILITY
    for seed in range(6):
        rng = np.random.default_rng(seed)
        q_target, q0 = panda.random_configurations(2, rng)
        problem = ev.make_problem(panda, panda.fk(q_target), q0=q0)[0]
        lm, Q = _answers(panda, problem, rng, 4)
        Q_fused, f_fused = np.empty_like(Q), np.empty(4)
        kernels["descend_batch_then_best"](Q, q0, mode, *lm._args, 3, 10, 1.0, 10, Q_fused, f_fused)
        Q_out, f = np.empty_like(Q), np.empty(4)
        kernels["descend_batch"](Q, q0, mode, *lm._args, 3, 10, 1.0, Q_out, f)
        best = int(np.argmin(f))
        kernels["descend_batch"](Q_out[best:best + 1].copy(), q0, mode, *lm._args, 10, 10, 1.0, Q_out[best:best + 1],
                                 f[best:best + 1])
        assert np.array_equal(Q_fused, Q_out) and np.array_equal(f_fused, f)


@pytest.mark.parametrize("prefer", ["nearest", "manipulability"])
def test_descent_stays_within_the_limits_of_full_turn_joints(ur5, prefer):
    """UR5's joints span two full turns (+-2 pi), limits LM's clip box leaves open (it wraps them): the descent
    keeps every answer inside [lower, upper] all the same, q0 near the limits pulling it outward. Outside, an answer
    taken back into the box lands a full turn from q0 (xArm's misses against TRAC-IK's Distance)."""
    from evoik_pin.solvers.lm import LevenbergMarquardt
    from evoik_pin.solvers.lm.nullspace import MODE_MANIPULABILITY, MODE_NEAREST, nullspace_kernel

    mode = MODE_NEAREST if prefer == "nearest" else MODE_MANIPULABILITY
    for seed in range(6):
        rng = np.random.default_rng(seed)
        q_target = ur5.random_configurations(1, rng)[0]
        q0 = np.where(rng.random(ur5.n) < 0.5, ur5.lower + 0.05, ur5.upper - 0.05)
        T = ur5.fk(q_target)
        lm = LevenbergMarquardt(ev.make_problem(ur5, T.translation, q0=q0)[0])
        Q = []
        while len(Q) < 3:  # answers near q0, inside the limits
            run = lm.run(np.clip(q0 + rng.normal(size=ur5.n), ur5.lower, ur5.upper), 100)
            if run.converged and ur5.within_bounds(run.q):
                Q.append(run.q)
        Q = np.array(Q)
        Q_out, f = np.empty_like(Q), np.empty(Q.shape[0])
        nullspace_kernel()["descend_batch"](Q, q0, mode, *lm._args, 30, 4, 0.5, Q_out, f)
        for q_in, q_out in zip(Q, Q_out, strict=True):
            assert ur5.within_bounds(q_out), (seed, q_out)
            assert np.linalg.norm(ur5.fk(q_out).translation - T.translation) <= 1e-6
            if prefer == "nearest":
                assert np.linalg.norm(q_out - q0) <= np.linalg.norm(q_in - q0) + 1e-12


def test_nearest_no_farther_than_lm_from_q0(panda):
    from evoik_pin.solvers.lm import LevenbergMarquardt

    rng = np.random.default_rng(11)
    checked = 0
    for i in range(12):
        q, q0 = panda.random_configurations(2, rng)
        q0 = np.clip(q + rng.normal(size=panda.n) * 0.4, panda.lower, panda.upper)  # LM from q0 often converges
        T = panda.fk(q)
        run = LevenbergMarquardt(ev.make_problem(panda, T, q0=q0)[0]).run(q0, 100)
        if not run.converged:
            continue
        checked += 1
        near = ev.solve(panda, T, q0=q0, prefer="nearest", seed=i)
        assert near.success, near.message
        assert np.linalg.norm(near.q - q0) <= np.linalg.norm(run.q - q0) + 1e-9
    assert checked >= 6


def test_prefer_is_reproducible_without_a_clock(panda):
    rng = np.random.default_rng(12)
    q, q0 = panda.random_configurations(2, rng)
    T = panda.fk(q)
    for prefer in ("nearest", "manipulability"):
        a, b = (ev.solve(panda, T, q0=q0, prefer=prefer, seed=4, timeout=None, max_restarts=8) for _ in range(2))
        assert a.success
        np.testing.assert_array_equal(a.q, b.q)



def test_descent_mode_skips_mimic_trees(panda):
    """The compiled descent works on q as the physical joints: a tree with mimic joints keeps the Python refine."""
    from types import SimpleNamespace

    from urdf_helpers import mimic_3r

    from evoik_pin.robot import load_robot
    from evoik_pin.solvers.lm import LevenbergMarquardt
    from evoik_pin.solvers.lm.nullspace import MODE_NEAREST
    from evoik_pin.solvers.search.descent import descent_mode
    from evoik_pin.solvers.search.prefer import make_criterion

    for robot, expected in ((load_robot(mimic_3r(), tip="tool"), None), (panda, MODE_NEAREST)):
        q = robot.random_configurations(1, np.random.default_rng(0))[0]
        problem = ev.make_problem(robot, robot.fk(q), q0=q)[0]
        criterion = make_criterion(problem, "nearest", (), wrapping_joints(robot, robot.lower, robot.upper))
        assert descent_mode("nearest", criterion, [SimpleNamespace(lm=LevenbergMarquardt(problem))]) == expected


@settings(max_examples=40, deadline=None)
@given(st.integers(0, 2**32 - 1), st.integers(1, 12), st.integers(1, 20))
def test_distinct_keeps_the_order_and_drops_near_duplicates(seed, count, size):
    from evoik_pin.solvers.search.descent import distinct

    rng = np.random.default_rng(seed)
    Q = rng.normal(size=(size, 3))
    for k in range(1, size):  # some answers repeat an earlier one within 1e-3
        if rng.random() < 0.4:
            Q[k] = Q[rng.integers(k)] + rng.normal(size=3) * 1e-5
    answers = [(float(k), q, 0) for k, q in enumerate(Q)]
    picked = distinct(answers, count)
    keys = [a[0] for a in picked]
    assert keys == sorted(keys) and len(picked) <= count
    P = np.array([a[1] for a in picked])
    assert all(np.linalg.norm(P[a] - P[b]) >= 1e-3 for a in range(len(P)) for b in range(a))
    last = int(keys[-1])
    for k in range(last + 1):  # every answer up to the last pick is picked or near an earlier pick
        if float(k) not in keys:
            assert min(np.linalg.norm(Q[k] - Q[int(j)]) for j in keys if j < k) < 1e-3
    if len(picked) < count:  # fewer than asked: every answer is near a pick
        assert all(min(np.linalg.norm(q - p) for p in P) < 1e-3 for q in Q)


def test_nearest_without_a_clock_reaches_its_branch_optimum(panda):
    """No clock (max_restarts): q0's own run and the starts around it and from the table are collected, and the
    best answers descend to the optimum of their branch: the answer is no farther than a known answer near q0,
    and |q - q0| is stationary along the self-motion manifold (the gradient q - q0 has no component in the null
    space of the tip's Jacobian) wherever no joint is on a bound."""
    rng = np.random.default_rng(23)
    stationary = 0
    for i in range(8):
        q_known = panda.random_configurations(1, rng)[0]
        q0 = np.clip(q_known + rng.normal(size=panda.n) * 0.5, panda.lower, panda.upper)
        T = panda.fk(q_known)
        r = ev.solve(panda, T, q0=q0, prefer="nearest", seed=i, timeout=None, max_restarts=8)
        assert r.success, r.message
        assert np.linalg.norm(r.q - q0) <= np.linalg.norm(q_known - q0) + 1e-9
        if np.min(np.minimum(r.q - panda.lower, panda.upper - r.q)) > 1e-6:
            J = panda.jacobian(r.q, "world")
            g = r.q - q0
            along = g - np.linalg.pinv(J) @ (J @ g)  # the gradient's null-space component
            assert np.linalg.norm(along) <= 1e-5 * max(1.0, np.linalg.norm(g)), (i, np.linalg.norm(along))
            stationary += 1
    assert stationary >= 4


@settings(max_examples=20, deadline=None)
@given(st.integers(0, 2**32 - 1), st.sampled_from(["panda", "ur5"]))
def test_seed_table_joint_distances(seed, name):
    """SeedTable.joint_distances: |Q - q0|^2 per entry, the full-turn joints (UR5's) by their chord on the unit
    circle (2 - 2 cos d, the same for every turn of d); its matrix-vector form equal to the plain one."""
    from evoik_pin.solvers.search.memetic import prepare

    robot = ev.load_robot(name)
    table, _ = prepare(robot, robot.lower, robot.upper, 256)
    wrap = wrapping_joints(robot, robot.lower, robot.upper)
    assert wrap.any() == (name == "ur5")
    q0 = robot.random_configurations(1, np.random.default_rng(seed))[0]
    d = table.Q - q0
    expected = np.where(wrap, 2.0 - 2.0 * np.cos(d), d * d).sum(axis=1)
    for _ in range(2):  # the first call keeps the entries' features, the second reads them
        np.testing.assert_allclose(table.joint_distances(q0, wrap), expected, rtol=1e-9, atol=1e-9)
    turned = np.where(wrap, q0 + 2 * np.pi, q0)  # a full turn of the wrapping joints: the same distances
    np.testing.assert_allclose(table.joint_distances(turned, wrap), expected, rtol=1e-9, atol=1e-9)


def test_nearest_ranks_table_entries_near_q0_first(panda):
    """prefer="nearest" starts LM from table entries near the target's pose *and* near q0: the first entries are
    nearer q0 in joint space than those ranked by pose alone, and the joint term scales the ranking, not replaces
    it (the entries stay near the pose: within the pose-only ranking's first 200 of 4096)."""
    from types import SimpleNamespace

    from evoik_pin.solvers.search.answer_choice import NEAR_JOINT_WEIGHT, _variant_starts
    from evoik_pin.solvers.search.memetic import prepare
    from evoik_pin.solvers.search.seed_table import default_table_size

    table, _ = prepare(panda, panda.lower, panda.upper, default_table_size(panda.n))
    wrap = wrapping_joints(panda, panda.lower, panda.upper)
    rng = np.random.default_rng(5)
    for _ in range(5):
        q, q0 = panda.random_configurations(2, rng)
        problem = ev.make_problem(panda, panda.fk(q), q0=q0)[0]
        by_pose, by_both = SimpleNamespace(), SimpleNamespace()
        _variant_starts(table, problem, [by_pose], 8, None)
        joint = NEAR_JOINT_WEIGHT * table.weight**2 * table.joint_distances(q0, wrap)
        _variant_starts(table, problem, [by_both], 8, None, joint)
        pose_first, both_first = np.array(list(by_pose.starts)), np.array(list(by_both.starts))
        assert len(pose_first) == len(both_first) == 8
        assert np.linalg.norm(both_first - q0, axis=1).mean() < np.linalg.norm(pose_first - q0, axis=1).mean()
        ff = table.frame_search(problem)
        order = np.argsort(table.distances(ff, table.target_point(problem, ff)))
        rank = {tuple(table.Q[k]): r for r, k in enumerate(order)}
        assert max(rank[tuple(s)] for s in both_first) < 200  # of 4096 (measured: 20-50)


@pytest.mark.parametrize("rows", [0, 3, 40])
def test_manipulability_costs_equal_cost_row_by_row(panda, rows):
    """Manipulability.costs (rows one by one up to SMALL_BATCH, batched above) equals cost on each row."""
    pref = Manipulability().bind(panda, None, panda.lower, panda.upper, np.zeros(panda.n, dtype=bool), panda.tip)
    Q = panda.random_configurations(rows, np.random.default_rng(rows))
    costs = pref.costs(Q)
    assert costs.shape == (rows,)
    np.testing.assert_allclose(costs, [pref.cost(q) for q in Q], rtol=1e-9, atol=1e-12)


@settings(max_examples=50, deadline=None)
@given(st.integers(0, 2**32 - 1), st.integers(1, 40), st.integers(1, 60), st.lists(st.integers(1, 9), min_size=1,
                                                                                    max_size=12))
def test_table_starts_hand_out_the_k_nearest_in_order(seed, size, k, chunks):
    """_TableStarts (prefer's table starts): the entry at d's argmin first, then the others of the k nearest by d,
    nearest first, entries at d = inf never; each once, whether taken in batches of any size or one by one."""
    from evoik_pin.solvers.search.answer_choice import _TableStarts

    rng = np.random.default_rng(seed)
    Q = rng.normal(size=(size, 3))
    d = rng.permutation(size).astype(float)  # distinct distances: one order
    d[rng.random(size) < 0.2] = np.inf
    d[rng.integers(size)] = -1.0  # at least one finite entry, the argmin
    first = int(d.argmin())
    expected = [first] + [int(i) for i in np.argsort(d)[:min(k, size)] if i != first and np.isfinite(d[i])]
    starts = _TableStarts(Q, d, k)
    got = [next(starts)]  # q0's neighbour alone first, as prefer="first" takes it
    for c in chunks:
        rows = starts.take(c)
        assert rows.shape[0] <= c and rows.shape[1] == 3
        got.extend(rows)
    got.extend(starts)  # the rest one by one
    assert np.array_equal(np.array(got), Q[expected])
    assert starts.take(5).shape == (0, 3)


@pytest.mark.parametrize("name", ["panda", "ur10"])
@pytest.mark.parametrize("prefer", ["nearest", "manipulability"])
def test_prefer_result_errors_are_the_answers_own(name, prefer):
    """prefer's Result reports the errors (and cost, success) of the q it returns: equal to the problem's own
    assessment of that q (the errors come from one LM evaluation at q, not a kinematics pass of their own)."""
    robot = ev.load_robot(name)
    rng = np.random.default_rng(7)
    for i in range(4):
        q, q0 = robot.random_configurations(2, rng)
        T = robot.fk(q)
        r = ev.solve(robot, T, q0=q0, prefer=prefer, seed=i, timeout=None, max_restarts=4)
        problem = ev.make_problem(robot, T, q0=q0)[0]
        pos, rot, cost = problem.assess(r.q)
        assert r.success == bool(problem.succeeded(pos, rot)), r.message
        assert r.success, r.message
        assert abs(r.position_error - pos) <= 1e-12 and abs(r.orientation_error - rot) <= 1e-12
        assert abs(r.cost - cost) <= 1e-12


def test_prefer_manipulability_on_a_five_joint_arm():
    """SO-ARM has 5 joints: its 6 x 5 Jacobian's J J^T is singular everywhere, so Yoshikawa's measure is the
    product of the singular values (sqrt(det(J^T J))); with a position goal (2 redundant joints) prefer= finds
    answers more dexterous than the first."""
    arm = ev.load_robot("so_arm")
    rng = np.random.default_rng(3)
    gains = []
    for i in range(6):
        p = arm.fk(arm.random_configurations(1, rng)[0]).translation
        goals = [Position(arm.tip, p)]
        first = ev.solve(arm, goals, seed=i)
        best = ev.solve(arm, goals, prefer="manipulability", seed=i, timeout=0.005)
        assert first.success and best.success, best.message
        m_first, m_best = arm.manipulability(first.q, "full"), arm.manipulability(best.q, "full")
        assert m_first > 0
        assert m_best >= m_first * (1 - 1e-9)
        gains.append(m_best > 1.01 * m_first)
    assert any(gains)


def test_nearest_descent_measures_full_turn_joints_at_their_nearest_turn(ur5):
    """The descent's criterion is |nearest_turn(q) - q0|^2, the distance prefer="nearest" ranks by (UR5's +-2 pi
    joints): f_out equals it, it never grows, and a long descent ends where its gradient (the turned q - q0) has
    no component along the self-motion wherever no joint is on a bound; a descent in plain differences stops short
    of that when a joint ends more than pi from q0."""
    from evoik_pin.solvers.lm import LevenbergMarquardt
    from evoik_pin.solvers.lm.nullspace import MODE_NEAREST, nullspace_kernel

    wrap = wrapping_joints(ur5, ur5.lower, ur5.upper)
    stationary = 0
    for seed in range(10):
        rng = np.random.default_rng(seed)
        q_target, q0 = ur5.random_configurations(2, rng)
        T = ur5.fk(q_target)
        lm = LevenbergMarquardt(ev.make_problem(ur5, T.translation, q0=q0)[0])
        _, Q = _answers(ur5, lm.problem, rng, 4)
        Q = nearest_turn(Q, q0, ur5.lower, ur5.upper, wrap)
        Q_out, f = np.empty_like(Q), np.empty(Q.shape[0])
        nullspace_kernel()["descend_batch"](Q, q0, MODE_NEAREST, *lm._args, 300, 10, 0.5, Q_out, f)
        for q_in, q_out, f_out in zip(Q, Q_out, f, strict=True):
            g = nearest_turn(q_out, q0, ur5.lower, ur5.upper, wrap) - q0
            assert f_out == pytest.approx(float(g @ g), rel=1e-9, abs=1e-12)
            assert f_out <= float(np.sum((q_in - q0) ** 2)) + 1e-12
            assert np.linalg.norm(ur5.fk(q_out).translation - T.translation) <= 1e-6
            if np.min(np.minimum(q_out - ur5.lower, ur5.upper - q_out)) > 1e-6:
                J = ur5.jacobian(q_out, "world")[:3]
                along = g - np.linalg.pinv(J) @ (J @ g)
                assert np.linalg.norm(along) <= 1e-5 * max(1.0, np.linalg.norm(g)), (seed, np.linalg.norm(along))
                stationary += 1
    assert stationary >= 20


def test_euler_flips_keep_the_pose(panda, ur5):
    """Panda's shoulder (joints 1-3 meet in a point) flips to another configuration of the same tip pose; UR5's
    joints have no such triple."""
    from evoik_pin.solvers.search.prefer import FLIP_TOLERANCE, euler_flips, flipped

    flips = euler_flips(panda, None)
    assert (0, 0.0) in flips
    assert euler_flips(panda, None) is flips  # cached
    assert euler_flips(ur5, None) == ()
    Q = panda.random_configurations(20, np.random.default_rng(3))
    F = flipped(Q, flips)
    assert F.shape == (20 * len(flips), panda.n)
    for q, qf in zip(np.tile(Q, (len(flips), 1)), F, strict=True):
        assert np.linalg.norm(qf - q) > 1.0
        T, Tf = _pin_pose(panda, q), _pin_pose(panda, qf)
        assert np.linalg.norm(Tf.translation - T.translation) <= FLIP_TOLERANCE
        assert np.linalg.norm(pin.log3(T.rotation.T @ Tf.rotation)) <= FLIP_TOLERANCE


def test_descent_takes_a_start_off_the_goals_onto_them_first(panda):
    """A flipped answer (off the goals by the URDF's rounding at most) is restored, then descended: it meets the
    goals and f_out is its distance; a start far off the goals that the restoring steps cannot bring back keeps its
    place with f_out inf."""
    from evoik_pin.solvers.lm.nullspace import MODE_NEAREST, nullspace_kernel
    from evoik_pin.solvers.search.prefer import euler_flips, flipped

    kernel = nullspace_kernel()["descend_batch"]
    restored = 0
    for seed in range(8):
        rng = np.random.default_rng(seed)
        q_target, q0 = panda.random_configurations(2, rng)
        T = panda.fk(q_target)
        lm, Q = _answers(panda, ev.make_problem(panda, T, q0=q0)[0], rng, 4)
        F = flipped(Q, euler_flips(panda, None))
        F = F[np.all((F >= panda.lower) & (F <= panda.upper), axis=1)]
        if F.shape[0] == 0:
            continue
        F_out, f = np.empty_like(F), np.empty(F.shape[0])
        kernel(F, q0, MODE_NEAREST, *lm._args, 30, 4, 0.5, F_out, f)
        for q_out, f_out in zip(F_out, f, strict=True):
            assert np.isfinite(f_out)
            assert f_out == pytest.approx(float(np.sum((q_out - q0) ** 2)), rel=1e-9, abs=1e-12)
            assert panda.within_bounds(q_out)
            M = _pin_pose(panda, q_out)
            assert np.linalg.norm(M.translation - T.translation) <= 1e-6
            assert np.linalg.norm(pin.log3(T.rotation.T @ M.rotation)) <= 1e-6
            restored += 1
        far = panda.random_configurations(1, rng)
        far_out, f_far = np.empty_like(far), np.empty(1)
        kernel(far, q0, MODE_NEAREST, *lm._args, 30, 1, 0.5, far_out, f_far)
        assert f_far[0] == np.inf
        assert np.array_equal(far_out, far)
    assert restored >= 4


def test_descent_in_collision_keeps_answers_and_drops_flips(panda):
    """With every descended configuration in collision, the answers keep their starts and no flip (off the goals
    until descended) is kept."""
    from types import SimpleNamespace

    from evoik_pin.solvers.lm.nullspace import MODE_NEAREST
    from evoik_pin.solvers.search.descent import descend
    from evoik_pin.solvers.search.prefer import euler_flips, flipped, make_criterion

    class Everywhere:  # a scene every configuration collides with
        def in_collision(self, q, margin):
            return True

    wrap = wrapping_joints(panda, panda.lower, panda.upper)
    checked = 0
    for seed in range(20):
        rng = np.random.default_rng(seed)
        q_target, q0 = panda.random_configurations(2, rng)
        T = panda.fk(q_target)
        problem = ev.make_problem(panda, T, q0=q0)[0]
        lm, Q = _answers(panda, problem, rng, 4)
        F = flipped(Q, euler_flips(panda, None))
        if not np.all((F >= panda.lower) & (F <= panda.upper), axis=1).any():
            continue
        criterion = make_criterion(problem, "nearest", (), wrap)
        answers = sorted(zip(criterion.costs(Q).tolist(), Q, [0] * len(Q), strict=True), key=lambda a: a[0])
        picked, _ = descend(answers, [SimpleNamespace(lm=lm)], q0, MODE_NEAREST, criterion, Everywhere(), problem,
                            wrap, None, euler_flips(panda, None))
        assert picked
        for _, q, _ in picked:
            assert min(np.abs(q - a).max() for a in Q) == 0.0
        checked += 1
    assert checked >= 3


@pytest.mark.parametrize("name", ["panda", "so_arm", "pr2_torso"])
def test_manipulability_gradient_in_closed_form_equals_central_differences(name):
    """The descent's manipulability gradient (Jacobi's formula on the chain's Jacobian derivative) equals central
    differences of the measure on a 7-joint arm, on a 5-joint one (sqrt(det(J^T J))) and on PR2's arm from its base,
    whose torso lift is prismatic; the measure it returns is Pinocchio's Yoshikawa measure."""
    from evoik_pin.robot import example_robot_data_dir
    from evoik_pin.solvers.lm import LevenbergMarquardt
    from evoik_pin.solvers.lm import nullspace as ns
    from evoik_pin.solvers.lm.kernel import make_workspace, task_error, weighted_stack

    if name == "pr2_torso":
        robot = ev.load_robot(str(example_robot_data_dir() / "pr2_description/urdf/pr2.urdf"), base="base_link",
                              tip="l_gripper_tool_frame")
    else:
        robot = ev.load_robot(name)
    Q = robot.random_configurations(8, np.random.default_rng(5))
    lm = LevenbergMarquardt(ev.make_problem(robot, robot.fk(Q[0]), q0=Q[0])[0])
    kin, _, _, goals, pt, Rt = lm._args
    n = robot.n
    ws = make_workspace(kin, goals, n, 1)
    J, JJ, M, g = np.empty((6, n)), np.empty((6, 6)), np.empty((6, n)), np.empty(n)

    def measure(q):
        task_error(True, kin, False, goals, weighted_stack(goals[0]), pt, Rt, q, ws.cur, ws)
        return ns._manipulability(kin[3], goals[3], ws.cur.pg, ws.cur.Z, ws.cur.O, J, JJ)

    h = 1e-6
    for q in Q:
        m = measure(q)
        assert ns._manipulability_gradient(kin[3], goals[3], ws.cur.pg, ws.cur.Z, ws.cur.O, J, JJ, M, g) == m
        assert m == pytest.approx(robot.manipulability(q, "full"), rel=1e-9)
        central = np.array([(measure(q + h * e) - measure(q - h * e)) / (2 * h) for e in np.eye(n)])
        assert np.abs(g - central).max() <= 1e-6 * np.abs(central).max()
