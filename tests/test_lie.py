"""evoik_pin.lie: the NumPy batch forms and the numba forms of log3, exp3, Jlog3, log6, exp6, Jlog6, the angle,
yaw and roll-pitch-yaw of rotations, against Pinocchio at random, near 0 and at / near pi."""

import numpy as np
import pinocchio as pin
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from evoik_pin import lie
from evoik_pin.lie import compiled as C


def _rotations(rng):
    """Random rotations plus the hard cases: identity, angles near 0 and at / near pi about several axes."""
    out = [pin.exp3(rng.standard_normal(3) * s) for s in (0.1, 1.0, 2.0, 3.0) for _ in range(5)]
    out.append(np.eye(3))
    for axis in (np.array([1.0, 0, 0]), np.array([0, 1.0, 0]), np.array([0, 0, 1.0]), np.array([1.0, -2.0, 0.5])):
        axis = axis / np.linalg.norm(axis)
        for a in (1e-9, 1e-6, 1e-4, 2e-4, 1e-3, 0.1, np.pi - 1e-2, np.pi - 1e-4, np.pi - 1e-7, np.pi):
            out.append(pin.exp3(a * axis))
    return np.array(out)


ROTATIONS = _rotations(np.random.default_rng(5))


def _same_log(phi, ref, theta):
    """Equal rotation vectors; at exactly pi the sign of the axis is a convention (both are logarithms)."""
    return np.allclose(phi, ref, atol=1e-9) or (abs(theta - np.pi) < 1e-6 and np.allclose(phi, -ref, atol=1e-9))


def _central_jlog6(M, log6_of):
    """Derivative (6, 6) of ``log6(M exp(dx))`` at dx = 0 by central differences of ``log6_of(pin.SE3)``."""
    D = np.empty((6, 6))
    for j in range(6):
        dx = np.zeros(6)
        dx[j] = 1e-6
        D[:, j] = (log6_of(M * pin.exp6(pin.Motion(dx))) - log6_of(M * pin.exp6(pin.Motion(-dx)))) / 2e-6
    return D


# ---------------------------------------------------------------------- NumPy batch forms
def test_log3_angle_and_exp3_batch_equal_pinocchio():
    phi = lie.log3(ROTATIONS)
    theta = lie.angle(ROTATIONS)
    for i, Rm in enumerate(ROTATIONS):
        ref = pin.log3(Rm)
        assert _same_log(phi[i], ref, theta[i])
        assert abs(theta[i] - np.linalg.norm(ref)) < 1e-12
    assert np.abs(lie.exp3(phi) - ROTATIONS).max() < 1e-12
    assert np.abs(lie.exp3(phi) - np.array([pin.exp3(p) for p in phi])).max() < 1e-14


def test_relative_angle_yaw_and_rpy_equal_pinocchio():
    Rt = ROTATIONS[3]
    ang = lie.relative_angle(Rt, ROTATIONS)
    assert np.allclose(ang, [np.linalg.norm(pin.log3(Rt.T @ R)) for R in ROTATIONS], atol=1e-9)
    rpy = lie.rpy(ROTATIONS)
    for i, Rm in enumerate(ROTATIONS):
        assert np.abs(pin.rpy.rpyToMatrix(*rpy[i]) - Rm).max() < 1e-9
        assert lie.yaw(Rm[None])[0] == pytest.approx(np.arctan2(Rm[1, 0], Rm[0, 0]), abs=0)
        assert C.yaw(np.ascontiguousarray(Rm)) == lie.yaw(Rm)[0]
    assert np.allclose(lie.rpy(ROTATIONS[:20]), [pin.rpy.matrixToRpy(R) for R in ROTATIONS[:20]], atol=1e-10)
    # gimbal lock: pitch = pi/2, the heading goes to roll and the matrix is still reproduced
    R = pin.rpy.rpyToMatrix(0.3, np.pi / 2, 0.0)
    assert np.abs(pin.rpy.rpyToMatrix(*lie.rpy(R)[0]) - R).max() < 1e-9


def test_wrap_angle():
    a = np.array([-7.0, -np.pi, 0.0, np.pi, 3 * np.pi + 0.1])
    w = lie.wrap_angle(a)
    assert ((w >= -np.pi) & (w < np.pi)).all()
    assert np.allclose(np.cos(w), np.cos(a)) and np.allclose(np.sin(w), np.sin(a))
    assert C.wrap_angle(3 * np.pi + 0.1) == pytest.approx(w[-1])


def test_log6_exp6_jlog3_jlog6_batch_equal_pinocchio():
    rng = np.random.default_rng(7)
    keep = lie.angle(ROTATIONS) < np.pi - 1e-3  # Jlog3 / Jlog6 blow up at pi, where log is not differentiable
    R = ROTATIONS
    t = rng.standard_normal((R.shape[0], 3))
    xi = lie.log6(R, t)
    Rb, tb = lie.exp6(xi)
    assert np.abs(Rb - R).max() < 1e-12 and np.abs(tb - t).max() < 1e-12  # a logarithm of each pose
    for i in range(R.shape[0]):
        M = pin.SE3(R[i], t[i])
        e_ref = pin.log6(M).vector
        # Pinocchio computes 1 - cos(theta) with cancellation: near 1e-4 its values are ~1e-9 off (ours use
        # 2 sin^2(theta / 2)); at exactly pi the axis sign is a convention
        assert np.abs(xi[i] - e_ref).max() < 1e-8 or abs(lie.angle(R[i])[0] - np.pi) < 1e-6
        E = pin.exp6(pin.Motion(xi[i]))
        assert np.abs(Rb[i] - E.rotation).max() < 1e-12 and np.abs(tb[i] - E.translation).max() < 1e-12
    J3 = lie.jlog3(lie.log3(R[keep]))
    J6 = lie.jlog6(R[keep], t[keep])
    for k, i in enumerate(np.nonzero(keep)[0]):
        M = pin.SE3(R[i], t[i])
        D = _central_jlog6(M, lambda X: lie.log6(X.rotation, X.translation)[0])
        assert np.abs(J6[k] - D).max() < 1e-7
        assert np.abs(J3[k] - D[3:, 3:]).max() < 1e-7
        if lie.angle(R[i])[0] >= 1e-2:  # below ~1e-2 Pinocchio's own Jlog6 loses digits (see the kernel test)
            assert np.abs(J3[k] - pin.Jlog3(R[i])).max() < 1e-9
            assert np.abs(J6[k] - pin.Jlog6(M)).max() < 1e-9


