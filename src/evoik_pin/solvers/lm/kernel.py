"""The Levenberg-Marquardt engine's compiled kernel (numba): whole LM runs, one call each.

One call of :func:`lm_run` runs a whole LM iteration from one start for a pose, position or planar target,
with the forward kinematics and Jacobian of :mod:`.chain` and the SO(3) / SE(3) closed forms of
:mod:`evoik_pin.lie.compiled`. :func:`lm_run_starts` runs several starts for one target, in order, until one
converges (memetic's restarts); :func:`lm_run_pairs` runs one start per (start, target) pair (batches).
The iteration is the one of :func:`.reference.reference_run` line for line (same error, damping rule, trust
region, active-set joint limits, wrapping, stall test, geodesic acceleration and finishing step); tests hold
the two to the same steps from the same starts. About 1 us per step, against 30-40 us for the Python loop.

Task error ``e`` by target kind (``params[P_KIND]``, :mod:`.layout`):

* pose: ``e = log6(T_t^-1 T(q))`` (m, rad; Pinocchio's formula), ``E = Jlog6(T_t^-1 T(q)) J_local``;
* position: ``e = p(q) - p_t`` with the base-frame translational Jacobian rows;
* planar: ``e = (p_x - x_t, p_y - y_t[, wrap(yaw(q) - yaw_t)])`` with base-frame rows vx, vy[, wz].

The constants and the ``params`` / ``box`` layouts come from :mod:`.layout`. numba compiles this module on
first use (about 15 s once per install, then cached on disk; :func:`.engine.compiled_kernel` loads it outside
any time budget).

Cost: about 7.5 us per run for Panda pose targets from seed-table starts (8 kinematics evaluations; some 30 % of
it in the damped solves, whose divisions and square roots form one chain, 30 % in the forward kinematics with its
sines and cosines). A run allocates nothing of its own: :func:`lm_run_pairs` and :func:`lm_run_starts` make one
:data:`Workspace` per call and reuse it for every run. :func:`lm_run_in` and this module's helpers are compiled
with ``_nrt=False`` (:data:`BORROWING`), numba's own option for functions that borrow their arrays
(``numba.cpython.unicode`` uses it; a numba without it compiles them as usual, with the same results): they
neither allocate nor count references to the arrays they are given, which their caller owns. Otherwise numba
brackets nearly every call with an atomic increment and decrement per array argument (its pruning of those
gives up across calls), a fifth of the run time; and a helper that allocated now fails to compile instead.
:func:`task_error`, :func:`task_jacobian` and :func:`lm_step`, which take 16 to 19 arrays each, are moreover
inlined into :func:`lm_run_in` (``inline="always"``): passing those arrays cost more than the calls (about 7 % of
the run time), for about 1 s more compile time.
"""

from __future__ import annotations

import math
from collections import namedtuple

import numpy as np
from numba import njit

from ...lie.compiled import jlog6, log6, wrap_angle, yaw
from .chain import coupled, expand, fold, forward, jacobian
from .layout import (
    B_CHI,
    B_CLO,
    B_HI,
    B_LO,
    B_WRAP,
    FINISHED,
    GEO_ALPHA,
    GEO_H,
    GEO_NEAR,
    GEO_SLOW,
    GROW,
    KIND_PLANAR,
    KIND_PLANAR_YAW,
    KIND_POSE,
    KIND_POSITION,
    LAMBDA_MAX,
    LAMBDA_MIN,
    P_DAMPING,
    P_FINISH,
    P_ITERATIONS,
    P_KIND,
    P_MAX_STEP,
    P_RTOL,
    P_STALL_RATIO,
    P_STALL_WINDOW,
    P_TOL,
    S_CONVERGED,
    S_EVALUATIONS,
    S_ITERATIONS,
    S_POS,
    S_ROT,
    SHRINK,
)

TWO_PI = 2.0 * math.pi


def _borrowing_options() -> dict:
    """``{"_nrt": False}`` where this numba has that option (every release since 0.60 does; it is numba's own, not
    a documented one), else ``{}``: the kernel then counts references as usual, with the same results, about a
    fifth slower."""
    try:
        from numba.core.cpu import CPUTargetOptions
    except ImportError:
        return {}
    return {"_nrt": False} if hasattr(CPUTargetOptions, "_nrt") else {}


