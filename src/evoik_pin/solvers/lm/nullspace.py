"""Compiled descent along the goals' self-motion manifold (numba): ``prefer="nearest"`` and ``"manipulability"``.

A redundant arm's answers to a goal stack form curves (one per IK branch); :func:`descend_batch` takes each answer
to a local optimum of the criterion (:data:`MODE_NEAREST`, :data:`MODE_MANIPULABILITY`) on its curve:

1. the criterion's descent direction v (for manipulability by forward differences) projected on the null space of
   the task Jacobian E, ``p = v - E^T (E E^T)^-1 E v``, joints on a bound that p pushes outward held;
2. a step ``t p`` kept inside the box (the joint limits, full-turn joints' too: an answer taken back into them
   would land a turn away from q0) and within ``max_step``;
3. Gauss-Newton steps until every goal is within its tolerances again (at most ``restore``);
4. the step kept only when step 3 met every goal and the criterion improved (the next t: the Barzilai-Borwein
   secant step), else t halves; the descent ends when t is below 1e-3 of its start or a kept step was shorter
   than :data:`MIN_STEP`. So the criterion never gets worse and every kept configuration meets every goal.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from .chain import coupled
from .kernel import _copy, damped_solve, make_workspace, task_error, task_jacobian, weighted_stack, within
from .layout import B_HI, B_LO, B_WRAP, LAMBDA_MIN, TWO_PI
from .tree_kinematics import frame_jacobian

__all__ = ["MODE_MANIPULABILITY", "MODE_NEAREST", "descend_batch", "descend_batch_then_best", "log_manipulability_rows",
           "nearest_turn_rows", "nullspace_kernel"]

#: What :func:`descend_batch` minimises: ``|q - q0|^2`` (full-turn joints at their turn nearest q0 inside the limits,
#: :func:`~evoik_pin.solvers.search.prefer.nearest_turn`'s rule) or ``-sqrt(det(J J^T))`` of the first goal's frame.
MODE_NEAREST, MODE_MANIPULABILITY = 0, 1
#: First step length (rad or m) of a manipulability ascent: its scale is unknown (no curvature to divide by).
MANIP_STEP = 0.2
#: Forward-difference step (rad or m) of the manipulability gradient.
MANIP_H = 1e-6
#: The secant step's range, times the first step's multiple t0: after a kept step s, the next multiple is
#: |s|^2 / s.(p_prev - p) (p the projected direction).
BB_RANGE = (0.01, 100.0)
#: A kept step shorter than this (rad or m) ends the descent.
MIN_STEP = 1e-9
#: A joint closer than this to a bound (rad or m) counts as on it.
ON_BOUND = 1e-12

_KERNEL: dict = {}

@njit(cache=True, nogil=True, forceinline=False)
def _manipulability(rev, support, pg, Z, O, J, JJ):
    """Yoshikawa's manipulability (:func:`~evoik_pin.robot.robot.yoshikawa`: sqrt(det(J J^T)), sqrt(det(J^T J))
    for fewer than 6 joints) of the first goal frame's base-frame Jacobian J (6, n) from a :data:`.kernel.State`'s
    pg, Z, O (0 at a singularity), by the Cholesky factor's diagonal. JJ (6, 6) scratch."""
    frame_jacobian(rev, support[0], pg[0], Z, O, J)
    n = J.shape[1]
    r = min(n, 6)
    for i in range(r):
        for j in range(i + 1):
            s = 0.0
            if n >= 6:
                for k in range(n):
                    s += J[i, k] * J[j, k]
            else:
                for k in range(6):
                    s += J[k, i] * J[k, j]
            JJ[i, j] = s
    logdet = 0.0
    for i in range(r):  # in-place Cholesky of the lower triangle
        for j in range(i + 1):
            s = JJ[i, j]
            for k in range(j):
                s -= JJ[i, k] * JJ[j, k]
            if i == j:
                if s <= 0.0:
                    return 0.0
                JJ[i, i] = math.sqrt(s)
                logdet += math.log(s)
            else:
                JJ[i, j] = s / JJ[j, j]
    return math.exp(0.5 * logdet)


