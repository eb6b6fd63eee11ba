"""memetic's guaranteed LM runs in one compiled call (numba), in memetic's order and with its decisions: for one goal
on one frame :func:`guaranteed_runs` (q0's nearness, the table's ranking, the runs), for a goal list
:func:`goal_guaranteed_runs` (the ranking, :meth:`~.seed_table.SeedTable.goal_starts`' composed starts, the runs). A
decision may differ from memetic's within a few ulps only (tests/test_guaranteed_runs.py,
tests/test_goal_guaranteed_runs.py hold the answers equal)."""

from __future__ import annotations

import numpy as np
from numba import njit

from ...goals.stack import G_JOINT
from ...lie.compiled import is_rotation_entries
from ..lm.chain import coupled, expand
from ..lm.kernel import lm_run_buffers, lm_run_buffers_basic
from ..lm.layout import B_HI, B_LO
from ..lm.tree_kinematics import frame_pose, tree_forward
from .nearest import nearest_per_goal, rank_goal_entries, seen_from, select_few, table_distances

__all__ = ["BASE_EACH_ENTRY", "BASE_FIXED", "BASE_FROM_GOAL", "REFUSED", "STAGE_Q0", "STAGE_TABLE", "guaranteed_runs",
           "guaranteed_runs_basic", "goal_guaranteed_runs", "goal_guaranteed_runs_basic"]

#: Which start solved the problem (guaranteed_runs's first return value; -1: none did; REFUSED: the target's rotation is
#: not a rotation matrix, nothing run).
STAGE_Q0, STAGE_TABLE, REFUSED = 0, 1, -2
#: How a goal list's composed starts see the goals (goal_guaranteed_runs's ``base_mode``): as they are (a fixed base),
#: from a floating base a goal sets, or from each composed start's table entry's base.
BASE_FIXED, BASE_FROM_GOAL, BASE_EACH_ENTRY = 0, 1, 2


_DOC = """Up to ``has_q0 + table_runs`` LM runs from q0 and the nearest table entries, stopping at the first that
    converges.

    Args:
        buf, held: the kernel's workspace. q0 (n,): the start given (read when ``has_q0``; its tip pose is taken at q0
            clipped into the search box, ``box``'s B_LO and B_HI rows). check_rt: first check that the target's
            rotation ``Rt[0]`` is a rotation matrix (:func:`~evoik_pin.lie.so3.is_rotation_entries`), else return
            REFUSED having run nothing. gap: the table's typical squared gap. Q
            (size, n): the table's configurations; FT (D, size) their features transposed (position, then the
            rotation's 9 entries: D = 12, 3 or 9), sq (size,) their squared norms (:func:`~.nearest.table_distances`).
            sp, sr: the features' scales of a position and of a rotation's entries
            (:meth:`~.seed_table.SeedTable.one_goal_features`). oriented: a run's error is position + orientation
            error (else position error). table_runs: the entries run at most (>= 1).
        kin ... params: the kernel's arguments (:func:`~..lm.kernel.lm_run_buffers`), one goal on one frame.
        q_out (n,), g_out (1, 2): the converged run's configuration and errors. errors (>= runs,): each run's error
            (m + rad). best_q (n,), best (6,): when none converges, memetic's best run (the first of the lowest
            errors): its configuration; its position error, orientation error, weighted |e|^2, iterations,
            evaluations and index.

    Returns:
        (STAGE_Q0, STAGE_TABLE, -1 (no start converged) or REFUSED: the start that converged; runs made; their
        evaluations; the converged (or last) run's position error m, orientation error rad (nan for a position),
        weighted |e|^2).
    """


