"""SO(3) / SE(3) maths compiled with numba, one rotation at a time into caller-owned buffers: :mod:`.so3`'s and
:mod:`.se3`'s closed forms (Pinocchio's), for compiled kernels (:mod:`evoik_pin.solvers.lm.kernel`)."""

from __future__ import annotations

import math

from numba import njit

from . import so3
from .so3 import NEAR_PI, PREC2, PREC3

__all__ = ["is_rotation_entries", "jlog3", "jlog6", "log3", "log6", "wrap_angle", "yaw"]

_TWO_PI = 2.0 * math.pi


#: :func:`.so3.is_rotation_entries` compiled (nine floats, row-major): the same operations, the same verdicts.
is_rotation_entries = njit(cache=True, nogil=True)(so3.is_rotation_entries)


@njit(cache=True, nogil=True, forceinline=False)
def wrap_angle(a):
    """The angle a (rad) wrapped into [-pi, pi)."""
    return (a + math.pi) % _TWO_PI - math.pi


@njit(cache=True, nogil=True, forceinline=False)
def yaw(R):
    """Heading (rad) of the rotation R (3, 3) about z: ``atan2(R[1, 0], R[0, 0])`` (see :func:`.so3.yaw`)."""
    return math.atan2(R[1, 0], R[0, 0])


@njit(cache=True, nogil=True, forceinline=False)
def log3(M, phi):
    """Rotation vector phi (3,) (rad) of the rotation M (3, 3), stable near 0 and near pi; returns the angle."""
    ax0, ax1, ax2 = M[2, 1] - M[1, 2], M[0, 2] - M[2, 0], M[1, 0] - M[0, 1]
    s = 0.5 * math.sqrt(ax0 * ax0 + ax1 * ax1 + ax2 * ax2)
    c = 0.5 * (M[0, 0] + M[1, 1] + M[2, 2] - 1.0)
    theta = math.atan2(s, c)
    if theta < math.pi - NEAR_PI:
        # theta / (2 sin theta), with its series near 0
        coef = 0.5 + theta * theta / 12.0 if s < 1e-8 else theta / (2.0 * s)
        phi[0], phi[1], phi[2] = coef * ax0, coef * ax1, coef * ax2
        return theta
    # near pi the antisymmetric part vanishes: the axis comes from the symmetric part,
    # a a^T = ((M + M^T) / 2 - cos I) / (1 - cos), its sign from the antisymmetric part
    omc = 1.0 - c
    d0, d1, d2 = (M[0, 0] - c) / omc, (M[1, 1] - c) / omc, (M[2, 2] - c) / omc
    if d0 >= d1 and d0 >= d2:
        a0 = math.sqrt(max(d0, 0.0))
        a1 = (M[0, 1] + M[1, 0]) / (2.0 * omc * a0)
        a2 = (M[0, 2] + M[2, 0]) / (2.0 * omc * a0)
    elif d1 >= d2:
        a1 = math.sqrt(max(d1, 0.0))
        a0 = (M[0, 1] + M[1, 0]) / (2.0 * omc * a1)
        a2 = (M[1, 2] + M[2, 1]) / (2.0 * omc * a1)
    else:
        a2 = math.sqrt(max(d2, 0.0))
        a0 = (M[0, 2] + M[2, 0]) / (2.0 * omc * a2)
        a1 = (M[1, 2] + M[2, 1]) / (2.0 * omc * a2)
    norm = math.sqrt(a0 * a0 + a1 * a1 + a2 * a2)
    if a0 * ax0 + a1 * ax1 + a2 * ax2 < 0.0:
        norm = -norm
    k = theta / norm
    phi[0], phi[1], phi[2] = k * a0, k * a1, k * a2
    return theta


@njit(cache=True, nogil=True, forceinline=False)
def jlog3(theta, w, A):
    """``pin.Jlog3``: A (3, 3), the derivative of ``log3(R exp(dw))`` at dw = 0, from ``w = log3(R)`` (angle
    theta): ``alpha w w^T + d I + [w]x / 2``."""
    if theta < PREC3:
        alpha = 1.0 / 12.0 + theta * theta / 720.0
        d = 0.5 * (2.0 - theta * theta / 6.0)
    else:
        st_1mct = 1.0 / math.tan(0.5 * theta)  # sin / (1 - cos), without the cancellation of 1 - cos
        alpha = 1.0 / (theta * theta) - st_1mct / (2.0 * theta)
        d = 0.5 * theta * st_1mct
    for i in range(3):
        for j in range(3):
            A[i, j] = alpha * w[i] * w[j]
        A[i, i] += d
    A[0, 1] -= 0.5 * w[2]  # + [w / 2]x (Pinocchio's addSkew(0.5 * w, A))
    A[1, 0] += 0.5 * w[2]
    A[0, 2] += 0.5 * w[1]
    A[2, 0] -= 0.5 * w[1]
    A[1, 2] -= 0.5 * w[0]
    A[2, 1] += 0.5 * w[0]


