"""The compiled LM kernel (numba): its kinematics and Lie-group formulas against Pinocchio's, and its runs
against the Python loop over Pinocchio that it compiles."""

import numpy as np
import pinocchio as pin
import pytest

import evoik_pin as ev
from evoik_pin.errors import OptionError
from evoik_pin.problem import IKProblem, Target
from evoik_pin.robot import list_robots, load_robot
from evoik_pin.solvers import lm_kernel as K
from evoik_pin.solvers.polish import LevenbergMarquardt


@pytest.fixture(scope="module")
def robots():
    return {name: load_robot(name) for name in list_robots()}


def _rotations(rng):
    """Random rotations plus the hard cases: identity, angles near 0 and at / near pi about several axes."""
    out = [pin.exp3(rng.standard_normal(3) * s) for s in (0.1, 1.0, 2.0, 3.0) for _ in range(5)]
    out.append(np.eye(3))
    for axis in (np.array([1.0, 0, 0]), np.array([0, 1.0, 0]), np.array([0, 0, 1.0]), np.array([1.0, -2.0, 0.5])):
        axis = axis / np.linalg.norm(axis)
        for angle in (1e-9, 1e-6, 1e-4, 2e-4, 1e-3, 0.1, np.pi - 1e-2, np.pi - 1e-4, np.pi - 1e-7, np.pi):
            out.append(pin.exp3(angle * axis))
    return out


@pytest.mark.parametrize("name", list_robots())
def test_kernel_kinematics_equal_pinocchio(robots, name):
    # every bundled and example arm: revolute, prismatic (vehicle_arm) and continuous (kinova) joints
    robot = robots[name]
    FR, Fp, rev = robot.chain_constants()
    n = robot.n
    R, p, Z, O, J = np.empty((3, 3)), np.empty(3), np.empty((n, 3)), np.empty((n, 3)), np.empty((6, n))
    for q in robot.random_configurations(5, np.random.default_rng(3)):
        K.forward(FR, Fp, rev, q, R, p, Z, O)
        K.jacobian(rev, p, Z, O, J)
        T = robot.fk(q)
        assert np.abs(R - T.rotation).max() < 1e-12 and np.abs(p - T.translation).max() < 1e-12
        # base-frame axes and tip point velocity: Pinocchio's LOCAL_WORLD_ALIGNED Jacobian, i.e. "world"
        assert np.abs(J - robot.jacobian(q, "world")).max() < 1e-12


