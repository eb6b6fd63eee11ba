"""NSGA-II (paper 003): operators, ZDT1, and the vehicle-arm IK front."""

import numpy as np
import pinocchio as pin
import pytest

import evoik_pin
from evoik_pin import Target, lie
from evoik_pin.api import make_problem
from evoik_pin.errors import OptionError
from evoik_pin.solvers.paper.ga import basic_polynomial_mutation
from evoik_pin.solvers.paper.nsga2 import (
    bounded_polynomial_mutation,
    crowding_distance,
    dominance_matrix,
    nondominated_ranks,
    nsga2_minimize,
    survival,
)
from evoik_pin.solvers.paper.nsga2_minimizer import _duplicate_rows
from evoik_pin.solvers.paper.pareto_sorting import _tournament, _tournament_pairs
from evoik_pin.solvers.paper.task_repair import _task_errors


def zdt1(X):
    f1 = X[:, 0]
    g = 1.0 + 9.0 * X[:, 1:].mean(axis=1)
    return np.column_stack([f1, g * (1.0 - np.sqrt(f1 / g))])


def igd(F):
    """Inverted generational distance of F (M, 2) to 1000 points of ZDT1's true front f2 = 1 - sqrt(f1)."""
    x = np.linspace(0.0, 1.0, 1000)
    ref = np.column_stack([x, 1.0 - np.sqrt(x)])
    return float(np.linalg.norm(ref[:, None] - F[None], axis=2).min(axis=1).mean())


def _brute_force_ranks(F, cv):
    D = dominance_matrix(F, cv)
    rank, left, r = np.full(len(F), -1), set(range(len(F))), 0
    while left:
        front = [j for j in left if not any(D[i, j] for i in left)]
        for j in front:
            rank[j] = r
        left -= set(front)
        r += 1
    return rank


def test_constraint_domination_and_sorting(rng):
    F = np.array([[1.0, 1.0], [0.0, 0.0], [2.0, 0.5], [0.5, 2.0]])
    cv = np.array([0.0, 0.3, 0.0, 0.1])
    D = dominance_matrix(F, cv)
    assert D[0, 1] and D[2, 1] and D[0, 3]  # feasible beats infeasible, whatever the objectives
    assert D[3, 1] and not D[1, 3]  # among infeasible, less violation wins
    assert not D[0, 2] and not D[2, 0]  # feasible, mutually non-dominated
    for _ in range(5):
        F = rng.random((40, 3))
        cv = np.where(rng.random(40) < 0.3, rng.random(40), 0.0)
        assert np.array_equal(nondominated_ranks(F, cv), _brute_force_ranks(F, cv))
        F, cv = np.round(F, 1), np.where(rng.random(40) < 0.5, np.round(rng.random(40), 1), 0.0)  # ties
        assert np.array_equal(nondominated_ranks(F, cv), _brute_force_ranks(F, cv))


def test_survival_takes_whole_fronts_then_the_least_crowded(rng):
    for _ in range(20):
        F = np.round(rng.random((60, 2)), 2)
        cv = np.where(rng.random(60) < 0.4, np.round(rng.random(60), 1), 0.0)
        size = int(rng.integers(4, 60))
        keep, rank, cd = survival(F, cv, size)
        full = _brute_force_ranks(F, cv)
        last = np.sort(full)[size - 1]
        assert len(keep) == size and len(set(keep)) == size and np.array_equal(rank, full[keep])
        assert set(np.nonzero(full < last)[0]) <= set(keep) and np.all(full[keep] <= last)
        cut = np.nonzero(full == last)[0]
        cd_cut = crowding_distance(F[cut])
        kept = np.isin(cut, keep)
        if not kept.all():  # the front that overflows keeps its largest crowding distances
            assert cd_cut[kept].min() >= cd_cut[~kept].max()
        for r in range(last + 1):
            members = np.nonzero(full[keep] == r)[0]
            assert np.allclose(cd[members], crowding_distance(F[keep[members]]) if r < last else
                               cd_cut[np.searchsorted(cut, keep[members])])


def test_tournament_rules_and_pairs(rng):
    pairs = _tournament_pairs(10, 10, rng)
    assert np.array_equal(np.bincount(pairs.ravel(), minlength=10), np.full(10, 2))  # each enters twice
    assert np.all(pairs[:, 0] != pairs[:, 1])
    rank, cd = np.array([0, 1, 0, 0]), np.array([0.5, np.inf, 0.7, 0.5])
    assert _tournament(rank, cd, np.array([[0, 1], [1, 0]]), rng).tolist() == [0, 0]  # lower rank
    assert _tournament(rank, cd, np.array([[0, 2], [2, 0]]), rng).tolist() == [2, 2]  # then larger distance
    ties = _tournament(rank, cd, np.tile([0, 3], (200, 1)), rng)  # then a fair coin
    assert 60 < np.sum(ties == 3) < 140


