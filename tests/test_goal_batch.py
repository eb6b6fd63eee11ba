"""Goal lists (evoik_pin.goals) in every entry point: solve_many (batched rounds through the kernel's pair entry
point, the k-d tree over the goal frames, the one-by-one fallback, workers, bad lists named by their index; Ray in
test_ray_backend.py, beside the other Ray tests, so that the suite starts Ray once),
solve_trajectory (warm-started frame to frame), and every method that takes them (the evolutionary ones through
IKProblem.evaluate, polish=True), the others refusing by name.

Comparisons use a deterministic budget (``timeout=None``, ``max_restarts``), so the answers do not depend on the
machine's load; throughput is measured in scripts/bench_goals_scale.py, never here.
"""

import numpy as np
import pinocchio as pin
import pytest
from test_batch import same

import evoik_pin as ek
from evoik_pin.errors import FrameError, MethodError, TargetError
from evoik_pin.goals import Pose, Position
from evoik_pin.problem import IKProblem
from evoik_pin.robot.frames import find_frame
from evoik_pin.solvers.batch import threads
from evoik_pin.solvers.batch.goal_lists import GoalSource, GoalTree
from evoik_pin.solvers.lm import LevenbergMarquardt, solve_pairs
from evoik_pin.solvers.search.seed_table import default_table_size, seed_table

BUDGET = {"timeout": None, "max_restarts": 2}
TALOS_FRAMES = ["left_sole_link", "right_sole_link", "arm_left_7_link", "arm_right_7_link"]


@pytest.fixture(scope="module")
def talos():
    return ek.load_robot("talos", floating_base=True)


@pytest.fixture(scope="module")
def baxter():
    return ek.load_robot("baxter")


def talos_lists(robot, count: int, seed: int) -> list:
    """Four pose goals (both soles, both wrists) at the frames' poses of random configurations: reachable."""
    Q = robot.random_configurations(count, np.random.default_rng(seed))
    return [[Pose(f, robot.fk(q, f)) for f in TALOS_FRAMES] for q in Q]


def far_list(robot) -> list:
    """A Talos problem out of reach: the left wrist 5 m from the feet."""
    q = np.zeros(robot.n)
    goals = [Pose(f, robot.fk(q, f)) for f in TALOS_FRAMES]
    goals[2] = Pose(TALOS_FRAMES[2], pin.SE3(np.eye(3), np.array([5.0, 0.0, 0.5])))
    return goals


@pytest.fixture(scope="module")
def lists(talos):
    out = talos_lists(talos, 40, 3)
    out[17] = far_list(talos)
    return out


def pinocchio_errors(robot, goals, q) -> list[tuple[float, float | None]]:
    """Each goal's (position m, rotation rad or None) by Pinocchio's kinematics of the whole URDF at ``q``."""
    model = robot.full_model
    data = model.createData()
    pin.framesForwardKinematics(model, data, robot.full_configuration(q))
    out = []
    for goal in goals:
        T = data.oMf[find_frame(model, goal.frame)]
        pt, Rt = goal.encode()
        rot = float(np.linalg.norm(pin.log3(Rt.T @ T.rotation))) if goal.has_orientation else None
        out.append((float(np.linalg.norm(T.translation - pt)), rot))
    return out


def consistent(robot, goals, r) -> None:
    """``r.goal_errors`` are Pinocchio's errors at ``r.q``, and ``success`` is every goal within its tolerances."""
    assert r.goal_errors is not None and len(r.goal_errors) == len(goals)
    for (p, o), (pp, po), g in zip(r.goal_errors, pinocchio_errors(robot, goals, r.q), goals, strict=True):
        assert p == pytest.approx(pp, abs=1e-9) and (o is None) == (po is None) == (not g.has_orientation)
        if o is not None:
            assert o == pytest.approx(po, abs=1e-9)
    assert r.position_error == pytest.approx(max(p for p, _ in r.goal_errors), abs=1e-9)
    assert r.success == all(g.met(p, o) for g, (p, o) in zip(goals, r.goal_errors, strict=True))
    assert robot.within_bounds(r.q)


# ---------------------------------------------------------------------------------------------- the kernel's pairs
def test_solve_pairs_runs_goal_stacks_as_lm_runs_each_problem(talos, lists):
    source = GoalSource(talos, lists[:6])
    (rows, arrays), = source.block(0, 6).groups
    Q = talos.random_configurations(6, np.random.default_rng(0))
    lo, hi = talos.lower, talos.upper
    res = solve_pairs(talos, Q, arrays, lo, hi, 1e-6, 1e-6)
    assert res.goal_errors.shape == (6, 4, 2)
    for i in range(6):
        one = LevenbergMarquardt(IKProblem(talos, lists[i])).run(Q[i], 30)
        assert np.array_equal(res.q[i], one.q) and res.converged[i] == one.converged
        assert np.array_equal(res.goal_errors[i], one.goal_errors)


