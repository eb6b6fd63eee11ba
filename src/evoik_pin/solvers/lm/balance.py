"""The compiled residuals and Jacobians of the goal kinds beyond one frame (the ``FAMILY_BEYOND_FRAME`` kinds of
:mod:`evoik_pin.goals.registry`), called by :func:`.kernel.task_error` and :func:`.kernel.task_jacobian`.

* Centre of mass: ``c(q) = (sum_k m_k (p_k + R_k c_k) + s_0) / M`` over the physical joints k (s_0 the first moment
  of the bodies no joint moves, M the total mass). Its Jacobian in one backward pass over the tree: with S_k the
  first moment of joint k's subtree and M_k its mass, column k is ``z_k x (S_k - M_k o_k) / M`` (revolute) or
  ``M_k z_k / M`` (prismatic). Rows of free axes are zero.
* Support polygon: the ground projection of c against the convex hull of the contact points (gift wrapping,
  counter-clockwise) shrunk by s = margin + tolerance (m); rows ``c_xy - proj(c_xy)``, zero inside, so a met goal
  puts c at least ``margin`` inside every edge.
* Relative pose: ``e = log6(T^-1 T_a^-1 T_b)``, Jacobian ``Jlog6 R_b^T (J_b(p_b) - J_a(p_b))``; with bands or free
  axes, the rows of :mod:`.axes`' pose with axes for frame b seen from frame a, from the same Jacobian difference
  in frame a's coordinates.
* Relative position: ``e = R_a^T (p_b - p_a) - p`` (frame a's axes; Jacobian ``R_a^T (J_b(p_b) - J_a(p_b))_v``) or
  ``(p_b - p_a) - p`` (the world's; ``J_b,v - J_a,v``, a joint moving both frames turning the vector).
"""

from __future__ import annotations

import math

from numba import njit

from ...goals import registry
from ...goals.bands import AUX_SIZE
from ...goals.center_of_mass import A_COM_AXES, A_COM_BODIES, A_COM_MASS, A_COM_MOMENT, A_COM_POINTS, A_COM_SHRINK
from ...goals.goal import A_REL_BAND, A_REL_JOINT, A_REL_P, A_REL_R, A_REL_SIGNS, BOTH
from ...goals.registry import COM_POINT, COM_SUPPORT, RELATIVE_BANDED_LOG6, RELATIVE_POINT_IN_A, RELATIVE_POINT_WORLD
from ...lie.compiled import log6
from .axes import axes_error, axes_jacobian
from .tree_kinematics import BORROWING, frame_pose, joint_column

#: Squared distance (m^2) under which two contact points are one; slopes below which two offset edges are parallel.
_SAME2, _PARALLEL = 1e-24, 1e-12
#: Added (m) to the error of a support goal whose shrunk polygon is empty or degenerate: never met.
EMPTY_POLYGON = 1.0
#: Codes of the support goal's active piece (kept in its tg row for the Jacobian).
_INSIDE, _EDGE, _VERTEX = 0.0, 1.0, 2.0


@njit(cache=True, nogil=True, forceinline=True, **BORROWING)
def com_position(Rj, pj, aux):
    """The centre of mass (x, y, z) (m, base frame) at the joint poses Rj (m, 3, 3), pj (m, 3)."""
    s0, s1, s2 = aux[A_COM_MOMENT], aux[A_COM_MOMENT + 1], aux[A_COM_MOMENT + 2]
    for k in range(Rj.shape[0]):
        b = A_COM_BODIES + 5 * k
        mk = aux[b]
        if mk != 0.0:
            c0, c1, c2 = aux[b + 1], aux[b + 2], aux[b + 3]
            s0 += mk * pj[k, 0] + Rj[k, 0, 0] * c0 + Rj[k, 0, 1] * c1 + Rj[k, 0, 2] * c2
            s1 += mk * pj[k, 1] + Rj[k, 1, 0] * c0 + Rj[k, 1, 1] * c1 + Rj[k, 1, 2] * c2
            s2 += mk * pj[k, 2] + Rj[k, 2, 0] * c0 + Rj[k, 2, 1] * c1 + Rj[k, 2, 2] * c2
    inv = 1.0 / aux[A_COM_MASS]
    return s0 * inv, s1 * inv, s2 * inv


