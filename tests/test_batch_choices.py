"""solve_many and solve_trajectory with prefer=, locked= and preferences in goal lists (issue 23, gap e): the
answers :func:`evoik_pin.solve` gives one by one, whatever the workers; locked joints held; bad input refused before
any work."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import evoik_pin as ev
from evoik_pin import api
from evoik_pin.errors import BoundsError, ConfigurationError, FrameError, MethodError, OptionError, TargetError
from evoik_pin.goals import JointLimitMargin, MinimalDisplacement, Pose, Position, Posture

#: a machine-independent budget: the same seed gives the same answer (prefer's default budget is a clock)
BUDGET = {"timeout": None, "max_restarts": 2}
LOCK = {"panda_joint3": 0.25}


@pytest.fixture(scope="module")
def panda():
    robot = ev.load_robot("panda")
    ev.prepare(robot)
    return robot


@pytest.fixture(scope="module")
def path(panda):
    """A smooth joint path (9 points on a line between two configurations) and its tip poses."""
    rng = np.random.default_rng(21)
    a, b = panda.random_configurations(2, rng)
    b = a + np.clip(b - a, -0.6, 0.6)
    Q = a + np.linspace(0.0, 1.0, 9)[:, None] * (b - a)
    return Q, [panda.fk(q) for q in Q]


@pytest.fixture(scope="module")
def poses(panda):
    rng = np.random.default_rng(22)
    Q = panda.random_configurations(4, rng)
    Q[:, 2] = LOCK["panda_joint3"]  # reachable with joint 3 locked too
    return Q, [panda.fk(q) for q in Q]


def _meets(robot, q, T, tol=1e-6):
    """The tip pose at q is T within tol (m, rad), by Pinocchio directly."""
    data = robot.model.createData()
    pin.framesForwardKinematics(robot.model, data, robot.to_pinocchio(q))
    M = data.oMf[robot.model.getFrameId(robot.tip)]
    return (np.linalg.norm(M.translation - T.translation) <= tol
            and np.linalg.norm(pin.log3(T.rotation.T @ M.rotation)) <= tol)


def _spawned(seed, N):
    """Target i's generator as solve_many documents it: SeedSequence(seed).spawn(N)[i]."""
    return [np.random.default_rng(s) for s in np.random.SeedSequence(seed).spawn(N)]


def _one_by_one(robot, targets, seed, q0=None, **options):
    Q0 = [None] * len(targets) if q0 is None else np.broadcast_to(q0, (len(targets), robot.n))
    return [ev.solve(robot, t, seed=g, q0=q, **options) for t, g, q in zip(targets, _spawned(seed, len(targets)), Q0,
                                                                          strict=True)]


# ---------------------------------------------------------------------- solve_trajectory
def test_trajectory_nearest_is_continuous_and_solve_one_by_one(panda, path):
    Q, targets = path
    q0 = Q[0]
    near = ev.solve_trajectory(panda, targets, q0=q0, prefer="nearest", seed=np.random.default_rng(7), **BUDGET)
    first = ev.solve_trajectory(panda, targets, q0=q0, seed=np.random.default_rng(7), **BUDGET)
    assert all(r.success for r in near) and all(_meets(panda, r.q, T) for r, T in zip(near, targets, strict=True))

    def steps(results):
        q = np.array([q0] + [r.q for r in results])
        return np.linalg.norm(np.diff(q, axis=0), axis=1)

    no_farther = steps(near) <= steps(first) + 1e-9
    assert no_farther.sum() >= len(targets) - 1, (steps(near), steps(first))
    # each point: solve(prefer="nearest") from the previous answer, drawing from the one generator in turn
    rng, previous = np.random.default_rng(7), q0
    for r, T in zip(near, targets, strict=True):
        one = ev.solve(panda, T, q0=previous, prefer="nearest", seed=rng, **BUDGET)
        np.testing.assert_array_equal(r.q, one.q)
        previous = one.q
    again = ev.solve_trajectory(panda, targets, q0=q0, prefer="nearest", seed=np.random.default_rng(7), **BUDGET)
    assert all(np.array_equal(a.q, b.q) for a, b in zip(near, again, strict=True))


