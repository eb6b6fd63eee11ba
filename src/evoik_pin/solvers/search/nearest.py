"""The seed table's selection of the k nearest entries, compiled (numba): memetic's first runs
(:mod:`.first_runs`) rank the table inside their one compiled call.

The distances are NumPy's, computed by the caller exactly as :meth:`~.seed_table.SeedTable.ranked` computes them
(:meth:`~.seed_table.SeedTable.distances`: BLAS's product, the same numbers); this only selects: one pass over them
keeping the k smallest in order, the lower index first between equal ones (``argmin``'s rule for the nearest;
NumPy's ``argpartition`` and ``argsort`` order exact ties as they happen to, which no continuous table meets).
"""

from __future__ import annotations

from numba import njit

__all__ = ["select_k"]


@njit(cache=True, nogil=True)
def select_k(d, allowed, k, out):  # pragma: no cover - compiled
    """Write into ``out[:m]`` the indices of the ``m = min(k, allowed entries)`` smallest of the distances ``d``
    (N,), smallest first (ties: the lower index first); returns m. ``allowed``: (N,) bool, or (0,) for every
    entry. ``out``: (>= k,) int64."""
    N = d.shape[0]
    if k <= 0:
        return 0
    masked = allowed.shape[0] == N
    m = 0
    thr = 0.0  # the k-th smallest so far, once there are k
    for i in range(N):
        if masked and not allowed[i]:
            continue
        v = d[i]
        if m == k:
            if not v < thr:  # the usual case: one predictable branch per entry
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
