"""DE operators against their formulas on fixed draws, and the ``de`` solver on the papers' arms."""

import numpy as np
import pytest

import evoik_pin as ek
from evoik_pin.errors import OptionError
from evoik_pin.solvers.paper.de import parse_strategy
from evoik_pin.solvers.paper.de_ops import (
    MUTATIONS,
    SCHEME_NUMBERS,
    binomial_crossover,
    distinct_indices,
    either_or,
    exponential_crossover,
    exponential_lengths,
    mutate,
    permutation_indices,
    trigonometric,
)

N, D = 8, 4


@pytest.fixture
def pop():
    return np.arange(N * D, dtype=float).reshape(N, D) ** 1.3 / 10.0


@pytest.fixture
def idx():
    # five distinct indices per row, none equal to the row
    return np.array([[(i + k) % N for k in (1, 3, 4, 6, 7)] for i in range(N)])


def _eq12(X, i, r, best, F, scheme):
    """Paper 002, eq. 12, written out for individual i."""
    x, b = X[i], X[best]
    r1, r2, r3, r4, r5 = (X[j] for j in r)
    return {
        "rand1": r1 + F * (r2 - r3),
        "best1": b + F * (r1 - r2),
        "rand2": r1 + F * (r2 - r3) + F * (r4 - r5),
        "best2": b + F * (r1 - r2) + F * (r3 - r4),
        "currenttobest1": x + F * (r1 - r2) + F * (b - x),
        "currenttobest2": x + F * (r1 - r2) + F * (r3 - r4) + F * (b - x),
        "randtobest1": r1 + F * (r2 - r3) + F * (b - r1),
        "currenttorand1": x + F * (r2 - r3) + F * (r1 - x),
    }[scheme]


@pytest.mark.parametrize("scheme", list(MUTATIONS))
def test_each_mutation_scheme_matches_eq12(pop, idx, scheme):
    best = 5
    F = np.linspace(0.2, 0.9, N)  # per-individual F exercises the broadcasting too
    V = mutate(pop, scheme, F, idx, best)
    for i in range(N):
        assert np.allclose(V[i], _eq12(pop, i, idx[i], best, F[i], scheme), rtol=0, atol=1e-12)
    V_scalar = mutate(pop, scheme, 0.5, idx, best)
    for i in range(N):
        assert np.allclose(V_scalar[i], _eq12(pop, i, idx[i], best, 0.5, scheme), rtol=0, atol=1e-12)


def test_scheme_numbers_follow_the_paper():
    assert SCHEME_NUMBERS[1] == "rand1" and SCHEME_NUMBERS[2] == "best1" and SCHEME_NUMBERS[8] == "currenttorand1"
    assert len(SCHEME_NUMBERS) == 8


def test_mutate_rejects_short_index_matrix(pop, idx):
    with pytest.raises(OptionError, match="index matrix"):
        mutate(pop, "rand2", 0.5, idx[:, :3], 0)
    with pytest.raises(OptionError, match="unknown mutation"):
        mutate(pop, "best3", 0.5, idx, 0)


def test_either_or_of_paper_004(pop, idx):
    use_rand1 = np.arange(N) % 2 == 0
    V = either_or(pop, 0.6, 0.8, idx, use_rand1)
    for i in range(N):
        r1, r2, r3 = pop[idx[i, 0]], pop[idx[i, 1]], pop[idx[i, 2]]
        expected = r1 + 0.6 * (r2 - r3) if use_rand1[i] else r1 + 0.8 * (r2 - r1 + r3 - r1)
        assert np.allclose(V[i], expected, atol=1e-12)


def test_trigonometric_mutation_of_fan_and_lampinen(pop, idx):
    costs = np.linspace(1.0, 3.0, N)
    V = trigonometric(pop, costs, idx)
    for i in range(N):
        x1, x2, x3 = pop[idx[i, 0]], pop[idx[i, 1]], pop[idx[i, 2]]
        f = np.abs(costs[idx[i, :3]])
        p1, p2, p3 = f / f.sum()
        expected = ((x1 + x2 + x3) / 3 + (p2 - p1) * (x1 - x2) + (p3 - p2) * (x2 - x3) + (p1 - p3) * (x3 - x1))
        assert np.allclose(V[i], expected, atol=1e-12)
    centre = trigonometric(pop, np.zeros(N), idx)  # all costs zero: the triangle's centre
    assert np.allclose(centre, (pop[idx[:, 0]] + pop[idx[:, 1]] + pop[idx[:, 2]]) / 3)


def test_binomial_crossover(pop):
    V = -pop - 1.0
    u = np.tile(np.linspace(0.05, 0.95, D), (N, 1))
    jrand = np.arange(N) % D
    CR = np.full(N, 0.5)
    CR[0] = 0.0  # only the forced coordinate comes from the donor
    U = binomial_crossover(pop, V, CR, u, jrand)
    for i in range(N):
        for j in range(D):
            from_donor = u[i, j] <= CR[i] or j == jrand[i]
            assert U[i, j] == (V[i, j] if from_donor else pop[i, j])
    assert (U[0] != pop[0]).sum() == 1