@njit(cache=True, nogil=True, forceinline=False)
def log6(M, t, e):
    """``pin.log6`` of the pose (M (3, 3), t (3,)): e (6,) = (v, w) with ``w = log3(M)``; returns the angle."""
    theta = log3(M, e[3:])
    w0, w1, w2 = e[3], e[4], e[5]
    if M[0, 0] + M[1, 1] + M[2, 2] >= 3.0 - PREC2:
        # Pinocchio's switch and series variable: the squared norm of the antisymmetric part (sin^2 theta)
        a0, a1, a2 = 0.5 * (M[2, 1] - M[1, 2]), 0.5 * (M[0, 2] - M[2, 0]), 0.5 * (M[1, 0] - M[0, 1])
        t2 = a0 * a0 + a1 * a1 + a2 * a2
        alpha = 1.0 - t2 / 12.0 - t2 * t2 / 720.0
        beta = 1.0 / 12.0 + t2 / 720.0
    else:
        st, sh = math.sin(theta), math.sin(0.5 * theta)
        omc = 2.0 * sh * sh  # 1 - cos(theta) without its cancellation near 0
        alpha = theta * st / (2.0 * omc)
        beta = 1.0 / (theta * theta) - st / (2.0 * theta * omc)
    wp = beta * (w0 * t[0] + w1 * t[1] + w2 * t[2])
    e[0] = alpha * t[0] - 0.5 * (w1 * t[2] - w2 * t[1]) + wp * w0
    e[1] = alpha * t[1] - 0.5 * (w2 * t[0] - w0 * t[2]) + wp * w1
    e[2] = alpha * t[2] - 0.5 * (w0 * t[1] - w1 * t[0]) + wp * w2
    return theta


@njit(cache=True, nogil=True, forceinline=False)
def jlog6(theta, w, t, A, B):
    """``pin.Jlog6`` of the pose whose log is (., w) (angle theta) and translation t (3,): the (6, 6) matrix
    ``[[A, B], [0, A]]`` as its blocks A = ``Jlog3`` and B (3, 3) (Pinocchio's formula)."""
    jlog3(theta, w, A)
    t2 = theta * theta
    if theta < PREC3:
        beta = 1.0 / 12.0 + t2 / 720.0
        beta_dot_over_theta = 1.0 / 360.0
    else:
        tinv = 1.0 / theta
        t2inv = tinv * tinv
        st, sh = math.sin(theta), math.sin(0.5 * theta)
        inv_2_2ct = 1.0 / (4.0 * sh * sh)  # 1 / (2 (1 - cos theta))
        beta = t2inv - st * tinv * inv_2_2ct
        beta_dot_over_theta = -2.0 * t2inv * t2inv + (1.0 + st * tinv) * t2inv * inv_2_2ct
    wTp = w[0] * t[0] + w[1] * t[1] + w[2] * t[2]
    h0, h1, h2 = 0.5 * t[0], 0.5 * t[1], 0.5 * t[2]
    for i in range(3):
        # row i of C = vi w^T + beta w_i t^T + wTp beta I + [t / 2]x (as three scalars: no array to allocate
        # per call), then row i of B = C A
        vi = beta_dot_over_theta * wTp * w[i] - (t2 * beta_dot_over_theta + 2.0 * beta) * t[i]
        c0 = vi * w[0] + beta * w[i] * t[0]
        c1 = vi * w[1] + beta * w[i] * t[1]
        c2 = vi * w[2] + beta * w[i] * t[2]
        if i == 0:
            c0 += wTp * beta
            c1 -= h2
            c2 += h1
        elif i == 1:
            c0 += h2
            c1 += wTp * beta
            c2 -= h0
        else:
            c0 -= h1
            c1 += h0
            c2 += wTp * beta
        for j in range(3):
            B[i, j] = c0 * A[0, j] + c1 * A[1, j] + c2 * A[2, j]
