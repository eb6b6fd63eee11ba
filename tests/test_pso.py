"""PSO of paper 002 (eq. 11): the update on fixed draws, the inertia schedule, and the ``pso`` solver."""

import numpy as np
import pinocchio as pin
import pytest

import evoik_pin as ek
from evoik_pin.errors import OptionError
from evoik_pin.solvers.paper.pso import inertia_weight, pso_step, ring_best


def test_inertia_weight_is_linear():
    assert inertia_weight(0, 100, 0.9, 0.4) == pytest.approx(0.9)
    assert inertia_weight(50, 100, 0.9, 0.4) == pytest.approx(0.65)
    assert inertia_weight(100, 100, 0.9, 0.4) == pytest.approx(0.4)


def test_pso_step_follows_eq11_with_clamping():
    rng = np.random.default_rng(0)
    X, V, P = rng.normal(size=(3, 6, 4))
    g = rng.normal(size=4)
    r1, r2 = rng.random((2, 6, 4))
    v_max = np.full(4, 0.5)
    X_new, V_new = pso_step(X, V, P, g, 0.7, 1.5, 1.5, r1, r2, v_max)
    for i in range(6):
        for d in range(4):
            v = 0.7 * V[i, d] + 1.5 * r1[i, d] * (P[i, d] - X[i, d]) + 1.5 * r2[i, d] * (g[d] - X[i, d])
            v = min(max(v, -0.5), 0.5)
            assert V_new[i, d] == pytest.approx(v) and X_new[i, d] == pytest.approx(X[i, d] + v)
    assert np.all(np.abs(V_new) <= 0.5)


def test_ring_neighbourhood_best():
    p_cost = np.array([3.0, 1.0, 4.0, 0.5, 2.0])
    assert ring_best(p_cost).tolist() == [1, 1, 3, 3, 3]


@pytest.mark.parametrize("name", ["planar2r", "ax18", "redundant7r"])
def test_pso_reaches_position_targets(name, reachable_pose):
    robot = ek.load_robot(name)
    target = reachable_pose(robot, 23).translation
    res = ek.solve(robot, target, method="pso", seed=6, tolerance=1e-8)
    assert res.success, res
    assert np.linalg.norm(robot.fk(res.q).translation - target) <= 1e-8
    assert len(res.history["w"]) == len(res.history["best_cost"])


@pytest.mark.parametrize("target_seed", [10, 11, 12])
def test_pso_reaches_pose_targets_of_aerial6r(target_seed, reachable_pose):
    # The default pose cost (m + weight x rad) is a sum of two norms; a swarm collapses onto the crease where one
    # of them is exactly zero, mm to cm from the target (0/40 targets, docs/BENCHMARKS.md). With the Euclidean
    # norm of the 6-D error and one r1, r2 per particle (steps stay in the plane of the particle's two
    # attractors and can follow a valley that is not aligned with the joint axes) PSO reached 40/40.
    robot = ek.load_robot("aerial6r")
    target = reachable_pose(robot, target_seed)
    res = ek.solve(robot, target, method="pso", seed=target_seed + 100, tolerance=1e-6, pose_metric="euclidean",
                   random_factors="per-particle", population=40)
    assert res.success, res.message
    assert res.generations > 20  # found by the swarm, not drawn in the initial population
    T = robot.fk(res.q)
    assert np.linalg.norm(T.translation - target.translation) <= 1e-6
    assert np.linalg.norm(pin.log3(target.rotation.T @ T.rotation)) <= 1e-6
    assert robot.within_bounds(res.q)
    assert res.cost == pytest.approx(np.hypot(res.position_error, res.orientation_error), abs=1e-15)


def test_pso_failing_on_a_summed_pose_cost_says_what_to_change(reachable_pose):
    robot = ek.load_robot("aerial6r")
    res = ek.solve(robot, reachable_pose(robot, 10), method="pso", seed=2, tolerance=1e-6, runs=1,
                   max_generations=60)
    h = res.history
    assert h["best_cost"][-1] < h["best_cost"][0] and np.all(np.diff(h["best_cost"]) <= 0)
    assert not res.success and robot.within_bounds(res.q)
    assert "exceeds the tolerance" in res.message
    assert "pose_metric='euclidean'" in res.message and "random_factors='per-particle'" in res.message