def test_exponential_crossover_and_lengths(pop):
    V = -pop - 1.0
    start = np.array([0, 1, 3, 2, 0, 3, 1, 2])
    length = np.array([1, 2, 2, 4, 3, 1, 4, 2])
    U = exponential_crossover(pop, V, start, length)
    for i in range(N):
        donor_cols = {(start[i] + m) % D for m in range(length[i])}
        for j in range(D):
            assert U[i, j] == (V[i, j] if j in donor_cols else pop[i, j])
    # L = 1, then L += 1 while u < CR (and L < D)
    u = np.array([[0.1, 0.2, 0.9, 0.1], [0.95, 0.1, 0.1, 0.1], [0.1, 0.1, 0.1, 0.99], [0.5, 0.5, 0.5, 0.5]])
    assert exponential_lengths(0.8, u).tolist() == [3, 1, 4, 4]
    assert exponential_lengths(0.4, u).tolist() == [3, 1, 4, 1]


def test_distinct_indices():
    rng = np.random.default_rng(0)
    idx = distinct_indices(rng, 10, 5)
    assert idx.shape == (10, 5)
    for i, row in enumerate(idx):
        assert len(set(row.tolist())) == 5 and i not in row
    assert np.array_equal(distinct_indices(np.random.default_rng(1), 10, 5),
                          distinct_indices(np.random.default_rng(1), 10, 5))
    with pytest.raises(OptionError, match="at least 6"):
        distinct_indices(rng, 5, 5)


def test_permutation_indices():
    rng = np.random.default_rng(3)
    N, k = 12, 4
    counts = np.zeros((N, N))
    for _ in range(3000):
        idx = permutation_indices(rng.random(N), rng.random(N - 1), k)
        assert idx.shape == (N, k)
        for i, row in enumerate(idx):
            assert len(set(row.tolist())) == k and i not in row
        for m in range(k):  # each column is a permutation: every individual serves once as r_m
            assert sorted(idx[:, m].tolist()) == list(range(N))
        counts[np.arange(N), idx[:, 0]] += 1
    # r_1 of every individual is spread evenly over the N - 1 others (expected 3000 / 11 = 273 each)
    off_diagonal = counts[~np.eye(N, dtype=bool)]
    assert np.all(np.diag(counts) == 0) and off_diagonal.min() > 200 and off_diagonal.max() < 350


@pytest.mark.parametrize("name, expected", [
    ("best1bin", ("best1", "bin")), ("rand1exp", ("rand1", "exp")),
    ("currenttobest1bin", ("currenttobest1", "bin")), ("randtobest1bin", ("randtobest1", "bin")),
    ("best2bin", ("best2", "bin")), ("rand2bin", ("rand2", "bin")), ("currenttorand1exp", ("currenttorand1", "exp")),
    ("eitherorbin", ("eitheror", "bin")), ("trigbin", ("trig", "bin")), ("DE/best/1/bin", ("best1", "bin")),
])
def test_scipy_style_strategy_names(name, expected):
    assert parse_strategy(name) == expected


def test_unknown_strategy_lists_accepted():
    with pytest.raises(OptionError, match="best1bin"):
        parse_strategy("best3bin")


# ---------------------------------------------------------------------------- the solver


@pytest.mark.parametrize("name", ["planar2r", "ax18", "redundant7r"])
def test_de_reaches_position_targets(name, reachable_pose):
    robot = ek.load_robot(name)
    target = reachable_pose(robot, 21).translation
    res = ek.solve(robot, target, method="de", seed=3, tolerance=1e-8)
    assert res.success, res
    assert res.position_error <= 1e-8
    assert np.linalg.norm(robot.fk(res.q).translation - target) <= 1e-8
    assert robot.within_bounds(res.q)
    assert res.method == "de" and res.evaluations > 0 and len(res.history["best_cost"]) == res.generations + 1


def test_de_reaches_a_pose_target_on_aerial6r(reachable_pose):
    robot = ek.load_robot("aerial6r")
    target = reachable_pose(robot, 8)
    # paper 004's DE for this arm: DE/rand/1/bin, F = 0.9, CR = 0.95 (exploratory; DE/best/1 stalls in local
    # minima of 6-D pose targets); 20 of 20 other targets in single runs (docs/BENCHMARKS.md)
    res = ek.solve(robot, target, method="de", seed=1, tolerance=1e-6, population=40, strategy="rand1bin", F=0.9,
                   CR=0.95, max_generations=1000)
    assert res.success, res
    assert res.position_error <= 1e-6 and res.orientation_error <= 1e-6


@pytest.mark.parametrize("strategy", ["rand1bin", "currenttobest1exp", "randtobest1bin", "best2bin",
                                      "rand2exp", "eitherorbin", "trigbin", "currenttobest2bin", "currenttorand1bin"])
def test_every_strategy_makes_progress(strategy, reachable_pose):
    robot = ek.load_robot("ax18")
    target = reachable_pose(robot, 5).translation
    res = ek.solve(robot, target, method="de", seed=0, strategy=strategy, tolerance=1e-4, max_generations=300)
    assert res.history["best_cost"][-1] < 0.1 * res.history["best_cost"][0], res


