"""An IKSolver's prepared velocity-box step (solvers/search/box_step.py), which a Tracker's steps take: every step's
Result equal, field by field, to the general path's (IKSolver.solve_within with the prepared steps off, the same seed)
for tip poses, 4 x 4 poses, positions and goal lists, with misses, structure changes and goal sets in between; bad input
still refused after a structure was prepared."""

import numpy as np
import pinocchio as pin
import pytest
from velocity_paths import pose_goals, smooth_path

import evoik_pin as ek
from evoik_pin.errors import FrameError, OptionError, TargetError
from evoik_pin.goals import Pose, Position, Posture
from evoik_pin.robot.velocity_limits import velocity_limits
from evoik_pin.solvers.search import box_step

#: Result fields a prepared step must reproduce (all but time_s).
FIELDS = ("position_error", "orientation_error", "cost", "success", "generations", "evaluations", "message",
          "method", "collision_free", "goal_errors", "chosen", "setup_s", "solutions", "front")


@pytest.fixture(scope="module")
def panda():
    return ek.load_robot("panda")


def _reference(robot, targets, q0, dt, seed, factor=True, **options):
    """The general path's Results: IKSolver.solve_within per step from the last answer (its prepared steps off), one
    generator throughout."""
    solver = ek.IKSolver(robot, **options)
    rng = np.random.default_rng(seed)
    step = velocity_limits(robot, factor) * dt
    q, out = np.array(q0, dtype=float), []
    box_step.PREPARED = False
    try:
        for t in targets:
            r = solver.solve_within(t, q, step, rng)
            q = r.q.copy()
            out.append(r)
    finally:
        box_step.PREPARED = True
    return out


def _assert_same(results, reference):
    assert len(results) == len(reference)
    for k, (a, b) in enumerate(zip(results, reference, strict=True)):
        assert np.array_equal(a.q, b.q), k
        for name in FIELDS:
            assert repr(getattr(a, name)) == repr(getattr(b, name)), (k, name)
        assert a.history == b.history == {}


def _tracked(robot, targets, q0, dt, seed, factor=True, **options):
    tracker = ek.Tracker(robot, dt=dt, q0=q0, seed=np.random.default_rng(seed), velocity_limits=factor, **options)
    return tracker, [tracker.step(t) for t in targets]


@pytest.mark.parametrize("form", ["se3", "matrix", "position", "goal list"])
def test_panda_steps_equal_the_general_path_with_a_jump(panda, form):
    dt = 0.001
    Q = smooth_path(panda, 200, dt, seed=2)
    T = [panda.fk(q) for q in Q]
    for i in range(80, 110):  # out of reach for a while: misses take the stage's search, then the path resumes
        T[i] = pin.SE3(T[i].rotation, T[i].translation + np.array([0.0, 0.3, 0.0]))
    targets = {"se3": T, "matrix": [t.homogeneous for t in T], "position": [t.translation.copy() for t in T],
               "goal list": [[Pose(panda.tip, t)] for t in T]}[form]
    tracker, results = _tracked(panda, targets, Q[0], dt, seed=1, factor=2.0)
    _assert_same(results, _reference(panda, targets, Q[0], dt, seed=1, factor=2.0))
    kept = tracker._solver._box_steps
    assert len(kept) == 1 and None not in kept.values()  # one structure, prepared once
    assert all(r.success for r in results[:80]) and not any(r.success for r in results[80:110])
    assert all(r.success for r in results[-20:])  # back on the path


def test_talos_four_goals_equal_the_general_path():
    talos = ek.load_robot("talos", floating_base=True)
    dt = 0.002
    Q = smooth_path(talos, 60, dt, seed=1, fraction=2.0)
    lists = pose_goals(talos, Q)
    tracker, results = _tracked(talos, lists, Q[0], dt, seed=4)
    _assert_same(results, _reference(talos, lists, Q[0], dt, seed=4))
    assert all(r.success and len(r.goal_errors) == 4 for r in results)


def test_structures_alternating_and_goal_sets_equal_the_general_path(panda):
    dt = 0.001
    Q = smooth_path(panda, 90, dt, seed=5)
    T = [panda.fk(q) for q in Q]
    targets = []
    for k, t in enumerate(T):
        elbow = panda.fk(Q[k], frame="panda_link4").translation
        targets.append([t, [Position(panda.tip, t.translation)],
                        [Pose(panda.tip, t, tolerance=1e-5), Position("panda_link4", elbow, weight=0.5)],
                        [Pose(panda.tip, [t.homogeneous, (t * pin.SE3(np.eye(3), np.array([0, 0, 0.1]))).homogeneous])],
                        [Pose(panda.tip, t, weight=2.0)]][k % 5])
    tracker, results = _tracked(panda, targets, Q[0], dt, seed=6)
    _assert_same(results, _reference(panda, targets, Q[0], dt, seed=6))
    kept = list(tracker._solver._box_steps.values())
    assert len(kept) == 5 and kept.count(None) == 1  # the goal set's structure: no prepared path, not sought again
    assert all(r.success for r in results)


