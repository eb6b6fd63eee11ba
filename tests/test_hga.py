"""Paper 001's hybrid GA finds every IK solution of the 2R and PUMA targets, to 0.001 deg of the closed form."""

import numpy as np
import pytest

import evoik_pin
from evoik_pin.errors import MethodError
from evoik_pin.solvers.paper.analytic import planar2r_ik, puma_ik

CM = 0.01
TARGETS_2R = [(20, 20), (20, 25), (15, 30), (38, 0)]
TARGETS_PUMA = [(-52.5, 39.3, -46.5), (-30, -20, 43), (-15, 79, -1.5), (-56.4, 49.7, -28.4)]
TOL_DEG = 0.001  # the paper's HGA accuracy


def _matches(found, expected):
    """Largest wrapped joint error (deg) pairing each closed-form solution with its nearest found one."""
    Q = np.array([r.q for r in found])
    worst = 0.0
    for q in expected:
        d = np.abs((np.degrees(Q - q) + 180) % 360 - 180).max(axis=1)
        worst = max(worst, d.min())
    return worst


@pytest.mark.parametrize("target", TARGETS_2R)
def test_hga_finds_both_2r_solutions(target):
    sols = evoik_pin.solve_all("planar2r", [target[0] * CM, target[1] * CM, 0.0], method="hga", seed=3)
    expected = planar2r_ik(target[0] * CM, target[1] * CM)
    assert len(sols) == 2
    assert _matches(sols, expected) < TOL_DEG
    assert all(s.success and s.position_error <= 1e-6 for s in sols)
    assert sols[0].cost <= sols[1].cost


@pytest.mark.parametrize("target", TARGETS_PUMA)
def test_hga_finds_the_four_puma_solutions(target):
    p = np.array(target) * CM
    sols = evoik_pin.solve_all("puma3r", p, method="hga", seed=3, population=1000, niches=4)  # Table 2
    assert len(sols) == 4
    assert _matches(sols, puma_ik(p)) < TOL_DEG


def test_hga_result_fields_and_determinism():
    kw = dict(method="hga", population=200, max_generations=8, seed=11)
    a = evoik_pin.solve("planar2r", [0.2, 0.2, 0.0], **kw)
    b = evoik_pin.solve("planar2r", [0.2, 0.2, 0.0], **kw)
    assert np.array_equal(a.q, b.q) and [s.q.tolist() for s in a.solutions] == [s.q.tolist() for s in b.solutions]
    assert a.success and a.method == "hga" and a.generations == 8
    assert np.array_equal(a.q, a.solutions[0].q)
    assert a.evaluations > 200 * 9  # the GA's evaluations plus the Nelder-Mead polish
    assert len(a.history["best_cost"]) == 9


def test_hga_unreachable_target_gives_no_solution():
    res = evoik_pin.solve("puma3r", [2.0, 0.0, 0.0], method="hga", population=200, seed=0)
    assert not res.success and res.solutions == [] and "no polished" in res.message
    assert evoik_pin.solve_all("puma3r", [2.0, 0.0, 0.0], method="hga", population=200, seed=0) == []


def test_solve_all_rejects_single_solution_methods():
    with pytest.raises(MethodError, match="returns one solution"):
        evoik_pin.solve_all("planar2r", [0.2, 0.2, 0.0], method="mode")