def test_duplicate_offspring_are_bred_again():
    X = np.array([[0.0, 1.0], [0.5, 0.5]])
    Y = np.array([[0.5, 0.5], [0.2, 0.3], [0.2, 0.3], [-0.0, 1.0], [0.2, 0.31]])
    assert _duplicate_rows(X, Y).tolist() == [True, False, True, True, False]

    def run(eliminate):
        seen = []

        def f(X):
            seen.append(X.copy())
            return zdt1(X)

        res = nsga2_minimize(f, np.zeros(2), np.ones(2), 2, np.random.default_rng(3), population=20, generations=30,
                             eliminate_duplicates=eliminate)
        assert res.evaluations == 20 * 31  # duplicates are bred again, never skipped: N per generation
        Z = np.concatenate(seen)
        return len(Z) - len(np.unique(Z, axis=0))

    assert run(True) == 0
    assert run(False) > 10  # with 2 variables, parents copied unchanged are frequent


def test_bounded_polynomial_mutation_stays_inside_and_differs_from_the_basic_one():
    rng = np.random.default_rng(3)
    lo, hi = np.array([-1.0, 0.0, 2.0]), np.array([1.0, 4.0, 2.5])
    X = rng.uniform(lo, hi, size=(2000, 3))
    X[:500] = lo  # entries on a bound are never pushed across it
    X[500:1000] = hi
    Y = bounded_polynomial_mutation(X, lo, hi, 20.0, 1.0, np.random.default_rng(4))
    assert np.all((Y >= lo) & (Y <= hi))
    on_lower = Y[:500][(Y[:500] != X[:500])]
    assert on_lower.size and np.all(on_lower > np.broadcast_to(lo, (500, 3))[Y[:500] != X[:500]])
    assert np.array_equal(bounded_polynomial_mutation(X, lo, hi, 20.0, 0.0, np.random.default_rng(4)), X)
    # With the same draws, the basic operator of paper 001's GA gives other children: its spread ignores the
    # bounds (an entry on the lower bound with u < 0.5 moves below it; the bounded one stays put).
    r = np.random.default_rng(4)
    mask, u = r.random(X.shape) < 1.0, r.random(X.shape)
    basic = np.clip(basic_polynomial_mutation(X, lo, hi, 20.0, mask, u), lo, hi)
    assert not np.array_equal(basic, Y)
    assert np.array_equal(Y[:500][u[:500] < 0.5], X[:500][u[:500] < 0.5])


def test_task_errors_are_log3_and_wrapped_yaw(reachable_pose):
    problem, _ = make_problem("redundant7r", [0.4, 0.3, 0.7])
    robot = problem.robot
    goal = reachable_pose(robot, 3)
    Q = robot.random_configurations(50, np.random.default_rng(5))
    _, R = robot.fk_batch(Q)
    # targets at random angles and at (or within 1e-9 rad of) pi from the first configuration's orientation
    for R_goal in (goal.rotation, R[0] @ lie.exp3([[0.0, 0.0, np.pi]])[0], R[0] @ lie.exp3([[np.pi - 1e-9, 0, 0]])[0]):
        problem, _ = make_problem(robot, Target(position=goal.translation, rotation=R_goal))
        e = _task_errors(problem, Q)
        P, R = robot.fk_batch(Q)
        assert np.allclose(e[:, :3], goal.translation - P, rtol=0, atol=1e-15)
        w = np.array([pin.log3(R_goal @ Rk.T) for Rk in R])
        assert np.allclose(e[:, 3:], w, rtol=0, atol=1e-9)
    assert np.linalg.norm(e[0, 3:]) == pytest.approx(np.pi - 1e-9, abs=1e-12)
    planar, _ = make_problem("vehicle_arm", Target.planar_target(1.5, 0.5, 3.0))
    Q = planar.robot.random_configurations(50, np.random.default_rng(6))
    P, R = planar.robot.fk_batch(Q)
    e = _task_errors(planar, Q)
    assert np.allclose(e[:, :2], [1.5, 0.5] - P[:, :2], rtol=0, atol=1e-15)
    dyaw = 3.0 - np.array([pin.rpy.matrixToRpy(Rk)[2] for Rk in R])
    assert np.allclose(np.cos(e[:, 2]), np.cos(dyaw)) and np.allclose(np.sin(e[:, 2]), np.sin(dyaw))
    assert np.all((-np.pi <= e[:, 2]) & (e[:, 2] < np.pi))


def test_crowding_distance():
    F = np.array([[0.0, 1.0], [0.25, 0.5], [0.5, 0.4], [1.0, 0.0]])
    cd = crowding_distance(F)
    assert np.isinf(cd[0]) and np.isinf(cd[3])
    assert cd[1] == pytest.approx(0.5 + 0.6) and cd[2] == pytest.approx(0.75 + 0.5)