@njit(cache=True, nogil=True, forceinline=True, **BORROWING)
def com_jacobian(parent, rev, Rj, pj, Z, O, aux, Jx):
    """Rows 0-2 of Jx (6, m): the centre of mass's Jacobian (m per rad or m per m) with respect to the physical
    joint values; rows 3-5 hold each subtree's first moment (scratch)."""
    m = parent.shape[0]
    for k in range(m):
        b = A_COM_BODIES + 5 * k
        mk, c0, c1, c2 = aux[b], aux[b + 1], aux[b + 2], aux[b + 3]
        for i in range(3):
            Jx[3 + i, k] = mk * pj[k, i] + Rj[k, i, 0] * c0 + Rj[k, i, 1] * c1 + Rj[k, i, 2] * c2
    for k in range(m - 1, -1, -1):  # a joint comes after its parent: its subtree is complete when reached
        a = parent[k]
        if a >= 0:
            for i in range(3):
                Jx[3 + i, a] += Jx[3 + i, k]
    inv = 1.0 / aux[A_COM_MASS]
    for k in range(m):
        mass = aux[A_COM_BODIES + 5 * k + 4]
        z0, z1, z2 = Z[k, 0], Z[k, 1], Z[k, 2]
        if rev[k]:
            l0 = (Jx[3, k] - mass * O[k, 0]) * inv
            l1 = (Jx[4, k] - mass * O[k, 1]) * inv
            l2 = (Jx[5, k] - mass * O[k, 2]) * inv
            Jx[0, k] = z1 * l2 - z2 * l1
            Jx[1, k] = z2 * l0 - z0 * l2
            Jx[2, k] = z0 * l1 - z1 * l0
        else:
            Jx[0, k], Jx[1, k], Jx[2, k] = z0 * mass * inv, z1 * mass * inv, z2 * mass * inv


@njit(cache=True, nogil=True, forceinline=True, **BORROWING)
def _contact(aux, base, i, Rj, pj):
    """Ground (x, y) (m) of contact point i (its aux entries from ``base``) at the joint poses Rj, pj."""
    o = base + 4 * i
    j = int(aux[o])
    l0, l1, l2 = aux[o + 1], aux[o + 2], aux[o + 3]
    if j < 0:
        return l0, l1
    return (pj[j, 0] + Rj[j, 0, 0] * l0 + Rj[j, 0, 1] * l1 + Rj[j, 0, 2] * l2,
            pj[j, 1] + Rj[j, 1, 0] * l0 + Rj[j, 1, 1] * l1 + Rj[j, 1, 2] * l2)


@njit(cache=True, nogil=True, forceinline=True, **BORROWING)
def _hull_next(aux, base, K, i, xi, yi, Rj, pj):
    """(index, x, y) of the hull vertex after vertex i (at xi, yi) counter-clockwise: the point with every other
    point on the left of the edge (of collinear ones the farthest); index -1 when every point coincides with i."""
    best, bx, by, bd = -1, 0.0, 0.0, 0.0
    for k in range(K):
        if k == i:
            continue
        x, y = _contact(aux, base, k, Rj, pj)
        dx, dy = x - xi, y - yi
        d = dx * dx + dy * dy
        if d <= _SAME2:
            continue
        if best < 0:
            best, bx, by, bd = k, x, y, d
            continue
        cr = (bx - xi) * dy - (by - yi) * dx
        if cr < 0.0 or (cr == 0.0 and d > bd):
            best, bx, by, bd = k, x, y, d
    return best, bx, by


