"""The Levenberg-Marquardt engine's compiled kernel (numba): whole LM runs (the iteration: :mod:`.engine`), one call
each, :class:`.reference.ReferenceLM`'s loop line for line. The frame family's rows are here (:func:`goal_error`), the
others' in :mod:`.axes` and :mod:`.balance`. Arguments travel in groups: ``kin`` (``Robot.tree_constants()``),
``goals`` (``GoalStack.arrays``), the targets (pt (G, 3), Rt (G, 3, 3)) and the :data:`Workspace`; two variants
(:func:`_run`), two entries each (:data:`Entries`; :func:`entries_for`).

Editing rules: compiled functions take :data:`BORROWING` (``_nrt=False``: no reference counting, a fifth of the run
time, so a helper that allocates fails to compile); the per-step helpers are inlined by LLVM (``forceinline=True``;
numba's ``inline="always"`` compiles far slower) and every other function says ``forceinline=False``, as callees
inherit the flag; numba's disk cache keys an entry on its own file: after editing an inlined helper in another file,
delete the kernel's cached ``*.nbi`` / ``*.nbc``.
"""

from __future__ import annotations

import math
from collections import namedtuple

import numpy as np
from numba import njit

from ...goals import registry
from ...goals.registry import FAMILY_AXES, FAMILY_BEYOND_FRAME, LOG6, PLANAR, PLANAR_YAW, POINT, RELATIVE_LOG6
from ...goals.stack import G_ANGLE, G_FAMILY, G_JOINT, G_KIND, G_ROW, G_ROWS, G_RTOL, G_TOL, G_WEIGHT
from ...lie.compiled import jlog6, log6, wrap_angle, yaw
from . import layout
from .axes import axes_error, axes_jacobian
from .balance import balance_columns, balance_error, balance_rows
from .chain import coupled, expand, fold
from .layout import B_CHI, B_CLO, B_HI, B_LO, B_WRAP, LAMBDA_MIN, P_ITERATIONS, TWO_PI
from .tree_kinematics import BORROWING, frame_jacobian, frame_pose, tree_forward


@njit(cache=True, nogil=True, forceinline=True)
def frame_rows(kind):
    """Rows of :func:`goal_error`'s residuals (6 pose, 2 planar, 3 point or planar with yaw, as the kinds declare
    them): :func:`lm_run_basic` reads them here rather than from ``G_ROWS`` so that LLVM unrolls the rows' loops."""
    return 6 if kind == LOG6 else (2 if kind == PLANAR else 3)


@njit(cache=True, nogil=True, forceinline=True, **BORROWING)
def goal_error(kind, R, p, pt, Rt, M, t, e):
    """One goal's error rows e (its ``G_ROWS`` rows) for its frame's pose (R (3, 3), p (3,)) and target
    (pt, Rt); returns (|e|^2, position error m, orientation error rad or 0). For pose goals also the frame pose
    seen from the target, ``T_t^-1 T_f`` = (M (3, 3), t (3,)), which :func:`goal_jacobian` needs."""
    if kind == PLANAR or kind == PLANAR_YAW:  # (x, y[, yaw]) with pt = (x_t, y_t, yaw_t)
        d0, d1 = p[0] - pt[0], p[1] - pt[1]
        e[0], e[1] = d0, d1
        pos = math.sqrt(d0 * d0 + d1 * d1)
        if kind != PLANAR_YAW:
            return d0 * d0 + d1 * d1, pos, 0.0
        dyaw = wrap_angle(yaw(R) - pt[2])
        e[2] = dyaw
        return d0 * d0 + d1 * d1 + dyaw * dyaw, pos, abs(dyaw)
    d0, d1, d2 = p[0] - pt[0], p[1] - pt[1], p[2] - pt[2]
    pos = math.sqrt(d0 * d0 + d1 * d1 + d2 * d2)
    if kind == POINT:
        e[0], e[1], e[2] = d0, d1, d2
        return pos * pos, pos, 0.0
    for i in range(3):
        t[i] = Rt[0, i] * d0 + Rt[1, i] * d1 + Rt[2, i] * d2  # R_t^T (p - p_t)
        for j in range(3):
            M[i, j] = Rt[0, i] * R[0, j] + Rt[1, i] * R[1, j] + Rt[2, i] * R[2, j]  # R_t^T R
    rot = log6(M, t, e)
    c = 0.0
    for i in range(6):
        c += e[i] * e[i]
    return c, pos, rot


