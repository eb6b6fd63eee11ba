"""The seed table's single-target ranking, compiled (numba): the k table entries nearest to one target's features.

:meth:`~evoik_pin.solvers.search.seed_table.SeedTable.ranked` runs it on every single-target solve, where NumPy's
matrix-vector product, ``argmin``, ``argpartition`` and ``argsort`` cost 8-35 us on 2,048-4,096 entries (several
array passes and a dozen dispatches); this is one pass over the entries, most of them dismissed by a lower bound
from their first three features: 2-7 us.

The distances are NumPy's formula, ``sq - 2 F f`` (``sq`` the entries' squared feature norms), each entry's product
``F_i . f`` summed in the features' order. NumPy's product goes through BLAS, whose summation order is its own, so
two distances can differ in their last bits from NumPy's; the ranking (ascending distance, the lower index first
between equal ones) is NumPy's wherever two of the k nearest entries are not within a few ulps of each other
(tests/test_first_runs.py holds them equal over thousands of targets). No fastmath: the numbers are the same on
every machine.
"""

from __future__ import annotations

import numpy as np
from numba import njit

__all__ = ["nearest_k"]


@njit(cache=True, nogil=True)
def nearest_k(F, lead, dims, sq, f, allowed, k, margin, d, out):  # pragma: no cover - compiled
    """Write into ``out[:m]`` the indices of the ``m = min(k, allowed entries)`` entries nearest to ``f``, nearest
    first; returns m.

    Args:
        F: (N, D) the table's features. lead: (N, 3) their first ``dims`` features (3: a pose's or a position's;
            2: a planar target's, and a zero), contiguous: ``|lead_i - f[:dims]|^2`` is a lower bound of entry i's
            squared distance, so an entry whose bound exceeds the k-th distance met so far (plus ``margin``, far
            above rounding) is skipped without its D-term product. dims: 2 or 3. sq: (N,) the features' squared
            norms. f: (D,) the target's features.
        allowed: (N,) bool, or (0,) for every entry. k: entries wanted (>= 0). margin: >= 0, relative to the
            distances' scale (1 + |f|^2), far above their rounding. d: (N,) scratch (the distances of the entries
            not skipped). out: (>= k,) int64.
    """
    N, D = F.shape
    if k <= 0:
        return 0
    fsq = 0.0  # distance_i = sq_i - 2 F_i f + |f|^2: the ranking leaves |f|^2 out, the bound needs it
    for j in range(D):
        fsq += f[j] * f[j]
    slack = fsq + margin * (1.0 + fsq)
    fx, fy = f[0], f[1]
    fz = f[2] if dims == 3 else 0.0  # a planar target's lead: its 2 and a zero
    masked = allowed.shape[0] == N
    m = 0
    thr = np.inf  # the k-th smallest distance met so far (without |f|^2)
    for i in range(N):
        if masked and not allowed[i]:
            continue
        if m == k:
            a = lead[i, 0] - fx
            b = lead[i, 1] - fy
            c = lead[i, 2] - fz
            if a * a + b * b + c * c > thr + slack:
                continue
        s = F[i, 0] * f[0]  # NumPy's F @ f row, summed in the features' order
        for j in range(1, D):
            s += F[i, j] * f[j]
        v = s * -2.0 + sq[i]
        d[i] = v
        if m == k:
            if not v < thr:  # ties: the lower index, met first, stays
                continue
            pos = m - 1
        else:
            pos = m
            m += 1
        while pos > 0 and d[out[pos - 1]] > v:
            out[pos] = out[pos - 1]
            pos -= 1
        out[pos] = i
        if m == k:
            thr = d[out[m - 1]]
    return m