@njit(cache=True, nogil=True, forceinline=True, **BORROWING)
def support_error(Rj, pj, aux, cx, cy, e, tg):
    """The support goal's 2 rows e = c_xy - (nearest point of the shrunk hull) for the CoM's ground point (cx, cy);
    returns the distance (m). tg (3,) keeps the active piece (code, outward normal) for :func:`com_rows`."""
    m = Rj.shape[0]
    K = int(aux[A_COM_POINTS])
    base = A_COM_BODIES + 5 * m
    s = aux[A_COM_SHRINK]
    i0, x0, y0 = 0, 0.0, 0.0  # the contact point with the least x (then y): a vertex of the hull
    for i in range(K):
        x, y = _contact(aux, base, i, Rj, pj)
        if i == 0 or x < x0 or (x == x0 and y < y0):
            i0, x0, y0 = i, x, y
    # pass 1: the largest violation of the shrunk edges' half-planes n.x <= n.P - s, and the hull's size
    worst = -1e300
    edges = 0
    i, xi, yi = i0, x0, y0
    mx, my = 0.0, 0.0
    while edges <= K:
        j, xj, yj = _hull_next(aux, base, K, i, xi, yi, Rj, pj)
        if j < 0:
            break
        L = math.sqrt((xj - xi) ** 2 + (yj - yi) ** 2)
        n0, n1 = (yj - yi) / L, -(xj - xi) / L
        worst = max(worst, n0 * (cx - xi) + n1 * (cy - yi) + s)
        mx += xi
        my += yi
        edges += 1
        i, xi, yi = j, xj, yj
        if i == i0:
            break
    if edges >= 3 and worst <= 0.0:
        e[0] = e[1] = 0.0
        tg[0] = _INSIDE
        return 0.0
    # pass 2: the nearest point over the shrunk edges, each clipped by every other edge's half-plane
    best = -1.0
    bx = by = bn0 = bn1 = 0.0
    code = _VERTEX
    if edges >= 3:
        i, xi, yi = i0, x0, y0
        for _ in range(edges):
            j, xj, yj = _hull_next(aux, base, K, i, xi, yi, Rj, pj)
            L = math.sqrt((xj - xi) ** 2 + (yj - yi) ** 2)
            u0, u1 = (xj - xi) / L, (yj - yi) / L
            n0, n1 = u1, -u0
            a0, a1 = xi - s * n0, yi - s * n1  # a point of the shrunk edge's line
            lo, hi = -1e300, 1e300
            feasible = True
            f, xf, yf = i0, x0, y0
            for _ in range(edges):
                g, xg, yg = _hull_next(aux, base, K, f, xf, yf, Rj, pj)
                if f != i:
                    Lf = math.sqrt((xg - xf) ** 2 + (yg - yf) ** 2)
                    m0, m1 = (yg - yf) / Lf, -(xg - xf) / Lf
                    den = m0 * u0 + m1 * u1
                    rhs = m0 * (xf - a0) + m1 * (yf - a1) - s
                    if abs(den) < _PARALLEL:
                        if rhs < -_PARALLEL:
                            feasible = False
                    elif den > 0.0:
                        hi = min(hi, rhs / den)
                    else:
                        lo = max(lo, rhs / den)
                f, xf, yf = g, xg, yg
            if feasible and lo <= hi:
                t0 = u0 * (cx - a0) + u1 * (cy - a1)
                t = min(max(t0, lo), hi)
                px, py = a0 + t * u0, a1 + t * u1
                d = (cx - px) ** 2 + (cy - py) ** 2
                if best < 0.0 or d < best:
                    best, bx, by, bn0, bn1 = d, px, py, n0, n1
                    code = _EDGE if lo < t0 < hi else _VERTEX
            i, xi, yi = j, xj, yj
    extra = 0.0
    if best < 0.0:  # an empty (margin too large) or degenerate polygon: towards its vertices' mean, never met
        bx, by = mx / max(edges, 1), my / max(edges, 1)
        if edges == 0:
            bx, by = x0, y0
        code = _VERTEX
        extra = EMPTY_POLYGON
    e[0], e[1] = cx - bx, cy - by
    tg[0], tg[1], tg[2] = code, bn0, bn1
    return math.sqrt(e[0] * e[0] + e[1] * e[1]) + extra


