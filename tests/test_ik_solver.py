"""IKSolver (issue 24): set up once, solve per target, the same answers as the general path of evoik_pin.solve
(make_problem + the method, no cached set-up), the same errors for bad input."""

import numpy as np
import pinocchio as pin
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import evoik_pin as ek
from evoik_pin import api
from evoik_pin.errors import ConfigurationError, FrameError, MethodError, OptionError, TargetError
from evoik_pin.goals import Pose, Position


def general(robot, target, method="memetic", seed=None, **options):
    """evoik_pin.solve's general path: a new problem and the method's whole set-up on every call."""
    problem, solver_options = api.make_problem(robot, target, **options)
    return api._run(problem, method, api._rng(seed), solver_options)


def same(a: ek.Result, b: ek.Result) -> None:
    assert np.array_equal(a.q, b.q)
    assert (a.success, a.position_error, a.orientation_error, a.cost) == (b.success, b.position_error,
                                                                          b.orientation_error, b.cost)
    assert (a.evaluations, a.generations, a.goal_errors, a.collision_free) == (b.evaluations, b.generations,
                                                                               b.goal_errors, b.collision_free)
    assert a.message.split(" (")[0] == b.message.split(" (")[0]


@pytest.fixture(scope="module")
def panda():
    return ek.load_robot("panda")


@pytest.fixture(scope="module")
def cases(panda):
    rng = np.random.default_rng(7)
    Qt, Qs = panda.random_configurations(40, rng), panda.random_configurations(40, rng)
    return [panda.fk(q) for q in Qt], Qs


# a deterministic budget, so that a loaded machine cannot change an answer (the clock is the one input that differs)
BUDGET = {"timeout": None, "max_restarts": 3}


def test_same_answers_as_the_general_path(panda, cases):
    targets, Qs = cases
    solver = ek.IKSolver(panda, **BUDGET)
    for i, T in enumerate(targets):
        q0 = Qs[i] if i % 2 else None
        reference = general(panda, T, seed=i, q0=q0, **BUDGET)
        same(solver.solve(T, q0=q0, seed=i), reference)
        same(ek.solve(panda, T, seed=i, q0=q0, **BUDGET), reference)


def test_target_forms_and_kinds_in_any_order(panda, cases):
    """Poses as SE3, 4x4 arrays and Targets, and positions, alternating on one solver (one LM engine retargeted, a new
    one when the kind changes)."""
    targets, Qs = cases
    solver = ek.IKSolver(panda, tolerance=1e-8, **BUDGET)
    for i, T in enumerate(targets[:12]):
        target = [T, T.homogeneous, ek.Target(T.translation, T.rotation), T.translation.copy()][i % 4]
        same(solver.solve(target, Qs[i], seed=i), general(panda, target, seed=i, q0=Qs[i], tolerance=1e-8, **BUDGET))


def test_a_target_array_is_not_written_through(panda, cases):
    """The engine keeps its own target arrays: solving the next target leaves the caller's pose untouched."""
    targets, _ = cases
    H = targets[0].homogeneous
    kept = H.copy()
    solver = ek.IKSolver(panda)
    solver.solve(H, seed=0)
    solver.solve(targets[1], seed=0)
    assert np.array_equal(H, kept)


