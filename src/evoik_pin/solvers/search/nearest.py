"""The seed table's rankings, compiled (numba): memetic's guaranteed runs and a goal list's starts rank the table with
these. :func:`table_distances` sums each entry's product in the features' order (no fastmath), so it may differ
from NumPy's BLAS product in the last bits only; :func:`select_k` keeps the k smallest in order, the lower index
first between equal ones (``argmin``'s rule)."""

from __future__ import annotations

import numpy as np
from numba import njit

__all__ = ["goal_target_features", "nearest_per_goal", "rank_goal_entries", "seen_from", "select_few", "select_k",
           "table_distances", "table_distances32", "table_distances_many"]


_SORT_FROM = 64  # select_k: by insertion up to this k, above by a stable sort (faster for a whole table)


@njit(cache=True, nogil=True, forceinline=False)
def select_k(d, allowed, k, out):  # pragma: no cover - compiled
    """Write into ``out[:m]`` the indices of the ``m = min(k, allowed entries)`` smallest of ``d`` (N,), smallest first
    (ties: the lower index first); returns m. ``allowed``: (N,) bool, or (0,) for every entry; ``out`` (>= k,) int64."""
    if k > _SORT_FROM:
        return _select_sorted(d, allowed, k, out)
    return select_few(d, allowed, k, out)


@njit(cache=True, nogil=True, forceinline=False)
def _select_sorted(d, allowed, k, out):  # pragma: no cover - compiled
    """:func:`select_k` by one stable sort of the allowed distances."""
    N = d.shape[0]
    index = np.nonzero(allowed)[0] if allowed.shape[0] == N else np.arange(N)
    order = np.argsort(d[index], kind="mergesort")
    m = min(k, index.shape[0])
    for r in range(m):
        out[r] = index[order[r]]
    return m


@njit(cache=True, nogil=True, forceinline=False)
def select_few(d, allowed, k, out):  # pragma: no cover - compiled
    """:func:`select_k` by insertion in one pass over d (apart: the sort's arrays beside it slowed this loop)."""
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


@njit(cache=True, nogil=True, forceinline=False)
def table_distances(FT, sq, f, d):  # pragma: no cover - compiled
    """The table's squared distances less ``|f|^2`` into ``d`` (N,): ``sq - 2 F f``, FT (D, N) the table's features
    transposed, sq (N,) their squared norms, f (D,) the target's features."""
    D, N = FT.shape
    f0 = f[0]
    for i in range(N):
        d[i] = FT[0, i] * f0
    for j in range(1, D):
        fj = f[j]
        for i in range(N):
            d[i] += FT[j, i] * fj
    for i in range(N):
        d[i] = d[i] * -2.0 + sq[i]


@njit(cache=True, nogil=True, forceinline=False, fastmath={"contract"})
def table_distances32(FT, sq, f, d):  # pragma: no cover - compiled
    """:func:`table_distances` in single precision (float32 arrays, fused multiply-adds), for rankings that only order
    starts: a goal list's and a goal set's."""
    D, N = FT.shape
    f0 = f[0]
    for i in range(N):
        d[i] = FT[0, i] * f0
    for j in range(1, D):
        fj = f[j]
        for i in range(N):
            d[i] += FT[j, i] * fj
    for i in range(N):
        d[i] = sq[i] - (d[i] + d[i])


@njit(cache=True, nogil=True, forceinline=False, fastmath={"contract"})
def table_distances_many(FT, sq, f, D):  # pragma: no cover - compiled
    """:func:`table_distances32` of V targets: D (V, N) float32 for features f (V, D) (OpenBLAS's threads on a busy
    machine took 15 ms for this product)."""
    for v in range(f.shape[0]):
        table_distances32(FT, sq, f[v], D[v])