@njit(cache=True, nogil=True, forceinline=True, **BORROWING)
def frame_a_origin(Rj, pj, aux):
    """Frame a's origin (m, base frame) of a two-frame goal's aux row at the joint poses Rj (m, 3, 3), pj (m, 3)."""
    ja = int(aux[A_REL_JOINT])
    f0, f1, f2 = aux[A_REL_P], aux[A_REL_P + 1], aux[A_REL_P + 2]
    if ja < 0:
        return f0, f1, f2
    return (pj[ja, 0] + Rj[ja, 0, 0] * f0 + Rj[ja, 0, 1] * f1 + Rj[ja, 0, 2] * f2,
            pj[ja, 1] + Rj[ja, 1, 0] * f0 + Rj[ja, 1, 1] * f1 + Rj[ja, 1, 2] * f2,
            pj[ja, 2] + Rj[ja, 2, 0] * f0 + Rj[ja, 2, 1] * f1 + Rj[ja, 2, 2] * f2)


@njit(cache=True, nogil=True, forceinline=True, **BORROWING)
def frame_a_pose(Rj, pj, aux, M):
    """Frame a's rotation (base frame) into M (3, 3) and its origin (m, :func:`frame_a_origin`) returned."""
    ja = int(aux[A_REL_JOINT])
    for i in range(3):
        for c in range(3):
            M[i, c] = aux[A_REL_R + 3 * i + c] if ja < 0 else (
                Rj[ja, i, 0] * aux[A_REL_R + c] + Rj[ja, i, 1] * aux[A_REL_R + 3 + c]
                + Rj[ja, i, 2] * aux[A_REL_R + 6 + c])
    return frame_a_origin(Rj, pj, aux)


@njit(cache=True, nogil=True, forceinline=True, **BORROWING)
def relative_error(Rj, pj, aux, jb, Rbf, pbf, pt, Rt, Rb, pb, M, t, e):
    """The relative pose goal's 6 rows ``e = log6(T_t^-1 T_a^-1 T_b)``, frame b (joint jb, folded placement Rbf, pbf)
    into Rb, pb and ``T_t^-1 T_a^-1 T_b`` into M, t; returns (position error m, rotation angle rad)."""
    pa0, pa1, pa2 = frame_a_pose(Rj, pj, aux, M)
    frame_pose(Rj, pj, jb, Rbf, pbf, Rb, pb)  # frame b's pose, as a one-frame goal's
    # W = R_a R_t row by row (in place in M); then M = W^T R_b and t = W^T (p_b - p_a) - R_t^T p_t
    for i in range(3):
        w0 = M[i, 0] * Rt[0, 0] + M[i, 1] * Rt[1, 0] + M[i, 2] * Rt[2, 0]
        w1 = M[i, 0] * Rt[0, 1] + M[i, 1] * Rt[1, 1] + M[i, 2] * Rt[2, 1]
        w2 = M[i, 0] * Rt[0, 2] + M[i, 1] * Rt[1, 2] + M[i, 2] * Rt[2, 2]
        M[i, 0], M[i, 1], M[i, 2] = w0, w1, w2
    d0, d1, d2 = pb[0] - pa0, pb[1] - pa1, pb[2] - pa2
    for i in range(3):
        t[i] = (M[0, i] * d0 + M[1, i] * d1 + M[2, i] * d2) - (Rt[0, i] * pt[0] + Rt[1, i] * pt[1] + Rt[2, i] * pt[2])
    w00, w01, w02 = M[0, 0], M[0, 1], M[0, 2]
    w10, w11, w12 = M[1, 0], M[1, 1], M[1, 2]
    w20, w21, w22 = M[2, 0], M[2, 1], M[2, 2]
    for c in range(3):
        b0, b1, b2 = Rb[0, c], Rb[1, c], Rb[2, c]
        M[0, c] = w00 * b0 + w10 * b1 + w20 * b2
        M[1, c] = w01 * b0 + w11 * b1 + w21 * b2
        M[2, c] = w02 * b0 + w12 * b1 + w22 * b2
    pos = math.sqrt(t[0] * t[0] + t[1] * t[1] + t[2] * t[2])
    rot = log6(M, t, e)
    return pos, rot