def test_trajectory_locked_manipulability_and_preferences(panda, poses):
    Q, targets = poses
    out = ev.solve_trajectory(panda, targets, locked=LOCK, prefer="manipulability", seed=1, **BUDGET)
    assert all(r.success and r.q.shape == (panda.n,) and r.q[2] == LOCK["panda_joint3"] for r in out)
    assert all(_meets(panda, r.q, T) for r, T in zip(out, targets, strict=True))
    mid = (panda.lower + panda.upper) / 2
    lists = [[Pose(panda.tip, T), Posture(mid, 0.5)] for T in targets]
    plain = ev.solve_trajectory(panda, [[Pose(panda.tip, T)] for T in targets], q0=Q[0], seed=2, **BUDGET)
    pref = ev.solve_trajectory(panda, lists, q0=Q[0], seed=2, **BUDGET)
    for a, b, T in zip(plain, pref, targets, strict=True):
        assert b.success and _meets(panda, b.q, T)
        assert np.linalg.norm(b.q - mid) <= np.linalg.norm(a.q - mid) + 1e-9


def test_trajectory_pro_box_with_prefer(panda, path):
    Q, targets = path
    out = ev.solve_trajectory(panda, targets, q0=Q[0], prefer="nearest", pro=True, delta=0.3, seed=0, **BUDGET)
    assert all(r.success for r in out)
    for previous, r in zip(out[:-1], out[1:], strict=True):
        assert np.all(np.abs(r.q - previous.q) <= 0.3 + 1e-12)  # inside the previous answer's box


def test_trajectory_bad_input_before_any_work(panda, path, monkeypatch):
    _, targets = path

    def no_work(*a, **k):
        raise AssertionError("a point was solved before the call's input was checked")

    monkeypatch.setattr(ev.IKSolver, "solve", no_work)
    monkeypatch.setattr(api, "_run", no_work)
    with pytest.raises(OptionError, match="prefer"):
        ev.solve_trajectory(panda, targets, prefer="closest", q0=np.zeros(7))
    with pytest.raises(OptionError, match="q0"):
        ev.solve_trajectory(panda, targets, prefer="nearest")
    with pytest.raises(MethodError, match="memetic"):
        ev.solve_trajectory(panda, targets, prefer="nearest", q0=np.zeros(7), method="de")
    with pytest.raises(FrameError, match="panda_joint9"):
        ev.solve_trajectory(panda, targets, locked={"panda_joint9": 0.0})
    with pytest.raises(BoundsError, match="panda_joint4"):
        ev.solve_trajectory(panda, targets, locked={"panda_joint4": 1.0})
    lists = [[Pose(panda.tip, T)] for T in targets]
    with pytest.raises(ConfigurationError, match="goal list 2.*Posture"):
        ev.solve_trajectory(panda, lists[:2] + [[Pose(panda.tip, targets[2]), Posture(np.zeros(3))]])
    with pytest.raises(OptionError, match="goal list 0.*q0"):
        ev.solve_trajectory(panda, [[Pose(panda.tip, targets[0]), MinimalDisplacement()]] + lists[1:])
    with pytest.raises(TargetError, match="goal list 1.*preferences only"):
        ev.solve_trajectory(panda, [lists[0], [Posture(np.zeros(7))]])