@njit(cache=True, nogil=True, forceinline=True, **BORROWING)
def task_error(extra, kin, mimic, goals, weighted, pt, Rt, q, s, ws):
    """Stacked task error ``s.e`` (rows,) at q (n,) for the targets pt (G, 3), Rt (G, 3, 3); returns the weighted
    |e|^2, writes each goal's (position error m, orientation error rad or 0) to ``s.ge`` and fills the rest of the
    :data:`State` s for :func:`task_jacobian` (with ``mimic``, :func:`.chain.expand`'s values in ``ws.x`` first).
    ``weighted``: some goal's weight is not 1 (scaled in a second pass, keeping the goal loop free of it). ``extra``:
    :func:`_run`'s."""
    parent, FR, Fp, rev, index, scale, offset = kin
    spec, gR, gp, _, gaux = goals
    Rj, pj, Rg, pg, tg, e, ge, M = s.Rj, s.pj, s.Rg, s.pg, s.tg, s.e, s.ge, ws.M
    if mimic:
        expand(index, scale, offset, q, ws.x)
        tree_forward(parent, FR, Fp, rev, ws.x, Rj, pj, s.Z, s.O)
    else:
        tree_forward(parent, FR, Fp, rev, q, Rj, pj, s.Z, s.O)
    c = 0.0
    for g in range(spec.shape[0]):
        kind = int(spec[g, G_KIND])
        r = int(spec[g, G_ROW])
        rows = int(spec[g, G_ROWS]) if extra is not None else frame_rows(kind)  # frame_rows says why
        R, p = Rg[g], pg[g]
        if extra is not None and int(spec[g, G_FAMILY]) == FAMILY_BEYOND_FRAME:
            cg, pos, rot = beyond_frame_error(kind, Rj, pj, gaux[g], int(spec[g, G_JOINT]), gR[g], gp[g], pt[g], Rt[g],
                                              R, p, M, tg[g], e[r:r + rows])
        else:
            frame_pose(Rj, pj, int(spec[g, G_JOINT]), gR[g], gp[g], R, p)
            # .axes's kinds (tg[g], unused by them, as scratch)
            if extra is not None and int(spec[g, G_FAMILY]) == FAMILY_AXES:
                cg, pos, rot = axes_error(kind, R, p, pt[g], Rt[g], gaux[g], M, tg[g], e[r:r + rows])
            else:
                cg, pos, rot = goal_error(kind, R, p, pt[g], Rt[g], M, tg[g], e[r:r + rows])
        c += cg
        ge[g, 0], ge[g, 1] = pos, rot
    if weighted:
        c = 0.0
        for g in range(spec.shape[0]):
            r = int(spec[g, G_ROW])
            w = spec[g, G_WEIGHT]
            for i in range(r, r + (int(spec[g, G_ROWS]) if extra is not None else frame_rows(int(spec[g, G_KIND])))):
                e[i] *= w
                c += e[i] * e[i]
    return c


@njit(cache=True, nogil=True, forceinline=True, **BORROWING)
def within(spec, ge):
    """True when every goal's errors ge (G, 2) are within its tolerances (a NaN error is not)."""
    for g in range(spec.shape[0]):
        if not (ge[g, 0] <= spec[g, G_TOL] and ge[g, 1] <= spec[g, G_RTOL]):
            return False
    return True


@njit(cache=True, nogil=True, forceinline=True, **BORROWING)
def goal_jacobian(kind, R, J, t, e, w, rv, A, B, E, r):
    """One goal's rows r.. of the task Jacobian E (unweighted) from its frame's base-frame Jacobian J (6, n) and the
    buffers :func:`goal_error` filled (R; e scaled by w; t). Position: J's translational rows; planar: vx, vy[, wz];
    pose: ``Jlog6(T_t^-1 T_f) (R^T J_v, R^T J_w)``, Jlog6 at rv (3,) = e[3:] / w. A, B (3, 3) scratch."""
    n = J.shape[1]
    if kind != LOG6:
        for i in range(frame_rows(kind)):
            row = 5 if i == 2 and kind == PLANAR_YAW else i
            for k in range(n):
                E[r + i, k] = J[row, k]
        return
    for i in range(3):
        rv[i] = e[3 + i] / w  # exactly e[3 + i] at weight 1
    theta = math.sqrt(rv[0] * rv[0] + rv[1] * rv[1] + rv[2] * rv[2])
    jlog6(theta, rv, t, A, B)
    for k in range(n):
        v0 = R[0, 0] * J[0, k] + R[1, 0] * J[1, k] + R[2, 0] * J[2, k]  # R^T J_v
        v1 = R[0, 1] * J[0, k] + R[1, 1] * J[1, k] + R[2, 1] * J[2, k]
        v2 = R[0, 2] * J[0, k] + R[1, 2] * J[1, k] + R[2, 2] * J[2, k]
        w0 = R[0, 0] * J[3, k] + R[1, 0] * J[4, k] + R[2, 0] * J[5, k]  # R^T J_w
        w1 = R[0, 1] * J[3, k] + R[1, 1] * J[4, k] + R[2, 1] * J[5, k]
        w2 = R[0, 2] * J[3, k] + R[1, 2] * J[4, k] + R[2, 2] * J[5, k]
        for i in range(3):
            E[r + i, k] = A[i, 0] * v0 + A[i, 1] * v1 + A[i, 2] * v2 + B[i, 0] * w0 + B[i, 1] * w1 + B[i, 2] * w2
            E[r + 3 + i, k] = A[i, 0] * w0 + A[i, 1] * w1 + A[i, 2] * w2