@njit(cache=True, nogil=True, forceinline=True, **BORROWING)
def relative_axes_error(Rj, pj, aux, jb, Rbf, pbf, pt, Rt, R, p, M, t, e):
    """The 6 rows e of a relative pose with bands or free axes: :func:`.axes.axes_error`'s ``BANDED_LOG6`` rows for
    ``R = R_a^T R_b``, ``t = R_a^T (p_b - p_a)`` (written to R, t); p ends as frame b's origin (m); M scratch."""
    pa0, pa1, pa2 = frame_a_pose(Rj, pj, aux, M)
    frame_pose(Rj, pj, jb, Rbf, pbf, R, p)
    d0, d1, d2 = p[0] - pa0, p[1] - pa1, p[2] - pa2
    for i in range(3):
        t[i] = M[0, i] * d0 + M[1, i] * d1 + M[2, i] * d2
    for c in range(3):  # R = R_a^T R_b, column by column in place
        b0, b1, b2 = R[0, c], R[1, c], R[2, c]
        for i in range(3):
            p[i] = M[0, i] * b0 + M[1, i] * b1 + M[2, i] * b2
        R[0, c], R[1, c], R[2, c] = p[0], p[1], p[2]
    band = aux[A_REL_BAND:A_REL_BAND + AUX_SIZE]
    c, pos, rot = axes_error(registry.BANDED_LOG6, R, t, pt, Rt, band, M, p, e)  # p as axes_error's scratch
    frame_pose(Rj, pj, jb, Rbf, pbf, M, p)  # frame b's origin again (M: scratch)
    return c, pos, rot


@njit(cache=True, nogil=True, forceinline=True, **BORROWING)
def relative_axes_jacobian(Rj, pj, aux, R, t, J, pt, Rt, rv, A, B, E, r):
    """Rows r.. of the task Jacobian E (unweighted) of a relative pose with bands or free axes: those of
    :func:`.axes.axes_jacobian` for :func:`relative_axes_error`'s R, t from ``J_b(p_b) - J_a(p_b)`` (6, n) turned
    in place into frame a's axes. rv, A, B scratch."""
    frame_a_pose(Rj, pj, aux, A)
    for k in range(J.shape[1]):  # J <- diag(R_a^T, R_a^T) J
        v0, v1, v2 = J[0, k], J[1, k], J[2, k]
        w0, w1, w2 = J[3, k], J[4, k], J[5, k]
        for i in range(3):
            J[i, k] = A[0, i] * v0 + A[1, i] * v1 + A[2, i] * v2
            J[3 + i, k] = A[0, i] * w0 + A[1, i] * w1 + A[2, i] * w2
    axes_jacobian(registry.BANDED_LOG6, R, t, J, pt, Rt, aux[A_REL_BAND:A_REL_BAND + AUX_SIZE], rv, A, B, E, r)


@njit(cache=True, nogil=True, forceinline=True, **BORROWING)
def relative_point_error(kind, Rj, pj, aux, jb, Rbf, pbf, pt, R, p, M, e):
    """The relative position goal's 3 rows e (see the module docstring; in frame a's axes for
    ``RELATIVE_POINT_IN_A``): frame b's pose into R (3, 3), p (3,) (its origin for :func:`balance_columns`);
    M (3, 3) ends as frame a's rotation. Returns (|e|^2, position error m, 0)."""
    pa0, pa1, pa2 = frame_a_pose(Rj, pj, aux, M)
    frame_pose(Rj, pj, jb, Rbf, pbf, R, p)
    d0, d1, d2 = p[0] - pa0, p[1] - pa1, p[2] - pa2
    c = 0.0
    for i in range(3):
        if kind == RELATIVE_POINT_IN_A:
            e[i] = M[0, i] * d0 + M[1, i] * d1 + M[2, i] * d2 - pt[i]
        else:
            e[i] = (d0 if i == 0 else (d1 if i == 1 else d2)) - pt[i]
        c += e[i] * e[i]
    return c, math.sqrt(c), 0.0