@njit(cache=True, nogil=True, forceinline=False)
def _manipulability_gradient(rev, support, pg, Z, O, J, JJ, M, v):
    """The gradient (n,) of :func:`_manipulability` m at q to ``v`` in closed form, from q's kinematics buffers (as
    :func:`_manipulability`'s) by Jacobi's formula: dm/dq_k = m <M, dJ/dq_k> with M = (J J^T)^-1 J (6, n), or
    J (J^T J)^-1 for fewer than 6 joints, and dJ/dq_k from the columns themselves (the chain's derivative of its
    Jacobian: a revolute joint k turns the columns of the joints it carries, z_k x J_i; it moves the frame's
    origin under the joints before it, z_i x J_k's linear part). Returns m; at a singularity (m 0) ``v`` is left
    unset. JJ (6, 6), M (6, n): scratch."""
    m = _manipulability(rev, support, pg, Z, O, J, JJ)  # J and JJ's Cholesky factor (lower triangle) filled
    if m <= 0.0:
        return m
    n = J.shape[1]
    r = min(n, 6)
    # M: the Cholesky factor's solves, column by column of J (n >= 6: A = J J^T, 6 x 6) or row by row (A = J^T J)
    for c in range(n if n >= 6 else 6):
        for i in range(r):  # forward: L y = b
            s = J[i, c] if n >= 6 else J[c, i]
            for k in range(i):
                s -= JJ[i, k] * (M[k, c] if n >= 6 else M[c, k])
            if n >= 6:
                M[i, c] = s / JJ[i, i]
            else:
                M[c, i] = s / JJ[i, i]
        for i in range(r - 1, -1, -1):  # back: L^T x = y
            s = M[i, c] if n >= 6 else M[c, i]
            for k in range(i + 1, r):
                s -= JJ[k, i] * (M[k, c] if n >= 6 else M[c, k])
            if n >= 6:
                M[i, c] = s / JJ[i, i]
            else:
                M[c, i] = s / JJ[i, i]
    frame = support[0]
    for k in range(n):
        g = 0.0
        if frame[k]:
            for i in range(n):
                if not frame[i]:
                    continue
                # a frame's supporting joints form one path from the base, numbered parents first: i < k means i
                # carries k
                if i < k:  # k moves the frame's origin: a revolute i's column z_i x (p - o_i) by z_i x J_k,lin
                    if rev[i]:
                        d0 = Z[i, 1] * J[2, k] - Z[i, 2] * J[1, k]
                        d1 = Z[i, 2] * J[0, k] - Z[i, 0] * J[2, k]
                        d2 = Z[i, 0] * J[1, k] - Z[i, 1] * J[0, k]
                        g += M[0, i] * d0 + M[1, i] * d1 + M[2, i] * d2
                elif rev[k]:  # k turns column i (its linear and angular parts): z_k x J_i
                    for h in range(0, 6, 3):
                        d0 = Z[k, 1] * J[h + 2, i] - Z[k, 2] * J[h + 1, i]
                        d1 = Z[k, 2] * J[h, i] - Z[k, 0] * J[h + 2, i]
                        d2 = Z[k, 0] * J[h + 1, i] - Z[k, 1] * J[h, i]
                        g += M[h, i] * d0 + M[h + 1, i] * d1 + M[h + 2, i] * d2
        v[k] = m * g
    return m


@njit(cache=True, nogil=True, forceinline=False)
def _turned(q, q0, box, k):
    """q[k] - q0[k], for a full-turn joint (``box``'s wrap row) from the turn of q[k] nearest q0[k] inside the
    limits (the same pose; :func:`~evoik_pin.solvers.search.prefer.nearest_turn`'s rule)."""
    d = q[k] - q0[k]
    if box[B_WRAP, k] == 0.0:
        return d
    s = d - TWO_PI * np.round(d / TWO_PI)
    if q0[k] + s > box[B_HI, k]:
        s -= TWO_PI
    if q0[k] + s < box[B_LO, k]:
        s += TWO_PI
    return s if box[B_LO, k] <= q0[k] + s <= box[B_HI, k] else d


@njit(cache=True, nogil=True)
def log_manipulability_rows(Q, kin, box, any_wrap, goals, pt, Rt, out):
    """``-log(m)`` of each row of ``Q`` (N, n) into ``out`` (N,), m the descent's manipulability of the first goal's
    frame (:func:`_manipulability`; 1e-300 at a singularity): the cost of
    :class:`~evoik_pin.goals.preferences.Manipulability` (weight 1) to about 1e-12. The other arguments are
    :func:`descend_batch`'s (the engine's ``_args``)."""
    n = Q.shape[1]
    ws = make_workspace(kin, goals, n, 1)
    J, JJ = np.empty((6, n)), np.empty((6, 6))
    weighted = weighted_stack(goals[0])
    cur = ws.cur
    for i in range(Q.shape[0]):
        _copy(Q[i], cur.q)
        task_error(True, kin, False, goals, weighted, pt, Rt, cur.q, cur, ws)
        out[i] = -math.log(max(_manipulability(kin[3], goals[3], cur.pg, cur.Z, cur.O, J, JJ), 1e-300))


