"""The folded kinematic tree (``Robot.tree_constants``: the m physical joints in topological order, each joint's
placement in its parent's folded frame, every axis turned onto z) evaluated in numba: joint poses, axes and origins,
frame poses and Jacobians."""

from __future__ import annotations

import math

from numba import njit

__all__ = ["BORROWING", "frame_jacobian", "frame_pose", "joint_column", "tree_forward"]


def _borrowing_options() -> dict:
    """``{"_nrt": False}`` where this numba has that (undocumented) option, else ``{}``: the kernel then counts
    references as usual, with the same results, about a fifth slower."""
    try:
        from numba.core.cpu import CPUTargetOptions
    except ImportError:
        return {}
    return {"_nrt": False} if hasattr(CPUTargetOptions, "_nrt") else {}


#: Options of the functions that borrow the arrays their caller owns (see :mod:`.kernel`'s docstring).
BORROWING = _borrowing_options()


@njit(cache=True, nogil=True, forceinline=True, **BORROWING)
def tree_forward(parent, FR, Fp, rev, x, Rj, pj, Z, O):
    """Joint poses at the physical joint values x (m,), in the base frame: Rj (m, 3, 3), pj (m, 3) (m) each joint's
    folded frame after its motion, ``(R_parent, p_parent) (FR[k], Fp[k]) Z(x_k)`` (a root from (FR[k], Fp[k])), and
    Z, O (m, 3) its axis and origin. The pose being composed stays in locals, read back only where the tree branches."""
    m = x.shape[0]
    r00 = r01 = r02 = r10 = r11 = r12 = r20 = r21 = r22 = p0 = p1 = p2 = 0.0
    for k in range(m):
        a = parent[k]
        if a < 0:
            r00, r01, r02 = FR[k, 0, 0], FR[k, 0, 1], FR[k, 0, 2]
            r10, r11, r12 = FR[k, 1, 0], FR[k, 1, 1], FR[k, 1, 2]
            r20, r21, r22 = FR[k, 2, 0], FR[k, 2, 1], FR[k, 2, 2]
            p0, p1, p2 = Fp[k, 0], Fp[k, 1], Fp[k, 2]
        else:
            if a != k - 1:  # a branch: start from the parent's pose
                r00, r01, r02 = Rj[a, 0, 0], Rj[a, 0, 1], Rj[a, 0, 2]
                r10, r11, r12 = Rj[a, 1, 0], Rj[a, 1, 1], Rj[a, 1, 2]
                r20, r21, r22 = Rj[a, 2, 0], Rj[a, 2, 1], Rj[a, 2, 2]
                p0, p1, p2 = pj[a, 0], pj[a, 1], pj[a, 2]
            f0, f1, f2 = Fp[k, 0], Fp[k, 1], Fp[k, 2]
            a00, a01, a02 = FR[k, 0, 0], FR[k, 0, 1], FR[k, 0, 2]
            a10, a11, a12 = FR[k, 1, 0], FR[k, 1, 1], FR[k, 1, 2]
            a20, a21, a22 = FR[k, 2, 0], FR[k, 2, 1], FR[k, 2, 2]
            p0 += r00 * f0 + r01 * f1 + r02 * f2
            p1 += r10 * f0 + r11 * f1 + r12 * f2
            p2 += r20 * f0 + r21 * f1 + r22 * f2
            r00, r01, r02 = (r00 * a00 + r01 * a10 + r02 * a20, r00 * a01 + r01 * a11 + r02 * a21,
                             r00 * a02 + r01 * a12 + r02 * a22)
            r10, r11, r12 = (r10 * a00 + r11 * a10 + r12 * a20, r10 * a01 + r11 * a11 + r12 * a21,
                             r10 * a02 + r11 * a12 + r12 * a22)
            r20, r21, r22 = (r20 * a00 + r21 * a10 + r22 * a20, r20 * a01 + r21 * a11 + r22 * a21,
                             r20 * a02 + r21 * a12 + r22 * a22)
        Z[k, 0], Z[k, 1], Z[k, 2] = r02, r12, r22
        O[k, 0], O[k, 1], O[k, 2] = p0, p1, p2
        if rev[k]:
            c, s = math.cos(x[k]), math.sin(x[k])
            r00, r01 = c * r00 + s * r01, c * r01 - s * r00
            r10, r11 = c * r10 + s * r11, c * r11 - s * r10
            r20, r21 = c * r20 + s * r21, c * r21 - s * r20
        else:
            v = x[k]
            p0 += v * r02
            p1 += v * r12
            p2 += v * r22
        Rj[k, 0, 0], Rj[k, 0, 1], Rj[k, 0, 2] = r00, r01, r02
        Rj[k, 1, 0], Rj[k, 1, 1], Rj[k, 1, 2] = r10, r11, r12
        Rj[k, 2, 0], Rj[k, 2, 1], Rj[k, 2, 2] = r20, r21, r22
        pj[k, 0], pj[k, 1], pj[k, 2] = p0, p1, p2