#: Options of the functions that borrow the arrays their caller owns (see the module docstring).
BORROWING = _borrowing_options()


@njit(cache=True, nogil=True)
def task_size(kind):
    """Rows m of the task error of a target kind: 6 (pose), 3 (position, planar with yaw), 2 (planar)."""
    if kind == KIND_POSE:
        return 6
    if kind == KIND_POSITION or kind == KIND_PLANAR_YAW:
        return 3
    return 2


@njit(cache=True, nogil=True, inline="always", **BORROWING)
def task_error(FR, Fp, rev, index, scale, offset, mimic, q, x, pt, Rt, kind, R, p, Z, O, M, t, e):
    """Task error e (m,) at q; returns (|e|^2, position error m, orientation error rad or 0).

    Fills the kinematics buffers R, p, Z, O (see :func:`.chain.forward`; with ``mimic``, the chain's joint values
    x of :func:`.chain.expand` first), and for pose targets the tip pose seen from the target, ``T_t^-1 T(q)`` =
    (M (3, 3), t (3,)), which :func:`task_jacobian` needs.
    """
    if mimic:
        expand(index, scale, offset, q, x)
        forward(FR, Fp, rev, x, R, p, Z, O)
    else:
        forward(FR, Fp, rev, q, R, p, Z, O)
    if kind == KIND_PLANAR or kind == KIND_PLANAR_YAW:  # (x, y[, yaw]) with pt = (x_t, y_t, yaw_t)
        d0, d1 = p[0] - pt[0], p[1] - pt[1]
        e[0], e[1] = d0, d1
        pos = math.sqrt(d0 * d0 + d1 * d1)
        if kind != KIND_PLANAR_YAW:
            return d0 * d0 + d1 * d1, pos, 0.0
        dyaw = wrap_angle(yaw(R) - pt[2])
        e[2] = dyaw
        return d0 * d0 + d1 * d1 + dyaw * dyaw, pos, abs(dyaw)
    d0, d1, d2 = p[0] - pt[0], p[1] - pt[1], p[2] - pt[2]
    pos = math.sqrt(d0 * d0 + d1 * d1 + d2 * d2)
    if kind == KIND_POSITION:
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


@njit(cache=True, nogil=True, inline="always", **BORROWING)
def task_jacobian(rev, index, scale, mimic, R, p, Z, O, t, e, kind, Jx, J, A, B, E):
    """Task Jacobian E (m, n) from the buffers :func:`task_error` filled for the same configuration.

    Position: the base-frame translational rows; planar: rows vx, vy[, wz]. Pose: ``Jlog6(T_t^-1 T) J_local``
    with ``J_local = (R^T J_v, R^T J_w)``. Jx (6, chain joints), J (6, n), A, B (3, 3) are scratch; with
    ``mimic`` the chain's columns Jx are folded into those of q (:func:`.chain.fold`).
    """
    if mimic:
        jacobian(rev, p, Z, O, Jx)
        fold(index, scale, Jx, J)
    else:
        jacobian(rev, p, Z, O, J)
    n = J.shape[1]
    if kind != KIND_POSE:
        m = E.shape[0]
        for i in range(m):
            row = 5 if i == 2 and kind == KIND_PLANAR_YAW else i
            for k in range(n):
                E[i, k] = J[row, k]
        return
    theta = math.sqrt(e[3] * e[3] + e[4] * e[4] + e[5] * e[5])
    jlog6(theta, e[3:], t, A, B)
    for k in range(n):
        v0 = R[0, 0] * J[0, k] + R[1, 0] * J[1, k] + R[2, 0] * J[2, k]  # R^T J_v
        v1 = R[0, 1] * J[0, k] + R[1, 1] * J[1, k] + R[2, 1] * J[2, k]
        v2 = R[0, 2] * J[0, k] + R[1, 2] * J[1, k] + R[2, 2] * J[2, k]
        w0 = R[0, 0] * J[3, k] + R[1, 0] * J[4, k] + R[2, 0] * J[5, k]  # R^T J_w
        w1 = R[0, 1] * J[3, k] + R[1, 1] * J[4, k] + R[2, 1] * J[5, k]
        w2 = R[0, 2] * J[3, k] + R[1, 2] * J[4, k] + R[2, 2] * J[5, k]
        for i in range(3):
            E[i, k] = A[i, 0] * v0 + A[i, 1] * v1 + A[i, 2] * v2 + B[i, 0] * w0 + B[i, 1] * w1 + B[i, 2] * w2
            E[3 + i, k] = A[i, 0] * w0 + A[i, 1] * w1 + A[i, 2] * w2


