"""Paper 000's multi-objective DE on the AX-18."""

import numpy as np
import pytest

import evoik_pin
from evoik_pin import load_robot
from evoik_pin.errors import OptionError
from evoik_pin.solvers.paper.mode import adaptive_probability, equitable_weights, nondominated_2d

CM = 0.01
TABLE2 = [(10, 10, 10), (0, 7.5, 12), (2, 13, -5), (-6, 9.5, 4.3), (3, -7, 13)]


def test_mode_reaches_table2_targets_within_1mm_on_most_seeds():
    """Paper parameters (Np 150, 200 generations, M 0.2, Cr 0.8, F 0.2; Mt 0.125), seeds 0-5 on each Table 2 target.

    Measured rate (issue 5): 199 of 200 runs within 1 mm (seeds 0-39 x 5 targets; the miss at 1.5 mm), and
    94 % (seeds 0-19) with the earlier Mt = 0.05. The test asks for at least 29 of its 30 runs, which a 99.5 %
    rate meets with probability 0.99; it does not rest on one chosen seed.
    """
    robot = load_robot("ax18")
    errors = []
    for target in TABLE2:
        for seed in range(6):
            res = evoik_pin.solve(robot, np.array(target) * CM, method="mode", seed=seed)
            errors.append(res.position_error)
            assert robot.within_bounds(res.q)
            w1, w2 = res.history["w1"], res.history["w2"]
            assert len(w1) == res.generations + 1
            assert np.all((w1 >= 0) & (w1 <= 1) & (w2 >= 0) & (w2 <= 1))
            assert np.allclose(w1 + w2, 1.0, atol=1e-12)
            assert w1[-1] > 0.9  # the weight moves onto the position as the best closes in (paper Fig. 4)
    errors = np.array(errors)
    assert (errors < 1e-3).sum() >= 29, np.round(errors * 1e3, 3)
    assert errors.max() < 5e-3


def test_equitable_weights_formula():
    f = np.array([0.2, 0.6, 1.2])
    w = equitable_weights(f)
    assert w == pytest.approx([(0.6 + 1.2) / (2 * 2.0), (0.2 + 1.2) / (2 * 2.0), (0.2 + 0.6) / (2 * 2.0)])
    assert w.sum() == pytest.approx(1.0)
    assert equitable_weights([0.0, 0.0], previous=[0.3, 0.7]).tolist() == [0.3, 0.7]


def test_adaptive_probability_rule():
    cost = np.array([0.0, 1.0, 2.0, 5.0])  # mean 2
    assert adaptive_probability(cost, 0.8) == pytest.approx([0.0, 0.4, 0.8, 0.8])
    assert adaptive_probability(np.ones(3), 0.2) == pytest.approx([0.2, 0.2, 0.2])


def test_front_is_nondominated_and_history_complete():
    res = evoik_pin.solve("ax18", np.array(TABLE2[0]) * CM, method="mode", seed=2, max_generations=60)
    F = res.front.objectives
    assert F.shape[1] == 2 and len(res.front) >= 2 and np.all(res.front.violation == 0)
    le = np.all(F[:, None] <= F[None], axis=2) & np.any(F[:, None] < F[None], axis=2)
    assert not le.any()
    robot = load_robot("ax18")
    assert np.allclose(F[:, 0], np.linalg.norm(robot.positions_batch(res.front.q) - np.array(TABLE2[0]) * CM, axis=1))
    assert np.allclose(F[:, 1], np.abs(res.front.q).max(axis=1))  # from q_init = zeros
    for key in ("w1", "w2", "best_fitness", "diversity", "best_position_error", "best_displacement"):
        assert len(res.history[key]) == 61
    assert nondominated_2d(np.array([[1.0, 1.0], [0.5, 2.0], [2.0, 2.0], [1.0, 1.0]])).tolist() == [1, 0]


def test_mode_displacement_is_measured_from_q0():
    q0 = np.radians([40.0, 60.0, -10.0, -100.0])
    res = evoik_pin.solve("ax18", np.array(TABLE2[0]) * CM, method="mode", seed=0, q0=q0, max_generations=80)
    assert np.allclose(res.front.objectives[:, 1], np.abs(res.front.q - q0).max(axis=1))


@pytest.mark.parametrize("variant", ["fixed", "binomial", "binomial-trigonometric"])
def test_variants_are_deterministic(variant):
    kw = dict(method="mode", seed=4, variant=variant, max_generations=30, population=40)
    a = evoik_pin.solve("ax18", [0.1, 0.1, 0.1], **kw)
    b = evoik_pin.solve("ax18", [0.1, 0.1, 0.1], **kw)
    assert np.array_equal(a.q, b.q) and np.array_equal(a.history["w1"], b.history["w1"])
    assert a.position_error < a.history["best_position_error"][0]


def test_bad_options():
    with pytest.raises(OptionError, match="variant"):
        evoik_pin.solve("ax18", [0.1, 0.1, 0.1], method="mode", variant="exp")
    with pytest.raises(OptionError, match="crossover_rate"):
        evoik_pin.solve("ax18", [0.1, 0.1, 0.1], method="mode", crossover_rate=1.5)
    with pytest.raises(OptionError, match="length_scale"):
        evoik_pin.solve("ax18", [0.1, 0.1, 0.1], method="mode", length_scale=0)