@pytest.mark.parametrize("bound_handling", ["clip", "reflect", "resample"])
def test_every_generation_stays_in_bounds(bound_handling):
    robot = ek.load_robot("redundant7r")
    lower, upper = robot.lower / 3, robot.upper / 3  # a box the unconstrained search would leave
    seen = []

    def check(generation, Q):
        seen.append(generation)
        assert Q.shape == (20, robot.n)
        assert np.all(Q >= lower) and np.all(Q <= upper), generation

    ek.solve(robot, [0.9, 0.2, 0.3], method="de", seed=2, population=20, bounds=(lower, upper),
             bound_handling=bound_handling, max_generations=40, F=1.5, callback=check, runs=1)
    assert seen == list(range(41))


def test_same_seed_same_result(reachable_pose):
    robot = ek.load_robot("redundant7r")
    target = reachable_pose(robot, 30).translation
    a = ek.solve(robot, target, method="de", seed=42, tolerance=1e-9, q0=np.zeros(robot.n))
    b = ek.solve(robot, target, method="de", seed=42, tolerance=1e-9, q0=np.zeros(robot.n))
    c = ek.solve(robot, target, method="de", seed=43, tolerance=1e-9, q0=np.zeros(robot.n))
    assert np.array_equal(a.q, b.q) and a.generations == b.generations and a.evaluations == b.evaluations
    assert np.array_equal(a.history["best_cost"], b.history["best_cost"])
    assert not np.array_equal(a.q, c.q)


def test_stopping_rules_and_callback_stop():
    robot = ek.load_robot("planar2r")
    res = ek.solve(robot, [5.0, 0.0, 0.0], method="de", seed=0, max_generations=15, runs=1)
    assert not res.success and res.generations == 15 and "max_generations" in res.message
    stalled = ek.solve(robot, [5.0, 0.0, 0.0], method="de", seed=0, stall_generations=5, max_generations=500, runs=1)
    assert "no improvement for 5" in stalled.message and stalled.generations < 500
    by_cost = ek.solve(robot, [0.2, 0.2, 0.0], method="de", seed=0, tolerance=0.0, cost_tolerance=1e-3, runs=1)
    assert "cost_tolerance" in by_cost.message and by_cost.cost <= 1e-3
    stopped = ek.solve(robot, [0.2, 0.2, 0.0], method="de", seed=0, tolerance=0.0, callback=lambda g, Q: g >= 3)
    assert stopped.generations == 3 and "callback" in stopped.message  # a callback stop ends the restarts too


def test_restarts_of_paper_002():
    robot = ek.load_robot("planar2r")
    res = ek.solve(robot, [5.0, 0.0, 0.0], method="de", seed=0, population=12, max_generations=10, runs=3)
    assert not res.success and res.generations == 30 and res.evaluations == 3 * 12 * 11
    assert len(res.history["best_cost"]) == 33 and res.history["run"].tolist() == [0.0] * 11 + [1.0] * 11 + [2.0] * 11
    assert "of 3)" in res.message
    # the best of the three short runs: the arm nearly stretched towards the target (reach 0.41 m)
    assert res.position_error == pytest.approx(5.0 - 0.41, abs=1e-3)
    assert res.position_error == pytest.approx(min(res.history["best_cost"]), rel=1e-12)
    once = ek.solve(robot, [0.2, 0.2, 0.0], method="de", seed=0, runs=3)
    assert once.success and "run" not in once.history


@pytest.mark.parametrize("options, match", [
    (dict(population=2), "population"),
    (dict(population=-5), "population"),
    (dict(mutation="rand2", population=5), "population"),
    (dict(F=-0.5), "F"),
    (dict(F=3.0), "F"),
    (dict(CR=1.5), "CR"),
    (dict(p_F=-0.1), "p_F"),
    (dict(mutation=9), "1-8"),
    (dict(mutation="best9"), "unknown mutation"),
    (dict(crossover="uniform"), "crossover"),
    (dict(strategy="best1uniform"), "unknown DE strategy"),
    (dict(bound_handling="wrap"), "bound_handling"),
    (dict(callback=3), "callback"),
    (dict(max_generations=-1), "max_generations"),
    (dict(stall_generations=0), "stall_generations"),
    (dict(runs=0), "runs"),
])
def test_bad_options_are_clear_errors(options, match):
    with pytest.raises(OptionError, match=match):
        ek.solve("planar2r", [0.2, 0.2, 0.0], method="de", seed=0, **options)


def test_mutation_by_paper_number_equals_by_name():
    a = ek.solve("ax18", [0.1, 0.1, 0.1], method="de", seed=4, mutation=7, max_generations=20, tolerance=0.0)
    b = ek.solve("ax18", [0.1, 0.1, 0.1], method="de", seed=4, mutation="randtobest1", max_generations=20,
                 tolerance=0.0)
    assert np.array_equal(a.q, b.q)