def test_log3_log6_and_their_jacobians_equal_pinocchio():
    rng = np.random.default_rng(5)
    phi, e = np.empty(3), np.empty(6)
    A, B = np.empty((3, 3)), np.empty((3, 3))
    for Rm in _rotations(rng):
        Rm = np.ascontiguousarray(Rm)
        theta = K.log3(Rm, phi)
        ref = pin.log3(Rm)
        # at exactly pi the sign of the axis is a convention: both are valid logarithms
        assert np.allclose(phi, ref, atol=1e-9) or (abs(theta - np.pi) < 1e-6 and np.allclose(phi, -ref, atol=1e-9))
        assert abs(theta - np.linalg.norm(ref)) < 1e-12
        assert np.abs(pin.exp3(phi) - Rm).max() < 1e-12
        if theta > np.pi - 1e-3:
            continue  # Jlog3 / Jlog6 blow up at pi, where log is not differentiable
        t = rng.standard_normal(3)
        M = pin.SE3(Rm, t)
        K.log6(Rm, t, e)
        assert np.abs(pin.exp6(pin.Motion(e)).homogeneous - M.homogeneous).max() < 1e-12  # a logarithm of M
        # Pinocchio's closed forms divide by 1 - cos(theta), which it computes with cancellation: near
        # theta = 1e-4 its own values are ~1e-9 off (the kernel's use 2 sin^2(theta / 2)), hence 1e-8 here
        assert np.abs(e - pin.log6(M).vector).max() < 1e-8
        K.jlog3(theta, phi, A)
        K.jlog6(theta, phi, t, A, B)
        # derivatives of log6(M exp(dx)) at dx = 0 by central differences of the kernel's log6
        D = np.empty((6, 6))
        for j in range(6):
            dx = np.zeros(6)
            dx[j] = 1e-6
            Mp, Mm = M * pin.exp6(pin.Motion(dx)), M * pin.exp6(pin.Motion(-dx))
            ep, em = np.empty(6), np.empty(6)
            K.log6(np.ascontiguousarray(Mp.rotation), Mp.translation.copy(), ep)
            K.log6(np.ascontiguousarray(Mm.rotation), Mm.translation.copy(), em)
            D[:, j] = (ep - em) / 2e-6
        assert np.abs(A - D[3:, 3:]).max() < 1e-7 and np.abs(A - D[:3, :3]).max() < 1e-7
        assert np.abs(B - D[:3, 3:]).max() < 1e-7 and np.abs(D[3:, :3]).max() < 1e-7
        if theta >= 1e-2:
            # and Pinocchio's: below ~1e-2 its 1 - cos(theta) and 1/theta^4 terms cancel (~1e-5 off near 2e-4,
            # where the central differences above confirm the kernel's values)
            Jl = pin.Jlog6(M)
            assert np.abs(A - pin.Jlog3(Rm)).max() < 1e-9
            assert np.abs(A - Jl[:3, :3]).max() < 1e-9 and np.abs(B - Jl[:3, 3:]).max() < 1e-9
            assert np.abs(A - Jl[3:, 3:]).max() < 1e-9 and np.abs(Jl[3:, :3]).max() == 0.0


@pytest.mark.parametrize("name", ["panda", "ur5", "kinova", "redundant7r", "ax18", "vehicle_arm"])
def test_compiled_runs_equal_the_python_loop(robots, name):
    """The kernel is the Python loop's iteration compiled: from the same starts, the same steps.

    Both sides round differently (our FK against Pinocchio's, about 1e-16), which can flip a comparison at
    1e-12 (whether a finishing step improved) or, rarely, an accept test early on, so the check is that
    nearly every run is identical (steps, evaluations, end configuration to 1e-8) and that both engines
    converge on the same starts.
    """
    robot = robots[name]
    rng = np.random.default_rng(17)
    position_only = name in ("ax18", "vehicle_arm")
    identical = 0
    runs = 40
    for _ in range(runs):
        qt, q0 = robot.random_configurations(2, rng)
        T = robot.fk(qt)
        problem = IKProblem(robot, Target(T.translation) if position_only else T)
        a = LevenbergMarquardt(problem).run(q0, 30)
        b = LevenbergMarquardt(problem, engine="python").run(q0, 30)
        assert a.converged == b.converged
        assert robot.within_bounds(a.q)
        identical += (a.iterations == b.iterations and a.evaluations == b.evaluations
                      and np.allclose(a.q, b.q, atol=1e-8))
        if a.converged:
            Tq = robot.fk(a.q)
            assert np.linalg.norm(Tq.translation - T.translation) <= 1e-6
            assert a.orientation_error is None if position_only else a.orientation_error <= 1e-6
            if not position_only:
                assert np.linalg.norm(pin.log3(T.rotation.T @ Tq.rotation)) <= 1e-6
    assert identical >= runs - 2