# ---------------------------------------------------------------------- solve_many
@pytest.mark.parametrize("workers", [1, 2])
def test_many_prefer_equals_solve_one_by_one(panda, poses, workers):
    Q, targets = poses
    q0 = np.zeros(panda.n)
    for prefer in ("nearest", "manipulability"):
        out = ev.solve_many(panda, targets, prefer=prefer, q0=q0, seed=5, workers=workers, **BUDGET)
        ref = _one_by_one(panda, targets, 5, q0=q0, prefer=prefer, **BUDGET)
        assert out.q.shape == (len(targets), panda.n)
        for k, (r, T) in enumerate(zip(ref, targets, strict=True)):
            assert out.success[k] and _meets(panda, out.q[k], T)
            np.testing.assert_array_equal(out.q[k], r.q)
            assert out[k].message == r.message


@pytest.mark.parametrize("workers", [1, 2])
def test_many_locked_holds_the_joints_and_meets_the_goals(panda, poses, workers):
    Q, targets = poses
    out = ev.solve_many(panda, targets, locked=LOCK, seed=6, workers=workers, **BUDGET)
    assert out.q.shape == (len(targets), panda.n)
    assert np.all(out.q[:, 2] == LOCK["panda_joint3"]) and out.success.all()
    assert all(_meets(panda, q, T) for q, T in zip(out.q, targets, strict=True))
    assert all(r.q[2] == LOCK["panda_joint3"] and "joints locked: panda_joint3=0.25" in r.message for r in out)
    # the batched rounds on the locked robot, q expanded back to the full layout
    sub = panda.locked(LOCK)
    on_sub = ev.solve_many(sub, targets, seed=6, workers=workers, **BUDGET)
    np.testing.assert_array_equal(np.delete(out.q, 2, axis=1), on_sub.q)
    # locked with prefer: solve's answers one by one; q0 and bounds in the full layout
    q0 = np.where(np.arange(panda.n) == 2, 0.25, 0.1)
    bounds = (panda.lower, np.minimum(panda.upper, Q.max(axis=0) + 0.2))  # narrower, every target inside
    both = ev.solve_many(panda, targets, locked=LOCK, prefer="nearest", q0=q0, bounds=bounds, seed=6,
                         workers=workers, **BUDGET)
    ref = _one_by_one(panda, targets, 6, q0=q0, locked=LOCK, prefer="nearest", bounds=bounds, **BUDGET)
    for k, r in enumerate(ref):
        np.testing.assert_array_equal(both.q[k], r.q)
        assert both.q[k, 2] == 0.25 and both.success[k] and np.all(both.q[k] <= bounds[1])


@pytest.mark.parametrize("workers", [1, 2])
def test_many_goal_lists_with_preferences_equal_solve(panda, poses, workers):
    Q, targets = poses
    mid = (panda.lower + panda.upper) / 2
    lists = [[Pose(panda.tip, T), Posture(mid, 0.5)] if k % 2 == 0 else [Pose(panda.tip, T)]
             for k, T in enumerate(targets)]
    lists[3] = [Position(panda.tip, targets[3].translation), JointLimitMargin(0.1), MinimalDisplacement(0.1)]
    out = ev.solve_many(panda, lists, q0=Q[0], seed=8, workers=workers, **BUDGET)
    ref = _one_by_one(panda, lists, 8, q0=Q[0], **BUDGET)
    for k in (0, 2, 3):  # the lists holding preferences: solve's answers
        np.testing.assert_array_equal(out.q[k], ref[k].q)
        assert out[k].goal_errors == ref[k].goal_errors
    assert out.success.all() and all(_meets(panda, out.q[k], targets[k]) for k in (0, 1, 2))
    # locked: the preferences are the locked robot's (a Posture by joint name; a vector would have its 6 joints)
    lists = [[Pose(panda.tip, T), Posture({"panda_joint1": 0.3}, 0.5)] for T in targets]
    with_prefer = ev.solve_many(panda, lists, q0=Q[0], prefer="nearest", locked=LOCK, seed=8, workers=workers,
                                **BUDGET)
    ref = _one_by_one(panda, lists, 8, q0=Q[0], prefer="nearest", locked=LOCK, **BUDGET)
    for k, r in enumerate(ref):
        np.testing.assert_array_equal(with_prefer.q[k], r.q)
        assert with_prefer.q[k, 2] == 0.25


