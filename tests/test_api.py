"""Public API: solve / solve_trajectory / methods with the DE family, bad input, unreachable targets."""

import numpy as np
import pinocchio as pin
import pytest

import evoik_pin as ek
from evoik_pin.errors import ConfigurationError, MethodError, OptionError, TargetError


@pytest.fixture(scope="module")
def arm():
    return ek.load_robot("redundant7r")


def spiral(count: int) -> np.ndarray:
    """Paper 002's Scenario 3 spiral (eq. 22), x = 200 cos(2z/100), y = 200 sin(2z/100), z = n pi (mm),
    n = 1..count, in metres."""
    z_mm = np.arange(1, count + 1) * np.pi
    return np.stack([200 * np.cos(2 * z_mm / 100), 200 * np.sin(2 * z_mm / 100), z_mm], axis=1) / 1000.0


def test_methods_lists_the_de_family():
    names = ek.methods()
    assert {"de", "isade", "pso"} <= set(names)


@pytest.mark.parametrize("method", ["de", "isade", "pso"])
def test_solve_by_name_with_a_robot_name(method):
    res = ek.solve("redundant7r", [0.4, 0.3, 0.7], method=method, seed=0, tolerance=1e-8)
    assert isinstance(res, ek.Result) and res.success and res.method == method
    assert res.q.shape == (7,) and res.orientation_error is None and res.time_s > 0


def test_pose_target_as_se3(arm):
    robot = ek.load_robot("aerial6r")
    q = robot.random_configurations(1, np.random.default_rng(2))[0]
    T = robot.fk(q)
    res = ek.solve(robot, pin.SE3(T.rotation, T.translation), method="isade", seed=3, tolerance=1e-6,
                   population=60, F_max=0.9, F_min=0.3, n_iter=2.0, max_generations=300)
    assert res.success and res.orientation_error <= 1e-6


def test_unknown_method_lists_known_ones():
    with pytest.raises(MethodError, match="isade") as info:
        ek.solve("planar2r", [0.2, 0.1, 0.0], method="gradient")
    assert "unknown method 'gradient'" in str(info.value)


def test_unknown_option_lists_accepted_ones():
    with pytest.raises(OptionError, match="population"):
        ek.solve("planar2r", [0.2, 0.1, 0.0], method="isade", populaton=30)


@pytest.mark.parametrize("target, error, match", [
    ([0.1, 0.2], TargetError, "3-vector"),
    (np.zeros((2, 3)), TargetError, "shape"),
    ([0.1, np.nan, 0.2], TargetError, "NaN"),
    ([np.inf, 0.1, 0.2], TargetError, "NaN"),
])
def test_bad_targets(target, error, match):
    with pytest.raises(error, match=match):
        ek.solve("redundant7r", target, method="isade", seed=0)


@pytest.mark.parametrize("options, error, match", [
    (dict(q0=[0.0] * 6), ConfigurationError, "q0"),
    (dict(q0=[0.0, 0.1, np.nan, 0.0, 0.0, 0.0, 0.0]), ConfigurationError, "NaN"),
    (dict(population=-10), OptionError, "population"),
    (dict(tolerance=-1e-6), OptionError, "tolerance"),
    (dict(rotation_tolerance=-1.0), OptionError, "rotation_tolerance"),
    (dict(max_generations=2.5), OptionError, "max_generations"),
    (dict(seed=-3), OptionError, "seed"),
    (dict(bounds=(np.zeros(7),)), OptionError, "bounds"),
])
def test_bad_options(options, error, match):
    with pytest.raises(error, match=match):
        ek.solve("redundant7r", [0.4, 0.3, 0.7], method="isade", **options)


@pytest.mark.parametrize("method", ["de", "isade", "pso"])
def test_far_target_returns_best_approximation(method):
    robot = ek.load_robot("planar2r")  # reach 0.25 + 0.16 = 0.41 m
    res = ek.solve(robot, [3.0, 0.0, 0.0], method=method, seed=1, max_generations=60)
    assert not res.success
    assert res.position_error == pytest.approx(3.0 - 0.41, abs=1e-6)  # the arm stretched towards the target
    assert "exceeds the tolerance" in res.message
    assert robot.within_bounds(res.q)


def test_q0_seeds_the_population(arm):
    q0 = np.full(arm.n, 0.2)
    target = arm.fk(q0).translation
    res = ek.solve(arm, target, method="isade", seed=0, q0=q0, tolerance=1e-12)
    assert res.success and res.generations == 0 and np.allclose(res.q, q0)


def test_spiral_piece_is_inside_the_workspace(arm):
    results = ek.solve_trajectory(arm, spiral(8), method="isade", q0=np.zeros(arm.n), seed=0, tolerance=1e-8)
    assert len(results) == 8 and all(r.success for r in results)


def test_pro_gives_smaller_joint_jumps_on_the_spiral(arm):
    pts = spiral(8)
    full = ek.solve_trajectory(arm, pts, method="isade", q0=np.zeros(arm.n), pro=False, seed=1, tolerance=1e-8)
    pro = ek.solve_trajectory(arm, pts, method="isade", q0=np.zeros(arm.n), pro=True, seed=1, tolerance=1e-8)
    assert all(r.success for r in pro)
    jumps_full = np.abs(np.diff([r.q for r in full], axis=0)).max(axis=1)
    jumps_pro = np.abs(np.diff([r.q for r in pro], axis=0)).max(axis=1)
    assert np.all(jumps_pro <= np.pi / 100 + 1e-12)  # every joint stays in the previous solution +- pi/100
    assert jumps_pro.mean() < 0.5 * jumps_full.mean()


def test_trajectory_seed_reproducible_and_validated(arm):
    pts = spiral(3)
    a = ek.solve_trajectory(arm, pts, method="de", pro=True, seed=5, tolerance=1e-7)
    b = ek.solve_trajectory(arm, pts, method="de", pro=True, seed=5, tolerance=1e-7)
    assert all(np.array_equal(x.q, y.q) for x, y in zip(a, b, strict=True))
    with pytest.raises(ConfigurationError, match="at least one target"):
        ek.solve_trajectory(arm, [], method="de")
    with pytest.raises(TargetError):
        ek.solve_trajectory(arm, [[0.1, 0.2, 0.3], [0.1, 0.2]], method="de", seed=0, max_generations=5)