def test_zdt1_front_is_close_to_the_true_front():
    res = nsga2_minimize(zdt1, np.zeros(30), np.ones(30), 2, np.random.default_rng(0), population=100,
                         generations=250)
    F = res.F[res.front]
    assert len(F) == 100 and res.evaluations == 100 * 251
    assert igd(F) < 0.01  # measured 0.005; a random population scores about 3
    again = nsga2_minimize(zdt1, np.zeros(30), np.ones(30), 2, np.random.default_rng(0), population=100,
                           generations=250)
    assert np.array_equal(res.X, again.X)


def _dominates_any(F):
    return bool((np.all(F[:, None] <= F[None], axis=2) & np.any(F[:, None] < F[None], axis=2)).any())


def test_vehicle_arm_front_is_feasible_and_nondominated():
    target = Target.planar_target(1.5, 0.5, 0.0)
    res = evoik_pin.solve("vehicle_arm", target, method="nsga2", seed=0, population=100, max_generations=40,
                          gains=[10, 10, 1, 1, 1])
    front = res.front
    assert len(front) >= 2 and front.objectives.shape == (len(front), 2)
    assert np.all(front.violation == 0)
    robot = evoik_pin.load_robot("vehicle_arm")
    P, R = robot.fk_batch(front.q)
    assert np.abs(P[:, :2] - [1.5, 0.5]).max() <= 1e-6  # the problem's tolerance
    assert np.abs(lie.yaw(R)).max() <= 1e-6
    assert not _dominates_any(front.objectives)
    S = np.sqrt(((front.q ** 2) * [10, 10, 1, 1, 1]).sum(axis=1))  # q_prev = zeros
    assert np.allclose(front.objectives[:, 1], S)
    assert res.front.objectives[:, 1].min() == pytest.approx(np.sqrt((res.q ** 2 * [10, 10, 1, 1, 1]).sum()))
    assert res.success


def test_larger_vehicle_gain_moves_the_base_less():
    """Paper 003, Fig. 2: along a trajectory, K = 100 on (q0, q1) moves the vehicle less than K = 1."""
    # An arc the arm can follow from a parked vehicle (paper: end-effector positions pointing along +x).
    targets = [Target.planar_target(0.6 + 0.25 * np.cos(a), 0.25 * np.sin(a), 0.0) for a in np.linspace(0, np.pi, 5)]

    def base_travel(k):
        results = evoik_pin.solve_trajectory("vehicle_arm", targets, method="nsga2", seed=1, population=60,
                                             max_generations=25, gains=[k, k, 1, 1, 1])
        assert all(r.success for r in results)
        Q = np.array([r.q for r in results])
        return np.linalg.norm(np.diff(Q[:, :2], axis=0), axis=1).sum()

    assert base_travel(100.0) < 0.5 * base_travel(1.0)  # measured 0.08 m against 0.66 m


def test_plain_nsga2_without_repair_and_options():
    target = Target.planar_target(1.5, 0.5, 0.0)
    res = evoik_pin.solve("vehicle_arm", target, method="nsga2", seed=0, population=40, max_generations=10,
                          repair_steps=0, tolerance=1e-2, rotation_tolerance=1e-2)
    assert len(res.history["min_violation"]) == 11
    assert np.all(np.diff(res.history["min_violation"]) <= 1e-15)  # elitism: never worse
    again = evoik_pin.solve("vehicle_arm", target, method="nsga2", seed=0, population=40, max_generations=10,
                            repair_steps=0, tolerance=1e-2, rotation_tolerance=1e-2)
    assert np.array_equal(res.front.q, again.front.q) and np.array_equal(res.q, again.q)
    with pytest.raises(OptionError, match="gains"):
        evoik_pin.solve("vehicle_arm", target, method="nsga2", gains=[1, 2])
    with pytest.raises(OptionError, match="pick"):
        evoik_pin.solve("vehicle_arm", target, method="nsga2", pick=5)


def test_a_planar_chain_given_a_3d_target_uses_the_rows_it_can_move():
    ek = evoik_pin
    # vehicle_arm moves in the base plane: with a 3-D position target [x, y, 0] the translational Jacobian's z
    # row is zero everywhere, det(J J^T) = 0 and 1 / (Y + 1) = 1 for every member; the default rows drop vz
    robot = ek.load_robot("vehicle_arm")
    res = ek.solve(robot, [1.2, 0.4, 0.0], method="nsga2", seed=0, population=40, max_generations=15,
                   tolerance=1e-4)
    g = res.front.objectives[:, 0]
    assert (g < 0.99).all() and np.ptp(g) > 0  # a real manipulability, not the constant 1 of det = 0
    assert len(np.unique(res.front.q.round(9), axis=0)) > 1  # the front did not collapse to one point
    assert "never moves its tip along vz" in res.message
    # a 3-D arm keeps all three translational rows, and says nothing
    arm = ek.load_robot("puma3r")
    assert "never moves" not in ek.solve(arm, [0.3, 0.2, 0.4], method="nsga2", seed=0, population=20,
                                         max_generations=3, tolerance=1e-3).message
