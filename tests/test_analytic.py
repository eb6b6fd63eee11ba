"""Closed-form IK of paper 000's AX-18 and paper 001's 2R and PUMA arms, and the ``algebraic`` method."""

import numpy as np
import pytest

import evoik_pin
from evoik_pin import load_robot
from evoik_pin.errors import MethodError
from evoik_pin.papers.robots import paper_robot_urdf
from evoik_pin.solvers.paper.analytic import (
    AX18_LIMITS,
    ax18_algebraic,
    ax18_fk,
    ax18_ik,
    planar2r_fk,
    planar2r_ik,
    puma_fk,
    puma_ik,
)

CM = 0.01
# Paper 001, Table 4: 2R targets (cm) and the two analytic solutions (deg), printed to one decimal.
TABLE4 = {(20, 20): [(10.7, 95.8), (79.2, -95.8)], (20, 25): [(21.8, 79.6), (80.7, -79.6)],
          (15, 30): [(36.4, 72.2), (90.4, -72.2)], (38, 0): [(-17.4, 45.2), (17.4, -45.2)]}
PUMA_TARGETS = [(-52.5, 39.3, -46.5), (-30, -20, 43), (-15, 79, -1.5), (-56.4, 49.7, -28.4)]
AX18_TARGETS = [(10, 10, 10), (0, 7.5, 12), (2, 13, -5), (-6, 9.5, 4.3), (3, -7, 13)]


def _wrapped_deg(a, b):
    return np.abs((np.degrees(np.asarray(a) - np.asarray(b)) + 180) % 360 - 180)


@pytest.mark.parametrize("target, expected", TABLE4.items())
def test_planar2r_matches_paper_table4(target, expected):
    sols = planar2r_ik(target[0] * CM, target[1] * CM)
    assert len(sols) == 2
    for q in sols:
        assert np.abs(planar2r_fk(q) - np.array(target) * CM).max() < 1e-12
    # The table truncates to one decimal (e.g. 21.89 deg printed as 21.8): within 0.1 deg.
    for exp in expected:
        assert min(_wrapped_deg(q, np.radians(exp)).max() for q in sols) < 0.1


def test_planar2r_boundary_and_out_of_reach():
    assert len(planar2r_ik(0.41, 0.0)) == 1  # fully stretched: both elbows coincide
    assert planar2r_ik(0.5, 0.0) == []
    assert planar2r_ik(0.05, 0.0) == []  # inside the inner hole |a1 - a2| = 9 cm


@pytest.mark.parametrize("target", PUMA_TARGETS)
def test_puma_four_solutions_reach_the_target(target):
    p = np.array(target) * CM
    sols = puma_ik(p)
    assert len(sols) == 4
    for q in sols:
        assert np.abs(puma_fk(q) - p).max() < 1e-12
    robot = load_robot("puma3r")
    assert np.abs(robot.positions_batch(np.array(sols)) - p).max() < 1e-12


def test_puma_target1_against_table5_and_the_documented_t3_discrepancy():
    """t1 and t2 match Table 5; t3 is 39.2 / 135.5 deg, not the table's 45 / 140.3 (PAPERS.md)."""
    sols = np.degrees(puma_ik(np.array(PUMA_TARGETS[0]) * CM))
    assert sorted(np.round(np.unique(np.round(sols[:, 0], 1)), 1)) == [-23.7, 130.1]
    assert sorted(np.round(sols[:, 1], 0)) == [12, 60, 120, 168]
    assert sorted(np.round(np.unique(np.round(sols[:, 2], 1)), 1)) == [39.2, 135.5]


def test_puma_random_round_trip(rng):
    robot = load_robot("puma3r")
    for q in robot.random_configurations(50, rng):
        sols = puma_ik(puma_fk(q))
        assert 1 <= len(sols) <= 4
        assert min(_wrapped_deg(s, q).max() for s in sols) < 1e-7


def test_unreachable_puma_gives_empty_list_and_a_message():
    far = np.array([2.0, 0.0, 0.0])
    assert puma_ik(far) == []
    res = evoik_pin.solve("puma3r", far, method="algebraic")
    assert not res.success and "out of reach" in res.message
    assert evoik_pin.solve_all("puma3r", far, method="algebraic") == []


def test_ax18_ik_round_trip(rng):
    robot = load_robot("ax18")
    for q in robot.random_configurations(50, rng):
        p, phi = ax18_fk(q), q[1] + q[2] + q[3]
        sols = ax18_ik(p, phi)
        assert sols and min(_wrapped_deg(s, q).max() for s in sols) < 1e-6
        assert np.abs(ax18_fk(np.array(sols)) - p).max() < 1e-12


@pytest.mark.parametrize("target", AX18_TARGETS)
def test_ax18_algebraic_reaches_table2_targets_within_limits(target):
    p = np.array(target) * CM
    best = ax18_algebraic(p)[0]
    assert best.position_error < 1e-9
    lo, hi = AX18_LIMITS
    assert np.all(best.q >= lo - 1e-12) and np.all(best.q <= hi + 1e-12)
    assert abs(best.phi - (best.q[1] + best.q[2] + best.q[3] - 2 * np.pi * round(
        (best.q[1] + best.q[2] + best.q[3] - best.phi) / (2 * np.pi)))) < 1e-9


def test_algebraic_method_on_the_bundled_robots():
    sols = evoik_pin.solve_all("planar2r", [0.2, 0.2, 0.0], method="algebraic")
    assert len(sols) == 2 and all(s.success for s in sols)
    sols = evoik_pin.solve_all("puma3r", np.array(PUMA_TARGETS[1]) * CM, method="algebraic")
    assert len(sols) == 4 and all(s.position_error < 1e-12 for s in sols)
    res = evoik_pin.solve("ax18", np.array(AX18_TARGETS[0]) * CM, method="algebraic")
    assert res.success and res.solutions and res.method == "algebraic"
    planar = evoik_pin.solve("planar2r", evoik_pin.Target.planar_target(0.2, 0.2), method="algebraic")
    assert planar.success


def test_algebraic_refuses_other_robots_and_altered_kinematics(tmp_path):
    with pytest.raises(MethodError, match="closed forms for the bundled robots"):
        evoik_pin.solve("redundant7r", [0.3, 0.2, 0.5], method="algebraic")
    altered = tmp_path / "puma3r.urdf"  # same name, other link length
    altered.write_text(paper_robot_urdf("puma3r").replace("0.4318", "0.45"))
    with pytest.raises(MethodError, match="does not match"):
        evoik_pin.solve(load_robot(altered), [-0.3, -0.2, 0.43], method="algebraic")
