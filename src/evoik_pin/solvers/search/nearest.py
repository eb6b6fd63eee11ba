"""The seed table's ranking for one target, compiled (numba): memetic's first runs (:mod:`.first_runs`) rank the
table inside their one compiled call.

:func:`table_distances` computes :meth:`~.seed_table.SeedTable.distances`'s formula, ``sq - 2 F f``, each entry's
product summed in the features' order (the loop over the entries vectorizes without reordering any sum; no
fastmath). NumPy's product goes through BLAS, whose summation order is its own, so a distance can differ from
NumPy's in its last bits, and two entries' order only where their distances are within a few ulps of each other
(tests/test_first_runs.py holds the rankings equal over thousands of targets). :func:`select_k` keeps the k smallest
in one pass, in order, the lower index first between equal ones (``argmin``'s rule).
"""

from __future__ import annotations

import numpy as np
from numba import njit

__all__ = ["goal_target_features", "nearest_per_goal", "rank_goal_entries", "seen_from", "select_few", "select_k",
           "table_distances", "table_distances32", "table_distances_many"]


#: select_k keeps the k smallest by insertion up to this k (a start's few nearest entries: one pass, no sort); above,
#: by a stable sort (memetic-all's goal starts rank the whole table: insertions took 2 ms for 4,096 entries, a
#: sort 0.3 ms).
_SORT_FROM = 64


@njit(cache=True, nogil=True, forceinline=False)
def select_k(d, allowed, k, out):  # pragma: no cover - compiled
    """Write into ``out[:m]`` the indices of the ``m = min(k, allowed entries)`` smallest of the distances ``d``
    (N,), smallest first (ties: the lower index first); returns m. ``allowed``: (N,) bool, or (0,) for every
    entry. ``out``: (>= k,) int64. By insertion (:func:`select_few`) up to ``_SORT_FROM`` kept, else by one stable
    sort (:func:`_select_sorted`): the same order."""
    if k > _SORT_FROM:
        return _select_sorted(d, allowed, k, out)
    return select_few(d, allowed, k, out)


@njit(cache=True, nogil=True, forceinline=False)
def _select_sorted(d, allowed, k, out):  # pragma: no cover - compiled
    """:func:`select_k` by one stable sort of the allowed distances (many kept: O(N log N) instead of O(N k))."""
    N = d.shape[0]
    index = np.nonzero(allowed)[0] if allowed.shape[0] == N else np.arange(N)
    order = np.argsort(d[index], kind="mergesort")
    m = min(k, index.shape[0])
    for r in range(m):
        out[r] = index[order[r]]
    return m


@njit(cache=True, nogil=True, forceinline=False)
def select_few(d, allowed, k, out):  # pragma: no cover - compiled
    """:func:`select_k` by insertion in one pass over d (a few kept: a start's nearest entries; memetic's first
    runs call it directly). A function of its own, without the sort's arrays: with them in the same function
    numba's reference counting slowed this loop by a third (2.0 -> 2.8 us for 4,096 entries: 5 % of a Panda
    single-pose solve, scripts/bench_latency.py)."""
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
    """The table's squared distances less ``|f|^2`` into ``d`` (N,): ``sq - 2 F f`` with FT (D, N) the table's
    features transposed, sq (N,) their squared norms and f (D,) the target's features."""
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
    """:func:`table_distances` in single precision: d (N,) float32 from FT (D, N), sq (N,) and f (D,) float32, fused
    multiply-adds. A goal list's rankings (:func:`rank_goal_entries`, :func:`nearest_per_goal`) and a goal set's
    (:func:`table_distances_many`), which decide a start's order only (no other path has to match them bit for
    bit): single precision's 1e-7 of the features' scale is far below the table's gaps, and its eight lanes a
    vector and half the memory read made a Talos ranking (48 features of 4,096 entries) several times faster than
    double precision's 30-50 us."""
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
    """:func:`table_distances32` of V targets: D (V, N) float32 for their features f (V, D). For the goal sets'
    ranking (FT (D, N) and sq (N,) float32: :meth:`~.seed_table.SeedTable.one_goal_features32`). Compiled rather
    than one NumPy product: OpenBLAS runs a product of this size on several threads, and on a busy machine (or
    beside ``solve_many``'s threads) waiting for them took 15 ms instead of 30 us (measured: a goal set of 10 Panda
    grasps, 2 cores, load 2)."""
    for v in range(f.shape[0]):
        table_distances32(FT, sq, f[v], D[v])


