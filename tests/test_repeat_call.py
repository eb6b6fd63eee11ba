"""IKSolver's per-call lane for single targets (issue 24, solvers/search/repeat_call.py): once a solver has
solved a pose (or a position) through memetic's compiled guaranteed runs, the next ones of that kind take the lane. Its
answers are the general path's, bit for bit; it refuses exactly what the general path refuses, with the same
errors; it hands a target none of its guaranteed runs solves to memetic, which goes on from their state."""

import threading

import numpy as np
import pinocchio as pin
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from test_guaranteed_runs import same  # the Results equal bit for bit, history too

import evoik_pin as ek
from evoik_pin import api
from evoik_pin.errors import ConfigurationError, OptionError, TargetError
from evoik_pin.goals import Pose
from evoik_pin.lie import compiled
from evoik_pin.lie.so3 import is_rotation_entries
from evoik_pin.solvers.search.repeat_call import RepeatCall
from evoik_pin.target import pose_arrays

BUDGET = {"timeout": None, "max_restarts": 2}  # deterministic: the clock cannot change an answer


def general(robot, target, seed=None, **options):
    """evoik_pin.solve's general path: a new problem and memetic's whole set-up on every call."""
    problem, solver_options = api.make_problem(robot, target, **options)
    return api._run(problem, "memetic", api._rng(seed), solver_options)


@pytest.fixture(scope="module")
def panda():
    return ek.load_robot("panda")


def laned(robot, **options):
    """An IKSolver whose two lanes (poses, positions) are open: two targets of each kind solved first."""
    solver = ek.IKSolver(robot, **options)
    rng = np.random.default_rng(99)
    for q in robot.random_configurations(2, rng):
        T = robot.fk(q)
        solver.solve(T, seed=0)
        solver.solve(T.translation.copy(), seed=0)
    assert set(solver._repeat_calls) == {True, False}
    return solver


@pytest.fixture
def counted(monkeypatch):
    """The number of lane solves made (a list, one entry per call)."""
    calls = []
    lane_solve = RepeatCall.solve
    monkeypatch.setattr(RepeatCall, "solve", lambda *args, **kw: calls.append(1) or lane_solve(*args, **kw))
    return calls


def test_lane_answers_are_the_general_paths(panda, counted):
    """Poses (SE3, 4x4, Target) and positions, with q0 near, far and none, and targets out of reach (memetic goes on
    from the guaranteed runs' state: later entries, DE restarts): the general path's Results, bit for bit."""
    rng = np.random.default_rng(5)
    solver = laned(panda, **BUDGET)
    counted.clear()
    Q, Qs = panda.random_configurations(60, rng), panda.random_configurations(60, rng)
    calls = []
    for i, q in enumerate(Q):
        T = panda.fk(q)
        target = [T, T.homogeneous, ek.Target(T.translation, T.rotation), T.translation.copy()][i % 4]
        q0 = [None, Qs[i], np.clip(q + 0.02, panda.lower, panda.upper)][i % 3]
        if i % 10 == 7:  # out of reach: none of the guaranteed runs converges
            target = [pin.SE3(T.rotation, 3.0 * T.translation), 3.0 * T.translation][i % 2]
        calls.append((target, q0, i))
    results = [solver.solve(t, q0, seed=i) for t, q0, i in calls]
    assert len(counted) == len(calls)  # every call took a lane
    for (t, q0, i), r in zip(calls, results, strict=True):
        same(r, general(panda, t, seed=i, q0=q0, **BUDGET))
    assert sum(not r.success for r in results) >= 4  # most of the six out of reach (3x the position)
    assert {r.message.split(" (")[0] for r in results if r.success} == {
        "tolerance reached by LM from q0", "tolerance reached by LM from seed table"}
    assert all(r.setup_s == 0.0 for r in results if r.success)  # a lane pays no set-up