@njit(cache=True, nogil=True, forceinline=True, **BORROWING)
def task_jacobian(extra, kin, mimic, goals, weighted, pt, Rt, s, ws, E):
    """Stacked task Jacobian E (rows, n) from the :data:`State` s :func:`task_error` filled for the same
    configuration and targets, scaled as it scales the rows. Scratch: ws's Jx, J, rv, A, Bm."""
    parent, _, _, rev, index, scale, _ = kin
    spec, _, _, support, gaux = goals
    Rg, pg, Z, O, tg, e = s.Rg, s.pg, s.Z, s.O, s.tg, s.e
    Jx, J, rv, A, B = ws.Jx, ws.J, ws.rv, ws.A, ws.Bm
    n = J.shape[1]
    for g in range(spec.shape[0]):
        kind = int(spec[g, G_KIND])
        r = int(spec[g, G_ROW])
        rows = int(spec[g, G_ROWS]) if extra is not None else frame_rows(kind)  # frame_rows says why
        if extra is not None and int(spec[g, G_FAMILY]) == FAMILY_BEYOND_FRAME:
            beyond_frame_jacobian(kind, parent, rev, index, scale, mimic, s.Rj, s.pj, Z, O, gaux[g], Rg[g], pg[g],
                                  tg[g], e[r:r + rows], spec[g, G_WEIGHT], pt[g], Rt[g], Jx, J, rv, A, B, E, r)
            continue
        if mimic:
            frame_jacobian(rev, support[g], pg[g], Z, O, Jx)
            fold(index, scale, Jx, J)
        else:
            frame_jacobian(rev, support[g], pg[g], Z, O, J)
        if extra is not None and int(spec[g, G_FAMILY]) == FAMILY_AXES:
            axes_jacobian(kind, Rg[g], pg[g], J, pt[g], Rt[g], gaux[g], rv, A, B, E, r)
        else:
            goal_jacobian(kind, Rg[g], J, tg[g], e[r:r + rows], spec[g, G_WEIGHT], rv, A, B, E, r)
    if weighted:
        for g in range(spec.shape[0]):
            r = int(spec[g, G_ROW])
            w = spec[g, G_WEIGHT]
            for i in range(r, r + (int(spec[g, G_ROWS]) if extra is not None else frame_rows(int(spec[g, G_KIND])))):
                for k in range(n):
                    E[i, k] *= w


@njit(cache=True, nogil=True, forceinline=False, **BORROWING)
def beyond_frame_error(kind, Rj, pj, aux, jf, Rf, pf, pt, Rt, R, p, M, t, e):
    """:func:`.balance.balance_error` behind a call, so that :func:`task_error` (inlined four times) stays small."""
    return balance_error(kind, Rj, pj, aux, jf, Rf, pf, pt, Rt, R, p, M, t, e)


@njit(cache=True, nogil=True, forceinline=False, **BORROWING)
def beyond_frame_jacobian(kind, parent, rev, index, scale, mimic, Rj, pj, Z, O, aux, R, p, t, e, w, pt, Rt, Jx, J, rv,
                          A, B, E, r):
    """Rows r.. of the task Jacobian E of a goal beyond one frame (behind a call, as :func:`beyond_frame_error`): a
    relative pose's by :func:`goal_jacobian`, the others' by :func:`.balance.balance_rows`."""
    balance_columns(kind, parent, rev, Rj, pj, Z, O, aux, p, Jx)
    src = Jx
    if mimic:
        fold(index, scale, Jx, J)
        src = J
    if kind == RELATIVE_LOG6:
        goal_jacobian(LOG6, R, src, t, e, w, rv, A, B, E, r)
    else:
        balance_rows(kind, Rj, pj, aux, R, p, t, src, pt, Rt, rv, A, B, E, r)