@njit(cache=True, nogil=True, forceinline=True, **BORROWING)
def relative_point_columns(rev, Rj, pj, Z, O, aux, p, Jx):
    """Rows 0-2 of Jx (6, m): ``J_b,v - J_a,v`` of a relative position in the world's axes, frame b's origin p (3,)
    and frame a's from its aux row: per joint k by its sign, its column at p_b (+1), minus its column at p_a (-1),
    or ``z x (p_b - p_a)`` (:data:`~evoik_pin.goals.goal.BOTH`; 0 for a prismatic joint)."""
    pa0, pa1, pa2 = frame_a_origin(Rj, pj, aux)
    for k in range(Jx.shape[1]):
        sign = aux[A_REL_SIGNS + k]
        if sign > 0.0 and sign != BOTH:
            joint_column(rev[k], p, Z, O, k, Jx)
            continue
        for i in range(6):
            Jx[i, k] = 0.0
        z0, z1, z2 = Z[k, 0], Z[k, 1], Z[k, 2]
        if sign == BOTH and rev[k]:
            l0, l1, l2 = p[0] - pa0, p[1] - pa1, p[2] - pa2
            Jx[0, k] = z1 * l2 - z2 * l1
            Jx[1, k] = z2 * l0 - z0 * l2
            Jx[2, k] = z0 * l1 - z1 * l0
        elif sign < 0.0 and rev[k]:
            l0, l1, l2 = pa0 - O[k, 0], pa1 - O[k, 1], pa2 - O[k, 2]
            Jx[0, k] = -(z1 * l2 - z2 * l1)
            Jx[1, k] = -(z2 * l0 - z0 * l2)
            Jx[2, k] = -(z0 * l1 - z1 * l0)
        elif sign < 0.0:
            Jx[0, k], Jx[1, k], Jx[2, k] = -z0, -z1, -z2


@njit(cache=True, nogil=True, forceinline=True, **BORROWING)
def relative_point_rows(kind, Rj, pj, aux, J, A, E, r):
    """Rows r..r+2 of the task Jacobian E (unweighted) of a relative position from rows 0-2 of J (6, n)
    (:func:`balance_columns`): as they are in the world's axes, turned by R_a^T in frame a's. A (3, 3) scratch."""
    n = E.shape[1]
    if kind == RELATIVE_POINT_WORLD:
        for i in range(3):
            for k in range(n):
                E[r + i, k] = J[i, k]
        return
    frame_a_pose(Rj, pj, aux, A)
    for k in range(n):
        v0, v1, v2 = J[0, k], J[1, k], J[2, k]
        for i in range(3):
            E[r + i, k] = A[0, i] * v0 + A[1, i] * v1 + A[2, i] * v2


@njit(cache=True, nogil=True, forceinline=True, **BORROWING)
def balance_error(kind, Rj, pj, aux, jf, Rf, pf, pt, Rt, R, p, M, t, e):
    """Rows e of a goal of a kind beyond one frame; returns (|e|^2, position error m, orientation error rad or 0).
    R (3, 3), p (3,), t (3,): the goal's pose buffers, as each kind's function fills them."""
    if kind == COM_POINT:
        c0, c1, c2 = com_position(Rj, pj, aux)
        p[0], p[1], p[2] = c0, c1, c2
        e[0] = aux[A_COM_AXES] * (c0 - pt[0])
        e[1] = aux[A_COM_AXES + 1] * (c1 - pt[1])
        e[2] = aux[A_COM_AXES + 2] * (c2 - pt[2])
        c = e[0] * e[0] + e[1] * e[1] + e[2] * e[2]
        return c, math.sqrt(c), 0.0
    if kind == COM_SUPPORT:
        c0, c1, c2 = com_position(Rj, pj, aux)
        p[0], p[1], p[2] = c0, c1, c2
        pos = support_error(Rj, pj, aux, c0, c1, e, t)
        return e[0] * e[0] + e[1] * e[1], pos, 0.0
    if kind == RELATIVE_BANDED_LOG6:
        return relative_axes_error(Rj, pj, aux, jf, Rf, pf, pt, Rt, R, p, M, t, e)
    if kind == RELATIVE_POINT_WORLD or kind == RELATIVE_POINT_IN_A:
        return relative_point_error(kind, Rj, pj, aux, jf, Rf, pf, pt, R, p, M, e)
    pos, rot = relative_error(Rj, pj, aux, jf, Rf, pf, pt, Rt, R, p, M, t, e)
    c = 0.0
    for i in range(6):
        c += e[i] * e[i]
    return c, pos, rot