def test_the_solvers_q0_and_options_hold_on_the_lane(panda, counted):
    """A solver's own q0 is every call's start; tolerances, orientation_weight and pose_metric give the general
    path's verdicts and costs."""
    rng = np.random.default_rng(8)
    Q = panda.random_configurations(12, rng)
    options = dict(q0=Q[0], tolerance=1e-4, rotation_tolerance=1e-3, orientation_weight=0.3, pose_metric="euclidean",
                   **BUDGET)
    solver = laned(panda, **options)
    counted.clear()
    for i, q in enumerate(Q[1:]):
        T = panda.fk(q)
        target = T if i % 2 else T.translation.copy()
        r = solver.solve(target, seed=i)
        same(r, general(panda, target, seed=i, **options))
        assert r.success
    assert len(counted) == 11


BAD = [("nan position", (0, 3, np.nan)), ("inf rotation", (2, 1, -np.inf)), ("not a rotation", (0, 1, 0.3)),
       ("huge rotation entry", (1, 1, 1e300)), ("beyond MAX_TARGET_NORM", (2, 3, 2e6)),
       ("bottom row", (3, 0, 0.5)), ("bottom row within 1e-9", (3, 3, 1.0 + 1e-12)), ("a mirror", None)]


@pytest.mark.parametrize("name,change", BAD, ids=[b[0] for b in BAD])
def test_bad_poses_on_a_laned_solver_get_the_general_errors(panda, name, change):
    """A solver with its lanes open refuses (or accepts) a pose exactly as the general path does, with its error."""
    solver = laned(panda, **BUDGET)
    H = panda.fk(np.full(panda.n, 0.2)).homogeneous
    if change is None:
        H[:3, 2] *= -1.0
    else:
        i, j, value = change
        H[i, j] = value
    forms = [H] + ([pin.SE3(H[:3, :3].copy(), H[:3, 3].copy())] if change is None or change[0] < 3 else [])
    for target in forms:
        outcomes = []
        for solve in (lambda t=target: solver.solve(t, seed=1), lambda t=target: general(panda, t, seed=1, **BUDGET)):
            try:
                outcomes.append(solve().q.tolist())
            except TargetError as exc:
                outcomes.append(str(exc))
        assert outcomes[0] == outcomes[1]
    assert name != "bottom row within 1e-9" or isinstance(outcomes[0], list)  # accepted, as Target.coerce does


def test_bad_q0_seed_and_forms_on_a_laned_solver(panda, counted):
    solver = laned(panda, **BUDGET)
    T = panda.fk(np.full(panda.n, 0.3))

    def outcome(solve):
        try:
            return solve().q.tolist()
        except (ConfigurationError, ValueError) as exc:
            return type(exc), str(exc)

    refused = 0
    for q0 in (np.zeros(3), np.full(7, np.nan), [1e308] * 7, "abc", np.zeros((1, 7))):
        lane, reference = outcome(lambda q0=q0: solver.solve(T, q0, seed=1)), outcome(
            lambda q0=q0: general(panda, T, seed=1, q0=q0, **BUDGET))
        assert lane == reference
        refused += isinstance(lane, tuple) and lane[0] is ConfigurationError
    assert refused >= 3  # the wrong shapes and the NaN at least
    for seed in (-1, 1.5, True, "x"):
        with pytest.raises(OptionError, match="seed"):
            solver.solve(T, seed=seed)
    counted.clear()
    # a list, integers, a 3-vector list: the general path, the same answers
    for target in (T.translation.tolist(), np.round(T.translation * 10).astype(int), T.homogeneous.tolist()):
        same(solver.solve(target, seed=2), general(panda, target, seed=2, **BUDGET))
    assert not counted
    # q0 as a list or an int array, a Generator seed: on the lane
    for q0, seed in (([0.1] * 7, 3), (np.arange(7) % 2, np.random.default_rng(4))):
        same(solver.solve(T, q0, seed=seed), general(panda, T, seed=3, q0=q0, **BUDGET))
    assert len(counted) == 2