@njit(cache=True, nogil=True, forceinline=False, **BORROWING)
def damped_solve(E, lam, rhs, L, y, dq):
    """dq (n,) = E^T (E E^T + lam I)^-1 rhs = (E^T E + lam I)^-1 E^T rhs by Cholesky of the smaller of the two
    systems (task space when E (m, n) has m <= n rows, joint space otherwise); L (min(m, n), min(m, n)) and y
    (max(m, n),) are scratch. False when the system is not positive."""
    m, n = E.shape
    joints = m > n
    size = n if joints else m
    for i in range(size):  # L L^T = Gram + lam I, the Gram matrix's entries made as they are needed
        for j in range(i + 1):
            s = 0.0
            if joints:  # entry (i, j) of E^T E (columns i, j) or of E E^T (rows i, j)
                for k in range(m):
                    s += E[k, i] * E[k, j]
            else:
                for k in range(n):
                    s += E[i, k] * E[j, k]
            if i == j:
                s += lam
            for k in range(j):
                s -= L[i, k] * L[j, k]
            if i == j:
                if s <= 0.0:
                    return False
                L[i, i] = math.sqrt(s)
            else:
                L[i, j] = s / L[j, j]
    for i in range(size):  # L z = b: b = rhs (task space) or E^T rhs (joint space)
        s = 0.0
        if joints:
            for k in range(m):
                s += E[k, i] * rhs[k]
        else:
            s = rhs[i]
        for k in range(i):
            s -= L[i, k] * y[k]
        y[i] = s / L[i, i]
    for i in range(size - 1, -1, -1):  # L^T y = z
        s = y[i]
        for k in range(i + 1, size):
            s -= L[k, i] * y[k]
        y[i] = s / L[i, i]
    if joints:
        for k in range(n):
            dq[k] = y[k]
        return True
    for k in range(n):
        s = 0.0
        for i in range(m):
            s += E[i, k] * y[i]
        dq[k] = s
    return True


@njit(cache=True, nogil=True, forceinline=False, **BORROWING)
def into_box(q, box, any_wrap, out):
    """out (n,) = q clipped into the box, wrapping joints shifted by 2 pi into [lower, lower + 2 pi)."""
    for k in range(q.shape[0]):
        x = min(max(q[k], box[B_CLO, k]), box[B_CHI, k])
        if any_wrap and box[B_WRAP, k] != 0.0 and (x < box[B_LO, k] or x > box[B_HI, k]):
            lo = box[B_LO, k]
            x = lo + ((x - lo) % TWO_PI)
        out[k] = x


@njit(cache=True, nogil=True, forceinline=True, **BORROWING)
def _trust_step(W, lam, rhs, L, y, dq, max_step):
    """dq = :func:`damped_solve`'s step, scaled down to length max_step when longer (the trust region); False when the
    system is not positive."""
    if not damped_solve(W, lam, rhs, L, y, dq):
        return False
    s2 = 0.0
    for k in range(dq.shape[0]):
        s2 += dq[k] * dq[k]
    if s2 > max_step * max_step:
        f = max_step / math.sqrt(s2)
        for k in range(dq.shape[0]):
            dq[k] *= f
    return True


@njit(cache=True, nogil=True, forceinline=False, **BORROWING)
def _copy(a, b):
    """b (k,) = a (k,) (a slice assignment would check the two for overlap, with numba's runtime)."""
    for i in range(a.shape[0]):
        b[i] = a[i]


@njit(cache=True, nogil=True, forceinline=True, **BORROWING)
def lm_step(q, on_bound, e, lam, box, any_wrap, max_step, ws, qn):
    """The next configuration qn (n,) from q, its error e and Jacobian ws.E, and whether a joint hit a bound:
    ``reference._step``'s rule. Scratch: ws's W, L, y, dq, dfix, rhs, held."""
    E, W, L, y, dq, dfix, rhs, held = ws.E, ws.W, ws.L, ws.y, ws.dq, ws.dfix, ws.rhs, ws.held
    m, n = E.shape
    for i in range(m):
        for k in range(n):
            W[i, k] = E[i, k]
    for k in range(n):
        held[k] = False
    if on_bound:  # joints on a bound that the descent direction -E^T e pushes outward are held there
        for k in range(n):
            g = 0.0
            for i in range(m):
                g += E[i, k] * e[i]
            if (q[k] <= box[B_CLO, k] and g > 0.0) or (q[k] >= box[B_CHI, k] and g < 0.0):
                held[k] = True
                for i in range(m):
                    W[i, k] = 0.0
    if not _trust_step(W, lam, e, L, y, dq, max_step):
        _copy(q, qn)
        return False
    clipped = False
    for k in range(n):
        x = q[k] - dq[k]
        xc = min(max(x, box[B_CLO, k]), box[B_CHI, k])
        qn[k] = xc
        if xc != x:
            clipped = True
            held[k] = True  # from here on: fixed at the bound it hit
    if clipped:
        # the fixed joints move to their bound (dfix); the others re-solve for the error that move leaves
        for k in range(n):
            dfix[k] = qn[k] - q[k] if held[k] else 0.0
        for i in range(m):
            s = e[i]
            for k in range(n):
                s += W[i, k] * dfix[k]
            rhs[i] = s
        for k in range(n):
            if held[k]:
                for i in range(m):
                    W[i, k] = 0.0
        if not _trust_step(W, lam, rhs, L, y, dq, max_step):
            _copy(q, qn)
            return False
        for k in range(n):
            qn[k] = min(max(q[k] + dfix[k] - dq[k], box[B_CLO, k]), box[B_CHI, k])
    if any_wrap:
        into_box(qn, box, any_wrap, qn)
    return clipped