@njit(cache=True, nogil=True, **BORROWING)
def damped_solve(E, lam, rhs, L, y, dq):
    """dq (n,) = E^T (E E^T + lam I)^-1 rhs by Cholesky (L (m, m), y (m,) scratch); False when not positive."""
    m, n = E.shape
    for i in range(m):
        for j in range(i + 1):
            s = 0.0
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
    for i in range(m):  # L z = rhs
        s = rhs[i]
        for k in range(i):
            s -= L[i, k] * y[k]
        y[i] = s / L[i, i]
    for i in range(m - 1, -1, -1):  # L^T y = z
        s = y[i]
        for k in range(i + 1, m):
            s -= L[k, i] * y[k]
        y[i] = s / L[i, i]
    for k in range(n):
        s = 0.0
        for i in range(m):
            s += E[i, k] * y[i]
        dq[k] = s
    return True


@njit(cache=True, nogil=True, **BORROWING)
def into_box(q, box, any_wrap, out):
    """out (n,) = q clipped into the box, wrapping joints shifted by 2 pi into [lower, lower + 2 pi)."""
    for k in range(q.shape[0]):
        x = min(max(q[k], box[B_CLO, k]), box[B_CHI, k])
        if any_wrap and box[B_WRAP, k] != 0.0 and (x < box[B_LO, k] or x > box[B_HI, k]):
            lo = box[B_LO, k]
            x = lo + ((x - lo) % TWO_PI)
        out[k] = x


@njit(cache=True, nogil=True, **BORROWING)
def _scaled_to(dq, max_step):
    """Scale dq (n,) down to length max_step when longer (the trust region)."""
    s2 = 0.0
    for k in range(dq.shape[0]):
        s2 += dq[k] * dq[k]
    if s2 > max_step * max_step:
        f = max_step / math.sqrt(s2)
        for k in range(dq.shape[0]):
            dq[k] *= f


@njit(cache=True, nogil=True, inline="always", **BORROWING)
def _trust_step(W, lam, rhs, L, y, dq, max_step):
    """dq = the damped step of :func:`damped_solve` scaled into the trust region (:func:`_scaled_to`); False when
    the damped system is not positive (dq is then meaningless)."""
    if not damped_solve(W, lam, rhs, L, y, dq):
        return False
    _scaled_to(dq, max_step)
    return True


@njit(cache=True, nogil=True, **BORROWING)
def _copy(a, b):
    """b (k,) = a (k,) (a slice assignment would check the two for overlap, with numba's runtime)."""
    for i in range(a.shape[0]):
        b[i] = a[i]


@njit(cache=True, nogil=True, inline="always", **BORROWING)
def lm_step(q, on_bound, E, e, lam, box, any_wrap, max_step, W, L, y, dq, dfix, rhs, held, qn):
    """The next configuration qn (n,) (written in place) and whether a joint hit a bound: the damped step,
    trust region, active-set limits and wrapping of ``reference._step`` (its docstring says why).
    W (m, n), L (m, m), y, rhs (m,), dq, dfix (n,) and held (n,) bool are scratch."""
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


