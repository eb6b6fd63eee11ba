"""solve_many's batch engine (solvers/batch/: api.py over threads.py): workers, chunking, per-target generators,
compact outcomes.

Every comparison uses a deterministic budget (``timeout=None``, ``max_restarts``), so the answers do not depend on
the machine's load; speed is measured in scripts/bench_scale.py, never here.
"""

import dataclasses
import sys

import numpy as np
import pinocchio as pin
import pytest

import evoik_pin as ev
from evoik_pin.errors import BackendError, OptionError
from evoik_pin.problem import Target
from evoik_pin.result import Result
from evoik_pin.scene import Scene
from evoik_pin.scene.examples import SHELF_INTERIOR, add_table_and_shelf, free_configurations
from evoik_pin.solvers.batch import threads
from evoik_pin.solvers.batch.batch_results import BatchOutcome
from evoik_pin.solvers.search.seed_table import DEFAULT_TABLE_SEEDS

BUDGET = {"timeout": None, "max_restarts": 2}


@pytest.fixture(scope="module")
def panda():
    return ev.load_robot("panda")


def mixed(robot, count: int, seed: int, every: int, far: dict[int, list[float]]) -> list:
    """Poses of random configurations, every ``every``-th one a position only, and the poses ``far`` {index:
    position} out of reach (the fallback, which draws random numbers, gets them)."""
    Q = robot.random_configurations(count, np.random.default_rng(seed))
    targets = [robot.fk(q) if i % every else robot.fk(q).translation for i, q in enumerate(Q)]
    for i, p in far.items():
        targets[i] = pin.SE3(np.eye(3), np.array(p))
    return targets


def same(a, b):
    """Two lists of results agree exactly: joint vectors bit for bit, verdicts, errors and messages."""
    assert len(a) == len(b)
    for x, y in zip(a, b, strict=True):
        assert np.array_equal(x.q, y.q) and x.success == y.success and x.message == y.message
        assert x.position_error == y.position_error and x.orientation_error == y.orientation_error


@pytest.fixture(scope="module")
def mixed_targets(panda):
    return mixed(panda, 120, 7, every=3, far={10: [2.0, 0.0, 0.5], 77: [0.0, -1.5, 0.2]})


@pytest.fixture
def small_chunks(monkeypatch):
    """Chunks of 8 targets, so that 120 targets make many chunks (and threads really share the work)."""
    monkeypatch.setattr(threads, "MIN_CHUNK", 8)


def test_same_answers_whatever_the_number_of_workers(panda, mixed_targets, small_chunks):
    runs = {w: ev.solve_many(panda, mixed_targets, seed=4, workers=w, **BUDGET) for w in (1, 2, 3)}
    assert threads.chunk_bounds(120, 3) != threads.chunk_bounds(120, 1)  # the chunking differs ...
    same(runs[1], runs[2])  # ... the answers do not
    same(runs[1], runs[3])
    res = runs[3]
    assert res.stats["workers"] == 3 and res.stats["backend"] == "local"
    assert res.stats["fallback"] >= 2 and not res[10].success and not res[77].success
    assert res.stats["solved"] == 118 and res.stats["batched"] + res.stats["fallback"] == 120
    for i, (r, t) in enumerate(zip(res, mixed_targets, strict=True)):  # in target order
        if i not in (10, 77):
            T = panda.fk(r.q)
            goal = t.translation if isinstance(t, pin.SE3) else t
            assert np.linalg.norm(T.translation - goal) <= 1e-6 and panda.within_bounds(r.q)
            assert (r.orientation_error is None) == (i % 3 == 0)


def test_a_fallback_target_draws_from_its_own_spawned_generator(panda, mixed_targets):
    # the contract the docstring states: target i draws from SeedSequence(seed).spawn(N)[i], after the batched
    # rounds tried the table_seeds nearest entries
    res = ev.solve_many(panda, mixed_targets, seed=4, workers=2, **BUDGET)
    gens = [np.random.default_rng(s) for s in np.random.SeedSequence(4).spawn(len(mixed_targets))]
    alone = ev.solve(panda, mixed_targets[77], seed=gens[77], table_offset=DEFAULT_TABLE_SEEDS, **BUDGET)
    assert "restart" in res[77].message and np.array_equal(res[77].q, alone.q) and res[77].message == alone.message
    assert np.array_equal(threads.target_generator(4, 77).random(3), np.random.default_rng(
        np.random.SeedSequence(4).spawn(100)[77]).random(3))