#: One configuration's kinematics and errors: q (n,), the joint poses Rj (m, 3, 3), pj (m, 3), axes and origins Z, O
#: (m, 3) (:func:`.tree_kinematics.tree_forward`), the goal frames' poses Rg (G, 3, 3), pg (G, 3) and positions seen
#: from their targets tg (G, 3) (:func:`goal_error`'s t), the task error e (rows,), each goal's errors ge (G, 2).
State = namedtuple("State", ["q", "Rj", "pj", "Z", "O", "Rg", "pg", "tg", "e", "ge"])
#: The buffers of LM runs, reused from run to run: three :data:`State` (the current configuration, a step's
#: candidate, the geodesic-acceleration probe) and scratch: x (m,), Jx (6, m), J (6, n), rv (3,), E, W (rows, n), A,
#: Bm, M (3, 3), L (s, s) with s = min(rows, n), y (max(rows, n),), rhs (rows,), v, dq, dfix (n,), held (n,) bool and
#: history (max_it + 1,), the |e|^2 after each accepted step.
Workspace = namedtuple("Workspace", ["cur", "cand", "probe", "x", "Jx", "J", "rv", "E", "W", "A", "Bm", "M", "L", "y",
                                     "rhs", "v", "dq", "dfix", "held", "history"])


@njit(cache=True, nogil=True, inline="always")
def workspace_size(n, m, G, rows, max_it):
    """Length of the float buffer of a :data:`Workspace` (:func:`carve`)."""
    s = min(rows, n)
    per_set = n + 9 * m + 3 * m + 3 * m + 3 * m + 9 * G + 3 * G + 3 * G + rows + 2 * G
    return 3 * per_set + m + 6 * m + 6 * n + 3 + 2 * rows * n + 27 + s * s + max(rows, n) + rows + 3 * n + max_it + 1


@njit(cache=True, nogil=True, inline="always")
def _carve_state(buf, o, n, m, G, rows):
    """A :data:`State` from buf at offset o, and the offset after it."""
    q, o = buf[o:o + n], o + n
    Rj, o = buf[o:o + 9 * m].reshape((m, 3, 3)), o + 9 * m
    pj, o = buf[o:o + 3 * m].reshape((m, 3)), o + 3 * m
    Z, o = buf[o:o + 3 * m].reshape((m, 3)), o + 3 * m
    O, o = buf[o:o + 3 * m].reshape((m, 3)), o + 3 * m
    Rg, o = buf[o:o + 9 * G].reshape((G, 3, 3)), o + 9 * G
    pg, o = buf[o:o + 3 * G].reshape((G, 3)), o + 3 * G
    tg, o = buf[o:o + 3 * G].reshape((G, 3)), o + 3 * G
    e, o = buf[o:o + rows], o + rows
    ge, o = buf[o:o + 2 * G].reshape((G, 2)), o + 2 * G
    return State(q, Rj, pj, Z, O, Rg, pg, tg, e, ge), o


@njit(cache=True, nogil=True, inline="always")
def carve(buf, held, n, m, G, rows, max_it):
    """The :data:`Workspace` of LM runs of at most max_it steps for n joints, m physical joints, G goals and
    ``rows`` task rows: views into buf (:func:`workspace_size`) and ``held`` (n,) bool (inlined: an entry receives
    two buffers, not some fifty arrays)."""
    s = min(rows, n)
    cur, o = _carve_state(buf, 0, n, m, G, rows)
    cand, o = _carve_state(buf, o, n, m, G, rows)
    probe, o = _carve_state(buf, o, n, m, G, rows)
    x, o = buf[o:o + m], o + m
    Jx, o = buf[o:o + 6 * m].reshape((6, m)), o + 6 * m
    J, o = buf[o:o + 6 * n].reshape((6, n)), o + 6 * n
    rv, o = buf[o:o + 3], o + 3
    E, o = buf[o:o + rows * n].reshape((rows, n)), o + rows * n
    W, o = buf[o:o + rows * n].reshape((rows, n)), o + rows * n
    A, o = buf[o:o + 9].reshape((3, 3)), o + 9
    Bm, o = buf[o:o + 9].reshape((3, 3)), o + 9
    M, o = buf[o:o + 9].reshape((3, 3)), o + 9
    L, o = buf[o:o + s * s].reshape((s, s)), o + s * s
    y, o = buf[o:o + max(rows, n)], o + max(rows, n)
    rhs, o = buf[o:o + rows], o + rows
    v, o = buf[o:o + n], o + n
    dq, o = buf[o:o + n], o + n
    dfix, o = buf[o:o + n], o + n
    history = buf[o:o + max(max_it, 0) + 1]
    return Workspace(cur, cand, probe, x, Jx, J, rv, E, W, A, Bm, M, L, y, rhs, v, dq, dfix, held, history)


