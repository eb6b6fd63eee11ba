"""The compiled single-target fast path (issue 24): the compiled ranking of the seed table (solvers/search/nearest.py)
gives the table's ranking, and memetic's guaranteed runs made in one compiled call
(solvers/search/first_runs.py) give the Results of the runs made one by one, bit for bit, over many targets."""

import numpy as np
import pytest

import evoik_pin as ek
from evoik_pin.solvers.search import memetic
from evoik_pin.solvers.search.nearest import select_k, table_distances
from evoik_pin.solvers.search.seed_table import default_table_size, seed_table


def targets(robot, count, seed):
    rng = np.random.default_rng(seed)
    return [robot.fk(q) for q in robot.random_configurations(count, rng)], robot.random_configurations(count, rng)


@pytest.mark.parametrize("name", ["panda", "ur5", "redundant7r"])
def test_compiled_ranking_is_the_tables_over_many_targets(name):
    """table_distances + select_k (first_runs's ranking: the same formula summed in the features' order, where NumPy
    uses BLAS) rank the entries as SeedTable.ranked does, over thousands of poses and positions; select_k on NumPy's
    own distances too, with and without a mask."""
    robot = ek.load_robot(name)
    table = seed_table(robot, robot.lower, robot.upper, default_table_size(robot.n))
    poses, _ = targets(robot, 2000, 11)
    allowed = np.random.default_rng(3).random(table.Q.shape[0]) < 0.3
    out = np.empty(17, dtype=np.int64)
    every = np.zeros(0, dtype=bool)
    d = np.empty(table.Q.shape[0])
    for i, T in enumerate(poses):
        for target in (ek.Target(T.translation, T.rotation), ek.Target(T.translation.copy())):
            key, f = table.one_target_features(target)
            _, FT, sq = table.compiled_features(key)
            table_distances(FT, sq, f, d)
            reference = list(table.ranked(target, 17))
            m = select_k(d, every, 17, out)
            assert out[:m].tolist() == reference
            assert np.allclose(d, table.distances(key, f), rtol=0.0, atol=1e-12)
            if i % 10 == 0:
                m = select_k(table.distances(key, f), every, 4, out)
                assert out[:m].tolist() == reference[:4]
                m = select_k(table.distances(key, f), allowed, 17, out)
                assert out[:m].tolist() == list(table.ranked(target, 17, allowed))


def test_selection_edge_cases():
    d = np.array([3.0, 1.0, 2.0, 1.0, 0.5])
    out = np.empty(5, dtype=np.int64)
    every = np.zeros(0, dtype=bool)
    assert select_k(d, every, 0, out) == 0
    assert select_k(d, every, 5, out) == 5 and out.tolist() == [4, 1, 3, 2, 0]  # ties: the lower index first
    assert select_k(d, every, 2, out) == 2 and out[:2].tolist() == [4, 1]
    assert select_k(d, np.zeros(5, dtype=bool), 3, out) == 0
    assert select_k(d, np.array([True, False, True, False, False]), 3, out) == 2 and out[:2].tolist() == [2, 0]


def same(a, b):
    assert np.array_equal(a.q, b.q)
    assert (a.success, a.position_error, a.orientation_error, a.cost, a.evaluations, a.generations, a.message) == (
        b.success, b.position_error, b.orientation_error, b.cost, b.evaluations, b.generations, b.message)
    assert a.history.keys() == b.history.keys()
    for key in a.history:
        assert np.array_equal(a.history[key], b.history[key])


@pytest.mark.parametrize("name", ["panda", "ur5", "redundant7r"])
def test_first_runs_give_the_one_by_one_results(name, monkeypatch):
    """Over many poses and positions, from random q0s, near q0s and none, on an IKSolver (the compiled entry) and
    through evoik_pin.solve: the Results of the runs made one by one (FIRST_RUNS off), bit for bit; also where no
    first run converges and memetic goes on from their state (later entries, DE restarts, out-of-reach targets)."""
    robot = ek.load_robot(name)
    poses, Qs = targets(robot, 300, 23)
    budget = {"timeout": None, "max_restarts": 2}  # deterministic: the clock cannot change an answer
    solver = ek.IKSolver(robot, **budget)
    rng = np.random.default_rng(2)
    calls = []
    for i, T in enumerate(poses):
        target = T if i % 3 else T.translation.copy()
        q0 = None if i % 2 else Qs[i]
        if i % 5 == 0:  # a q0 near a solution: tried first
            q0 = robot.random_configurations(1, rng)[0]
            target = robot.fk(q0)
            q0 = np.clip(q0 + 0.01, robot.lower, robot.upper)
        if i % 50 == 1:  # out of reach: no first run converges, memetic searches from the start
            target = 3.0 * T.translation
        calls.append((target, q0, i))
    made = []
    one_call = memetic._first_runs
    monkeypatch.setattr(memetic, "_first_runs", lambda *args: made.append(1) or one_call(*args))
    fast = [solver.solve(t, q0=q0, seed=i) for t, q0, i in calls]
    general = [ek.solve(robot, t, q0=q0, seed=i, **budget) for t, q0, i in calls[::7]]
    assert len(made) == len(calls) + len(general)
    monkeypatch.setattr(memetic, "FIRST_RUNS", False)
    slow = [ek.IKSolver(robot, **budget).solve(t, q0=q0, seed=i) for t, q0, i in calls]
    for a, b in zip(fast, slow, strict=True):
        same(a, b)
    for a, b in zip(general, slow[::7], strict=True):
        same(a, b)
    stages = {r.message.split(" (")[0] for r in fast}
    assert {"tolerance reached by LM from q0", "tolerance reached by LM from seed table"} <= stages
    assert sum(not r.success for r in fast) >= 5
    # and some solved after the guaranteed runs (memetic went on from the compiled runs' state)
    runs = [int(r.message.split(" LM run(s)")[0].split("(")[-1]) for r in fast if r.success]
    assert any(k > memetic.GUARANTEED_TABLE_RUNS + 1 for k in runs)
    from evoik_pin.solvers.search.first_runs import STAGE_Q0

    assert memetic._FROM_Q0 == STAGE_Q0

