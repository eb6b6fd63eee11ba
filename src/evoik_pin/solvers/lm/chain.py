"""The folded serial chain in numba (``Robot.chain_constants``: ``T = F_0 Z(x_1) F_1 ... Z(x_m) F_m``, ``Z(x)`` a
rotation about or translation along z), and the coupling ``x_k = scale_k q[index_k] + offset_k`` of the physical
joint values to q (mimic joints): :func:`expand` maps q to x, :func:`fold` the Jacobian columns of x to q's."""

from __future__ import annotations

import math

from numba import njit

from .tree_kinematics import joint_column

__all__ = ["coupled", "expand", "fold", "forward", "jacobian"]


@njit(cache=True, nogil=True, forceinline=False)
def forward(FR, Fp, rev, q, R, p, Z, O):
    """Tip rotation R (3, 3) and position p (3,) at q (n,), and each joint's axis Z (n, 3) and origin O (n, 3),
    all in the base frame (written in place)."""
    n = q.shape[0]
    for i in range(3):
        p[i] = Fp[0, i]
        for j in range(3):
            R[i, j] = FR[0, i, j]
    for k in range(n):
        for i in range(3):
            Z[k, i] = R[i, 2]
            O[k, i] = p[i]
        if rev[k]:
            c, s = math.cos(q[k]), math.sin(q[k])
            for i in range(3):
                a, b = R[i, 0], R[i, 1]
                R[i, 0] = c * a + s * b
                R[i, 1] = c * b - s * a
        else:
            for i in range(3):
                p[i] += q[k] * R[i, 2]
        f0, f1, f2 = Fp[k + 1, 0], Fp[k + 1, 1], Fp[k + 1, 2]
        for i in range(3):
            r0, r1, r2 = R[i, 0], R[i, 1], R[i, 2]
            p[i] += r0 * f0 + r1 * f1 + r2 * f2
            R[i, 0] = r0 * FR[k + 1, 0, 0] + r1 * FR[k + 1, 1, 0] + r2 * FR[k + 1, 2, 0]
            R[i, 1] = r0 * FR[k + 1, 0, 1] + r1 * FR[k + 1, 1, 1] + r2 * FR[k + 1, 2, 1]
            R[i, 2] = r0 * FR[k + 1, 0, 2] + r1 * FR[k + 1, 1, 2] + r2 * FR[k + 1, 2, 2]


@njit(cache=True, nogil=True, forceinline=False)
def jacobian(rev, p, Z, O, J):
    """Base-frame Jacobian J (6, n) of the tip point p (3,) from the joint axes Z and origins O (n, 3)."""
    for k in range(Z.shape[0]):
        joint_column(rev[k], p, Z, O, k, J)


@njit(cache=True, nogil=True, forceinline=False)
def expand(index, scale, offset, q, x):
    """Physical joint values x (m,) of the joint vector q (n,): ``x[k] = scale[k] * q[index[k]] + offset[k]``
    (exactly q when index, scale, offset are the identity, ones and zeros)."""
    for k in range(x.shape[0]):
        x[k] = scale[k] * q[index[k]] + offset[k]


@njit(cache=True, nogil=True, forceinline=False)
def fold(index, scale, Jx, J):
    """Jacobian J (6, n) with respect to q from Jx (6, m) with respect to the physical values x: column
    index[k] of J gathers scale[k] times column k of Jx (exactly Jx for the identity coupling)."""
    for k in range(J.shape[1]):
        for i in range(6):
            J[i, k] = 0.0
    for k in range(Jx.shape[1]):
        c, s = index[k], scale[k]
        for i in range(6):
            J[i, c] += s * Jx[i, k]


@njit(cache=True, nogil=True, forceinline=False)
def coupled(index, scale, offset, n):
    """False when the coupling is the identity (m == n, x == q): kernels then skip :func:`expand` and :func:`fold`."""
    if index.shape[0] != n:
        return True
    for k in range(n):
        if index[k] != k or scale[k] != 1.0 or offset[k] != 0.0:
            return True
    return False
