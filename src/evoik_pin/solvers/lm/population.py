"""The LM kernel's task rows of a whole population, one compiled call: what :func:`task_rows` gives for one
configuration, for N configurations each with its own targets.

:func:`task_rows_batch` runs, per configuration, the kernel's (its :func:`.kernel.task_error` and
:func:`.kernel.task_jacobian`, inlined here as in the LM run) over the rows of Q in one workspace, so every goal kind
the kernel knows (pose, position, planar, bands and free axes, orientation, direction, look-at, centre of mass,
support polygon, relative pose) gets the same rows, with the same sign convention ``e = f(q) - target`` and
``E = de/dq``, each goal's rows scaled by the square root of its weight. NSGA-II's repair steps read them
(through :meth:`evoik_pin.problem.IKProblem.goal_rows`). A Python loop of N one-configuration calls pays
numba's dispatch (some 20 arrays to type-check and unbox) and a workspace per call: on Talos (38 joints, 17 rows)
this entry takes 0.47 ms for N = 100, the loop 0.84 ms (docs/BENCHMARKS.md, scripts/bench_nsga2_repair.py).

The kernel's helpers are inlined (``forceinline=True``): after editing them in :mod:`.kernel`, :mod:`.tree`,
:mod:`.axes` or :mod:`.balance`, delete this module's cached ``*.nbi`` / ``*.nbc`` too (numba keys an entry point on
its own file only).
"""

from __future__ import annotations

import numpy as np
from numba import njit

from ...goals.stack import G_WEIGHT
from .chain import coupled
from .kernel import make_workspace, stack_rows, task_error, task_jacobian
from .tree import BORROWING

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
    """:func:`task_rows_batch`'s loop, borrowing the workspace (no reference counting of the some 40 arrays each
    inlined call reads, as the kernel's entries)."""
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
    """What one LM step reads at q (n,), for tests, diagnostics and prefer's refinement (the null space of
    :func:`~evoik_pin.solvers.search.choose.refine`): :func:`task_rows_batch` on this one configuration, the stacked
    task error e_out (rows,), its Jacobian E_out (rows, n) and each goal's errors g_out (G, 2), written in place.
    Returns the weighted |e|^2. One compiled entry serves both (the population's signature: these are its rows)."""
    task_rows_batch(np.ascontiguousarray(q, dtype=float)[None], parent, FR, Fp, rev, index, scale, offset, spec, gR,
                    gp, support, gaux, pt[None], Rt[None], e_out[None], E_out[None], g_out[None])
    return float(e_out @ e_out)