def _guaranteed_runs(extra, name):
    """:func:`guaranteed_runs` compiled for one variant of the kernel's run (``extra``: :func:`~..lm.kernel._run`'s, a
    constant of the closure)."""

    def runs(buf, held, q0, has_q0, check_rt, gap, Q, FT, sq, sp, sr, oriented, table_runs, kin, box, any_wrap, goals,
             pt, Rt, params, q_out, g_out, errors, best_q, best):  # pragma: no cover - compiled
        if check_rt:
            T = Rt[0]
            if not is_rotation_entries(T[0, 0], T[0, 1], T[0, 2], T[1, 0], T[1, 1], T[1, 2], T[2, 0], T[2, 1], T[2, 2]):
                return REFUSED, 0, 0, np.nan, np.nan, np.nan
        parent, FR, Fp, rev, index, scale, offset = kin
        spec, gR, gp = goals[0], goals[1], goals[2]
        n = q0.shape[0]
        D = FT.shape[0]
        has_position = D != 9
        ro = 3 if has_position else 0  # where the rotation's entries start (D > 3: they are features)
        # the target's features, the products SeedTable.one_goal_features makes
        f = np.empty(D)
        if has_position:
            for j in range(3):
                f[j] = sp * pt[0, j]
        if D > 3:
            for j in range(9):
                f[ro + j] = sr * Rt[0, j // 3, j % 3]
        d = np.empty(FT.shape[1])
        table_distances(FT, sq, f, d)
        # the nearest entries, nearest first (select_k's order), in one pass over the distances
        out = np.empty(max(table_runs, 1), dtype=np.int64)
        ranked = select_few(d, np.zeros(0, dtype=np.bool_), table_runs, out)
        q0_first = has_q0
        if has_q0:
            # q0's tip pose (clipped into the box) and its squared distance to the target in the table's metric
            qc = np.empty(n)
            for i in range(n):
                qc[i] = min(max(q0[i], box[B_LO, i]), box[B_HI, i])
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
            if d0 > gap and ranked > 0:  # a random guess, not a previous solution: second unless nearer than the
                first = out[0]  # nearest entry
                de = 0.0
                for j in range(D):
                    c = f[j] - FT[j, first]
                    de += c * c
                q0_first = d0 <= de
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
            # the kernel's variant by a constant branch: a dispatcher bound in the closure instead makes numba's cache
            # miss in every new process (the variant compiled again each time)
            if extra is not None:
                pos, rot, converged, it, ev, cost = lm_run_buffers(buf, held, start, kin, box, any_wrap, goals, pt, Rt,
                                                                   params, q_out, g_out)
            else:
                pos, rot, converged, it, ev, cost = lm_run_buffers_basic(buf, held, start, kin, box, any_wrap, goals,
                                                                         pt, Rt, params, q_out, g_out)
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

    return _compiled(runs, name, _DOC)


def _compiled(runs, name: str, doc: str):
    """``runs`` compiled (numba, cached) under ``name`` with docstring ``doc``."""
    runs.__name__ = runs.__qualname__ = name
    runs.__doc__ = doc
    return njit(cache=True, nogil=True, forceinline=False)(runs)


#: memetic's guaranteed runs per variant of the kernel's run (``lm_run_basic``, ``lm_run_all``).
guaranteed_runs_basic = _guaranteed_runs(None, "guaranteed_runs_basic")
guaranteed_runs = _guaranteed_runs(True, "guaranteed_runs")


_GOAL_DOC = """q0's LM run, then up to ``table_runs`` of :meth:`~.seed_table.SeedTable.goal_starts`' starts in its
    order (a start composed goal by goal, the next table entry by the goals' summed nearness, alternately), stopping
    at the first run that converges.

    Args:
        buf, held: the kernel's workspace. q0 (n,): the start given (run first when ``has_q0``). Q (N, n): the
            table's configurations. FT, sq, PT, psq, pstart, gscale, gpos, gori, idx, idx_start: the goal list's
            table layout (:meth:`~.seed_table.SeedTable.goal_layout`). weight: the table's rotation weight (m). wpt
            (G, 3), wRt (G, 3, 3): the goals' targets as the table ranks them (:func:`~.seed_table.seed_targets`).
            base (6,), base_mode: BASE_FIXED, BASE_FROM_GOAL (``base``: every start's floating base) or
            BASE_EACH_ENTRY. allowed: (N,) bool or (0,) for every entry. oriented, table_runs: as guaranteed_runs'.
        kin ... params: the kernel's arguments (:func:`~..lm.kernel.lm_run_buffers`) for the goal list.
        q_out (n,), g_out (G, 2), errors, best_q, best: as guaranteed_runs', the best by the lowest weighted |e|^2
            (LMOutcome.rank for several goals); best_g (G, 2): its goals' errors.

    Returns:
        guaranteed_runs'.
    """


def _goal_guaranteed_runs(extra, name):
    """:func:`goal_guaranteed_runs` compiled for one variant of the kernel's run (as :func:`_guaranteed_runs`)."""

    def runs(buf, held, q0, has_q0, Q, FT, sq, PT, psq, pstart, gscale, gpos, gori, weight, wpt, wRt, idx,
             idx_start, base, base_mode, allowed, oriented, table_runs, kin, box, any_wrap, goals, pt, Rt, params,
             q_out, g_out, errors, best_q, best, best_g):  # pragma: no cover - compiled
        N, n = Q.shape
        G = wpt.shape[0]
        composed = (table_runs + 1) // 2  # starts 2j (composed j) and 2j + 1 (entry j) read the j-th ranked entry
        rows = np.empty(max(composed, 1), dtype=np.int64)
        ranked = rank_goal_entries(FT, sq, gscale, gpos, gori, weight, wpt, wRt, allowed, composed, rows)
        rpt, rRt = np.empty((G, 3)), np.empty((G, 3, 3))
        picks = np.empty((G, max(composed, 1)), dtype=np.int64)
        if base_mode != BASE_EACH_ENTRY and ranked > 0:  # each goal's nearest entries, once for every composed start
            if base_mode == BASE_FROM_GOAL:
                seen_from(base, wpt, wRt, rpt, rRt)
            else:
                rpt[:], rRt[:] = wpt, wRt
            nearest_per_goal(PT, psq, pstart, gscale, gpos, gori, weight, rpt, rRt, allowed, ranked, picks)
        start = np.empty(n)
        total = has_q0 + min(table_runs, 2 * ranked)
        evaluations = 0
        pos = rot = cost = np.nan
        for s in range(total):
            t = s - has_q0  # the start's place among goal_starts' (-1: q0)
            if t < 0:
                start[:] = q0
            else:
                j = t // 2
                row = rows[j]
                start[:] = Q[row]
                if base_mode == BASE_FROM_GOAL:
                    start[:6] = base
                if t % 2 == 0:  # composed: each goal's chain from the entry nearest for that goal alone
                    column = j
                    if base_mode == BASE_EACH_ENTRY:  # the goals seen from this entry's base
                        seen_from(Q[row, :6], wpt, wRt, rpt, rRt)
                        nearest_per_goal(PT, psq, pstart, gscale, gpos, gori, weight, rpt, rRt, allowed, 1, picks)
                        column = 0
                    for g in range(G):
                        e = picks[g, column]
                        for a in range(idx_start[g], idx_start[g + 1]):
                            i = idx[a]
                            start[i] = Q[e, i]
            if extra is not None:
                pos, rot, converged, it, ev, cost = lm_run_buffers(buf, held, start, kin, box, any_wrap, goals, pt, Rt,
                                                                   params, q_out, g_out)
            else:
                pos, rot, converged, it, ev, cost = lm_run_buffers_basic(buf, held, start, kin, box, any_wrap, goals,
                                                                         pt, Rt, params, q_out, g_out)
            errors[s] = pos + (rot if oriented else 0.0)
            evaluations += ev
            if converged:
                return (STAGE_Q0 if t < 0 else STAGE_TABLE), s + 1, evaluations, pos, rot, cost
            if s == 0 or cost < best[2]:  # memetic's _Search._keep: a strictly lower rank (weighted |e|^2) replaces
                best_q[:] = q_out
                best_g[:] = g_out
                best[0], best[1], best[2], best[3], best[4], best[5] = pos, rot, cost, it, ev, s
        return -1, total, evaluations, pos, rot, cost

    return _compiled(runs, name, _GOAL_DOC)


#: memetic's guaranteed runs for goal lists of several goals, per variant of the kernel's run.
goal_guaranteed_runs_basic = _goal_guaranteed_runs(None, "goal_guaranteed_runs_basic")
goal_guaranteed_runs = _goal_guaranteed_runs(True, "goal_guaranteed_runs")