def test_other_methods_go_one_by_one_with_per_target_generators(panda, mixed_targets):
    some = mixed_targets[:3]
    res = ev.solve_many(panda, some, method="de", seed=9, max_generations=3, workers=2)
    gens = [np.random.default_rng(s) for s in np.random.SeedSequence(9).spawn(3)]
    for r, t, g in zip(res, some, gens, strict=True):
        assert r.method == "de" and np.array_equal(r.q, ev.solve(panda, t, method="de", seed=g, max_generations=3).q)
    assert res.stats["fallback"] == 3 and res.stats["batched"] == 0


def test_a_generator_seed_gives_one_draw_of_entropy(panda, mixed_targets):
    a = ev.solve_many(panda, mixed_targets[70:80], seed=np.random.default_rng(3), **BUDGET)
    b = ev.solve_many(panda, mixed_targets[70:80], seed=np.random.default_rng(3), **BUDGET)
    same(a, b)


def test_batched_results_are_whole_results(panda, mixed_targets):
    res = ev.solve_many(panda, mixed_targets[:6], seed=0, workers=1, **BUDGET)
    r = res[1]
    assert "batched LM from seed table" in r.message and r.method == "memetic" and r.success
    made = Result(q=r.q, position_error=0.0, orientation_error=None, cost=0.0, success=True, generations=0,
                  evaluations=0, time_s=0.0)
    assert set(vars(r)) == set(vars(made))  # every field of the dataclass, as its constructor sets them
    assert r.q.shape == (7,) and r.collision_free is None and r.min_distance is None and r.setup_s == 0.0
    assert r.cost == pytest.approx(r.position_error + r.orientation_error)
    assert {k: v.tolist() for k, v in r.history.items()} == {"best_cost": [r.cost], "mean_cost": [r.cost],
                                                              "diversity": [0.0]}
    assert dataclasses.replace(r, success=False).success is False
    assert res[0].orientation_error is None and res[0].cost == res[0].position_error  # a position target


def test_q0_goes_first_in_every_chunk(panda, small_chunks):
    Q = panda.random_configurations(40, np.random.default_rng(8))
    H = np.array([panda.fk(q).homogeneous for q in Q])
    one = ev.solve_many(panda, H, q0=Q + 1e-3, seed=0, workers=1, **BUDGET)
    two = ev.solve_many(panda, H, q0=Q + 1e-3, seed=0, workers=2, **BUDGET)
    same(one, two)
    assert all("from q0" in r.message for r in two)
    assert np.abs(np.array([r.q for r in two]) - Q).max() < 1e-2  # the solutions next to q0


def test_a_scene_with_several_workers(panda, small_chunks):
    scene = add_table_and_shelf(Scene(panda))
    Q = free_configurations(scene, 24, np.random.default_rng(2), SHELF_INTERIOR)
    H = np.array([panda.fk(q).homogeneous for q in Q])
    one = ev.solve_many(panda, H, scene=scene, seed=0, workers=1, **BUDGET)
    two = ev.solve_many(panda, H, scene=scene, seed=0, workers=2, **BUDGET)
    same(one, two)
    for r in two:
        assert r.success and r.collision_free and not scene.in_collision(r.q) and r.min_distance >= 0.0


def test_progress_bar(panda, mixed_targets, capsys):
    ev.solve_many(panda, mixed_targets[:20], seed=0, progress=True, **BUDGET)
    assert "solve_many" in capsys.readouterr().err


def test_default_workers_follow_the_affinity(monkeypatch):
    monkeypatch.setattr(threads.os, "sched_getaffinity", lambda pid: {0, 3, 5}, raising=False)
    assert threads.default_workers() == 3 and threads.check_workers(None) == 3