@settings(max_examples=25, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(st.integers(0, 2**31 - 1), st.integers(0, 1000), st.booleans())
def test_property_same_q_for_any_seed(panda, target_seed, seed, with_q0):
    rng = np.random.default_rng(target_seed)
    T = panda.fk(panda.random_configurations(1, rng)[0])
    q0 = panda.random_configurations(1, rng)[0] if with_q0 else None
    solver = _solver(panda)
    assert np.array_equal(solver.solve(T, q0, seed).q, general(panda, T, seed=seed, q0=q0, **BUDGET).q)


_SOLVERS: dict = {}


def _solver(robot):
    if robot not in _SOLVERS:
        _SOLVERS[robot] = ek.IKSolver(robot, **BUDGET)
    return _SOLVERS[robot]


def test_other_methods_polish_and_far_joints(cases, panda):
    targets, _ = cases
    solver = ek.IKSolver(panda, method="de", polish=True, max_generations=20)
    for i, T in enumerate(targets[:3]):
        same(solver.solve(T, seed=i), general(panda, T, method="de", seed=i, polish=True, max_generations=20))
    # a mobile base with near-unbounded joints: the search box follows each target (problem.target_box)
    from test_near_unbounded import _arm, _targets

    robot = ek.load_robot(_arm(["x", "y", "yaw"]))
    solver = ek.IKSolver(robot, **BUDGET)
    _, far = _targets(robot, 4, seed=3)
    for i, T in enumerate(far):
        same(solver.solve(T, seed=i), general(robot, T, seed=i, **BUDGET))


def test_goal_lists_and_a_scene(cases):
    from evoik_pin.scene import Scene
    from evoik_pin.scene.examples import SHELF_INTERIOR, add_table_and_shelf, free_configurations

    baxter = ek.load_robot("baxter")
    rng = np.random.default_rng(3)
    solver = ek.IKSolver(baxter, **BUDGET)
    for i, q in enumerate(baxter.random_configurations(3, rng)):
        goals = [Pose("left_gripper", baxter.fk(q, frame="left_gripper")),
                 Position("right_gripper", baxter.fk(q, frame="right_gripper").translation)]
        r = solver.solve(goals, seed=i)
        same(r, general(baxter, goals, seed=i, **BUDGET))
        assert r.goal_errors is not None
    panda = ek.load_robot("panda")
    scene = add_table_and_shelf(Scene(panda))
    Q = free_configurations(scene, 3, np.random.default_rng(1), SHELF_INTERIOR)
    solver = ek.IKSolver(panda, scene=scene, **BUDGET)
    for i, q in enumerate(Q):
        T = panda.fk(q)
        r = solver.solve(T, seed=i)
        same(r, general(panda, T, seed=i, scene=scene, **BUDGET))
        assert r.collision_free is not None


def test_bad_input_gets_the_errors_of_solve(panda, cases):
    targets, _ = cases
    solver = ek.IKSolver(panda)
    bad_pose = targets[0].homogeneous.copy()
    bad_pose[0, 3] = np.nan
    for target, q0, error in [(bad_pose, None, TargetError), (np.zeros(5), None, TargetError),
                              (targets[0], np.zeros(3), ConfigurationError),
                              (targets[0], np.full(7, np.inf), ConfigurationError)]:
        with pytest.raises(error) as by_solver:
            solver.solve(target, q0)
        with pytest.raises(error) as by_general:
            general(panda, target, q0=q0)
        assert str(by_solver.value) == str(by_general.value)
    with pytest.raises(OptionError, match="seed"):
        solver.solve(targets[0], seed=-1)
    with pytest.raises(OptionError, match="population"):
        ek.IKSolver(panda, population=2)
    with pytest.raises(OptionError, match="unknown option"):
        ek.IKSolver(panda, popsize=8)
    with pytest.raises(MethodError):
        ek.IKSolver(panda, method="nope")
    with pytest.raises(MethodError):  # a goal list for a method that takes one target
        ek.IKSolver(panda, method="algebraic").solve([Pose("panda_hand_tcp", targets[0])])


def test_solve_keeps_refusing_what_it_refused(panda, cases):
    """evoik_pin.solve's cached solvers are keyed by option types and values: 32.0 is no integer, 32 is."""
    T = cases[0][0]
    ek.solve(panda, T, seed=0, population=32)
    with pytest.raises(OptionError, match="population"):
        ek.solve(panda, T, seed=0, population=32.0)
    with pytest.raises(TargetError):  # a bad target with a bad option: the target's error first, as always
        ek.solve(panda, np.full(3, np.nan), seed=0, population=2)
    with pytest.raises(ConfigurationError, match="q0"):  # the problem's checks (q0 here) before the method's options
        ek.solve(panda, T, q0=np.zeros(3), seed=0, population=2)
    # bounds changed on the robot: the next solve searches the new box
    lower, upper = panda.lower.copy(), panda.upper.copy()
    try:
        panda.set_bounds(lower, np.minimum(upper, lower + 0.5))
        r = ek.solve(panda, T, seed=0, **BUDGET)
        assert panda.within_bounds(r.q)
        same(r, general(panda, T, seed=0, **BUDGET))
    finally:
        panda.set_bounds(lower, upper)


def test_se3_and_matrix_targets_agree(panda, cases):
    T = cases[0][0]
    solver = ek.IKSolver(panda)
    assert np.array_equal(solver.solve(T, seed=1).q, solver.solve(pin.SE3(T.homogeneous), seed=1).q)


@settings(max_examples=300, deadline=None)
@given(st.integers(0, 2**31 - 1), st.floats(-10.0, -3.0), st.booleans())
def test_property_rotation_check_gives_the_numpy_verdict(seed, log_eps, mirror):
    """Target's rotation check (written on Python floats) accepts exactly the matrices with |R^T R - I|_F <= 1e-6 and
    det R > 0, as numpy computes them (away from the threshold's last bits)."""
    rng = np.random.default_rng(seed)
    R = pin.SE3.Random().rotation @ np.diag([1.0, 1.0, -1.0 if mirror else 1.0])
    R = R + 10.0**log_eps * rng.standard_normal((3, 3))
    D = R.T @ R - np.eye(3)
    frob_sq = float((D * D).sum())
    if abs(frob_sq - 1e-12) < 1e-15:
        return
    accepted = frob_sq <= 1e-12 and np.linalg.det(R) >= 0
    try:
        ek.Target(np.zeros(3), R)
        assert accepted
    except TargetError as exc:
        assert not accepted and "not a rotation matrix" in str(exc)


def test_seed_table_ranking_and_nearness_are_the_batch_formulas(panda, cases):
    """The single-target features of the seed table (without the batch encoding, the distances computed in place)
    rank as the batch formulas do, and a pose's features are its table row's."""
    from evoik_pin.goals.stack import encode_targets, target_kind
    from evoik_pin.solvers.search.seed_table import default_table_size, seed_table

    table = seed_table(panda, panda.lower, panda.upper, default_table_size(panda.n))
    for T in cases[0][:10]:
        for target in (ek.Target(T.translation, T.rotation), ek.Target(T.translation.copy())):
            key, f = table.encoded_features(target_kind(target), *encode_targets([target]))
            ff = table.frame_features(key)
            d = ff.sq - 2.0 * (ff.F @ f[0])
            part = np.argpartition(d, 16)[:17]
            first = int(d.argmin())
            reference = [first] + [int(i) for i in part[d[part].argsort()] if i != first]
            problem = ek.IKProblem(panda, target)
            assert table.frame_search(problem) is ff
            assert list(table.ranked(ff, table.target_point(problem, ff), 17)) == reference
            assert np.array_equal(table.target_point(problem, ff), f[0])
            assert np.array_equal(ff.point(table.positions[first], table.rotations[first]), ff.F[first])


def test_which_calls_of_solve_keep_a_solver(panda, tmp_path):
    from pathlib import Path

    from evoik_pin.ik_solver import cached_solver
    from evoik_pin.scene import Scene

    a = cached_solver(panda, "memetic", {"tolerance": 1e-8})
    assert a is cached_solver(panda, "memetic", {"tolerance": 1e-8, "q0": np.zeros(7)})  # q0 is per call
    assert a is not cached_solver(panda, "memetic", {"tolerance": 1e-7})
    scene = Scene(panda)
    assert cached_solver(panda, "memetic", {"scene": scene}) is cached_solver(panda, "memetic", {"scene": scene})
    # bounds by value (the solver keeps copies): equal arrays share a solver, other values make another
    lower, upper = panda.lower / 2, panda.upper / 2
    kept = cached_solver(panda, "memetic", {"bounds": (lower, upper)})
    assert kept is cached_solver(panda, "memetic", {"bounds": (lower.copy(), list(upper))})
    assert kept is not cached_solver(panda, "memetic", {"bounds": (lower, upper * 0.9)})
    lower[:] = 0.0  # the caller's arrays changed after the call: the kept solver's box is its own copy
    assert np.array_equal(kept._template.lower, panda.lower / 2)
    # the general path: a scene file (read on every call: it may change), a robot by name, bad options or bounds
    for options in ({"scene": str(tmp_path / "s.yaml")}, {"scene": Path(tmp_path / "s.yaml")},
                    {"population": 2}, {"tolerance": float("nan")}, {"bounds": (panda.lower, panda.lower - 1.0)},
                    {"bounds": "wide"}):
        assert cached_solver(panda, "memetic", options) is None
    assert cached_solver("panda", "memetic", {}) is None


def test_solve_from_threads_gives_the_sequential_answers(panda, cases):
    """evoik_pin.solve keeps one solver per thread: threads solving at once get the answers of a sequential loop."""
    from concurrent.futures import ThreadPoolExecutor

    targets, Qs = cases
    expected = [ek.solve(panda, T, q0=Qs[i], seed=i, **BUDGET).q for i, T in enumerate(targets)]

    def work(offset):
        return [(i, ek.solve(panda, targets[i], q0=Qs[i], seed=i, **BUDGET).q)
                for i in range(offset, len(targets), 2)]

    with ThreadPoolExecutor(2) as pool:
        for chunk in pool.map(work, (0, 1)):
            for i, q in chunk:
                assert np.array_equal(q, expected[i])


def test_a_solver_handed_to_another_thread_uses_that_threads_buffers(panda, cases):
    """An IKSolver made and used in one thread, then used in another while the first keeps solving (the same goal
    stack: the same kernel workspace key), gives the answers of the general path in both."""
    import threading

    targets, Qs = cases
    solver = ek.IKSolver(panda, **BUDGET)
    solver.solve(targets[0], seed=0)
    out = {}

    def other():
        out["b"] = [solver.solve(targets[i], Qs[i], seed=i).q for i in range(0, 20, 2)]

    thread = threading.Thread(target=other)
    thread.start()
    mine = [ek.solve(panda, targets[i], q0=Qs[i], seed=i, **BUDGET).q for i in range(1, 20, 2)]
    thread.join()
    for k, i in enumerate(range(0, 20, 2)):
        assert np.array_equal(out["b"][k], general(panda, targets[i], seed=i, q0=Qs[i], **BUDGET).q)
    for k, i in enumerate(range(1, 20, 2)):
        assert np.array_equal(mine[k], general(panda, targets[i], seed=i, q0=Qs[i], **BUDGET).q)


def test_goal_sets_and_a_closed_form_tip_goal_take_the_fast_path_too(panda):
    """An IKSolver (and solve's kept one) hands a goal set to memetic's goal-set search, as memetic does, and a
    closed form's one goal on the tip to that closed form (a failure of either before the fast path knew them)."""
    T = panda.fk(np.full(panda.n, 0.3))
    far = pin.SE3(T.rotation, T.translation + np.array([2.0, 0.0, 0.0]))  # beyond the Panda's reach
    solver = ek.IKSolver(panda)
    for r in (solver.solve([Pose(panda.tip, [far, T])], seed=0), ek.solve(panda, [Pose(panda.tip, [far, T])], seed=0)):
        assert r.success and r.chosen == [1]
        assert np.linalg.norm(panda.fk(r.q).translation - T.translation) <= 1e-6
    puma = ek.load_robot("puma3r")
    p = puma.fk(np.array([0.3, -0.5, 0.8])).translation
    r = ek.IKSolver(puma, method="algebraic").solve([Position(puma.tip, p)])
    assert r.success and len(r.solutions) == 4 and np.linalg.norm(puma.fk(r.q).translation - p) <= 1e-6


def _outcome(make):
    """(the Target's position and rotation, or None; the error's type and message, or None) of ``make()``."""
    try:
        t = make()
    except (TargetError, ConfigurationError) as exc:
        return None, (type(exc), str(exc))
    return (t.position.tolist(), None if t.rotation is None else t.rotation.tolist()), None


BAD_POSES = {
    "nan position": (0, 3, np.nan), "inf position": (1, 3, np.inf), "nan rotation": (0, 0, np.nan),
    "inf rotation": (2, 1, -np.inf), "not a rotation": (0, 1, 0.3), "huge rotation entry": (1, 1, 1e300),
    "beyond MAX_TARGET_NORM": (2, 3, 2e6), "huge position": (0, 3, 1e308), "bottom row": (3, 0, 0.5),
    "nan bottom row": (3, 3, np.nan),
}


@pytest.mark.parametrize("bad", sorted(BAD_POSES))
def test_pose_forms_get_the_checks_of_the_target_constructor(panda, cases, bad):
    """SE3 and 4x4 poses, good or bad, give what Target's own checks give (the same position and rotation, or the
    same error and message), and IKSolver.solve raises what the general path raises."""
    i, j, value = BAD_POSES[bad]
    H = cases[0][0].homogeneous.copy()
    mirrored = H.copy()
    mirrored[:3, 2] *= -1.0
    H[i, j] = value
    solver = ek.IKSolver(panda, **BUDGET)
    for pose in (H, mirrored):
        reference = _outcome(lambda pose=pose: ek.Target(pose[:3, 3], pose[:3, :3]))
        if pose[3].tolist() != [0.0, 0.0, 0.0, 1.0] and np.isfinite(pose[3]).all():
            reference = _outcome(lambda pose=pose: (_ for _ in ()).throw(TargetError(
                f"the bottom row of a 4 x 4 homogeneous pose must be [0 0 0 1], got {pose[3].tolist()}")))
        assert _outcome(lambda pose=pose: ek.Target.coerce(pose)) == reference
        if i < 3:  # an SE3 has no bottom row
            se3 = pin.SE3(pose[:3, :3].copy(), pose[:3, 3].copy())
            assert _outcome(lambda se3=se3: ek.Target.coerce(se3)) == reference
        by_solver = _outcome(lambda pose=pose: solver.solve(pose, seed=1) and ek.Target.coerce(pose))
        by_general = _outcome(lambda pose=pose: general(panda, pose, seed=1, **BUDGET) and ek.Target.coerce(pose))
        assert by_solver == by_general


@settings(max_examples=200, deadline=None)
@given(st.integers(0, 2**31 - 1), st.floats(-10.0, 1.0), st.booleans(), st.floats(-7.0, 7.0))
def test_property_coerce_of_a_pose_is_the_constructors_verdict(seed, log_eps, mirror, log_norm):
    """Target.coerce of an SE3 or a 4x4 pose accepts and refuses exactly what Target(position, rotation) does, with
    the same message, and keeps the same numbers."""
    rng = np.random.default_rng(seed)
    R = pin.SE3.Random().rotation @ np.diag([1.0, 1.0, -1.0 if mirror else 1.0])
    R = R + 10.0**log_eps * rng.standard_normal((3, 3))
    p = rng.standard_normal(3)
    p *= 10.0**log_norm / np.linalg.norm(p)
    H = np.eye(4)
    H[:3, :3], H[:3, 3] = R, p
    reference = _outcome(lambda: ek.Target(p.copy(), R.copy()))
    assert _outcome(lambda: ek.Target.coerce(H)) == reference
    assert _outcome(lambda: ek.Target.coerce(pin.SE3(R, p))) == reference


@pytest.mark.parametrize("q0", [np.zeros(3), np.full(7, np.nan), np.full(7, np.inf), [0.0] * 6 + [-np.inf],
                                np.zeros((1, 7)), "abc", [1e308] * 7, [0.1] * 7, np.arange(7), [True] * 7])
def test_q0_gets_the_checks_of_the_general_path(panda, cases, q0):
    """A q0 of the wrong shape, with NaN or inf, of huge finite entries (their sum overflows), a list, integers:
    the solver's verdict and answer are the general path's."""
    T = cases[0][0]
    solver = ek.IKSolver(panda, **BUDGET)

    def run(solve):
        try:
            r = solve()
        except (ConfigurationError, TargetError, ValueError) as exc:
            return type(exc), str(exc)
        return r.q.tolist(), r.message.split(" (")[0]

    assert run(lambda: solver.solve(T, q0, seed=3)) == run(lambda: general(panda, T, seed=3, q0=q0, **BUDGET))


def test_goal_lists_take_memetics_own_verdict(panda):
    """IKSolver.solve hands memetic's Result of a goal list without goal sets back as it is (memetic judged each goal
    on the errors it returns; the general path's _with_goal_verdict recomputes them): the same success, message,
    goal errors and chosen members as the general path, for one goal of each kind and for two goals, met or not."""
    from evoik_pin.goals import Orientation, Pose, Position

    solver = ek.IKSolver(panda, **BUDGET)
    rng = np.random.default_rng(12)
    unmet = 0
    for i, q in enumerate(panda.random_configurations(12, rng)):
        T = panda.fk(q)
        if i % 4 == 3:  # out of reach: goals not met, the message names them
            T = T.copy()
            T.translation = 3.0 * T.translation
        lists = ([Pose(panda.tip, T)], [Pose(panda.tip, T, free="rz")], [Position(panda.tip, T.translation)],
                 [Orientation(panda.tip, T.rotation)],
                 [Pose(panda.tip, T), Position("panda_link4", panda.fk(q, "panda_link4").translation)])
        goals = lists[i % len(lists)]
        a, b = solver.solve(goals, seed=i), general(panda, goals, seed=i, **BUDGET)
        same(a, b)
        assert a.message == b.message and a.chosen == b.chosen == [None] * len(goals)
        unmet += not a.success
    assert unmet >= 2


def test_one_solver_alternating_single_targets_goal_sets_and_goal_lists(panda):
    """One IKSolver (its plan keeps a few engines and compiled entries) fed single targets, goal sets and one-goal
    lists in turn: every answer meets its goal by Pinocchio, and a goal set's errors and member (the kernel's, from
    the run that met it) are those the general verdict computes at the answer."""
    from evoik_pin.problem import IKProblem

    rng = np.random.default_rng(11)
    solver = ek.IKSolver(panda, timeout=None, max_restarts=20)  # verdicts independent of the machine's load
    for i in range(6):
        Q = panda.random_configurations(3, rng)
        far = pin.SE3(pin.exp3(rng.normal(size=3)), np.array([1.5, 0.0, 0.4]))  # out of the arm's reach
        members = [far, panda.fk(Q[0]), far, panda.fk(Q[1])]
        calls = [[Pose(panda.tip, members)], [Pose(panda.tip, panda.fk(Q[1]))], panda.fk(Q[2])]
        for target in calls if i % 2 == 0 else calls[1:] + calls[:1]:
            r = solver.solve(target, seed=i)
            assert r.success, r.message
            M = panda.fk(r.q)
            if isinstance(target, list) and target[0].alternatives is not None:  # the goal set
                problem = IKProblem(panda, target)
                errors, chosen = problem.goal_errors_and_chosen(r.q)
                assert r.chosen == chosen and r.chosen[0] in (1, 3)
                assert np.allclose(np.array(r.goal_errors, dtype=float), np.array(errors, dtype=float),
                                   rtol=0, atol=1e-12)
                T = members[r.chosen[0]]
            else:
                T = target[0].target if isinstance(target, list) else target
            assert np.linalg.norm(M.translation - T.translation) <= 1e-6
            assert np.linalg.norm(pin.log3(T.rotation.T @ M.rotation)) <= 1e-6


def test_locked_joints_are_the_locked_robots_answers_in_the_full_layout(panda, cases):
    """IKSolver(locked=...) solves on robot.locked(values): the same answers as the general path on that robot, the
    locked joints put back at their values; solve keeps such a solver like any other (locked is a plain dict)."""
    from evoik_pin.ik_solver import cached_solver

    targets, Qs = cases
    values = {"panda_joint1": 0.3, "panda_joint5": -0.2}
    sub = panda.locked(values)
    keep = [panda.joint_names.index(j) for j in sub.joint_names]
    locked_at = [panda.joint_names.index(j) for j in values]
    solver = ek.IKSolver(panda, locked=values, **BUDGET)
    for i, T in enumerate(targets[:6]):
        q0 = Qs[i] if i % 2 else None
        reference = general(sub, T, seed=i, q0=None if q0 is None else q0[keep], **BUDGET)
        r = solver.solve(T, q0=q0, seed=i)
        assert r.q.shape == (panda.n,)
        assert np.array_equal(r.q[keep], reference.q) and np.array_equal(r.q[locked_at], [0.3, -0.2])
        assert (r.success, r.position_error, r.cost) == (reference.success, reference.position_error, reference.cost)
        assert "joints locked: panda_joint1=0.3, panda_joint5=-0.2" in r.message
        assert np.array_equal(ek.solve(panda, T, seed=i, q0=q0, locked=values, **BUDGET).q, r.q)
    kept = cached_solver(panda, "memetic", {"locked": dict(values), **BUDGET})
    assert kept is not None and kept is cached_solver(panda, "memetic", {"locked": dict(values), **BUDGET})
    assert kept is not cached_solver(panda, "memetic", {"locked": {"panda_joint1": 0.3}, **BUDGET})


def test_prefer_and_locked_are_checked_when_the_solver_is_made(panda):
    with pytest.raises(OptionError, match="prefer"):
        ek.IKSolver(panda, prefer="closest")
    with pytest.raises(MethodError, match="prefer='nearest' collects answers with method 'memetic'"):
        ek.IKSolver(panda, method="de", prefer="nearest")
    with pytest.raises(FrameError):
        ek.IKSolver(panda, locked={"no_such_joint": 0.0})
    with pytest.raises(TargetError):  # solve's order: the target's error before the option's
        ek.solve(panda, np.full(3, np.nan), prefer="manipulability", population=2)
    with pytest.raises(OptionError, match="prefer"):  # and prefer's before the target's
        ek.solve(panda, np.full(3, np.nan), prefer="closest")


def test_solve_all_takes_solves_locked_and_refuses_prefer(panda, cases):
    """solve_all runs solve's pipeline: locked joints held in every solution (each q in the full layout, each meeting
    the pose by the full robot's FK); prefer (one answer among many) stays an unknown option of memetic-all."""
    T = cases[0][0]
    values = {"panda_joint1": 0.2}
    solutions = ek.solve_all(panda, T, seed=0, count=3, locked=values, timeout=None, max_starts=64)
    assert solutions and all(s.q.shape == (panda.n,) and s.q[0] == 0.2 for s in solutions)
    for s in solutions:
        reached = panda.fk(s.q)
        assert np.linalg.norm(reached.translation - T.translation) <= 1e-6 and panda.within_bounds(s.q)
    with pytest.raises(OptionError, match=r"unknown option\(s\) prefer for method 'memetic-all'"):
        ek.solve_all(panda, T, prefer="nearest", q0=np.zeros(panda.n))


def test_alternating_goal_lists_of_several_goals():
    """A solver alternating goal lists of different structures (two hands; with the head's position or direction;
    with the centre of mass) solves each of them on every round."""
    from evoik_pin.goals import CenterOfMass, Direction

    talos = ek.load_robot("talos", floating_base=True)
    rng = np.random.default_rng(5)
    solver = ek.IKSolver(talos, **BUDGET)
    q = talos.random_configurations(1, rng)[0]
    hands = [Pose("arm_left_7_link", talos.fk(q, "arm_left_7_link")),
             Pose("arm_right_7_link", talos.fk(q, "arm_right_7_link"))]
    model = talos.full_model
    com = pin.centerOfMass(model, model.createData(), talos.full_configuration(q))
    lists = [hands, hands + [Position("head_2_link", talos.fk(q, "head_2_link").translation)],
             hands + [Direction("head_2_link", (1.0, 0.0, 0.0), talos.fk(q, "head_2_link").rotation[:, 0])],
             hands + [CenterOfMass(com, tolerance=1e-3)]]
    for round_ in range(2):
        for i, goals in enumerate(lists):
            result = solver.solve(goals, q0=q, seed=10 * round_ + i)
            assert result.success, (round_, i, result.message)