def test_the_goal_tree_ranks_the_table_as_memetic_does(talos, lists):
    problem = IKProblem(talos, lists[0])
    table = seed_table(talos, problem.lower, problem.upper, default_table_size(talos.n))
    (_, arrays), = GoalSource(talos, lists[:1]).block(0, 1).groups
    exact = GoalTree(talos, table, arrays.stack).nearest(arrays, 5)[0]
    assert exact.tolist() == list(table.ranked_goals(problem, 5))


# ---------------------------------------------------------------------------------------------- solve_many
def test_solve_many_solves_goal_lists_as_solve_does(talos, lists):
    res = ek.solve_many(talos, lists, seed=4, workers=1, **BUDGET)
    assert len(res) == 40 and res.q.shape == (40, talos.n) and res.stats["batched"] >= 30
    assert res.stats["solved"] == 39 and not res.success[17]
    for i, (r, goals) in enumerate(zip(res, lists, strict=True)):
        consistent(talos, goals, r)
        assert res.position_error[i] == r.position_error and res.success[i] == r.success
        assert np.isfinite(res.orientation_error[i])  # pose goals: the largest rotation error
    batched = next(r for r in res if "batched LM" in r.message)
    assert batched.cost == pytest.approx(sum(p + o for p, o in batched.goal_errors))
    # the unreachable list went to memetic with its own generator, from its first start: the rounds tried ranked
    # table entries, memetic's goal-list starts begin with composed ones (threads.BatchSolver._singles)
    gens = [np.random.default_rng(s) for s in np.random.SeedSequence(4).spawn(len(lists))]
    alone = ek.solve(talos, lists[17], seed=gens[17], table_offset=0, **BUDGET)
    same([res[17]], [alone])
    assert res[17].goal_errors == alone.goal_errors and "goals not met: " in alone.message


@pytest.mark.parametrize("kind", ["pose", "position"])
def test_a_tip_target_and_its_one_goal_list_are_one_problem(baxter, kind):
    """solve_many reads a tip target as the goal list [Pose(tip, T)] / [Position(tip, p)]: both forms give the same
    answers, bit for bit (one engine, one seed-table ranking), and only the goal list reports per-goal errors."""
    Q = baxter.random_configurations(40, np.random.default_rng(5))
    poses = [baxter.fk(q) for q in Q]
    if kind == "pose":
        targets, lists = np.array([T.homogeneous for T in poses]), [[Pose(baxter.tip, T)] for T in poses]
    else:
        targets, lists = [T.translation for T in poses], [[Position(baxter.tip, T.translation)] for T in poses]
    tip, goals = ek.solve_many(baxter, targets, seed=2), ek.solve_many(baxter, lists, seed=2)
    assert tip.stats["batched"] == goals.stats["batched"] > 0
    assert np.array_equal(tip.q, goals.q) and np.array_equal(tip.success, goals.success)
    assert np.array_equal(tip.position_error, goals.position_error)
    assert tip[0].goal_errors is None and len(goals[0].goal_errors) == 1


def test_same_answers_whatever_the_number_of_workers(talos, lists, monkeypatch):
    monkeypatch.setattr(threads, "MIN_CHUNK", 8)
    one = ek.solve_many(talos, lists, seed=4, workers=1, **BUDGET)
    two = ek.solve_many(talos, lists, seed=4, workers=2, **BUDGET)
    assert threads.chunk_bounds(40, 2) != threads.chunk_bounds(40, 1)
    same(one, two)
    assert [r.goal_errors for r in one] == [r.goal_errors for r in two]


def test_lists_of_different_structures_are_grouped(talos, baxter):
    mixed = talos_lists(talos, 6, 5)
    q = talos.random_configurations(3, np.random.default_rng(6))
    for i, k in ((1, 0), (3, 1), (4, 2)):  # a left hand alone, by position, weighted
        mixed[i] = [Pose("left_sole_link", talos.fk(q[k], "left_sole_link")),
                    Position("arm_left_7_link", talos.fk(q[k], "arm_left_7_link").translation, weight=2.0)]
    assert GoalSource(talos, mixed).structures == 2
    res = ek.solve_many(talos, mixed, seed=1, workers=2, **BUDGET)
    assert res.success.all()
    for r, goals in zip(res, mixed, strict=True):
        consistent(talos, goals, r)
    assert res[1].goal_errors[1][1] is None  # a position goal has no rotation error
    one = [Pose("left_gripper", baxter.fk(np.zeros(baxter.n), "left_gripper"))]
    w = ek.solve_many(baxter, [one], seed=0)
    assert w.success.all() and len(w[0].goal_errors) == 1
    alone = ek.solve_many(baxter, one, seed=0)  # one goal list alone is one problem, as one target alone is
    assert len(alone) == 1 and np.array_equal(alone.q, w.q)


