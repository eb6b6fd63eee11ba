"""Pinocchio FK of each bundled paper arm equals that paper's own closed form."""

import numpy as np
import pytest

from evoik_pin.papers.dh import DHRow, dh_transform
from evoik_pin.papers.robots import PAPER_ROBOTS, VEHICLE_ARM_LENGTHS
from evoik_pin.robot import bundled_robots_dir, load_robot

CM = 0.01
N_RANDOM = 200


def _random(robot, rng, n=N_RANDOM):
    return robot.random_configurations(n, rng)


def ax18_closed_form(t):
    """Paper 000, section III-A: p_x, p_y, p_z of the AX-18 tool."""
    d1, a1, a2, a3, d2, a4 = 4.36 * CM, 6.75 * CM, 17.23 * CM, 6.3 * CM, 2.0 * CM, 11.7 * CM
    t1, t2, t3, t4 = t
    c1, s1, c2, s2 = np.cos(t1), np.sin(t1), np.cos(t2), np.sin(t2)
    c23, s23 = np.cos(t2 + t3), np.sin(t2 + t3)
    c234, s234 = np.cos(t2 + t3 + t4), np.sin(t2 + t3 + t4)
    return np.array([
        a4 * c1 * c234 + d2 * c1 * s234 + a1 * c1 * c2 + a3 * c1 * c234 + a2 * c1 * c23,
        a4 * s1 * c234 + a1 * c2 * s1 + d2 * s1 * s234 + a3 * s1 * c234 + a2 * s1 * c23,
        d1 + a1 * s2 + a4 * s234 - d2 * c234 + a2 * s23 + a3 * s234,
    ])


def puma_closed_form(t):
    """Paper 001, eq. 20: the PUMA wrist point."""
    a2, d, a3, d4 = 43.18 * CM, 14.90 * CM, 2.03 * CM, 43.30 * CM
    t1, t2, t3 = t
    C1, S1, C2, S2 = np.cos(t1), np.sin(t1), np.cos(t2), np.sin(t2)
    C23, S23 = np.cos(t2 + t3), np.sin(t2 + t3)
    reach = S23 * d4 + a3 * C23 + a2 * C2
    return np.array([C1 * reach - d * S1, S1 * reach + d * C1, d4 * C23 - a3 * S23 - a2 * S2])


def planar2r_closed_form(t):
    a1, a2 = 25 * CM, 16 * CM
    return np.array([a1 * np.cos(t[0]) + a2 * np.cos(t[0] + t[1]), a1 * np.sin(t[0]) + a2 * np.sin(t[0] + t[1]), 0])


def redundant7r_closed_form(t):
    """Paper 002: the product of the standard-DH matrices of eqs. 3-9, written out independently."""
    alpha = [-np.pi / 2, np.pi / 2, -np.pi / 2, np.pi / 2, -np.pi / 2, 0, 0]
    a = [0, 0.2, 0.25, 0.3, 0.2, 0.2, 0.1]
    d = [0.5, 0, 0, 0, 0, 0, 0.005]
    T = np.eye(4)
    for i in range(7):
        ct, st, ca, sa = np.cos(t[i]), np.sin(t[i]), np.cos(alpha[i]), np.sin(alpha[i])
        T = T @ np.array([[ct, -st * ca, st * sa, a[i] * ct],
                          [st, ct * ca, -ct * sa, a[i] * st],
                          [0, sa, ca, d[i]],
                          [0, 0, 0, 1]])
    return T


def vehicle_closed_form(q):
    """Paper 003, eq. 3: (x, y, yaw) of the vehicle-arm tip."""
    l1, l2, l3 = VEHICLE_ARM_LENGTHS
    s2, s23, s234 = q[2], q[2] + q[3], q[2] + q[3] + q[4]
    return np.array([q[0] + l1 * np.cos(s2) + l2 * np.cos(s23) + l3 * np.cos(s234),
                     q[1] + l1 * np.sin(s2) + l2 * np.sin(s23) + l3 * np.sin(s234), s234])


@pytest.mark.parametrize("name, closed_form", [
    ("ax18", ax18_closed_form), ("puma3r", puma_closed_form), ("planar2r", planar2r_closed_form),
])
def test_position_closed_forms(name, closed_form, rng):
    robot = load_robot(name)
    for q in _random(robot, rng):
        assert np.abs(robot.fk(q).translation - closed_form(q)).max() < 1e-9


def test_redundant7r_matches_dh_product(rng):
    robot = load_robot("redundant7r")
    for q in _random(robot, rng):
        T = robot.fk(q)
        ref = redundant7r_closed_form(q)
        assert np.abs(T.translation - ref[:3, 3]).max() < 1e-9
        assert np.abs(T.rotation - ref[:3, :3]).max() < 1e-9


def test_vehicle_arm_matches_eq3(rng):
    robot = load_robot("vehicle_arm")
    for q in _random(robot, rng):
        T = robot.fk(q)
        x, y, yaw = vehicle_closed_form(q)
        assert abs(T.translation[0] - x) < 1e-9 and abs(T.translation[1] - y) < 1e-9
        assert abs(T.translation[2]) < 1e-12
        assert abs(np.angle(np.exp(1j * (np.arctan2(T.rotation[1, 0], T.rotation[0, 0]) - yaw)))) < 1e-9


def test_aerial6r_matches_its_dh_table(rng):
    """The URDF of paper 004's arm equals the product of its Table 1 rows (standard DH)."""
    table = [(-np.pi / 2, 6.4, 0, 0), (0, 30.2, 0, -np.pi / 2), (np.pi / 2, 0, 0, np.pi / 2),
             (np.pi / 2, 0, 23.5, 0), (-np.pi / 2, 5.3, 0, np.pi / 2), (0, 5.6, -2, 0)]
    rows = [DHRow(a * CM, al, d * CM, th) for al, a, d, th in table]
    robot = load_robot("aerial6r")
    for q in _random(robot, rng):
        ref = np.eye(4)
        for row, qi in zip(rows, q, strict=True):
            ref = ref @ dh_transform(row, qi)
        T = robot.fk(q)
        assert np.abs(T.translation - ref[:3, 3]).max() < 1e-9
        assert np.abs(T.rotation - ref[:3, :3]).max() < 1e-9


@pytest.mark.parametrize("deg", [(-135, -123.27, 188.83, 134.84), (45, 72.42, -2.29, -133.6)])
def test_ax18_figure1_angles_reach_10_10_10_cm(deg):
    """Paper 000, Fig. 1: both configurations put the tool at (10, 10, 10) cm."""
    p = load_robot("ax18").fk(np.radians(deg)).translation
    assert np.abs(p / CM - 10.0).max() < 0.005


def test_paper_limits_in_radians():
    assert np.allclose(np.degrees(load_robot("ax18").lower), [-150, -60, -150, -150])
    assert np.allclose(np.degrees(load_robot("ax18").upper), [150, 240, 150, 150])
    assert np.allclose(np.degrees(load_robot("aerial6r").lower), [-90, 47, -90, -90, -90, -90])
    assert np.allclose(load_robot("redundant7r").upper, [np.pi, np.pi / 6, 2 * np.pi / 3] + [np.pi / 2] * 4)


@pytest.mark.parametrize("name", list(PAPER_ROBOTS))
def test_committed_urdf_is_what_the_generator_writes(name):
    committed = (bundled_robots_dir() / f"{name}.urdf").read_text()
    assert committed == PAPER_ROBOTS[name](), f"robots/{name}.urdf is stale: run scripts/make_paper_robots.py"