def test_a_lane_follows_the_plan_and_the_thread(panda, counted):
    """Goal lists and goal sets solved between single targets (other engines, the engine's step budget changed by
    the later stages), and the solver used from another thread: the answers stay the general path's."""
    rng = np.random.default_rng(21)
    solver = laned(panda, **BUDGET)
    Q = panda.random_configurations(12, rng)
    for i, q in enumerate(Q):
        T = panda.fk(q)
        same(solver.solve(T, seed=i), general(panda, T, seed=i, **BUDGET))
        same(solver.solve(3.0 * T.translation, seed=i), general(panda, 3.0 * T.translation, seed=i, **BUDGET))
        solver.solve([Pose(panda.tip, T, free="rz")], seed=i)
        solver.solve([Pose(panda.tip, [T, panda.fk(Q[i - 1])])], seed=i)
    out = {}

    def other():
        out["q"] = [solver.solve(panda.fk(q), seed=i).q for i, q in enumerate(Q)]

    thread = threading.Thread(target=other)
    thread.start()
    thread.join()
    for i, q in enumerate(Q):
        assert np.array_equal(out["q"][i], general(panda, panda.fk(q), seed=i, **BUDGET).q)
        same(solver.solve(panda.fk(q), seed=i), general(panda, panda.fk(q), seed=i, **BUDGET))


def test_no_lane_where_the_guaranteed_runs_do_not_serve(panda):
    """A scene, a custom objective, a polish, another method: no lane (the general path's own)."""
    from evoik_pin.objectives import PoseError
    from evoik_pin.scene import Scene

    T = panda.fk(np.full(panda.n, 0.2))
    objective = PoseError(ek.Target(T.translation, T.rotation))
    plain = ek.IKSolver(panda)
    for i in range(2):  # a plain solver's lane opens after its second solve (the compiled entry found)
        plain.solve(T, seed=i)
    assert set(plain._repeat_calls) == {True}
    for options in ({"scene": Scene(panda)}, {"objective": objective}, {"polish": True},
                    {"method": "de", "max_generations": 5}, {"batch": 2}, {"table_offset": 1}, {"engine": "python"},
                    {"table_size": 0}):
        solver = ek.IKSolver(panda, **options)
        for i in range(2):
            solver.solve(T, seed=i)
        assert not solver._repeat_calls, options


@settings(max_examples=300, deadline=None)
@given(st.integers(0, 2**31 - 1), st.floats(-10.0, 1.0), st.booleans(), st.floats(-7.0, 7.0), st.booleans())
def test_property_pose_arrays_accept_what_coerce_accepts(seed, log_eps, mirror, log_norm, as_matrix):
    """pose_arrays (the lane's checks) accepts a pose only where Target.coerce accepts it, with the same numbers,
    and gives None wherever coerce refuses."""
    rng = np.random.default_rng(seed)
    R = pin.SE3.Random().rotation @ np.diag([1.0, 1.0, -1.0 if mirror else 1.0])
    R = R + 10.0**log_eps * rng.standard_normal((3, 3))
    p = rng.standard_normal(3)
    p *= 10.0**log_norm / np.linalg.norm(p)
    if as_matrix:
        target = np.eye(4)
        target[:3, :3], target[:3, 3] = R, p
    else:
        target = pin.SE3(R, p)
    arrays = pose_arrays(target)
    # the repeat call's check of a rotation, made inside its compiled guaranteed runs, is the same test as coerce's
    entries = np.ascontiguousarray(R).reshape(9)
    assert bool(compiled.is_rotation_entries(*entries)) == is_rotation_entries(*entries.tolist())
    try:
        t = ek.Target.coerce(target)
    except TargetError:
        assert arrays is None
        unchecked = pose_arrays(target, check_rotation=False)
        assert unchecked is None or not is_rotation_entries(*entries.tolist())
        return
    assert arrays is not None
    assert np.array_equal(arrays[0], t.position) and np.array_equal(arrays[1], t.rotation)
    positions = pose_arrays(p.copy())
    assert positions is not None and np.array_equal(positions[0], ek.Target.coerce(p.copy()).position)
    assert positions[1] is None


def goal_lists(robot, T, q):
    """One-goal lists of each kind on the tip, and on another frame, for the pose T = fk(q)."""
    from evoik_pin.goals import Orientation, Position

    return [[Pose(robot.tip, T)], [Pose(robot.tip, T, free="rz")],
            [Pose(robot.tip, T, tolerance=[2e-3, 2e-3, 2e-3, 0.05, 0.05, 0.05])], [Position(robot.tip, T.translation)],
            [Orientation(robot.tip, T.rotation)], [Pose("panda_link6", robot.fk(q, "panda_link6"))]]


