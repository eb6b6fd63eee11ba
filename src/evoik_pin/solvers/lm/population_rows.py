"""The LM kernel's task rows (:func:`.kernel.task_error`, :func:`.kernel.task_jacobian`) of a whole population in one
compiled call, for NSGA-II's repair (:meth:`evoik_pin.problem.IKProblem.goal_rows`). The kernel's helpers are inlined:
after editing them, delete this module's cached ``*.nbi`` / ``*.nbc`` too."""

from __future__ import annotations

import numpy as np
from numba import njit

from .chain import coupled
from .kernel import make_workspace, task_error, task_jacobian, weighted_stack
from .tree_kinematics import BORROWING

__all__ = ["task_rows", "task_rows_batch"]


@njit(cache=True, nogil=True, forceinline=False)
def task_rows_batch(Q, parent, FR, Fp, rev, index, scale, offset, spec, gR, gp, support, gaux, P, Rts, e_out, E_out,
                    g_out):
    """The task rows at each row of Q (N, n) towards its own targets P[i] (G, 3), Rts[i] (G, 3, 3): the stacked task
    error e_out[i] (rows,), its Jacobian E_out[i] (rows, n) and each goal's errors g_out[i] (G, 2) (position m,
    orientation rad or 0). The other arrays: the kernel's groups kin and goals, flat."""
    kin, goals = (parent, FR, Fp, rev, index, scale, offset), (spec, gR, gp, support, gaux)
    _rows_in(make_workspace(kin, goals, Q.shape[1], 0), Q, kin, goals, P, Rts, e_out, E_out, g_out)


@njit(cache=True, nogil=True, forceinline=False, **BORROWING)
def _rows_in(ws, Q, kin, goals, P, Rts, e_out, E_out, g_out):
    """:func:`task_rows_batch`'s loop, borrowing the workspace (:data:`.tree_kinematics.BORROWING`)."""
    n, G = Q.shape[1], goals[0].shape[0]
    mimic = coupled(kin[4], kin[5], kin[6], n)
    weighted = weighted_stack(goals[0])
    s = ws.cur
    for j in range(Q.shape[0]):
        task_error(True, kin, mimic, goals, weighted, P[j], Rts[j], Q[j], s, ws)
        task_jacobian(True, kin, mimic, goals, weighted, P[j], Rts[j], s, ws, ws.E)
        e, E = e_out[j], E_out[j]
        for i in range(s.e.shape[0]):
            e[i] = s.e[i]
            for k in range(n):
                E[i, k] = ws.E[i, k]
        for g in range(G):
            g_out[j, g, 0], g_out[j, g, 1] = s.ge[g, 0], s.ge[g, 1]


def task_rows(q, parent, FR, Fp, rev, index, scale, offset, spec, gR, gp, support, gaux, pt, Rt, e_out, E_out, g_out):
    """The kernel's task rows at one configuration q (n,) (:func:`task_rows_batch` on a population of one): writes
    e_out (rows,), E_out (rows, n) and g_out (G, 2) in place; returns the weighted |e|^2."""
    task_rows_batch(np.ascontiguousarray(q, dtype=float)[None], parent, FR, Fp, rev, index, scale, offset, spec, gR,
                    gp, support, gaux, pt[None], Rt[None], e_out[None], E_out[None], g_out[None])
    return float(e_out @ e_out)
