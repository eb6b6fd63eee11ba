"""The LM kernel's task rows of a whole population in one compiled call (NSGA-II's repair reads them through
:meth:`evoik_pin.problem.IKProblem.goal_rows`).

:func:`task_rows_batch` evaluates the kernel's :func:`.kernel.task_error` and :func:`.kernel.task_jacobian` at each
row of Q, so every goal kind gets the kernel's own rows (``e = f(q) - target``, ``E = de/dq``, each goal's rows
scaled by the square root of its weight); one call avoids numba's per-call dispatch cost for a population.

The kernel's helpers are inlined (``forceinline=True``): after editing them in :mod:`.kernel`,
:mod:`.tree_kinematics`, :mod:`.axes` or :mod:`.balance`, delete this module's cached ``*.nbi`` / ``*.nbc`` too
(numba keys an entry point on its own file only).
"""

from __future__ import annotations

import numpy as np
from numba import njit

from ...goals.stack import G_WEIGHT
from .chain import coupled
from .kernel import make_workspace, stack_rows, task_error, task_jacobian
from .tree_kinematics import BORROWING

__all__ = ["task_rows", "task_rows_batch"]


@njit(cache=True, nogil=True, forceinline=False)
def task_rows_batch(Q, parent, FR, Fp, rev, index, scale, offset, spec, gR, gp, support, gaux, P, Rts, e_out, E_out,
                    g_out):
    """The task rows (:func:`task_rows`) at each row of Q (N, n), row i with its own targets P[i] (G, 3), Rts[i]
    (G, 3, 3) (a goal set's member per configuration; the stack's ``pt``, ``Rt`` repeated otherwise): the stacked
    task error e_out[i] (rows,), its Jacobian E_out[i] (rows, n) and each goal's errors g_out[i] (G, 2) (position m,
    orientation rad or 0). The tree and stack arguments are :func:`.kernel.lm_run`'s. One workspace serves every row."""
    ws = make_workspace(Q.shape[1], parent.shape[0], spec.shape[0], stack_rows(spec), 0)
    _rows_in(ws, Q, parent, FR, Fp, rev, index, scale, offset, spec, gR, gp, support, gaux, P, Rts, e_out, E_out,
             g_out)


@njit(cache=True, nogil=True, forceinline=False, **BORROWING)
def _rows_in(ws, Q, parent, FR, Fp, rev, index, scale, offset, spec, gR, gp, support, gaux, P, Rts, e_out, E_out,
             g_out):
    """:func:`task_rows_batch`'s loop, borrowing the workspace (:data:`.tree_kinematics.BORROWING`)."""
    n, G = Q.shape[1], spec.shape[0]
    mimic = coupled(index, scale, offset, n)
    weighted = False
    for g in range(G):
        if spec[g, G_WEIGHT] != 1.0:
            weighted = True
    for j in range(Q.shape[0]):
        task_error(True, parent, FR, Fp, rev, index, scale, offset, mimic, Q[j], ws.x, spec, weighted, gR, gp, gaux,
                   P[j], Rts[j], ws.Rj, ws.pj, ws.Z, ws.O, ws.Rg, ws.pg, ws.tg, ws.M, ws.e, ws.ge)
        task_jacobian(True, rev, index, scale, mimic, spec, weighted, support, gaux, P[j], Rts[j], ws.Rg, ws.pg, ws.Z,
                      ws.O, ws.tg, ws.e, ws.Jx, ws.J, ws.rv, ws.A, ws.Bm, ws.E, parent, ws.Rj, ws.pj)
        e, E = e_out[j], E_out[j]
        for i in range(ws.e.shape[0]):
            e[i] = ws.e[i]
            for k in range(n):
                E[i, k] = ws.E[i, k]
        for g in range(G):
            g_out[j, g, 0], g_out[j, g, 1] = ws.ge[g, 0], ws.ge[g, 1]


def task_rows(q, parent, FR, Fp, rev, index, scale, offset, spec, gR, gp, support, gaux, pt, Rt, e_out, E_out, g_out):
    """The kernel's task rows at one configuration q (n,): :func:`task_rows_batch` on a population of one. Writes the
    stacked task error e_out (rows,), its Jacobian E_out (rows, n) and each goal's errors g_out (G, 2) in place;
    returns the weighted |e|^2."""
    task_rows_batch(np.ascontiguousarray(q, dtype=float)[None], parent, FR, Fp, rev, index, scale, offset, spec, gR,
                    gp, support, gaux, pt[None], Rt[None], e_out[None], E_out[None], g_out[None])
    return float(e_out @ e_out)