def test_chunks_cover_every_target_once():
    for n, w in [(1, 4), (255, 2), (1000, 1), (5000, 2), (100_000, 16)]:
        bounds = threads.chunk_bounds(n, w)
        assert bounds[0][0] == 0 and bounds[-1][1] == n
        assert all(a < b and b == c for (a, b), (c, _) in zip(bounds, bounds[1:] + [(n, None)], strict=True))
        sizes = [b - a for a, b in bounds]
        if w == 1 or n <= threads.MIN_CHUNK:
            assert len(bounds) == 1
        else:  # guided: shrinking chunks, each at least MIN_CHUNK but the last, at most a 1 / (2 w) share of the rest
            assert all(x >= y for x, y in zip(sizes[:-1], sizes[1:], strict=True))
            assert min(sizes[:-1]) >= threads.MIN_CHUNK
            assert all(b - a <= max(threads.MIN_CHUNK, -(-(n - a) // (threads.GUIDED_SHARE * w))) for a, b in bounds)
            assert len(bounds) > 2 * w
    ray = threads.chunk_bounds(100_000, 4, minimum=1000, maximum=20_000)  # the Ray backend's guided chunks
    assert ray[0] == (0, 12_500) and all(1000 <= b - a <= 20_000 for a, b in ray[:-1]) and ray[-1][1] == 100_000


@pytest.mark.parametrize("kwargs, match", [
    ({"workers": 0}, "workers"), ({"workers": 1.5}, "workers"), ({"workers": True}, "workers"),
    ({"backend": "gpu"}, "backend"), ({"address": "127.0.0.1:6379"}, "address"), ({"seed": -1}, "seed"),
])
def test_bad_input(panda, kwargs, match):
    with pytest.raises(OptionError, match=match):
        ev.solve_many(panda, [np.array([0.3, 0.0, 0.5])], **kwargs)


def test_ray_missing_names_the_extra(panda, monkeypatch):
    monkeypatch.setitem(sys.modules, "ray", None)  # import ray -> ImportError
    with pytest.raises(BackendError, match=r"pip install 'evoik_pin\[ray\]'"):
        ev.solve_many(panda, [np.array([0.3, 0.0, 0.5])], backend="ray")


def test_outcomes_concatenate_in_order(panda, mixed_targets):
    solver = threads.BatchSolver(panda, ev.api.make_problem, ev.api._run, "memetic", 5, dict(BUDGET))
    targets = Target.coerce_many(mixed_targets[:20])
    whole = solver.solve(targets)
    parts = BatchOutcome.concatenate([solver.solve(targets[:7]), solver.solve(targets[7:11], offset=7),
                                            solver.solve(targets[11:], offset=11)])
    same(whole.results(), parts.results())
    assert sorted(parts.singles) == sorted(whole.singles) == [10]


def test_results_are_a_lazy_sequence_with_the_same_answers_as_arrays(panda, mixed_targets):
    """solve_many returns a sequence of Result made on first access, and the same answers as read-only arrays."""
    res = ev.solve_many(panda, mixed_targets, seed=3, workers=1, **BUDGET)
    N = len(mixed_targets)
    assert len(res) == N and res.q.shape == (N, panda.n)
    assert res[3] is res[3] and res[-1] is res[N - 1]  # made once, then kept
    listed = list(res)
    assert [r.q.tolist() for r in res[5:9]] == [r.q.tolist() for r in listed[5:9]]
    with pytest.raises(IndexError):
        res[N]
    for i, r in enumerate(listed):
        assert isinstance(r, Result) and np.array_equal(res.q[i], r.q)
        assert res.success[i] == r.success and res.position_error[i] == r.position_error
        assert res.cost[i] == r.cost and res.evaluations[i] == r.evaluations
        if r.orientation_error is None:  # the position-only targets
            assert np.isnan(res.orientation_error[i])
        else:
            assert res.orientation_error[i] == r.orientation_error
    assert res.stats["solved"] == int(res.success.sum()) == sum(r.success for r in listed)
    with pytest.raises(ValueError):
        res.q[0, 0] = 1.0  # the arrays are views of the answers: read-only
    # an (N, 4, 4) array of poses (no Target objects made) gives the answers of the same poses as Target objects
    H = np.array([panda.fk(q).homogeneous for q in panda.random_configurations(40, np.random.default_rng(4))])
    from_array = ev.solve_many(panda, H, seed=3, workers=1, **BUDGET)
    from_objects = ev.solve_many(panda, [pin.SE3(T) for T in H], seed=3, workers=1, **BUDGET)
    same(from_array, from_objects)
    assert from_array.success.all()


def test_table_seeds_none_is_memetics_default():
    """table_seeds=None means memetic's own default (17 for a target), in solve_many as in solve."""
    robot = ev.load_robot("panda")
    rng = np.random.default_rng(3)
    poses = np.array([robot.fk(q).homogeneous for q in robot.random_configurations(20, rng)])
    a = ev.solve_many(robot, poses, seed=1, workers=1, table_seeds=None, timeout=None, max_restarts=2)
    b = ev.solve_many(robot, poses, seed=1, workers=1, timeout=None, max_restarts=2)
    assert np.array_equal(a.q, b.q) and np.array_equal(a.success, b.success)
