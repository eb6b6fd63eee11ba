"""The compiled guaranteed runs of a goal list of several goals (issue 30): memetic's guaranteed runs of a whole robot
(q0's, then SeedTable.goal_starts' first starts: composed goal by goal and ranked entries alternately) made in one
compiled call (solvers/search/guaranteed_runs.py: goal_guaranteed_runs) give the Results of the runs made one by one,
bit for bit, on a fixed base, on a floating base set by a goal, and on a floating base each composed start takes from
its entry; and the compiled helpers they share with goal_starts (nearest.py: the ranking, seen_from) compute what they
say."""

import numpy as np
import pinocchio as pin
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import evoik_pin as ek
from evoik_pin.goals import Pose, Position
from evoik_pin.solvers.search import memetic
from evoik_pin.solvers.search.nearest import seen_from
from evoik_pin.solvers.search.seed_table import default_table_size, seed_table

#: (robot name, floating base, goals as (frame, kind)): the three ways goal_starts composes its starts.
WHOLE_ROBOTS = {
    "baxter": (False, (("left_gripper", "pose"), ("right_gripper", "pose"))),  # a fixed base
    "go2": (True, (("base", "pose"), ("FL_foot", "position"), ("FR_foot", "position"), ("RL_foot", "position"),
                   ("RR_foot", "position"))),  # the base set by its pose goal
    "talos": (True, (("left_sole_link", "pose"), ("right_sole_link", "pose"), ("arm_left_7_link", "pose"))),
}


def whole_robot(name):
    floating, goals = WHOLE_ROBOTS[name]
    return ek.load_robot(name, tips=[f for f, _ in goals], floating_base=floating), goals


def goal_lists(robot, goals, count, seed):
    """Goal lists met at random configurations (returned third), every fifth one with its first goal moved out of
    reach (no guaranteed run converges: memetic goes on from their state, to its DE restarts), and as many random
    configurations (returned second)."""
    rng = np.random.default_rng(seed)
    out = []
    generating = robot.random_configurations(count, rng)
    for i, q in enumerate(generating):
        made = []
        for g, (frame, kind) in enumerate(goals):
            T = robot.fk(q, frame)
            if i % 5 == 4 and g == 0:
                T = pin.SE3(T.rotation, T.translation + np.array([0.0, 0.0, 5.0]))
            made.append(Pose(frame, T) if kind == "pose" else Position(frame, T.translation))
        out.append(made)
    return out, robot.random_configurations(count, rng), generating


def same(a, b):
    assert np.array_equal(a.q, b.q)
    assert (a.success, a.position_error, a.orientation_error, a.cost, a.evaluations, a.generations, a.message) == (
        b.success, b.position_error, b.orientation_error, b.cost, b.evaluations, b.generations, b.message)
    assert a.goal_errors == b.goal_errors
    assert a.history.keys() == b.history.keys()
    for key in a.history:
        assert np.array_equal(a.history[key], b.history[key])


@pytest.mark.parametrize("name", list(WHOLE_ROBOTS))
def test_goal_guaranteed_runs_give_the_one_by_one_results(name, monkeypatch):
    """Over many goal lists, from no q0, a random q0 and the answer's own configuration, on an IKSolver (its compiled
    entry kept) and through evoik_pin.solve: the Results of the runs made one by one (COMPILED_GUARANTEED_RUNS off), bit
    for bit, also where no guaranteed run converges (out of reach); the compiled call is made on every solve."""
    robot, goals = whole_robot(name)
    lists, Qs, generating = goal_lists(robot, goals, 25, 5)
    budget = {"timeout": None, "max_restarts": 1}  # deterministic: the clock cannot change an answer
    calls = []
    made = memetic._guaranteed_runs
    monkeypatch.setattr(memetic, "_guaranteed_runs", lambda *args: calls.append(args[-1] is None) or made(*args))
    fast, slow = [], []
    for flag, results in ((True, fast), (False, slow)):
        monkeypatch.setattr(memetic, "COMPILED_GUARANTEED_RUNS", flag)
        solver = ek.IKSolver(robot, **budget)
        for i, goal_list in enumerate(lists):
            q0 = None if i % 3 == 0 else Qs[i] if i % 3 == 1 else generating[i]
            results.append(solver.solve(goal_list, q0=q0, seed=i))
            results.append(ek.solve(robot, goal_list, seed=i, q0=q0, **budget))
    assert calls == [True] * (2 * len(lists))  # COMPILED_GUARANTEED_RUNS on: every solve made the goal lists' runs
    for a, b in zip(fast, slow, strict=True):
        same(a, b)
    stages = {r.message.split(" (")[0] for r in fast}
    assert {"tolerance reached by LM from q0", "tolerance reached by LM from seed table"} <= stages
    assert sum(r.success for r in fast) >= 0.7 * len(fast) and sum(not r.success for r in fast) >= 4


def test_a_goal_list_from_its_answer_converges_from_q0(monkeypatch):
    """q0 is a goal list's first start: from a configuration meeting the goals, the first run (q0's) converges."""
    robot, goals = whole_robot("baxter")
    rng = np.random.default_rng(7)
    solver = ek.IKSolver(robot)
    for q in robot.random_configurations(5, rng):
        goal_list = [Pose(frame, robot.fk(q, frame)) for frame, _ in goals]
        r = solver.solve(goal_list, q0=q, seed=0)
        assert r.success and r.message.startswith("tolerance reached by LM from q0 (1 LM run(s)")