#: The buffers of LM runs (:func:`make_workspace`) for n joints, nx chain joints and m task rows, reused from
#: run to run. The kinematics come in three sets: the current configuration (q, R, p, Z, O, tx, e), a step's
#: candidate (qn, R2, p2, Z2, O2, tx2, en) and the geodesic-acceleration probe (qh, R3, p3, Z3, O3, tx3, eh):
#: R (3, 3) and p (3,) the tip pose, Z, O (nx, 3) the joint axes and origins (:func:`.chain.forward`), tx (3,)
#: the tip position seen from the target (:func:`task_error`'s t), e (m,) the task error. Scratch: x (nx,),
#: Jx (6, nx), J (6, n), E, W (m, n), A, Bm, M (3, 3), L (m, m), y, rhs (m,), v, dq, dfix (n,), held (n,)
#: bool, and history (max_it + 1,), the |e|^2 after each accepted step.
Workspace = namedtuple("Workspace", ["q", "R", "p", "Z", "O", "tx", "e", "qn", "R2", "p2", "Z2", "O2", "tx2", "en",
                                     "qh", "R3", "p3", "Z3", "O3", "tx3", "eh", "x", "Jx", "J", "E", "W", "A", "Bm",
                                     "M", "L", "y", "rhs", "v", "dq", "dfix", "held", "history"])


@njit(cache=True, nogil=True)
def make_workspace(n, nx, m, max_it):
    """The :data:`Workspace` of LM runs of at most max_it steps for n joints, nx chain joints and m task rows.

    One workspace serves any number of runs one after the other (a run writes each buffer before it reads it),
    never two at a time: the batch entry points make one per call, so concurrent calls share nothing.
    """
    return Workspace(
        np.empty(n), np.empty((3, 3)), np.empty(3), np.empty((nx, 3)), np.empty((nx, 3)), np.empty(3), np.empty(m),
        np.empty(n), np.empty((3, 3)), np.empty(3), np.empty((nx, 3)), np.empty((nx, 3)), np.empty(3), np.empty(m),
        np.empty(n), np.empty((3, 3)), np.empty(3), np.empty((nx, 3)), np.empty((nx, 3)), np.empty(3), np.empty(m),
        np.empty(nx), np.empty((6, nx)), np.empty((6, n)), np.empty((m, n)), np.empty((m, n)), np.empty((3, 3)),
        np.empty((3, 3)), np.empty((3, 3)), np.empty((m, m)), np.empty(m), np.empty(m),
        np.empty(n), np.empty(n), np.empty(n), np.empty(n, dtype=np.bool_), np.empty(max(max_it, 0) + 1))


@njit(cache=True, nogil=True)
def lm_run(q_start, FR, Fp, rev, index, scale, offset, box, any_wrap, pt, Rt, params, q_out):
    """One LM run from ``q_start`` (n,); the end configuration goes to ``q_out`` (n,).

    Args:
        FR (m+1, 3, 3), Fp (m+1, 3), rev (m,) bool: the folded chain of the m physical joints
            (``Robot.chain_constants``); index (m,) int64, scale, offset (m,): how they follow q
            (``Robot.chain_coupling``).
        box (5, n): rows B_LO, B_HI, B_CLO, B_CHI, B_WRAP. any_wrap: some joint wraps.
        pt (3,), Rt (3, 3): the target as :func:`.layout.encode_target` writes it.
        params (PARAMS_SIZE,): tolerance (m), rotation tolerance (rad), initial damping, max step, stall window,
            stall ratio, finish (0/1), max iterations, target kind (:mod:`.layout`).

    Returns:
        (position error m, orientation error rad (nan when the target has no orientation), converged,
        iterations, forward-kinematics evaluations), as :func:`.reference.reference_run` counts them.
    """
    ws = make_workspace(q_start.shape[0], FR.shape[0] - 1, task_size(int(params[P_KIND])), int(params[P_ITERATIONS]))
    return lm_run_in(ws, q_start, FR, Fp, rev, index, scale, offset, box, any_wrap, pt, Rt, params, q_out)