@njit(cache=True, nogil=True, forceinline=False)
def goal_target_features(scale, positioned, oriented, weight, pt, Rt, f):  # pragma: no cover - compiled
    """The goals' targets' features into ``f`` (>= D,) float32, goal after goal: ``scale[g]`` x its position when
    ``positioned[g]``, then ``scale[g] x weight`` x its rotation's entries when ``oriented[g]`` (the products
    :meth:`~.seed_table.SeedTable.goal_features` makes); returns D. scale, positioned, oriented (G,); weight: m per
    unit of the rotation's Frobenius distance; pt (G, 3) m, Rt (G, 3, 3)."""
    D = 0
    for g in range(pt.shape[0]):
        s = scale[g]
        if positioned[g]:
            for j in range(3):
                f[D] = s * pt[g, j]
                D += 1
        if oriented[g]:
            sw = s * weight
            for j in range(9):
                f[D] = sw * Rt[g, j // 3, j % 3]
                D += 1
    return D


@njit(cache=True, nogil=True, forceinline=False)
def rank_goal_entries(FT, sq, scale, positioned, oriented, weight, pt, Rt, allowed, k, out):  # pragma: no cover
    """The ``k`` table entries nearest a goal list's targets (:meth:`~.seed_table.SeedTable.ranked_goals`' metric),
    nearest first (ties: the lower index first), into ``out`` (>= k,) int64; returns how many. FT (D, N), sq (N,)
    float32: the goal list's table features transposed and their squared norms; the rest as
    :func:`goal_target_features` reads them; allowed (N,) bool or (0,)."""
    N = FT.shape[1]
    f = np.empty(12 * pt.shape[0] + 1, dtype=np.float32)  # the products in double precision, rounded once
    D = goal_target_features(scale, positioned, oriented, weight, pt, Rt, f)
    d = np.empty(N, dtype=np.float32)
    if D == 0:  # no goal has a position or an orientation to match: every entry as near (features all zero)
        d[:] = 0.0
    else:
        table_distances32(FT, sq, f[:D], d)
    return select_k(d, allowed, k, out)


@njit(cache=True, nogil=True, forceinline=False)
def nearest_per_goal(FT, sq, start, scale, positioned, oriented, weight, pt, Rt, allowed, k, out):  # pragma: no cover
    """Per goal g, the ``k`` table entries nearest its target by the goal's own features, nearest first (ties: the
    lower index first), into ``out[g]`` (G, >= k) int64: :meth:`~.seed_table.SeedTable.goal_starts`' composed starts.
    FT (D, N) float32: the goals' features transposed, goal g's rows from ``start[g]``; sq (G, N) float32; the other
    arguments as :func:`goal_target_features` reads them; allowed (N,) bool or (0,); k <= the allowed entries."""
    for g in range(pt.shape[0]):  # each goal ranked alone (a goal without features: every entry as near)
        rank_goal_entries(FT[start[g]:start[g + 1]], sq[g], scale[g:g + 1], positioned[g:g + 1], oriented[g:g + 1],
                          weight, pt[g:g + 1], Rt[g:g + 1], allowed, k, out[g])


@njit(cache=True, nogil=True, forceinline=False)
def seen_from(base, pt, Rt, P_out, R_out):  # pragma: no cover - compiled
    """Targets pt (G, 3) m, Rt (G, 3, 3) seen from a floating base's pose ``base`` (x, y, z m, yaw, pitch, roll
    rad; ``B = Rz Ry Rx``): ``B^-1 T`` per target, into P_out (G, 3) and R_out (G, 3, 3)."""
    cy, sy = np.cos(base[3]), np.sin(base[3])
    cp, sp = np.cos(base[4]), np.sin(base[4])
    cr, sr = np.cos(base[5]), np.sin(base[5])
    B = np.empty((3, 3))
    B[0, 0], B[0, 1], B[0, 2] = cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr
    B[1, 0], B[1, 1], B[1, 2] = sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr
    B[2, 0], B[2, 1], B[2, 2] = -sp, cp * sr, cp * cr
    for g in range(pt.shape[0]):
        d0, d1, d2 = pt[g, 0] - base[0], pt[g, 1] - base[1], pt[g, 2] - base[2]
        for i in range(3):
            P_out[g, i] = d0 * B[0, i] + d1 * B[1, i] + d2 * B[2, i]
            for c in range(3):
                R_out[g, i, c] = B[0, i] * Rt[g, 0, c] + B[1, i] * Rt[g, 1, c] + B[2, i] * Rt[g, 2, c]
