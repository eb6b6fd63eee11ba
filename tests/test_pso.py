"""PSO of paper 002 (eq. 11): the update on fixed draws, the inertia schedule, and the ``pso`` solver."""

import numpy as np
import pytest

import evoik_pin as ek
from evoik_pin.errors import OptionError
from evoik_pin.solvers.pso import inertia_weight, pso_step, ring_best


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


def test_pso_on_a_pose_target_of_aerial6r_reports_what_it_reached(reachable_pose):
    # Measured (docs/BENCHMARKS.md): paper 002's PSO is not reliable on 6-D pose targets of aerial6r. The pose
    # objective (m + orientation_weight x rad) is a sum of two norms; the swarm collapses onto the manifold where
    # one of them is zero (exact orientation at weight 1, exact position at 0.1) mm to cm from the target. Best
    # found: 13 of 20 targets (N 40, orientation weight 0.1-0.15, runs 10); population, topology, inertia,
    # re-initialisation and bound handling did not raise that. So no success is asserted here, only that it
    # improves and reports its result consistently.
    robot = ek.load_robot("aerial6r")
    res = ek.solve(robot, reachable_pose(robot, 10), method="pso", seed=2, tolerance=1e-6, runs=1)
    h = res.history
    assert h["best_cost"][-1] < h["best_cost"][0] and np.all(np.diff(h["best_cost"]) <= 0)
    assert robot.within_bounds(res.q)
    assert res.success == (res.position_error <= 1e-6 and res.orientation_error <= 1e-6)
    if not res.success:
        assert "exceeds the tolerance" in res.message


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
    (dict(reinit_stagnant=0), "reinit_stagnant"),
    (dict(bound_handling="none"), "bound_handling"),
    (dict(runs=-2), "runs"),
])
def test_bad_options_are_clear_errors(options, match):
    with pytest.raises(OptionError, match=match):
        ek.solve("planar2r", [0.2, 0.2, 0.0], method="pso", seed=0, **options)
