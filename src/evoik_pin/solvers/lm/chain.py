"""The coupling ``x_k = scale_k q[index_k] + offset_k`` of the physical joint values to q (mimic joints) in numba:
:func:`expand` maps q to x, :func:`fold` the Jacobian columns of x to q's."""

from __future__ import annotations

from numba import njit

__all__ = ["coupled", "expand", "fold"]


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
