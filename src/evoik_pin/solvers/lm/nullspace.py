"""Compiled descent along the goals' self-motion manifold (numba): ``prefer="nearest"`` and ``"manipulability"``.

A redundant arm's answers to a goal stack (Panda on a pose: 7 joints, 6 rows) form curves (one per IK branch, cut by
the joint limits); the answer nearest q0 or the most dexterous one is a continuous optimum along such a curve,
which picking among a few discrete LM answers only approximates. :func:`descend_batch` takes each given answer
(every goal met) to a local optimum of the criterion on its curve:

1. the criterion's descent direction projected on the null space of the task Jacobian E (n,): for nearness
   ``v = q0 - q`` (the negative gradient of ``|q - q0|^2 / 2``), for manipulability the gradient of Yoshikawa's
   ``sqrt(det(J J^T))`` (the first goal frame's 6 x n LOCAL_WORLD_ALIGNED Jacobian) by forward differences;
   ``p = v - E^T (E E^T)^-1 E v`` with joints on a bound that p pushes outward held (their column of E zeroed);
2. a step ``t p`` (t = 1 first for nearness: the minimum of |q - q0|^2 on the tangent plane; a step of
   ``MANIP_STEP`` rad first for manipulability), shortened to stay inside the box and within ``max_step``;
3. Gauss-Newton steps from there until every goal is within its tolerances again (at most ``restore``);
4. the step is kept only when step 3 met every goal and the criterion improved (then the next t is the secant
   (Barzilai-Borwein) step of the last two directions); otherwise t halves. The descent ends when t is below 1e-3
   of its start or a kept step was shorter than :data:`MIN_STEP`.

So the criterion never gets worse and every kept configuration meets every goal (the kernel's own test,
:func:`.kernel.within`). A step costs 1-5 kinematics evaluations (n more for manipulability's gradient).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from ...goals.stack import G_WEIGHT
from .chain import coupled
from .kernel import _copy, damped_solve, make_workspace, stack_rows, task_error, task_jacobian, within
from .layout import B_CHI, B_CLO, LAMBDA_MIN
from .tree_kinematics import frame_jacobian

__all__ = ["MODE_MANIPULABILITY", "MODE_NEAREST", "descend_batch", "nullspace_kernel"]

#: What :func:`descend_batch` optimises: nearness to q0 (``|q - q0|^2``, lower is better) or manipulability
#: (``-sqrt(det(J J^T))`` of the first goal's frame, lower is better).
MODE_NEAREST, MODE_MANIPULABILITY = 0, 1
#: First step length (rad or m) of a manipulability ascent: its scale is unknown (no curvature to divide by).
MANIP_STEP = 0.2
#: Forward-difference step (rad or m) of the manipulability gradient.
MANIP_H = 1e-6
#: The secant (Barzilai-Borwein) step's range, times the first step's multiple t0: after a kept step, the next
#: step's multiple is |s|^2 / s.(p_prev - p) (s the kept step, p the projected direction), which converges in a few
#: steps where the fixed step t = 1 converges linearly (measured: 20 steps left 1e-5 rad to go).
BB_RANGE = (0.01, 100.0)
#: A kept step shorter than this (rad or m) ends the descent.
MIN_STEP = 1e-9
#: A joint closer than this to a bound (rad or m) counts as on it.
ON_BOUND = 1e-12

_KERNEL: dict = {}

@njit(cache=True, nogil=True, forceinline=True)
def _jacobian(rev, index, scale, mimic, spec, weighted, support, gaux, pt, Rt, Rg, pg, Z, O, tg, e, Jx, J, rv, A,
              B, E, parent, Rj, pj):
    """:func:`.kernel.task_jacobian` at the configuration whose buffers these are, compiled for every goal kind
    (``extra``: the descent serves any goal list)."""
    task_jacobian(True, rev, index, scale, mimic, spec, weighted, support, gaux, pt, Rt, Rg, pg, Z, O, tg, e, Jx, J,
                  rv, A, B, E, parent, Rj, pj)


@njit(cache=True, nogil=True, forceinline=False)
def _manipulability(rev, support, pg, Z, O, J, JJ):
    """sqrt(det(J J^T)) of the first goal frame's base-frame (LOCAL_WORLD_ALIGNED) Jacobian J (6, n), from the
    kinematics buffers :func:`.kernel.task_error` filled (pg its frame's position, Z, O the joint axes and origins);
    0 at a singularity. JJ (6, 6) scratch. The Cholesky factor's diagonal gives the determinant."""
    frame_jacobian(rev, support[0], pg[0], Z, O, J)
    n = J.shape[1]
    for i in range(6):
        for j in range(i + 1):
            s = 0.0
            for k in range(n):
                s += J[i, k] * J[j, k]
            JJ[i, j] = s
    logdet = 0.0
    for i in range(6):  # in-place Cholesky of the lower triangle
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
def _criterion(mode, q, q0, rev, support, pg, Z, O, J, JJ):
    """The criterion at q (lower is better), from q's kinematics buffers."""
    if mode == MODE_NEAREST:
        s = 0.0
        for k in range(q.shape[0]):
            d = q[k] - q0[k]
            s += d * d
        return s
    return -_manipulability(rev, support, pg, Z, O, J, JJ)


@njit(cache=True, nogil=True, forceinline=False)
def descend_batch(Q, q0, mode, parent, FR, Fp, rev, index, scale, offset, box, any_wrap, spec, gR, gp, support, gaux,
                  pt, Rt, iterations, restore, max_step, Q_out, f_out):
    """Each answer Q[i] (N, n) taken along its self-motion manifold to a local optimum of the criterion (``mode``,
    see the module docstring) in at most ``iterations`` kept-or-rejected steps, each restored to the goals by at
    most ``restore`` Gauss-Newton steps; the result to Q_out[i] (Q[i] itself when no step was kept or Q[i] does not
    meet the goals) and its criterion to f_out[i] (|q - q0|^2 or -manipulability). ``max_step`` (rad or m): the
    longest step. The other arguments are :func:`.kernel.lm_run`'s (one goal stack and its targets pt, Rt).
    Returns the kinematics evaluations made."""
    N, n = Q.shape
    m, G = parent.shape[0], spec.shape[0]
    ws = make_workspace(n, m, G, stack_rows(spec), 1)
    JJ = np.empty((6, 6))
    p, q_prev, p_prev = np.empty(n), np.empty(n), np.empty(n)
    evaluations = 0
    for i in range(N):
        evaluations += _descend(ws, JJ, p, q_prev, p_prev, Q[i], q0, mode, parent, FR, Fp, rev, index, scale, offset,
                                box, any_wrap, spec, gR, gp, support, gaux, pt, Rt, iterations, restore, max_step,
                                Q_out[i], f_out, i)
    return evaluations


@njit(cache=True, nogil=True, forceinline=False)
def _descend(ws, JJ, p, q_prev, p_prev, q_start, q0, mode, parent, FR, Fp, rev, index, scale, offset, box, any_wrap,
             spec, gR, gp, support, gaux, pt, Rt, iterations, restore, max_step, q_out, f_out, i):
    """:func:`descend_batch` for one answer; returns its kinematics evaluations."""
    n = q_start.shape[0]
    mimic = False  # the manipulability's Jacobian is over the physical joints: mimic trees are not descended
    weighted = False
    for g in range(spec.shape[0]):
        if spec[g, G_WEIGHT] != 1.0:
            weighted = True
    m = ws.E.shape[0]
    # the kept configuration's kinematics buffers and the candidate's, traded when a step is kept
    cur = (ws.q, ws.Rj, ws.pj, ws.Z, ws.O, ws.Rg, ws.pg, ws.tg, ws.e, ws.ge)
    cand = (ws.qn, ws.Rj2, ws.pj2, ws.Z2, ws.O2, ws.Rg2, ws.pg2, ws.tg2, ws.en, ws.ge2)
    q, Rj, pj, Z, O, Rg, pg, tg, e, ge = cur
    qn, Rj2, pj2, Z2, O2, Rg2, pg2, tg2, en, ge2 = cand
    x, Jx, J, rv, E, W, A, Bm, M = ws.x, ws.Jx, ws.J, ws.rv, ws.E, ws.W, ws.A, ws.Bm, ws.M
    L, y, rhs, v, dq, held = ws.L, ws.y, ws.rhs, ws.v, ws.dq, ws.held
    if coupled(index, scale, offset, n):  # left as it is (see above): a criterion of inf says so
        _copy(q_start, q_out)
        f_out[i] = np.inf
        return 0
    _copy(q_start, q)
    task_error(True, parent, FR, Fp, rev, index, scale, offset, mimic, q, x, spec, weighted, gR, gp, gaux, pt, Rt, Rj,
               pj, Z, O, Rg, pg, tg, M, e, ge)
    evaluations = 1
    f = _criterion(mode, q, q0, rev, support, pg, Z, O, J, JJ)
    _copy(q, q_out)
    f_out[i] = f
    if not within(spec, ge):
        return evaluations
    t0 = 1.0 if mode == MODE_NEAREST else -1.0  # -1: set from the first direction's length
    t = t0
    have_v = False
    have_prev = False  # q_prev, p_prev: the last kept step's start and its direction (the secant step's data)
    for _ in range(iterations):
        q, Rj, pj, Z, O, Rg, pg, tg, e, ge = cur
        qn, Rj2, pj2, Z2, O2, Rg2, pg2, tg2, en, ge2 = cand
        if not have_v:
            # the descent direction v at q, then the task Jacobian at q (the gradient's probes overwrite the
            # candidate's buffers only)
            if mode == MODE_NEAREST:
                for k in range(n):
                    v[k] = q0[k] - q[k]
            else:
                for k in range(n):
                    _copy(q, qn)
                    qn[k] += MANIP_H
                    task_error(True, parent, FR, Fp, rev, index, scale, offset, mimic, qn, x, spec, weighted, gR, gp,
                               gaux, pt, Rt, Rj2, pj2, Z2, O2, Rg2, pg2, tg2, M, en, ge2)
                    v[k] = (-_criterion(mode, qn, q0, rev, support, pg2, Z2, O2, J, JJ) + f) / MANIP_H
                evaluations += n
            _jacobian(rev, index, scale, mimic, spec, weighted, support, gaux, pt, Rt, Rg, pg, Z, O, tg, e, Jx, J, rv,
                      A, Bm, E, parent, Rj, pj)
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
                    if not held[k] and ((q[k] <= box[B_CLO, k] + ON_BOUND and p[k] < 0.0)
                                        or (q[k] >= box[B_CHI, k] - ON_BOUND and p[k] > 0.0)):
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
                s = min(s, (box[B_CHI, k] - q[k]) / p[k])
            elif p[k] < 0.0:
                s = min(s, (box[B_CLO, k] - q[k]) / p[k])
        if s <= 0.0:
            break
        for k in range(n):
            qn[k] = min(max(q[k] + s * p[k], box[B_CLO, k]), box[B_CHI, k])
        # Gauss-Newton back onto the goals
        met = False
        for _r in range(restore + 1):
            task_error(True, parent, FR, Fp, rev, index, scale, offset, mimic, qn, x, spec, weighted, gR, gp, gaux, pt,
                       Rt, Rj2, pj2, Z2, O2, Rg2, pg2, tg2, M, en, ge2)
            evaluations += 1
            if within(spec, ge2):
                met = True
                break
            if _r == restore:
                break
            _jacobian(rev, index, scale, mimic, spec, weighted, support, gaux, pt, Rt, Rg2, pg2, Z2, O2, tg2, en, Jx,
                      J, rv, A, Bm, W, parent, Rj2, pj2)
            if not damped_solve(W, LAMBDA_MIN, en, L, y, dq):
                break
            for k in range(n):
                qn[k] = min(max(qn[k] - dq[k], box[B_CLO, k]), box[B_CHI, k])
        f_new = _criterion(mode, qn, q0, rev, support, pg2, Z2, O2, J, JJ) if met else np.inf
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
    _copy(cur[0], q_out)
    f_out[i] = f
    return evaluations


#: About how long (s, one core) compiling the null-space descent takes from an empty cache (its first use after an
#: install, announced by :func:`.compiling.load`).
NULLSPACE_COMPILE_SECONDS = 25.0


def nullspace_kernel() -> dict:
    """:func:`descend_batch` and :func:`.population_rows.task_rows` (the task Jacobian whose null space
    :func:`evoik_pin.solvers.search.prefer.refine` steps in), compiled (or loaded from numba's disk cache) on a
    one-joint robot, outside any time budget."""
    if not _KERNEL:
        from .compiling import load
        from .engine import warmup_problem
        from .population_rows import task_rows

        tree, box, goals, pt, Rt = warmup_problem()
        load("the null-space descent of prefer= and preferences", [
            (descend_batch, (np.zeros((1, 1)), np.zeros(1), MODE_NEAREST, *tree, box, False, *goals, pt, Rt, 1, 1,
                             0.5, np.empty((1, 1)), np.empty(1))),
            (task_rows, (np.zeros(1), *tree, *goals, pt, Rt, np.empty(6), np.empty((6, 1)), np.empty((1, 2))))],
             NULLSPACE_COMPILE_SECONDS)
        _KERNEL.update(descend_batch=descend_batch, task_rows=task_rows)
    return _KERNEL