@settings(max_examples=60, deadline=None)
@given(st.lists(st.floats(-3.0, 3.0), min_size=6, max_size=6), st.integers(0, 2**31))
def test_seen_from_is_the_targets_in_the_bases_frame(base, seed):
    """seen_from(base, pt, Rt) = B^-1 T for B the base's pose (x, y, z, yaw, pitch, roll: Rz Ry Rx, Pinocchio's
    rpyToMatrix of roll, pitch, yaw), to rounding."""
    rng = np.random.default_rng(seed)
    base = np.array(base)
    targets = [pin.SE3.Random() for _ in range(3)]
    for T in targets:
        T.translation = rng.uniform(-2, 2, 3)
    pt = np.array([T.translation for T in targets])
    Rt = np.array([T.rotation for T in targets])
    P_out, R_out = np.empty((3, 3)), np.empty((3, 3, 3))
    seen_from(base, pt, Rt, P_out, R_out)
    B = pin.SE3(pin.rpy.rpyToMatrix(base[5], base[4], base[3]), base[:3])
    for g, T in enumerate(targets):
        rel = B.actInv(T)
        assert np.allclose(P_out[g], rel.translation, rtol=0.0, atol=1e-12)
        assert np.allclose(R_out[g], rel.rotation, rtol=0.0, atol=1e-12)


@pytest.mark.parametrize("name", ["baxter", "talos"])
def test_goal_ranking_is_the_summed_nearness(name):
    """SeedTable.ranked_goals (nearest.rank_goal_entries, in single precision) gives the entries nearest in the goals'
    summed nearness computed by NumPy in double precision: each place's entry as near as NumPy's to within 1e-5 of
    the largest squared feature norm (single precision's rounding), distinct, allowed; the same order but for
    near-ties, with and without a mask."""
    from evoik_pin.problem import IKProblem

    robot, goals = whole_robot(name)
    table = seed_table(robot, robot.lower, robot.upper, default_table_size(robot.n))
    rng = np.random.default_rng(12)
    allowed = rng.random(table.Q.shape[0]) < 0.4
    lists, _, _ = goal_lists(robot, goals, 40, 3)
    exact = rankings = 0
    for goal_list in lists:
        problem = IKProblem(robot, goal_list)
        F, sq = table.goal_table_features(tuple(g.frame for g in goal_list), table.goal_spec(goal_list))
        _, pt, Rt = problem.goal_stack()
        spec = table.goal_spec(goal_list)
        f = table.goal_features(spec, pt[None], Rt[None])[0]
        for k, mask in ((1, None), (17, None), (17, allowed)):
            d = sq - 2.0 * (F @ f)
            if mask is not None:
                d = np.where(mask, d, np.inf)
            got = np.array(list(table.ranked_goals(problem, k, mask)))
            reference = np.argsort(d, kind="stable")[:k]
            assert len(set(got.tolist())) == k and np.isfinite(d[got]).all()
            assert np.abs(d[got] - d[reference]).max() <= 1e-5 * max(1.0, float(sq.max()))
            exact += got.tolist() == reference.tolist()
            rankings += 1
    assert exact >= 0.9 * rankings


def test_the_helpers_goal_starts_call_are_loaded_before_the_clock():
    """load_goal_helpers (memetic's set-up for a goal list, before its clock) loads the specializations of the compiled
    helpers that goal_starts and ranked_goals then call from Python: the starts of goal lists on a fixed base, a
    floating base set by a goal and one taken from each entry, with and without a mask, add none (a new one would
    be loaded, or compiled, inside a solve's budget)."""
    from evoik_pin.problem import IKProblem
    from evoik_pin.solvers.search import nearest
    from evoik_pin.solvers.search.seed_table import load_goal_helpers

    load_goal_helpers()
    helpers = (nearest.rank_goal_entries, nearest.nearest_per_goal, nearest.seen_from)
    loaded = [len(f.signatures) for f in helpers]
    assert all(count >= 1 for count in loaded)
    for name in WHOLE_ROBOTS:
        robot, goals = whole_robot(name)
        table = seed_table(robot, robot.lower, robot.upper, default_table_size(robot.n))
        mask = np.random.default_rng(1).random(table.Q.shape[0]) < 0.5
        lists, _, _ = goal_lists(robot, goals, 2, 9)
        for goal_list in lists:
            problem = IKProblem(robot, goal_list)
            for allowed in (None, mask):
                starts = list(table.goal_starts(problem, 6, allowed))
                assert len(starts) == 6 and all(q.shape == (robot.n,) for q in starts)
                assert len(list(table.ranked_goals(problem, 3, allowed))) == 3
    assert [len(f.signatures) for f in helpers] == loaded


@settings(max_examples=40, deadline=None)
@given(st.integers(1, 300), st.integers(0, 2**31), st.booleans(), st.sampled_from([np.float32, np.float64]))
def test_select_k_keeps_the_k_smallest_lower_index_first(k, seed, masked, dtype):
    """select_k, by insertion (k <= 64) or by a stable sort (larger k: memetic-all's goal starts rank the whole table),
    gives the k smallest allowed entries in (distance, index) order, as NumPy's stable argsort does, ties included;
    so does its insertion alone (select_few, which memetic's guaranteed runs call directly) at any k."""
    from evoik_pin.solvers.search.nearest import select_few, select_k

    rng = np.random.default_rng(seed)
    d = rng.integers(0, 40, 200).astype(dtype)  # many ties
    allowed = rng.random(200) < 0.6 if masked else np.zeros(0, dtype=bool)
    index = np.nonzero(allowed)[0] if masked else np.arange(200)
    reference = index[np.argsort(d[index], kind="stable")][:k]
    for select in (select_k, select_few):
        out = np.empty(k, dtype=np.int64)
        m = select(d, allowed, k, out)
        assert m == reference.size and out[:m].tolist() == reference.tolist()
