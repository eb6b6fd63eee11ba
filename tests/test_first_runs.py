"""The compiled single-target fast path (issue 24): the seed table's compiled ranking (solvers/search/nearest.py) ranks
as NumPy's formula does, and memetic's guaranteed runs made in one compiled call (solvers/search/first_runs.py) give
the Results of the runs made one by one, bit for bit, over many targets."""

import numpy as np
import pytest

import evoik_pin as ek
from evoik_pin.solvers.search import memetic
from evoik_pin.solvers.search.seed_table import COMPILED_K, default_table_size, seed_table


def numpy_ranking(table, target, k, allowed=None):
    """The ranking before the compiled one: NumPy's sq - 2 F f (BLAS), argmin, then argpartition and argsort."""
    key, f = table.target_features([target])
    F, sq = table._table_features(key)
    d = sq - 2.0 * (F @ f[0])
    if allowed is not None:
        d = np.where(allowed, d, np.inf)
        k = min(k, int(np.count_nonzero(allowed)))
    first = int(d.argmin())
    part = np.argpartition(d, k - 1)[:k]
    return [first] + [int(i) for i in part[d[part].argsort()] if i != first]


def targets(robot, count, seed):
    rng = np.random.default_rng(seed)
    return [robot.fk(q) for q in robot.random_configurations(count, rng)], robot.random_configurations(count, rng)


@pytest.mark.parametrize("name", ["panda", "ur5", "redundant7r"])
def test_compiled_ranking_is_numpys_over_many_targets(name):
    robot = ek.load_robot(name)
    table = seed_table(robot, robot.lower, robot.upper, default_table_size(robot.n))
    poses, _ = targets(robot, 1500, 11)
    allowed = np.random.default_rng(3).random(table.Q.shape[0]) < 0.3
    for i, T in enumerate(poses):
        for target in (ek.Target(T.translation, T.rotation), ek.Target(T.translation.copy())):
            k = (1, 4, 17, COMPILED_K)[i % 4]
            assert list(table.ranked(target, k)) == numpy_ranking(table, target, k)
            if i % 10 == 0:  # with a mask (a scene's collision-free entries)
                assert list(table.ranked(target, k, allowed)) == numpy_ranking(table, target, k, allowed)


def test_compiled_ranking_of_planar_targets():
    robot = ek.load_robot("planar2r")
    table = seed_table(robot, robot.lower, robot.upper, default_table_size(robot.n))
    rng = np.random.default_rng(5)
    for x, y, yaw in rng.uniform(-1.0, 1.0, (300, 3)):
        for target in (ek.Target.planar_target(x, y), ek.Target.planar_target(x, y, yaw)):
            assert list(table.ranked(target, 17)) == numpy_ranking(table, target, 17)


def test_ranking_edge_cases():
    robot = ek.load_robot("panda")
    table = seed_table(robot, robot.lower, robot.upper, default_table_size(robot.n))
    T = robot.fk(np.zeros(robot.n))
    target = ek.Target(T.translation, T.rotation)
    assert list(table.ranked(target, 0)) == []
    none = np.zeros(table.Q.shape[0], dtype=bool)
    assert list(table.ranked(target, 5, none)) == []
    two = none.copy()
    two[[10, 20]] = True
    assert sorted(table.ranked(target, 5, two)) == [10, 20]  # k capped at the allowed entries
    whole = list(table.ranked(target, table.Q.shape[0]))  # above COMPILED_K: NumPy's sort
    assert sorted(whole) == list(range(table.Q.shape[0])) and whole[:17] == list(table.ranked(target, 17))


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
    through evoik_pin.solve: the Results of the runs made one by one (FIRST_RUNS off), bit for bit."""
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