def test_per_particle_random_factors_keep_the_step_in_the_plane_of_the_attractors():
    rng = np.random.default_rng(1)
    X, V, P = rng.normal(size=(3, 5, 6))
    g = rng.normal(size=6)
    r1, r2 = rng.random((2, 5, 1))
    X_new, V_new = pso_step(X, V, P, g, 0.0, 1.5, 1.5, r1, r2, np.full(6, 100.0))
    for i in range(5):  # with w = 0 the velocity is r1 c1 (p - x) + r2 c2 (g - x): rank 2 with those two
        basis = np.stack([P[i] - X[i], g - X[i]], axis=1)
        coef, *_ = np.linalg.lstsq(basis, V_new[i], rcond=None)
        assert np.allclose(coef, [1.5 * r1[i, 0], 1.5 * r2[i, 0]])
    robot = ek.load_robot("ax18")
    a = ek.solve(robot, [0.1, 0.1, 0.1], method="pso", seed=5, random_factors="per-particle", max_generations=30)
    b = ek.solve(robot, [0.1, 0.1, 0.1], method="pso", seed=5, max_generations=30)
    assert not np.array_equal(a.history["best_cost"], b.history["best_cost"])  # the option reaches the solver


def test_reinit_stagnant_restarts_particles_and_keeps_the_best(reachable_pose):
    robot = ek.load_robot("ax18")
    target = reachable_pose(robot, 12).translation
    res = ek.solve(robot, target, method="pso", seed=4, tolerance=1e-8, reinit_stagnant=3, runs=1,
                   max_generations=200)
    again = ek.solve(robot, target, method="pso", seed=4, tolerance=1e-8, reinit_stagnant=3, runs=1,
                     max_generations=200)
    assert np.array_equal(res.q, again.q) and robot.within_bounds(res.q)
    assert np.all(np.diff(res.history["best_cost"]) <= 0)
    plain = ek.solve(robot, target, method="pso", seed=4, tolerance=0.0, runs=1, max_generations=res.generations)
    # late in the run re-drawn particles keep the swarm spread out, where the plain swarm has collapsed
    assert res.history["diversity"][-1] > plain.history["diversity"][-1]


@pytest.mark.parametrize("bound_handling", ["clip", "reflect", "resample"])
def test_every_iteration_stays_in_bounds(bound_handling):
    robot = ek.load_robot("redundant7r")
    lower, upper = robot.lower / 4, robot.upper / 4
    seen = []

    def check(generation, Q):
        seen.append(generation)
        assert np.all(Q >= lower) and np.all(Q <= upper), generation

    ek.solve(robot, [0.9, -0.3, 0.4], method="pso", seed=1, bounds=(lower, upper), velocity_clamp=1.0,
             bound_handling=bound_handling, max_generations=30, callback=check, runs=1)
    assert seen == list(range(31))


def test_same_seed_same_result_and_ring_topology(reachable_pose):
    robot = ek.load_robot("ax18")
    target = reachable_pose(robot, 12).translation
    a = ek.solve(robot, target, method="pso", seed=3, tolerance=1e-8)
    b = ek.solve(robot, target, method="pso", seed=3, tolerance=1e-8)
    assert np.array_equal(a.q, b.q) and a.generations == b.generations
    ring = ek.solve(robot, target, method="pso", seed=3, tolerance=1e-8, topology="ring")
    assert ring.success and not np.array_equal(ring.q, a.q)


@pytest.mark.parametrize("options, match", [
    (dict(population=1), "population"),
    (dict(w_start=-0.1), "w_start"),
    (dict(c1=20.0), "c1"),
    (dict(velocity_clamp=0.0), "velocity_clamp"),
    (dict(velocity_clamp="fast"), "velocity_clamp"),
    (dict(topology="star"), "topology"),
    (dict(random_factors="per-joint"), "random_factors 'per-joint' is not one of"),
    (dict(reinit_stagnant=0), "reinit_stagnant"),
    (dict(bound_handling="none"), "bound_handling"),
    (dict(runs=-2), "runs"),
])
def test_bad_options_are_clear_errors(options, match):
    with pytest.raises(OptionError, match=match):
        ek.solve("planar2r", [0.2, 0.2, 0.0], method="pso", seed=0, **options)