@njit(cache=True, nogil=True)
def nearest_turn_rows(Q, q0, lower, upper, wrap, out):
    """:func:`~evoik_pin.solvers.search.prefer.nearest_turn` of each row of ``Q`` (N, n) into ``out`` (N, n), the same
    floating-point operations in the same order (the same numbers)."""
    for i in range(Q.shape[0]):
        for k in range(Q.shape[1]):
            q = Q[i, k]
            out[i, k] = q
            if wrap[k]:
                s = q + TWO_PI * np.round((q0[k] - q) / TWO_PI)
                if s > upper[k]:
                    s = s - TWO_PI
                if s < lower[k]:
                    s = s + TWO_PI
                if s >= lower[k] and s <= upper[k]:
                    out[i, k] = s


@njit(cache=True, nogil=True, forceinline=False)
def _criterion(mode, q, q0, box, rev, support, pg, Z, O, J, JJ):
    """The criterion at q (lower is better), from q's kinematics buffers."""
    if mode == MODE_NEAREST:
        s = 0.0
        for k in range(q.shape[0]):
            d = _turned(q, q0, box, k)
            s += d * d
        return s
    return -_manipulability(rev, support, pg, Z, O, J, JJ)


@njit(cache=True, nogil=True, forceinline=False)
def descend_batch(Q, q0, mode, kin, box, any_wrap, goals, pt, Rt, iterations, restore, max_step, Q_out, f_out):
    """Each answer Q[i] (N, n) taken to a local optimum of the criterion ``mode`` in at most ``iterations`` steps,
    each restored to the goals by at most ``restore`` Gauss-Newton steps; the result to Q_out[i] (Q[i] itself when
    no step was kept) and its criterion to f_out[i]. A Q[i] off the goals is first taken onto them by at most
    ``restore`` Gauss-Newton steps; where they fail, Q_out[i] is Q[i] and f_out[i] inf. ``max_step`` (rad or m):
    the longest step. The other arguments are :func:`.kernel.lm_run_buffers`'. Returns the kinematics evaluations."""
    ws, JJ, M, p, q_prev, p_prev = _scratch(kin, goals, Q.shape[1])
    evaluations = 0
    for i in range(Q.shape[0]):
        evaluations += _descend(ws, JJ, M, p, q_prev, p_prev, Q[i], q0, mode, kin, box, goals, pt, Rt, iterations,
                                restore, max_step, Q_out[i], f_out, i)
    return evaluations


@njit(cache=True, nogil=True, forceinline=False)
def descend_batch_then_best(Q, q0, mode, kin, box, any_wrap, goals, pt, Rt, iterations, restore, max_step, further,
                            Q_out, f_out):
    """:func:`descend_batch`, then the answer of least criterion (the first of equals; none when every f_out is inf)
    ``further`` steps on from where it ended, as a descent of its own (its step length starts again): prefer's trial
    of its best answers and the best one's first round in one call. Returns the kinematics evaluations."""
    evaluations = descend_batch(Q, q0, mode, kin, box, any_wrap, goals, pt, Rt, iterations, restore, max_step, Q_out,
                                f_out)
    best = -1
    for i in range(Q.shape[0]):
        if f_out[i] < np.inf and (best < 0 or f_out[i] < f_out[best]):
            best = i
    if best >= 0 and further > 0:
        ws, JJ, M, p, q_prev, p_prev = _scratch(kin, goals, Q.shape[1])
        start = Q_out[best].copy()
        evaluations += _descend(ws, JJ, M, p, q_prev, p_prev, start, q0, mode, kin, box, goals, pt, Rt, further,
                                restore, max_step, Q_out[best], f_out, best)
    return evaluations


@njit(cache=True, nogil=True)
def _scratch(kin, goals, n):
    """A descent's workspace (:func:`.kernel.make_workspace`) and its scratch arrays JJ (6, 6), M (6, n), p, q_prev,
    p_prev (n,)."""
    return make_workspace(kin, goals, n, 1), np.empty((6, 6)), np.empty((6, n)), np.empty(n), np.empty(n), np.empty(n)