@njit(cache=True, nogil=True, forceinline=True, **BORROWING)
def balance_columns(kind, parent, rev, Rj, pj, Z, O, aux, p, Jx):
    """The physical Jacobian Jx (6, m) a goal of a kind beyond one frame starts from: the centre of mass's (rows
    0-2, :func:`com_jacobian`) or, for a relative pose, ``J_b(p_b) - J_a(p_b)`` at frame b's origin p (3,)."""
    if kind == COM_POINT or kind == COM_SUPPORT:
        com_jacobian(parent, rev, Rj, pj, Z, O, aux, Jx)
        return
    if kind == RELATIVE_POINT_WORLD:
        relative_point_columns(rev, Rj, pj, Z, O, aux, p, Jx)
        return
    for k in range(Jx.shape[1]):
        sign = aux[A_REL_SIGNS + k]
        if sign == 0.0:
            for i in range(6):
                Jx[i, k] = 0.0
        else:
            joint_column(rev[k], p, Z, O, k, Jx)
            if sign < 0.0:
                for i in range(6):
                    Jx[i, k] = -Jx[i, k]


@njit(cache=True, nogil=True, forceinline=True, **BORROWING)
def com_rows(kind, aux, t, J, E, r):
    """Rows r.. of the task Jacobian E (unweighted) of a CoM goal from the CoM's Jacobian (rows 0-2 of J (6, n)):
    the constrained axes (COM_POINT), or the support goal's active piece (t: code, outward normal): zero inside,
    ``n n^T`` on an edge, the ground rows at a vertex."""
    n = E.shape[1]
    if kind == COM_POINT:
        for i in range(3):
            a = aux[A_COM_AXES + i]
            for k in range(n):
                E[r + i, k] = a * J[i, k]
        return
    code, n0, n1 = t[0], t[1], t[2]
    for k in range(n):
        if code == _INSIDE:
            E[r, k] = E[r + 1, k] = 0.0
        elif code == _EDGE:
            d = n0 * J[0, k] + n1 * J[1, k]
            E[r, k], E[r + 1, k] = n0 * d, n1 * d
        else:
            E[r, k], E[r + 1, k] = J[0, k], J[1, k]


@njit(cache=True, nogil=True, forceinline=True, **BORROWING)
def balance_rows(kind, Rj, pj, aux, R, p, t, J, pt, Rt, rv, A, B, E, r):
    """Rows r.. of the task Jacobian E (unweighted) of a goal beyond one frame other than a plain relative pose, from
    :func:`balance_columns`' J (folded); R, p, t: :func:`balance_error`'s buffers; rv (3,), A, B (3, 3) scratch."""
    if kind == RELATIVE_BANDED_LOG6:
        relative_axes_jacobian(Rj, pj, aux, R, t, J, pt, Rt, rv, A, B, E, r)
    elif kind == RELATIVE_POINT_WORLD or kind == RELATIVE_POINT_IN_A:
        relative_point_rows(kind, Rj, pj, aux, J, A, E, r)
    else:
        com_rows(kind, aux, t, J, E, r)