@njit(cache=True, nogil=True, **BORROWING)
def lm_run_in(ws, q_start, FR, Fp, rev, index, scale, offset, box, any_wrap, pt, Rt, params, q_out):
    """:func:`lm_run` in the buffers of the workspace ``ws`` (:func:`make_workspace` for these n and chain
    joints, the task rows of ``params[P_KIND]`` and at least ``params[P_ITERATIONS]`` steps); the other arguments
    and the result are :func:`lm_run`'s."""
    n = q_start.shape[0]
    mimic = coupled(index, scale, offset, n)
    kind = int(params[P_KIND])
    oriented = kind == KIND_POSE or kind == KIND_PLANAR_YAW
    m = task_size(kind)
    tol_p, tol_r = params[P_TOL], params[P_RTOL]
    max_step = params[P_MAX_STEP]
    window = int(params[P_STALL_WINDOW])
    stall = params[P_STALL_RATIO] * params[P_STALL_RATIO]
    finish = params[P_FINISH] != 0.0
    max_it = int(params[P_ITERATIONS])
    # the current configuration's buffers and the candidate's trade places when a step is accepted
    q, R, p, Z, O, tx, e = ws.q, ws.R, ws.p, ws.Z, ws.O, ws.tx, ws.e
    qn, R2, p2, Z2, O2, tx2, en = ws.qn, ws.R2, ws.p2, ws.Z2, ws.O2, ws.tx2, ws.en
    qh, R3, p3, Z3, O3, tx3, eh = ws.qh, ws.R3, ws.p3, ws.Z3, ws.O3, ws.tx3, ws.eh
    x, Jx, J, E, W, A, Bm, M = ws.x, ws.Jx, ws.J, ws.E, ws.W, ws.A, ws.Bm, ws.M
    L, y, rhs, v, dq, dfix, held, history = ws.L, ws.y, ws.rhs, ws.v, ws.dq, ws.dfix, ws.held, ws.history

    into_box(q_start, box, any_wrap, q)
    on_bound = False
    for k in range(n):
        if q[k] <= box[B_CLO, k] or q[k] >= box[B_CHI, k]:
            on_bound = True
    c, pos, rot = task_error(FR, Fp, rev, index, scale, offset, mimic, q, x, pt, Rt, kind, R, p, Z, O, M, tx, e)
    evaluations = 1
    if pos <= tol_p and (not oriented or rot <= tol_r):
        _copy(q, q_out)
        return pos, rot if oriented else np.nan, True, 0, evaluations
    lam = params[P_DAMPING]
    have_E = False
    history[0] = c
    hlen = 1
    it = 0
    creeping = False  # the last accepted step did not halve |e| near the target: accelerate the next
    converged = False
    while it < max_it:
        it += 1
        if not have_E:
            task_jacobian(rev, index, scale, mimic, R, p, Z, O, tx, e, kind, Jx, J, A, Bm, E)
            have_E = True
        on_bound_n = lm_step(q, on_bound, E, e, lam, box, any_wrap, max_step, W, L, y, dq, dfix, rhs, held, qn)
        if creeping and not (on_bound or on_bound_n):
            # geodesic acceleration (reference._geodesic): r'' from one extra FK at q + h v
            for k in range(n):
                d = qn[k] - q[k]
                if any_wrap and box[B_WRAP, k] != 0.0:
                    d = (d + math.pi) % TWO_PI - math.pi
                v[k] = d
                qh[k] = q[k] + GEO_H * d
            task_error(FR, Fp, rev, index, scale, offset, mimic, qh, x, pt, Rt, kind, R3, p3, Z3, O3, M, tx3, eh)
            evaluations += 1
            for i in range(m):
                s = 0.0
                for k in range(n):
                    s += E[i, k] * v[k]
                rhs[i] = (2.0 / GEO_H) * ((eh[i] - e[i]) / GEO_H - s)
            if damped_solve(E, lam, rhs, L, y, dq):  # dq = -a
                a2 = 0.0
                v2 = 0.0
                for k in range(n):
                    a2 += dq[k] * dq[k]
                    v2 += v[k] * v[k]
                if 2.0 * math.sqrt(a2) <= GEO_ALPHA * math.sqrt(v2):
                    for k in range(n):
                        qh[k] = q[k] + v[k] - 0.5 * dq[k]
                    into_box(qh, box, any_wrap, qn)
        cn, pos_n, rot_n = task_error(FR, Fp, rev, index, scale, offset, mimic, qn, x, pt, Rt, kind, R2, p2, Z2, O2,
                                      M, tx2, en)
        evaluations += 1
        if cn < c:
            creeping = GEO_SLOW * c < cn < GEO_NEAR
            q, qn = qn, q
            R, R2 = R2, R
            p, p2 = p2, p
            Z, Z2 = Z2, Z
            O, O2 = O2, O
            tx, tx2 = tx2, tx
            e, en = en, e
            on_bound, pos, rot, c = on_bound_n, pos_n, rot_n, cn
            if pos <= tol_p and (not oriented or rot <= tol_r):
                converged = True
                break
            have_E = False
            lam = max(lam * SHRINK, LAMBDA_MIN)
            history[hlen] = c
            hlen += 1
            if hlen > window and c > stall * history[hlen - 1 - window]:
                break
        else:
            lam *= GROW
            if lam > LAMBDA_MAX:
                break
    if converged and finish and c > FINISHED:
        # one more, (almost) undamped step: quadratic convergence takes ~1e-6 to ~1e-12 (kept if better)
        task_jacobian(rev, index, scale, mimic, R, p, Z, O, tx, e, kind, Jx, J, A, Bm, E)
        lm_step(q, False, E, e, LAMBDA_MIN, box, any_wrap, max_step, W, L, y, dq, dfix, rhs, held, qn)
        cn, pos_n, rot_n = task_error(FR, Fp, rev, index, scale, offset, mimic, qn, x, pt, Rt, kind, R2, p2, Z2, O2,
                                      M, tx2, en)
        it += 1
        evaluations += 1
        if cn < c:
            q = qn
            pos, rot = pos_n, rot_n
    _copy(q, q_out)
    return pos, rot if oriented else np.nan, converged, it, evaluations