def test_locked_joints_take_the_inner_solvers_prepared_step(panda):
    dt = 0.001
    Q = smooth_path(panda, 40, dt, seed=8)
    Q[:, 6] = 0.0
    targets = [[Pose(panda.tip, panda.fk(q))] for q in Q]
    tracker, results = _tracked(panda, targets, Q[0], dt, seed=2, locked={"panda_joint7": 0.0})
    _assert_same(results, _reference(panda, targets, Q[0], dt, seed=2, locked={"panda_joint7": 0.0}))
    inner = tracker._solver._locked.solver  # the solver on the robot with panda_joint7 locked
    assert len(inner._box_steps) == 1 and None not in inner._box_steps.values()


def test_bad_input_refused_after_a_structure_was_prepared(panda):
    dt = 0.001
    Q = smooth_path(panda, 3, dt, seed=7)
    tracker = ek.Tracker(panda, dt=dt, q0=Q[0])
    T = panda.fk(Q[1])
    tracker.step([Pose(panda.tip, T)])
    tracker.step(T)
    kept = tracker._solver._box_steps
    assert len(kept) == 2 and None not in kept.values()
    q = tracker.q
    with pytest.raises(OptionError, match="preferences"):
        tracker.step([Pose(panda.tip, T), Posture(Q[1])])
    with pytest.raises(FrameError):
        tracker.step([Pose("no_such_frame", T)])
    with pytest.raises(TargetError):
        tracker.step([])
    bad = T.homogeneous.copy()
    bad[:3, :3] *= 2.0  # no rotation
    with pytest.raises(TargetError):
        tracker.step(bad)
    with pytest.raises(TargetError):
        tracker.step(pin.SE3(2.0 * T.rotation, T.translation))
    with pytest.raises(TargetError):
        tracker.step(np.full(3, np.nan))
    assert np.array_equal(tracker.q, q)  # a refused step leaves the tracker where it was
    assert tracker.step(panda.fk(Q[2])).success


@pytest.mark.parametrize("rows", [[(1e-7, 2e-7), (3e-7, np.nan), (0.0, 5e-7)],
                                  [(np.nan, 1e-3), (-0.0, 0.0), (2e-6, 1e-9)],
                                  [(4e-7, np.nan), (np.nan, np.nan), (1e-6, 1e-6)]])
def test_settle_is_the_python_verdict_and_summary(rows):
    from evoik_pin.problem import goal_summary
    from evoik_pin.solvers.search.box_step import settle

    goals = [Pose("a", np.eye(4), weight=2.0), Position("b", np.zeros(3), weight=0.5),
             Pose("c", np.eye(4), tolerance=1e-6, rotation_tolerance=1e-6)]
    errors = [g.reported(p, r) for g, (p, r) in zip(goals, rows, strict=True)]
    checks = np.array([(g.has_position, g.reports_angle, g.tolerance, g.rotation_tolerance, g.weight) for g in goals],
                      dtype=float)
    q, box = np.array([0.5, -2.0, 3.0]), np.array([[0.0] * 3, [1.0] * 3, [0.0] * 3, [1.0] * 3, [0.0] * 3])
    met, largest, angle, angled, cost = settle(q, box, np.array(rows, dtype=float), checks, 0.7)
    pos, rot, expected_cost = goal_summary(goals, errors, 0.7)
    assert met == all(g.met(p, r) for g, (p, r) in zip(goals, errors, strict=True))
    assert repr((largest, angle if angled else None, cost)) == repr((pos, rot, expected_cost))
    assert q.tolist() == [0.5, 0.0, 1.0]  # clipped into rows B_LO, B_HI


def test_solve_within_checks_its_step_and_takes_any_float_form(panda):
    """A step that is not (n,) finite and >= 0 is refused at the boundary, prepared step or not; a list or an
    integer array is the same step as its float64 array."""
    solver = ek.IKSolver(panda)
    q = panda.random_configurations(1, np.random.default_rng(0))[0]
    T = panda.fk(q + 0.001)
    step = np.full(panda.n, 0.01)
    first = solver.solve_within(T, q, step, seed=1)
    assert first.success
    for bad in (np.full(panda.n, -0.01), np.full(panda.n, np.nan), np.full(3, 0.01), "abc", [[0.01] * panda.n]):
        with pytest.raises(OptionError, match="step must be"):
            solver.solve_within(T, q, bad, seed=1)
    again = [solver.solve_within(T, q, form, seed=1) for form in (step, step.tolist(), np.full(panda.n, 0.01))]
    strided = np.repeat(q, 2)[::2]  # a float64 view that is not contiguous: the same q_prev
    again += [solver.solve_within(T, strided, np.repeat(step, 2)[::2], seed=1)]
    assert all(np.array_equal(r.q, first.q) for r in again)
    whole = np.ones(panda.n, dtype=int)  # an integer array: 1 rad per joint
    assert np.array_equal(solver.solve_within(T, q, whole, seed=1).q, solver.solve_within(T, q, whole * 1.0, seed=1).q)