@njit(cache=True, nogil=True, forceinline=False)
def nearest_per_goal(FT, sq, start, scale, positioned, oriented, weight, pt, Rt, allowed, k, out):  # pragma: no cover
    """Per goal g, the indices of the ``k`` table entries nearest to its target by the goal's own features, nearest
    first (ties: the lower index first), into ``out[g]``: the composed starts of a goal list
    (:meth:`~.seed_table.SeedTable.goal_starts`), one call for every goal.

    Args:
        FT (D, N) float32: the goals' table features transposed and stacked, goal g's in rows
            ``start[g]:start[g + 1]`` (``scale[g]`` x its frame's position when ``positioned[g]``, then
            ``scale[g] x weight`` x its rotation's entries when ``oriented[g]``); sq (G, N) float32: their squared
            norms per goal (single precision: :func:`table_distances32`). scale (G,): sqrt of each goal's
            weight; positioned, oriented (G,) bool. weight: m per unit of the rotation's Frobenius distance.
        pt (G, 3), Rt (G, 3, 3): the goals' targets (m). allowed: (N,) bool, or (0,) for every entry.
        k: entries per goal (<= the allowed entries). out: (G, >= k) int64.
    """
    G, N = pt.shape[0], FT.shape[1]
    d = np.empty(N, dtype=np.float32)
    f = np.empty(12, dtype=np.float32)  # the products in double precision, rounded once (as the table's features)
    for g in range(G):
        D = 0
        s = scale[g]
        if positioned[g]:  # the products SeedTable._goal_feature_blocks makes, in its order: the same numbers
            for j in range(3):
                f[D] = s * pt[g, j]
                D += 1
        if oriented[g]:
            sw = s * weight
            for j in range(9):
                f[D] = sw * Rt[g, j // 3, j % 3]
                D += 1
        if D == 0:  # a goal without a position or an orientation to match: every entry as near
            d[:] = 0.0
        else:
            table_distances32(FT[start[g]:start[g] + D], sq[g], f[:D], d)
        select_k(d, allowed, k, out[g])


@njit(cache=True, nogil=True, forceinline=False)
def goal_target_features(scale, positioned, oriented, weight, pt, Rt, f):  # pragma: no cover - compiled
    """The goals' targets' features into ``f`` (>= D,), goal after goal (``scale[g]`` x its position when
    ``positioned[g]``, then ``scale[g] x weight`` x its rotation's entries when ``oriented[g]``: the products
    :meth:`~.seed_table.SeedTable._goal_feature_blocks` makes, so the same numbers); returns D, their number.
    scale, positioned, oriented (G,): :meth:`~.seed_table.SeedTable.goal_spec`'s; weight: m per unit of the
    rotation's Frobenius distance; pt (G, 3) m, Rt (G, 3, 3)."""
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
    """The ``k`` table entries nearest to a goal list's targets in the sum over the goals of their weighted squared
    distances (:meth:`~.seed_table.SeedTable.ranked_goals`' metric), nearest first (ties: the lower index first),
    into ``out``; returns how many (k or fewer: the allowed entries).

    Args:
        FT (D, N), sq (N,) float32: the goal list's table features transposed
            (:meth:`~.seed_table.SeedTable.goal_features` of every entry's frame poses) and their squared norms
            (single precision: :func:`table_distances32`). scale, positioned, oriented (G,), weight, pt
            (G, 3), Rt (G, 3, 3): as :func:`goal_target_features` reads them. allowed: (N,) bool, or (0,) for
            every entry. out: (>= k,) int64.
    """
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
def seen_from(base, pt, Rt, P_out, R_out):  # pragma: no cover - compiled
    """Targets pt (G, 3) m, Rt (G, 3, 3) in the world seen from a floating base's pose ``base`` (its six entries:
    x, y, z m, yaw, pitch, roll rad; rotation ``B = Rz(yaw) Ry(pitch) Rx(roll)``): ``B^-1 T`` per target, into
    P_out (G, 3) and R_out (G, 3, 3)."""
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