def test_compiled_run_holds_joints_on_their_limits(robots):
    # targets whose solution has joint 5 on its upper limit, from starts 0.3 rad around it: the clip and
    # re-solve path of the step runs; the answers stay inside the box and equal the Python loop's
    robot = robots["panda"]
    rng = np.random.default_rng(8)
    on_limit = 0
    for _ in range(20):
        qt = robot.random_configurations(1, rng)[0]
        qt[5] = robot.upper[5]
        T = robot.fk(qt)
        q0 = np.clip(qt + 0.3 * rng.standard_normal(robot.n), robot.lower, robot.upper)
        a = LevenbergMarquardt(IKProblem(robot, T)).run(q0, 30)
        b = LevenbergMarquardt(IKProblem(robot, T), engine="python").run(q0, 30)
        assert robot.within_bounds(a.q) and a.converged == b.converged and np.allclose(a.q, b.q, atol=1e-8)
        on_limit += a.converged and a.q[5] == robot.upper[5]
    assert on_limit >= 5


def test_wrapping_joints_wrap_in_the_kernel(robots):
    # kinova's continuous joints: a start just below -pi and a target just above +pi on that joint
    robot = robots["kinova"]
    k = int(np.nonzero(robot.continuous)[0][0])
    q0 = robot.random_configurations(1, np.random.default_rng(9))[0]
    q0[k] = -np.pi + 0.05
    qt = q0.copy()
    qt[k] = np.pi - 0.05
    a = LevenbergMarquardt(IKProblem(robot, robot.fk(qt))).run(q0, 30)
    assert a.converged and a.iterations <= 6
    assert abs(a.q[k] - qt[k]) < 1e-6 and robot.within_bounds(a.q)


def test_engine_option(robots, reachable_pose):
    robot = robots["panda"]
    T = reachable_pose(robot, 4)
    for engine in ("compiled", "python"):
        res = ev.solve(robot, T, seed=11, engine=engine, timeout=None, max_restarts=5)
        assert res.success and res.position_error <= 1e-6
    with pytest.raises(OptionError, match="compiled"):
        ev.solve(robot, T, engine="fortran")
    # planar targets always take the Python loop, whatever the engine
    planar = robots["planar2r"]
    x, y = reachable_pose(planar, 5).translation[:2]
    res = ev.solve(planar, Target.planar_target(x, y), seed=1, engine="compiled", timeout=None, max_restarts=5)
    assert res.success and res.position_error <= 1e-6


@pytest.mark.parametrize("name", ["panda", "ax18"])
def test_compiled_pairs_equal_one_run_per_pair(robots, name):
    # solve_many's compiled rounds: one kernel call over all pairs gives what one LM run per pair gives
    from evoik_pin.solvers.polish import compiled_pairs

    robot = robots[name]
    rng = np.random.default_rng(21)
    Qt, Q0 = robot.random_configurations(30, rng), robot.random_configurations(30, rng)
    targets = [Target(robot.fk(q).translation) if name == "ax18" else Target.coerce(robot.fk(q)) for q in Qt]
    out = compiled_pairs(robot, Q0, targets, robot.lower, robot.upper, 1e-6, 1e-6)
    assert 0 < out.converged.sum() < 30
    for i, t in enumerate(targets):
        one = LevenbergMarquardt(IKProblem(robot, t)).run(Q0[i], 30)
        assert np.array_equal(out.q[i], one.q) and out.converged[i] == one.converged
        assert out.position_error[i] == one.position_error and out.evaluations[i] == one.evaluations
        if name == "ax18":
            assert out.orientation_error is None
        else:
            assert out.orientation_error[i] == one.orientation_error


def test_solve_many_engines_agree_on_success(robots):
    robot = robots["kinova"]
    H = np.array([robot.fk(q).homogeneous for q in robot.random_configurations(200, np.random.default_rng(22))])
    for engine in ("compiled", "python"):
        res = ev.solve_many(robot, H, seed=3, engine=engine, timeout=None, max_restarts=10)
        assert res.stats["success_rate"] == 1.0
        for r, T in zip(res, H, strict=True):
            Tq = robot.fk(r.q)
            assert np.linalg.norm(Tq.translation - T[:3, 3]) <= 1e-6 and robot.within_bounds(r.q)
            assert np.linalg.norm(pin.log3(T[:3, :3].T @ Tq.rotation)) <= 1e-6