def test_one_goal_lists_take_a_lane_with_the_general_answers(panda, counted):
    """A one-goal list of each kind (a pose, free axes, bands, a position, an orientation, another frame), solved
    again with new targets, takes the lane of its goal stack: the general path's Results (goal errors and chosen
    too), bit for bit, from q0s near, far and none, and out of reach (memetic goes on from the runs' state)."""
    rng = np.random.default_rng(31)
    solver = ek.IKSolver(panda, **BUDGET)
    Q, Qs = panda.random_configurations(36, rng), panda.random_configurations(36, rng)
    results = []
    for i, q in enumerate(Q):
        T = panda.fk(q)
        if i % 6 == 5:  # out of reach
            T = pin.SE3(T.rotation, 3.0 * T.translation)
        goals = goal_lists(panda, T, q)[i // 6]  # six targets of each kind in turn, as a loop over targets makes
        q0 = [None, Qs[i], np.clip(q + 0.02, panda.lower, panda.upper)][i % 3]
        r = solver.solve(goals, q0, seed=i)
        reference = general(panda, goals, seed=i, q0=q0, **BUDGET)
        same(r, reference)
        assert r.goal_errors == reference.goal_errors and r.chosen == reference.chosen == [None]
        results.append(r)
    assert len(counted) >= len(Q) - 2 * 6  # each stack's lane opens after its first (or second) solve
    assert sum(r.success for r in results) >= len(Q) - 6


def test_a_goal_set_takes_its_stacks_lane_member_by_member(panda, counted):
    """A goal set binds to the stack of a one-goal Pose (the members are targets): it takes that lane for its
    members (the nearest the seed table first), never as its first member, and the member it meets is reported."""
    rng = np.random.default_rng(32)
    solver = ek.IKSolver(panda, **BUDGET)
    Q = panda.random_configurations(6, rng)
    for i, q in enumerate(Q):
        solver.solve([Pose(panda.tip, panda.fk(q))], seed=i)  # the one-goal Pose's lane opens
    counted.clear()
    far = pin.SE3(np.eye(3), np.array([2.0, 0.0, 0.5]))
    T = panda.fk(Q[0])
    r = solver.solve([Pose(panda.tip, [far, T])], seed=0)
    assert counted and r.success and r.chosen == [1]
    M = panda.fk(r.q)
    assert np.linalg.norm(M.translation - T.translation) <= 1e-6
    assert np.linalg.norm(pin.log3(T.rotation.T @ M.rotation)) <= 1e-6


def set_of(robot, rng, reachable: int, far: int):
    """A goal set on the tip: ``reachable`` poses (forward kinematics) and ``far`` beyond the Panda's reach (1.3 to
    1.6 m from the base), shuffled; and the reachable ones' indices."""
    members = [robot.fk(q) for q in robot.random_configurations(reachable, rng)]
    for _ in range(far):
        d = rng.normal(size=3)
        d[2] = abs(d[2])
        members.append(pin.SE3(pin.exp3(rng.normal(size=3)), d / np.linalg.norm(d) * rng.uniform(1.3, 1.6)))
    order = rng.permutation(len(members))
    return [Pose(robot.tip, [members[k] for k in order])], [int(np.nonzero(order == k)[0][0]) for k in range(reachable)]


def test_goal_sets_alone_open_a_lane_and_meet_the_member_they_report(panda, counted):
    """A solver fed goal sets only opens the lane of their stack (after its first sets) and serves the sets there:
    each answer meets the member reported, whose errors are those the general verdict computes at the answer; the
    sets whose nearest members none of the guaranteed runs meet go to the goal-set search, which finds a reachable
    one."""
    from evoik_pin.problem import IKProblem

    rng = np.random.default_rng(33)
    solver = ek.IKSolver(panda, **BUDGET)
    for i in range(30):
        goals, reachable = set_of(panda, rng, 3, 7)
        q0 = None if i % 2 else panda.random_configurations(1, rng)[0]
        r = solver.solve(goals, q0, seed=i)
        assert r.success, r.message
        errors, chosen = IKProblem(panda, goals).goal_errors_and_chosen(r.q)
        assert r.chosen == chosen and r.chosen[0] in reachable
        assert np.allclose(np.array(r.goal_errors, dtype=float), np.array(errors, dtype=float), rtol=0, atol=1e-12)
        T = goals[0].alternatives[r.chosen[0]].target
        M = panda.fk(r.q)
        assert np.linalg.norm(M.translation - T.translation) <= 1e-6
        assert np.linalg.norm(pin.log3(T.rotation.T @ M.rotation)) <= 1e-6
    assert len(counted) >= 25  # the lane opens after the first set or two


def test_a_one_member_goal_set_is_its_member_on_the_lane(panda, counted):
    """A goal set of one member takes the lane as that member's one-goal list: its answer, bit for bit, member 0."""
    rng = np.random.default_rng(35)
    solver = ek.IKSolver(panda, **BUDGET)
    Q, Qs = panda.random_configurations(8, rng), panda.random_configurations(8, rng)
    for i, q in enumerate(Q):
        T = panda.fk(q)
        q0 = None if i % 2 else Qs[i]
        r = solver.solve([Pose(panda.tip, [T])], q0, seed=i)
        if i >= 2:  # the lane is open
            reference = general(panda, [Pose(panda.tip, T)], seed=i, q0=q0, **BUDGET)
            assert np.array_equal(r.q, reference.q) and r.goal_errors == reference.goal_errors
        assert r.success and r.chosen == [0]
    assert len(counted) >= 6


def test_a_goal_set_no_lane_member_meets_is_the_goal_set_searchs(panda, monkeypatch):
    """When the lane tries no member (or meets none), the set is the goal-set search's from the start: the general
    path's Result, bit for bit."""
    from evoik_pin.solvers.search import repeat_call

    rng = np.random.default_rng(34)
    solver = ek.IKSolver(panda, **BUDGET)
    for i in range(3):
        solver.solve(set_of(panda, rng, 1, 1)[0], seed=i)  # the lane opens
    monkeypatch.setattr(repeat_call, "SET_MEMBERS", 0)
    for i in range(4):
        goals, _ = set_of(panda, rng, 2, 3)
        q0 = None if i % 2 else panda.random_configurations(1, rng)[0]
        r = solver.solve(goals, q0, seed=i)
        reference = general(panda, goals, seed=i, q0=q0, **BUDGET)
        same(r, reference)
        assert r.success and r.chosen == reference.chosen and r.goal_errors == reference.goal_errors


def test_a_trajectory_gives_the_answers_of_its_points_solved_one_by_one(panda):
    """solve_trajectory (plain options: it solves through the kept IKSolver and its lanes) gives, point by point, the
    general path's answer from the previous point's q with the one shared generator, for poses, positions, one-goal
    lists and another method; memetic's later stages draw from that generator (out-of-reach points)."""
    from evoik_pin.problem import Target

    rng = np.random.default_rng(41)
    q = panda.random_configurations(1, rng)[0]
    path = []
    for k in range(24):
        q = np.clip(q + 0.05 * rng.standard_normal(panda.n), panda.lower, panda.upper)
        T = panda.fk(q)
        path.append(pin.SE3(T.rotation, 3.0 * T.translation) if k % 8 == 5 else T)
    cases = [(path, "memetic", BUDGET), ([T.translation.copy() for T in path], "memetic", BUDGET),
             ([[Pose(panda.tip, T, free="rz")] for T in path], "memetic", BUDGET),
             (path[:4], "de", {"max_generations": 10})]
    for targets, method, options in cases:
        got = ek.solve_trajectory(panda, targets, method=method, seed=3, q0=np.zeros(panda.n), **options)
        shared = api._rng(3)
        previous = np.zeros(panda.n)
        for target, r in zip(targets, got, strict=True):
            t = target if isinstance(target, list) else Target.coerce(target)
            problem, solver_options = api.make_problem(panda, t, q0=previous, **options)
            reference = api._run(problem, method, shared, solver_options)
            same(r, reference)
            previous = reference.q
        assert method != "memetic" or sum(not r.success for r in got) >= 2