@njit(cache=True, nogil=True)
def _onto_goals(kin, mimic, goals, weighted, pt, Rt, q, state, ws, W, L, y, dq, box, spec, restore):
    """At most ``restore`` Gauss-Newton steps inside the box taking ``q`` (n,) (``state``: its task errors, evaluated)
    onto the goals; returns (whether they are met, the kinematics evaluations made). ``W``, ``L``, ``y``, ``dq``:
    scratch."""
    evaluations = 0
    for _r in range(restore):
        if within(spec, state.ge):
            break
        task_jacobian(True, kin, mimic, goals, weighted, pt, Rt, state, ws, W)
        if not damped_solve(W, LAMBDA_MIN, state.e, L, y, dq):
            break
        for k in range(q.shape[0]):
            q[k] = min(max(q[k] - dq[k], box[B_LO, k]), box[B_HI, k])
        task_error(True, kin, mimic, goals, weighted, pt, Rt, q, state, ws)
        evaluations += 1
    return within(spec, state.ge), evaluations


@njit(cache=True, nogil=True, forceinline=False)
def _descend(ws, JJ, M, p, q_prev, p_prev, q_start, q0, mode, kin, box, goals, pt, Rt, iterations, restore, max_step,
             q_out, f_out, i):
    """:func:`descend_batch` for one answer; returns its kinematics evaluations."""
    n = q_start.shape[0]
    rev, spec, support = kin[3], goals[0], goals[3]
    mimic = False  # the manipulability's Jacobian is over the physical joints: mimic trees are not descended
    weighted = weighted_stack(spec)
    m = ws.E.shape[0]
    cur, cand = ws.cur, ws.cand  # the kept configuration's State and the candidate's, traded when a step is kept
    J, E, W, L, y, rhs, v, dq, held = ws.J, ws.E, ws.W, ws.L, ws.y, ws.rhs, ws.v, ws.dq, ws.held
    if coupled(kin[4], kin[5], kin[6], n):  # left as it is (see above): a criterion of inf says so
        _copy(q_start, q_out)
        f_out[i] = np.inf
        return 0
    q = cur.q
    _copy(q_start, q)
    task_error(True, kin, mimic, goals, weighted, pt, Rt, q, cur, ws)
    evaluations = 1
    if not within(spec, cur.ge):  # a start off the goals (a flipped answer): Gauss-Newton onto them first
        met, count = _onto_goals(kin, mimic, goals, weighted, pt, Rt, q, cur, ws, W, L, y, dq, box, spec, restore)
        evaluations += count
        if not met:
            _copy(q_start, q_out)
            f_out[i] = np.inf  # left where it is: not an answer
            return evaluations
    f = _criterion(mode, q, q0, box, rev, support, cur.pg, cur.Z, cur.O, J, JJ)
    _copy(q, q_out)
    f_out[i] = f
    t0 = 1.0 if mode == MODE_NEAREST else -1.0  # -1: set from the first direction's length
    t = t0
    have_v = False
    have_prev = False  # q_prev, p_prev: the last kept step's start and its direction (the secant step's data)
    for _ in range(iterations):
        q, qn = cur.q, cand.q
        if not have_v:
            # the descent direction v at q, then the task Jacobian at q (the gradient's probes overwrite the
            # candidate's buffers only)
            if mode == MODE_NEAREST:
                for k in range(n):
                    v[k] = -_turned(q, q0, box, k)
            elif _manipulability_gradient(rev, support, cur.pg, cur.Z, cur.O, J, JJ, M, v) <= 0.0:
                for k in range(n):  # a singularity: forward differences
                    _copy(q, qn)
                    qn[k] += MANIP_H
                    task_error(True, kin, mimic, goals, weighted, pt, Rt, qn, cand, ws)
                    v[k] = (-_criterion(mode, qn, q0, box, rev, support, cand.pg, cand.Z, cand.O, J, JJ) + f) / MANIP_H
                evaluations += n
            task_jacobian(True, kin, mimic, goals, weighted, pt, Rt, cur, ws, E)
            # p: v projected on the null space of E, joints on a bound that p pushes outward held (twice: holding
            # one joint changes the others' motion)
            for k in range(n):
                held[k] = False
            for _pass in range(3):
                for r in range(m):
                    s = 0.0
                    for k in range(n):
                        W[r, k] = 0.0 if held[k] else E[r, k]
                        s += W[r, k] * v[k]
                    rhs[r] = s
                if not damped_solve(W, LAMBDA_MIN, rhs, L, y, dq):
                    return evaluations
                again = False
                for k in range(n):
                    p[k] = 0.0 if held[k] else v[k] - dq[k]
                    if not held[k] and ((q[k] <= box[B_LO, k] + ON_BOUND and p[k] < 0.0)
                                        or (q[k] >= box[B_HI, k] - ON_BOUND and p[k] > 0.0)):
                        held[k] = True
                        again = True
                if not again:
                    break
            norm = 0.0
            for k in range(n):
                norm += p[k] * p[k]
            norm = math.sqrt(norm)
            if norm < 1e-12:
                break
            have_v = True
            if t0 < 0.0:
                t0 = MANIP_STEP / norm
                t = t0
            if have_prev:  # Barzilai-Borwein: the secant of the direction's change over the last kept step
                ss = 0.0
                sy = 0.0
                for k in range(n):
                    d = q[k] - q_prev[k]
                    ss += d * d
                    sy += d * (p_prev[k] - p[k])
                if sy > 0.0:
                    t = min(max(ss / sy, BB_RANGE[0] * t0), BB_RANGE[1] * t0)
        # the step t p, shortened to the box and to max_step
        s = min(t, max_step / norm)
        for k in range(n):
            if p[k] > 0.0:
                s = min(s, (box[B_HI, k] - q[k]) / p[k])
            elif p[k] < 0.0:
                s = min(s, (box[B_LO, k] - q[k]) / p[k])
        if s <= 0.0:
            break
        for k in range(n):
            qn[k] = min(max(q[k] + s * p[k], box[B_LO, k]), box[B_HI, k])
        # Gauss-Newton back onto the goals
        task_error(True, kin, mimic, goals, weighted, pt, Rt, qn, cand, ws)
        met, count = _onto_goals(kin, mimic, goals, weighted, pt, Rt, qn, cand, ws, W, L, y, dq, box, spec, restore)
        evaluations += 1 + count
        f_new = _criterion(mode, qn, q0, box, rev, support, cand.pg, cand.Z, cand.O, J, JJ) if met else np.inf
        if f_new < f - 1e-15 * max(1.0, abs(f)):
            _copy(q, q_prev)
            _copy(p, p_prev)
            have_prev = True
            cur, cand = cand, cur
            f = f_new
            have_v = False
            t = min(2.0 * t, 1.0) if mode == MODE_NEAREST else 2.0 * t
            if s * norm < MIN_STEP:  # converged: further steps would not move q beyond the goals' own accuracy
                break
        else:
            t *= 0.5
            if t < 1e-3 * t0:
                break
    _copy(cur.q, q_out)
    f_out[i] = f
    return evaluations