@njit(cache=True, nogil=True)
def lm_run_pairs(Q, FR, Fp, rev, index, scale, offset, box, any_wrap, P, Rts, params, Q_out, stats):
    """:func:`lm_run` on M (start, target) pairs: starts Q (M, n), target positions P (M, 3) and rotations
    Rts (M, 3, 3) (:func:`.layout.encode_targets`); end configurations to Q_out (M, n) and, per pair, the
    ``S_*`` columns (errors, converged, iterations, evaluations) to the rows of stats (M, STATS_SIZE). The runs
    share one workspace, made here."""
    ws = make_workspace(Q.shape[1], FR.shape[0] - 1, task_size(int(params[P_KIND])), int(params[P_ITERATIONS]))
    for i in range(Q.shape[0]):
        pos, rot, converged, it, evaluations = lm_run_in(ws, Q[i], FR, Fp, rev, index, scale, offset, box, any_wrap,
                                                         P[i], Rts[i], params, Q_out[i])
        stats[i, S_POS], stats[i, S_ROT] = pos, rot
        stats[i, S_CONVERGED] = 1.0 if converged else 0.0
        stats[i, S_ITERATIONS], stats[i, S_EVALUATIONS] = it, evaluations


@njit(cache=True, nogil=True)
def lm_run_starts(Q, FR, Fp, rev, index, scale, offset, box, any_wrap, pt, Rt, params, Q_out, stats):
    """:func:`lm_run` from the starts Q (K, n) for one target, in order, until one converges.

    Each run's end configuration goes to Q_out[k] and its ``S_*`` statistics to stats[k] (rows of starts not
    run are left untouched). Returns the index of the converged run, or -(1 + the number of runs) when none
    converged (every start was run then). The runs share one workspace, made here."""
    ws = make_workspace(Q.shape[1], FR.shape[0] - 1, task_size(int(params[P_KIND])), int(params[P_ITERATIONS]))
    for k in range(Q.shape[0]):
        pos, rot, converged, it, evaluations = lm_run_in(ws, Q[k], FR, Fp, rev, index, scale, offset, box, any_wrap,
                                                         pt, Rt, params, Q_out[k])
        stats[k, S_POS], stats[k, S_ROT] = pos, rot
        stats[k, S_CONVERGED] = 1.0 if converged else 0.0
        stats[k, S_ITERATIONS], stats[k, S_EVALUATIONS] = it, evaluations
        if converged:
            return k
    return -(1 + Q.shape[0])