@njit(cache=True, nogil=True, forceinline=False)
def make_workspace(kin, goals, n, max_it):
    """A fresh :data:`Workspace` for runs of at most max_it steps on the tree ``kin``, n joints and stack ``goals``
    (runs one after the other, never two at once)."""
    m, G, rows = kin[0].shape[0], goals[0].shape[0], stack_rows(goals[0])
    return carve(np.empty(workspace_size(n, m, G, rows, max_it)), np.empty(n, dtype=np.bool_), n, m, G, rows, max_it)


@njit(cache=True, nogil=True, forceinline=False)
def stack_rows(spec):
    """Total task rows of a goal stack: the last goal's first row plus its size."""
    G = spec.shape[0]
    return int(spec[G - 1, G_ROW]) + int(spec[G - 1, G_ROWS])


@njit(cache=True, nogil=True, forceinline=False, **BORROWING)
def _outcome(spec, ge, g_out):
    """(largest position error, largest orientation error or nan) over the goals' errors ge (G, 2), copied to
    g_out (G, 2) with nan orientation errors for goals without one."""
    pos = 0.0
    rot = np.nan
    for g in range(spec.shape[0]):
        oriented = spec[g, G_ANGLE] != 0.0  # its kind reports an angle (its declaration)
        g_out[g, 0] = ge[g, 0]
        g_out[g, 1] = ge[g, 1] if oriented else np.nan
        pos = max(pos, ge[g, 0]) if ge[g, 0] == ge[g, 0] else ge[g, 0]  # a NaN error stays NaN
        if oriented:
            rot = ge[g, 1] if rot != rot else max(rot, ge[g, 1])
    return pos, rot


@njit(cache=True, nogil=True, forceinline=True, **BORROWING)
def weighted_stack(spec):
    """Whether some goal of spec (G, GOAL_SIZE) has a weight other than 1 (a flag set in a loop would be typed as
    the literal False, compiling each callee once more)."""
    for g in range(spec.shape[0]):
        if spec[g, G_WEIGHT] != 1.0:
            return True
    return False


