"""memetic's guaranteed LM runs for one target (or a goal list of one goal on one frame) in one compiled call
(numba): q0's nearness, the seed table's ranking and the runs, in the order
:func:`~evoik_pin.solvers.search.memetic._solve` makes them.

A single-target solve that one of its first runs solves (nearly every one: the run from the table's nearest entry
or a near q0 converges) spent most of its time in Python around those runs: q0's tip pose from Pinocchio and its
nearness, the ranking's dispatches, an engine call and an outcome object per run (about 10-20 us). Here they are
one call. The runs are those memetic makes whatever the clock says (``guaranteed``: q0's and the
``GUARANTEED_TABLE_RUNS`` nearest entries'), so the clock plays no part; when none of them converges, memetic
solves the problem its own way from the start (the same runs again, then the clock-checked rest), and the answer
is its own.

The decisions are memetic's: q0 first when its tip pose is within the table's typical gap of the target, or nearer
than the nearest entry; then the nearest entry, q0 (when it went second), the next entries. q0's tip pose comes from
the kernel's kinematics and its distances are summed in the features' order, where memetic used Pinocchio and BLAS:
the numbers can differ in their last bits, so a decision can only differ when q0 is within a few ulps of the gap or
of the entry's distance (and the ranking only where two entries' distances are, :mod:`.nearest`):
tests/test_first_runs.py holds the answers equal over thousands of targets.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from ..lm.chain import coupled, expand
from ..lm.kernel import lm_run_buffers, lm_run_buffers_basic
from ..lm.layout import G_JOINT
from ..lm.tree import frame_pose, tree_forward
from .nearest import select_k, table_distances

__all__ = ["STAGE_Q0", "STAGE_TABLE", "first_runs", "first_runs_basic"]

#: Which start solved the problem (first_runs's first return value; -1: none did).
STAGE_Q0, STAGE_TABLE = 0, 1


#: first_runs' docstring (both variants').
_DOC = """Up to ``has_q0 + table_runs`` LM runs (the kernel's, :func:`~..lm.kernel.lm_run_buffers`) from q0 and the
    nearest table entries, stopping at the first that converges.

    Args:
        buf, held: the kernel's workspace. q0 (n,): the start given (read when ``has_q0``). lower, upper (n,): the
            search box (q0's tip pose is taken at q0 clipped into it). gap: the table's typical squared gap
            (``SeedTable.typical_gap_sq``). Q (size, n): the table's configurations; F (size, D) their features
            (the goal frame's position, then its rotation's 9 entries: D = 12; position alone: D = 3; rotation
            alone: D = 9), FT (D, size) the same transposed, sq (size,) their squared norms (the ranking:
            :func:`~.nearest.table_distances`). sp, sr: the features' scales of a position (1 for a single target,
            sqrt(weight) for a goal) and of a rotation's entries (the table's rotation weight (m), times
            sqrt(weight) for a goal). oriented: whether the engine counts the orientation error (``lm.oriented``:
            a run's error is position + orientation error, else position error).
            table_runs: the entries run at most (>= 1).
        parent ... Rt, params: the kernel's arguments (:func:`~..lm.kernel.lm_run`), one goal on one frame (the
            tip's for a single target).
        q_out (n,), g_out (1, 2): the converged run's configuration and errors. errors (>= runs,): each run's
            position error + orientation error (m + rad), in order. best_q (n,), best (6,): when none converges,
            the run memetic keeps as its best (the first of the lowest errors): its configuration, and its position
            error, orientation error, weighted |e|^2, iterations, evaluations and index among the runs (best: (6,)).

    Returns:
        (STAGE_Q0 or STAGE_TABLE: the start that converged, or -1; runs made; their forward-kinematics evaluations
        summed; the converged (or last) run's position error m, orientation error rad (nan for a position),
        weighted |e|^2).
    """


def _first_runs(extra, name):
    """:func:`first_runs` compiled for one variant of the kernel's run (``extra``: :func:`~..lm.kernel._run`'s: None
    for stacks of the first four kinds, True for any), a constant of the closure whose branch numba prunes before
    typing: each variant calls (and links) the one entry of its run, as the kernel's entries do."""

    def runs(buf, held, q0, has_q0, lower, upper, gap, Q, F, FT, sq, sp, sr, oriented, table_runs, parent, FR, Fp,
             rev, index, scale, offset, box, any_wrap, spec, gR, gp, support, gaux, pt, Rt, params, q_out, g_out,
             errors, best_q, best):  # pragma: no cover - compiled
        n = q0.shape[0]
        D = F.shape[1]
        has_position = D != 9
        ro = 3 if has_position else 0  # where the rotation's entries start (D > 3: they are features)
        # the target's features (SeedTable.one_target_features, .one_goal_features: sp x its position, then sr x its
        # rotation's entries; the products NumPy makes, so the same numbers)
        f = np.empty(D)
        if has_position:
            for j in range(3):
                f[j] = sp * pt[0, j]
        if D > 3:
            for j in range(9):
                f[ro + j] = sr * Rt[0, j // 3, j % 3]
        d = np.empty(F.shape[0])
        table_distances(FT, sq, f, d)
        # the nearest entries, nearest first, in one pass over the distances (the nearest alone, which q0's decision
        # reads, is the first of them: select_k keeps argmin's order)
        out = np.empty(max(table_runs, 1), dtype=np.int64)
        ranked = select_k(d, np.zeros(0, dtype=np.bool_), table_runs, out)
        q0_first = has_q0
        if has_q0:
            # q0's tip pose (clipped into the box) and its squared distance to the target in the table's metric
            qc = np.empty(n)
            for i in range(n):
                qc[i] = min(max(q0[i], lower[i]), upper[i])
            m = parent.shape[0]
            Rj, pj, Z, O = np.empty((m, 3, 3)), np.empty((m, 3)), np.empty((m, 3)), np.empty((m, 3))
            x = np.empty(m)
            if coupled(index, scale, offset, n):
                expand(index, scale, offset, qc, x)
            else:  # loops, not slice assignments: those compile numba's shape-mismatch message (seconds, once)
                for i in range(m):
                    x[i] = qc[i]
            tree_forward(parent, FR, Fp, rev, x, Rj, pj, Z, O)
            R, p = np.empty((3, 3)), np.empty(3)
            frame_pose(Rj, pj, int(spec[0, G_JOINT]), gR[0], gp[0], R, p)
            d0 = 0.0
            if has_position:
                for j in range(3):
                    c = f[j] - sp * p[j]
                    d0 += c * c
            if D > 3:
                for j in range(9):
                    c = f[ro + j] - sr * R[j // 3, j % 3]
                    d0 += c * c
            if d0 > gap:  # a random guess rather than a previous solution: second unless nearer than the nearest entry
                if ranked > 0:
                    first = out[0]
                    de = 0.0
                    for j in range(D):
                        c = f[j] - F[first, j]
                        de += c * c
                    q0_first = d0 <= de
                else:
                    q0_first = True
        # the starts in memetic's order: q0 first or after the nearest entry, then the next entries (-1: q0)
        order = np.empty(table_runs + 1, dtype=np.int64)
        count = 0
        if q0_first:
            order[count] = -1
            count += 1
        for r in range(ranked):
            order[count] = out[r]
            count += 1
            if r == 0 and has_q0 and not q0_first:
                order[count] = -1
                count += 1
        evaluations = 0
        pos = rot = cost = np.nan
        for s in range(count):
            row = order[s]
            start = q0 if row < 0 else Q[row]
            if extra is not None:
                pos, rot, converged, it, ev, cost = lm_run_buffers(
                    buf, held, start, parent, FR, Fp, rev, index, scale, offset, box, any_wrap, spec, gR, gp, support,
                    gaux, pt, Rt, params, q_out, g_out)
            else:
                pos, rot, converged, it, ev, cost = lm_run_buffers_basic(
                    buf, held, start, parent, FR, Fp, rev, index, scale, offset, box, any_wrap, spec, gR, gp, support,
                    gaux, pt, Rt, params, q_out, g_out)
            error = pos + (rot if oriented else 0.0)
            errors[s] = error
            evaluations += ev
            if converged:
                return (STAGE_Q0 if row < 0 else STAGE_TABLE), s + 1, evaluations, pos, rot, cost
            if s == 0 or error < errors[int(best[5])]:  # memetic's _Search._keep: a strictly lower error replaces
                for i in range(n):
                    best_q[i] = q_out[i]
                best[0], best[1], best[2], best[3], best[4], best[5] = pos, rot, cost, it, ev, s
        return -1, count, evaluations, pos, rot, cost

    runs.__name__ = runs.__qualname__ = name
    runs.__doc__ = _DOC
    return njit(cache=True, nogil=True, forceinline=False)(runs)


#: memetic's first runs for stacks of the first four kinds (the kernel's ``lm_run_basic``) and for any stack
#: (``lm_run_all``): :meth:`.memetic.MemeticPlan.first_runs` picks the one of its engine's kernel.
first_runs_basic = _first_runs(None, "first_runs_basic")
first_runs = _first_runs(True, "first_runs")