def test_many_one_goal_list_with_preferences_is_one_problem(panda, poses):
    _, targets = poses
    out = ev.solve_many(panda, [Pose(panda.tip, targets[0]), Posture(np.zeros(panda.n), 0.1)], seed=0, **BUDGET)
    assert len(out) == 1 and out.success[0]


def test_many_bad_input_before_any_work(panda, poses, monkeypatch):
    _, targets = poses

    def no_work(*a, **k):
        raise AssertionError("a target was solved before the call's input was checked")

    monkeypatch.setattr(ev.IKSolver, "solve", no_work)
    monkeypatch.setattr(api, "_run", no_work)
    q0 = np.zeros(panda.n)
    with pytest.raises(OptionError, match="prefer"):
        ev.solve_many(panda, targets, prefer="closest", q0=q0)
    with pytest.raises(OptionError, match="q0"):
        ev.solve_many(panda, targets, prefer="nearest")
    with pytest.raises(MethodError, match="memetic"):
        ev.solve_many(panda, targets, prefer="manipulability", method="de")
    with pytest.raises(FrameError, match="panda_joint9"):
        ev.solve_many(panda, targets, locked={"panda_joint9": 0.0})
    with pytest.raises(BoundsError, match="panda_joint4"):
        ev.solve_many(panda, targets, locked={"panda_joint4": 1.0})
    with pytest.raises(OptionError, match="locked"):
        ev.solve_many(panda, targets, locked=[("panda_joint1", 0.0)])
    with pytest.raises(ConfigurationError, match="7 joints"):  # q0 in the full layout
        ev.solve_many(panda, targets, locked=LOCK, q0=np.zeros(6))
    lists = [[Pose(panda.tip, T)] for T in targets]
    with pytest.raises(FrameError, match="goal list 1.*nope"):
        ev.solve_many(panda, [lists[0], lists[1] + [Posture({"nope": 0.0})]])
    with pytest.raises(ConfigurationError, match="goal list 2.*Posture"):
        ev.solve_many(panda, lists[:2] + [lists[2] + [Posture(np.zeros(7))]], locked=LOCK)  # 6 joints when locked
    with pytest.raises(OptionError, match="goal list 1.*q0"):
        ev.solve_many(panda, [lists[0], lists[1] + [MinimalDisplacement()]])
    with pytest.raises(TargetError, match="goal list 1.*preferences only"):
        ev.solve_many(panda, [lists[0], [Posture(np.zeros(7))]])


# ---------------------------------------------------------------------- the layouts
@settings(max_examples=10, deadline=None)
@given(st.sets(st.integers(0, 6), min_size=1, max_size=3), st.integers(0, 2**32 - 1))
def test_expand_rows_and_shrink_q_are_inverse(joints, seed):
    from evoik_pin.robot.locking import expand_q, expand_rows, kept_columns, locked_robot, shrink_q

    robot = ev.load_robot("panda")
    rng = np.random.default_rng(seed)
    q_full = robot.random_configurations(1, rng)[0]
    values = {robot.joint_names[k]: float(q_full[k]) for k in sorted(joints)}
    sub = locked_robot(robot, values)
    Q = sub.random_configurations(5, rng)
    full = expand_rows(robot, sub, values, Q)
    assert full.shape == (5, robot.n)
    assert np.array_equal(full[:, sorted(joints)], np.broadcast_to(q_full[sorted(joints)], (5, len(joints))))
    assert np.array_equal(full[:, kept_columns(robot, sub)], Q)
    for q, row in zip(Q, full, strict=True):
        assert np.array_equal(shrink_q(robot, sub, row), q) and np.array_equal(expand_q(robot, sub, values, q), row)
        assert np.allclose(sub.fk(q).homogeneous, robot.fk(row).homogeneous, atol=1e-12)