@njit(cache=True, nogil=True, forceinline=True, **BORROWING)
def frame_pose(Rj, pj, j, Rf, pf, R, p):
    """Pose R (3, 3), p (3,) in the base frame of a frame at folded placement (Rf (3, 3), pf (3,)) on joint j
    (:func:`tree_forward`'s poses), or at the constant pose (Rf, pf) when j < 0 (written in place)."""
    if j < 0:
        for i in range(3):
            p[i] = pf[i]
            for c in range(3):
                R[i, c] = Rf[i, c]
        return
    f0, f1, f2 = pf[0], pf[1], pf[2]
    for i in range(3):
        r0, r1, r2 = Rj[j, i, 0], Rj[j, i, 1], Rj[j, i, 2]
        p[i] = pj[j, i] + (r0 * f0 + r1 * f1 + r2 * f2)
        R[i, 0] = r0 * Rf[0, 0] + r1 * Rf[1, 0] + r2 * Rf[2, 0]
        R[i, 1] = r0 * Rf[0, 1] + r1 * Rf[1, 1] + r2 * Rf[2, 1]
        R[i, 2] = r0 * Rf[0, 2] + r1 * Rf[1, 2] + r2 * Rf[2, 2]


@njit(cache=True, nogil=True, forceinline=True, **BORROWING)
def frame_jacobian(rev, support, p, Z, O, J):
    """Base-frame Jacobian J (6, m) of a frame's origin p (3,) with respect to the physical joint values: the
    columns of the joints that move it (``support`` (m,) bool: the frame's joint and its ancestors) from their
    axes Z and origins O (m, 3), zero columns for the others."""
    m = Z.shape[0]
    for k in range(m):
        if support[k]:
            joint_column(rev[k], p, Z, O, k, J)
        else:
            for i in range(6):
                J[i, k] = 0.0


@njit(cache=True, nogil=True, forceinline=True, **BORROWING)
def joint_column(revolute, p, Z, O, k, J):
    """Column k of the base-frame Jacobian J (6, m) of the point p (3,): joint k's axis Z[k] and origin O[k] give
    (z x (p - o), z) for a revolute joint, (z, 0) for a prismatic one."""
    z0, z1, z2 = Z[k, 0], Z[k, 1], Z[k, 2]
    if revolute:
        l0, l1, l2 = p[0] - O[k, 0], p[1] - O[k, 1], p[2] - O[k, 2]
        J[0, k] = z1 * l2 - z2 * l1
        J[1, k] = z2 * l0 - z0 * l2
        J[2, k] = z0 * l1 - z1 * l0
        J[3, k], J[4, k], J[5, k] = z0, z1, z2
    else:
        J[0, k], J[1, k], J[2, k] = z0, z1, z2
        J[3, k] = J[4, k] = J[5, k] = 0.0