def _run(extra, name, doc):
    """The one source of :func:`lm_run_basic` and :func:`lm_run_all`: ``extra`` a constant of the closure (True: any
    goal family; None: one-frame goals only, the other branches pruned before typing; cached apart by cell)."""

    def run(ws, q_start, kin, box, any_wrap, goals, pt, Rt, params, q_out, g_out):
        spec = goals[0]
        n = q_start.shape[0]
        mimic = coupled(kin[4], kin[5], kin[6], n)
        weighted = weighted_stack(spec)
        m = ws.E.shape[0]
        max_step = params[layout.P_MAX_STEP]
        window = int(params[layout.P_STALL_WINDOW])
        stall = params[layout.P_STALL_RATIO] * params[layout.P_STALL_RATIO]
        finish = params[layout.P_FINISH] != 0.0
        max_it = int(params[P_ITERATIONS])
        cur, cand, probe = ws.cur, ws.cand, ws.probe  # cur and cand trade places when a step is accepted
        E, v, dq, history = ws.E, ws.v, ws.dq, ws.history

        into_box(q_start, box, any_wrap, cur.q)
        on_bound = False
        for k in range(n):
            if cur.q[k] <= box[B_CLO, k] or cur.q[k] >= box[B_CHI, k]:
                on_bound = True
        c = task_error(extra, kin, mimic, goals, weighted, pt, Rt, cur.q, cur, ws)
        evaluations = 1
        if within(spec, cur.ge):
            _copy(cur.q, q_out)
            pos, rot = _outcome(spec, cur.ge, g_out)
            return pos, rot, True, 0, evaluations, c
        lam = params[layout.P_DAMPING]
        have_E = False
        history[0] = c
        hlen = 1
        it = 0
        creeping = False  # the last accepted step did not halve |e| near the target: accelerate the next
        converged = False
        while it < max_it:
            it += 1
            q, e, qn, qh = cur.q, cur.e, cand.q, probe.q
            if not have_E:
                task_jacobian(extra, kin, mimic, goals, weighted, pt, Rt, cur, ws, E)
                have_E = True
            on_bound_n = lm_step(q, on_bound, e, lam, box, any_wrap, max_step, ws, qn)
            if creeping and not (on_bound or on_bound_n):
                # geodesic acceleration (ReferenceLM._geodesic): r'' from one extra FK at q + h v
                for k in range(n):
                    d = qn[k] - q[k]
                    if any_wrap and box[B_WRAP, k] != 0.0:
                        d = (d + math.pi) % TWO_PI - math.pi
                    v[k] = d
                    qh[k] = q[k] + layout.GEO_H * d
                task_error(extra, kin, mimic, goals, weighted, pt, Rt, qh, probe, ws)
                evaluations += 1
                rhs = ws.rhs
                for i in range(m):
                    s = 0.0
                    for k in range(n):
                        s += E[i, k] * v[k]
                    rhs[i] = (2.0 / layout.GEO_H) * ((probe.e[i] - e[i]) / layout.GEO_H - s)
                if damped_solve(E, lam, rhs, ws.L, ws.y, dq):  # dq = -a
                    a2 = 0.0
                    v2 = 0.0
                    for k in range(n):
                        a2 += dq[k] * dq[k]
                        v2 += v[k] * v[k]
                    if 2.0 * math.sqrt(a2) <= layout.GEO_ALPHA * math.sqrt(v2):
                        for k in range(n):
                            qh[k] = q[k] + v[k] - 0.5 * dq[k]
                        into_box(qh, box, any_wrap, qn)
            cn = task_error(extra, kin, mimic, goals, weighted, pt, Rt, qn, cand, ws)
            evaluations += 1
            if cn < c:
                creeping = layout.GEO_SLOW * c < cn < layout.GEO_NEAR
                cur, cand = cand, cur
                on_bound, c = on_bound_n, cn
                if within(spec, cur.ge):
                    converged = True
                    break
                have_E = False
                lam = max(lam * layout.SHRINK, LAMBDA_MIN)
                history[hlen] = c
                hlen += 1
                if hlen > window and c > stall * history[hlen - 1 - window]:
                    break
            else:
                lam *= layout.GROW
                if lam > layout.LAMBDA_MAX:
                    break
        if converged and finish and c > layout.FINISHED:
            # one more, (almost) undamped step: quadratic convergence takes ~1e-6 to ~1e-12 (kept if better and
            # every goal stays met: a lower weighted |e|^2 may trade one goal past its tolerance for another's rows)
            task_jacobian(extra, kin, mimic, goals, weighted, pt, Rt, cur, ws, E)
            lm_step(cur.q, False, cur.e, LAMBDA_MIN, box, any_wrap, max_step, ws, cand.q)
            cn = task_error(extra, kin, mimic, goals, weighted, pt, Rt, cand.q, cand, ws)
            it += 1
            evaluations += 1
            if cn < c and within(spec, cand.ge):
                cur, c = cand, cn
        _copy(cur.q, q_out)
        pos, rot = _outcome(spec, cur.ge, g_out)
        return pos, rot, converged, it, evaluations, c

    run.__name__ = run.__qualname__ = name
    run.__doc__ = doc
    return njit(cache=True, nogil=True, forceinline=False, **BORROWING)(run)


lm_run_basic = _run(None, "lm_run_basic", """One LM run in the workspace ``ws`` (:func:`carve`) for stacks of
one-frame goals only (``G_FAMILY`` = ``FAMILY_FRAME``); the other arguments and the result are :func:`lm_run`'s.""")
lm_run_all = _run(True, "lm_run_all", """:func:`lm_run_basic` for any stack.""")


#: A variant's compiled entries, in the caller's buffers: ``run`` (:func:`lm_run`) and ``runs`` (:func:`lm_runs`).
Entries = namedtuple("Entries", ["run", "runs"])


def _entries(extra, suffix):
    """The :data:`Entries` of one variant (``extra``: :func:`_run`'s), named apart by ``suffix`` for numba's disk
    cache; one variant per entry since numba re-optimizes every run an entry links."""

    def run(buf, held, q_start, kin, box, any_wrap, goals, pt, Rt, params, q_out, g_out):
        """:func:`lm_run` in buf (:func:`workspace_size`) and held (n,) bool, kept by a caller making many runs."""
        spec = goals[0]
        ws = carve(buf, held, q_start.shape[0], kin[0].shape[0], spec.shape[0], stack_rows(spec),
                   int(params[P_ITERATIONS]))
        if extra is not None:
            return lm_run_all(ws, q_start, kin, box, any_wrap, goals, pt, Rt, params, q_out, g_out)
        return lm_run_basic(ws, q_start, kin, box, any_wrap, goals, pt, Rt, params, q_out, g_out)

    def runs(buf, held, Q, kin, box, any_wrap, goals, P, Rts, params, Q_out, stats, g_stats, first):
        """:func:`lm_runs` in the caller's buffers (as ``run``)."""
        spec = goals[0]
        ws = carve(buf, held, Q.shape[1], kin[0].shape[0], spec.shape[0], stack_rows(spec), int(params[P_ITERATIONS]))
        last = P.shape[0] - 1
        for k in range(Q.shape[0]):
            t = min(k, last)
            if extra is not None:
                pos, rot, converged, it, evaluations, c = lm_run_all(ws, Q[k], kin, box, any_wrap, goals, P[t],
                                                                     Rts[t], params, Q_out[k], g_stats[k])
            else:
                pos, rot, converged, it, evaluations, c = lm_run_basic(ws, Q[k], kin, box, any_wrap, goals, P[t],
                                                                       Rts[t], params, Q_out[k], g_stats[k])
            stats[k, layout.S_POS], stats[k, layout.S_ROT], stats[k, layout.S_COST] = pos, rot, c
            stats[k, layout.S_CONVERGED] = 1.0 if converged else 0.0
            stats[k, layout.S_ITERATIONS], stats[k, layout.S_EVALUATIONS] = it, evaluations
            if converged and first:
                return k
        return -(1 + Q.shape[0])

    run.__name__ = run.__qualname__ = "lm_run_buffers" + suffix
    runs.__name__ = runs.__qualname__ = "lm_runs_buffers" + suffix
    return Entries(*(njit(cache=True, nogil=True, forceinline=False, **BORROWING)(f) for f in (run, runs)))


