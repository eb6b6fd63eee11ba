"""The folded kinematic tree evaluated in numba: joint poses, axes and origins, frame poses and frame Jacobians.

The robot layer exports the tree as constants (``Robot.tree_constants``, :mod:`evoik_pin.robot.tree`): the m
physical joints in topological order with their parents, each joint's placement in its parent's folded frame
(every joint axis turned onto z), and frames as (joint, folded placement) pairs (``Robot.frame_constants``).
Joint values x follow the joint vector q (n,) through the coupling of :mod:`.chain` (:func:`.chain.expand`,
:func:`.chain.fold`). For a serial chain (``parent[k] = k - 1``) these functions do the floating-point operations
of :func:`.chain.forward` and :func:`.chain.jacobian`, in the same order, so their results are identical bit for
bit (tests/test_robot_tree.py compares them on every bundled arm); tests check them against Pinocchio on the
example-robot-data trees, on random URDF trees, with mimic joints and with a floating base.
"""

from __future__ import annotations

import math

from numba import njit

__all__ = ["frame_jacobian", "frame_pose", "tree_forward"]


@njit(cache=True, nogil=True)
def tree_forward(parent, FR, Fp, rev, x, Rj, pj, Z, O):
    """Joint poses at the physical joint values x (m,): Rj (m, 3, 3), pj (m, 3) (m) the pose of each joint's folded
    frame after its motion, Z (m, 3) and O (m, 3) each joint's axis and origin, all in the base frame (written in
    place). ``(R_k, p_k) = (R_parent, p_parent) (FR[k], Fp[k]) Z(x_k)``; a root joint (parent -1) starts from
    (FR[k], Fp[k])."""
    m = x.shape[0]
    for k in range(m):
        a = parent[k]
        if a < 0:
            for i in range(3):
                pj[k, i] = Fp[k, i]
                for j in range(3):
                    Rj[k, i, j] = FR[k, i, j]
        else:
            f0, f1, f2 = Fp[k, 0], Fp[k, 1], Fp[k, 2]
            for i in range(3):
                r0, r1, r2 = Rj[a, i, 0], Rj[a, i, 1], Rj[a, i, 2]
                pj[k, i] = pj[a, i] + (r0 * f0 + r1 * f1 + r2 * f2)
                Rj[k, i, 0] = r0 * FR[k, 0, 0] + r1 * FR[k, 1, 0] + r2 * FR[k, 2, 0]
                Rj[k, i, 1] = r0 * FR[k, 0, 1] + r1 * FR[k, 1, 1] + r2 * FR[k, 2, 1]
                Rj[k, i, 2] = r0 * FR[k, 0, 2] + r1 * FR[k, 1, 2] + r2 * FR[k, 2, 2]
        for i in range(3):
            Z[k, i] = Rj[k, i, 2]
            O[k, i] = pj[k, i]
        if rev[k]:
            c, s = math.cos(x[k]), math.sin(x[k])
            for i in range(3):
                u, v = Rj[k, i, 0], Rj[k, i, 1]
                Rj[k, i, 0] = c * u + s * v
                Rj[k, i, 1] = c * v - s * u
        else:
            for i in range(3):
                pj[k, i] += x[k] * Rj[k, i, 2]


@njit(cache=True, nogil=True)
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


@njit(cache=True, nogil=True)
def frame_jacobian(rev, support, p, Z, O, J):
    """Base-frame Jacobian J (6, m) of a frame's origin p (3,) with respect to the physical joint values: the
    columns of the joints that move it (``support`` (m,) bool: the frame's joint and its ancestors) from their
    axes Z and origins O (m, 3), zero columns for the others."""
    m = Z.shape[0]
    for k in range(m):
        if not support[k]:
            for i in range(6):
                J[i, k] = 0.0
            continue
        z0, z1, z2 = Z[k, 0], Z[k, 1], Z[k, 2]
        if rev[k]:
            l0, l1, l2 = p[0] - O[k, 0], p[1] - O[k, 1], p[2] - O[k, 2]
            J[0, k] = z1 * l2 - z2 * l1
            J[1, k] = z2 * l0 - z0 * l2
            J[2, k] = z0 * l1 - z1 * l0
            J[3, k], J[4, k], J[5, k] = z0, z1, z2
        else:
            J[0, k], J[1, k], J[2, k] = z0, z1, z2
            J[3, k] = J[4, k] = J[5, k] = 0.0