@settings(max_examples=60, deadline=None)
@given(st.lists(st.floats(-1.0, 1.0), min_size=3, max_size=3), st.floats(0.0, np.pi))
def test_log3_exp3_round_trip_any_axis_and_angle(axis, theta):
    axis = np.array(axis)
    if np.linalg.norm(axis) < 1e-3:
        axis = np.array([0.0, 0.0, 1.0])
    phi = theta * axis / np.linalg.norm(axis)
    R = lie.exp3(phi)
    assert np.abs(R - pin.exp3(phi)).max() < 1e-12
    back = lie.log3(R)[0]
    assert abs(np.linalg.norm(back) - theta) < 1e-9
    assert np.abs(lie.exp3(back)[0] - R[0]).max() < 1e-12


def test_rotation_to_z():
    rng = np.random.default_rng(2)
    for axis in [np.array([0.0, 0.0, 1.0]), np.array([1.0, 0.0, 0.0]), np.array([0.0, 0.0, -2.0]),
                 *rng.standard_normal((10, 3))]:
        B = lie.rotation_to_z(axis)
        assert np.abs(B.T @ B - np.eye(3)).max() < 1e-12 and np.linalg.det(B) == pytest.approx(1.0)
        assert np.allclose(B[:, 2], axis / np.linalg.norm(axis))
    assert np.array_equal(lie.rotation_to_z([0.0, 0.0, 1.0]), np.eye(3))


# ---------------------------------------------------------------------- numba forms
def test_compiled_log3_log6_and_their_jacobians_equal_pinocchio_and_the_batch_forms():
    rng = np.random.default_rng(5)
    phi, e = np.empty(3), np.empty(6)
    A, B = np.empty((3, 3)), np.empty((3, 3))
    for Rm in ROTATIONS:
        Rm = np.ascontiguousarray(Rm)
        theta = C.log3(Rm, phi)
        ref = pin.log3(Rm)
        assert _same_log(phi, ref, theta)
        assert abs(theta - np.linalg.norm(ref)) < 1e-12
        assert np.abs(phi - lie.log3(Rm)[0]).max() < 1e-15
        assert np.abs(pin.exp3(phi) - Rm).max() < 1e-12
        if theta > np.pi - 1e-3:
            continue
        t = rng.standard_normal(3)
        M = pin.SE3(Rm, t)
        C.log6(Rm, t, e)
        assert np.abs(pin.exp6(pin.Motion(e)).homogeneous - M.homogeneous).max() < 1e-12
        assert np.abs(e - pin.log6(M).vector).max() < 1e-8
        assert np.abs(e - lie.log6(Rm, t)[0]).max() < 1e-14
        C.jlog3(theta, phi, A)
        C.jlog6(theta, phi, t, A, B)

        def log6_of(X):
            out = np.empty(6)
            C.log6(np.ascontiguousarray(X.rotation), X.translation.copy(), out)
            return out

        D = _central_jlog6(M, log6_of)
        assert np.abs(A - D[3:, 3:]).max() < 1e-7 and np.abs(A - D[:3, :3]).max() < 1e-7
        assert np.abs(B - D[:3, 3:]).max() < 1e-7 and np.abs(D[3:, :3]).max() < 1e-7
        J6 = lie.jlog6(Rm, t)[0]
        # the two forms sum B's terms in another order; just above the series threshold (theta ~ 1e-5) the
        # terms of Pinocchio's beta-dot cancel from ~1e17 to 1/360, so their roundings differ by ~1e-12
        assert np.abs(J6[:3, :3] - A).max() < 1e-12 and np.abs(J6[:3, 3:] - B).max() < 1e-10
        if theta >= 1e-2:
            Jl = pin.Jlog6(M)
            assert np.abs(A - pin.Jlog3(Rm)).max() < 1e-9
            assert np.abs(A - Jl[:3, :3]).max() < 1e-9 and np.abs(B - Jl[:3, 3:]).max() < 1e-9


@settings(max_examples=50, deadline=None)
@given(st.lists(st.floats(-10, 10), min_size=3, max_size=3), st.floats(1e-4, 0.5))
def test_is_rotation_accepts_rotations_and_refuses_the_rest(phi, scale):
    from evoik_pin.lie import is_rotation

    R = lie.exp3(np.array(phi))[0]
    assert is_rotation(R) and is_rotation(np.stack([R, R])).all()
    assert not is_rotation(R * (1.0 + scale))  # scaled
    assert not is_rotation(-R)  # a reflection: det -1
    bad = R.copy()
    bad[0, 0] = np.nan
    assert not is_rotation(bad)
    assert is_rotation(np.stack([R, bad])).tolist() == [True, False]