@pytest.mark.parametrize("bad, error, match", [
    ([], TargetError, "goal list 5: the goal list is empty"),
    ([Pose("no_such_link", np.eye(4))], FrameError, "goal list 5: .*no_such_link"),
    (np.zeros(3), TargetError, "goal list 5 is a ndarray, not a list of goals"),
    ([Pose("left_sole_link", np.eye(4)), "left_sole_link"], TargetError, "goal list 5 is a list, not a list of goals"),
])
def test_a_bad_list_is_named_by_its_index_before_any_work(talos, lists, bad, error, match, monkeypatch):
    called = []
    monkeypatch.setattr(threads.BatchSolver, "solve", lambda *a, **k: called.append(1))
    given = list(lists[:10])
    given[5] = bad
    with pytest.raises(error, match=match):
        ek.solve_many(talos, given, seed=0)
    with pytest.raises(error, match=match):
        ek.solve_trajectory(talos, given, seed=0)
    assert not called


def test_nan_targets_and_clashes_are_refused(talos, lists):
    with pytest.raises(TargetError, match="NaN"):
        Position("left_sole_link", [0.0, np.nan, 0.0])  # a goal checks its target when made
    T = talos.fk(np.zeros(talos.n), "left_sole_link")
    clash = [Pose("left_sole_link", T), Position("left_sole_link", T.translation + 0.1)]
    with pytest.raises(TargetError, match="goal list 2: frame 'left_sole_link' has two goals"):
        ek.solve_many(talos, [lists[0], lists[1], clash], seed=0)


def test_methods_without_goal_lists_are_refused_by_name(talos, lists):
    with pytest.raises(MethodError, match="'algebraic' solves one target for the tip .* goal lists are solved by "
                                          "'memetic'"):
        ek.solve_many(talos, lists[:3], method="algebraic", seed=0)
    with pytest.raises(MethodError, match="'de' returns one solution; solve_all needs one of"):
        ek.solve_all(talos, lists[0], method="de", seed=0)


# ---------------------------------------------------------------------------------------------- solve_trajectory
def test_a_trajectory_of_goal_lists_is_warm_started_frame_to_frame(talos):
    q = talos.random_configurations(1, np.random.default_rng(8))[0]
    frames = []
    for k in range(4):  # a walk: the base and the hands move a little each frame
        qk = q.copy()
        qk[0] += 0.02 * k
        qk[10:] += 0.01 * k
        qk = np.clip(qk, talos.lower, talos.upper)
        frames.append([Pose(f, talos.fk(qk, f)) for f in TALOS_FRAMES])
    results = ek.solve_trajectory(talos, frames, seed=0, **BUDGET)
    assert all(r.success for r in results)
    for k in range(1, 4):  # each answer is the next frame's q0: solved from it alone, the same answer
        again = ek.solve(talos, frames[k], q0=results[k - 1].q, seed=np.random.default_rng(0), **BUDGET)
        assert "LM from q0" in results[k].message and np.array_equal(again.q, results[k].q)
        consistent(talos, frames[k], results[k])
    with pytest.raises(MethodError, match="'algebraic' solves one target"):
        ek.solve_trajectory(talos, frames, method="algebraic")


# ---------------------------------------------------------------------------------------------- every method
SMALL = {"de": {}, "isade": {}, "pso": {}, "mode": {}, "ga": {},
         "ga-binary": {"population": 120, "elite": 10, "encoding": "bounds"}}


@pytest.mark.parametrize("method", sorted(SMALL))
def test_every_evolutionary_method_solves_goal_lists(method, talos, baxter):
    assert set(SMALL) | {"memetic", "memetic-all", "nsga2", "hga"} == set(ek.api.GOAL_METHODS)  # test_goal_methods
    q = baxter.random_configurations(1, np.random.default_rng(1))[0]
    problems = [(talos, talos_lists(talos, 1, 2)[0]),
                (baxter, [Pose("left_gripper", baxter.fk(q, "left_gripper")),
                          Position("right_gripper", baxter.fk(q, "right_gripper").translation)])]
    for robot, goals in problems:
        r = ek.solve(robot, goals, method=method, seed=0, max_generations=4, **SMALL[method])
        assert r.method == method
        consistent(robot, goals, r)
        polished = ek.solve(robot, goals, method=method, seed=0, max_generations=4, polish=True, **SMALL[method])
        consistent(robot, goals, polished)
        assert polished.position_error <= r.position_error and "polished by Levenberg-Marquardt" in polished.message


def test_the_closed_forms_refuse_goal_lists_by_name(talos):
    with pytest.raises(MethodError, match="method 'algebraic' solves one target for the tip .* goal lists are solved "
                                          "by 'memetic', 'memetic-all', 'de'"):
        ek.solve(talos, talos_lists(talos, 1, 2)[0], method="algebraic", seed=0)