#: The entries of the run for stacks of one-frame goals (:func:`lm_run_basic`) and for any stack (:func:`lm_run_all`).
BASIC = _entries(None, "_basic")
ALL = _entries(True, "")
lm_run_buffers_basic, lm_runs_buffers_basic = BASIC  # each entry under a name of its own
lm_run_buffers, lm_runs_buffers = ALL


def entries_for(spec: np.ndarray) -> Entries:
    """The entries for the goal stack spec (G, GOAL_SIZE): :data:`BASIC` (faster) when every goal is of the frame
    family, else :data:`ALL`."""
    return ALL if bool((spec[:, G_FAMILY] != registry.FAMILY_FRAME).any()) else BASIC


def _buffers(n: int, kin: tuple, spec: np.ndarray, params: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The two buffers of a :data:`Workspace` for n joints and the tree, goal stack and step budget of a call."""
    size = workspace_size(n, kin[0].shape[0], spec.shape[0], int(stack_rows(spec)), int(params[P_ITERATIONS]))
    return np.empty(int(size)), np.empty(n, dtype=np.bool_)


def lm_runs(Q, kin, box, any_wrap, goals, P, Rts, params, Q_out, stats, g_stats, first=False):
    """LM runs from the starts Q (K, n) in one workspace: run k towards the targets P[k] (T, G, 3), Rts[k]
    (T, G, 3, 3) (pairs: T = K), or all towards P[0], Rts[0] (T = 1); with ``first``, until one converges. Run k's
    end configuration goes to Q_out[k], its ``S_*`` columns to stats[k] (K, STATS_SIZE), its goals' errors to
    g_stats[k] (G, 2); rows of runs not made are untouched. Returns the index of the run that stopped them
    (``first``), else -(1 + K). The other arguments are :func:`lm_run`'s."""
    return entries_for(goals[0]).runs(*_buffers(Q.shape[1], kin, goals[0], params), Q, kin, box, any_wrap, goals, P,
                                      Rts, params, Q_out, stats, g_stats, first)


def lm_run(q_start, kin, box, any_wrap, goals, pt, Rt, params, q_out, g_out):
    """One LM run from ``q_start`` (n,); the end configuration goes to ``q_out`` (n,), each goal's errors to
    g_out (G, 2) (position m, orientation rad; nan for a goal without orientation).

    Args (after q_start):
        kin: parent (m,) int64, FR (m, 3, 3), Fp (m, 3), rev (m,) bool: the folded tree of the m physical joints, and
            index (m,) int64, scale, offset (m,): how they follow q (``Robot.tree_constants``).
        box (5, n): rows B_LO, B_HI, B_CLO, B_CHI, B_WRAP. any_wrap: some joint wraps.
        goals: spec (G, GOAL_SIZE), gR (G, 3, 3), gp (G, 3), support (G, m) bool, gaux (G, A): the goal stack
            (:class:`~evoik_pin.goals.stack.GoalStack`); pt (G, 3), Rt (G, 3, 3): its targets
            (:func:`~evoik_pin.goals.stack.encode_target`).
        params (PARAMS_SIZE,): the run's settings (:mod:`.layout`). q_out, g_out.

    Returns:
        (position error m, orientation error rad (nan when no goal has an orientation), converged, iterations,
        forward-kinematics evaluations, weighted |e|^2), the errors the largest over the goals.
    """
    return entries_for(goals[0]).run(*_buffers(q_start.shape[0], kin, goals[0], params), q_start, kin, box, any_wrap,
                                     goals, pt, Rt, params, q_out, g_out)