#: About how long (s, one core) compiling the null-space descent takes from an empty cache (:func:`.compiling.load`).
NULLSPACE_COMPILE_SECONDS = 25.0


def nullspace_kernel() -> dict:
    """:func:`descend_batch` (and :func:`descend_batch_then_best`), :func:`nearest_turn_rows`,
    :func:`log_manipulability_rows` and :func:`.population_rows.task_rows` (for :func:`~..search.prefer.refine`),
    loaded (or compiled) outside any time budget."""
    if not _KERNEL:
        from .compiling import load
        from .engine import warmup_problem
        from .population_rows import task_rows

        tree, box, goals, pt, Rt = warmup_problem()
        z = np.zeros((1, 1))
        load("the null-space descent of prefer= and preferences", [
            (descend_batch, (z, z[0], MODE_NEAREST, tree, box, False, goals, pt, Rt, 1, 1, 0.5, np.empty((1, 1)),
                             np.empty(1))),
            (descend_batch_then_best, (z, z[0], MODE_NEAREST, tree, box, False, goals, pt, Rt, 1, 1, 0.5, 1,
                                       np.empty((1, 1)), np.empty(1))),
            (nearest_turn_rows, (z, z[0], z[0], z[0], np.zeros(1, dtype=np.bool_), np.empty((1, 1)))),
            (log_manipulability_rows, (z, tree, box, False, goals, pt, Rt, np.empty(1))),
            (task_rows, (np.zeros(1), *tree, *goals, pt, Rt, np.empty(6), np.empty((6, 1)), np.empty((1, 2))))],
             NULLSPACE_COMPILE_SECONDS)
        _KERNEL.update(descend_batch=descend_batch, descend_batch_then_best=descend_batch_then_best,
                       task_rows=task_rows, nearest_turn_rows=nearest_turn_rows,
                       log_manipulability_rows=log_manipulability_rows)
    return _KERNEL
