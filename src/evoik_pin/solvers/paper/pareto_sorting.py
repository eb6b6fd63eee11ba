"""NSGA-II's sorting and selection (Deb et al. 2002), vectorized: constraint domination, non-dominated sorting,
crowding distance, survival, crowded tournaments. ``F`` (N, k) minimized, ``violation`` (N,) >= 0 (0 = feasible).
"""

from __future__ import annotations

import numpy as np

__all__ = ["crowding_distance", "dominance_matrix", "nondominated_ranks", "survival"]


def dominance_matrix(F: np.ndarray, violation: np.ndarray | None = None) -> np.ndarray:
    """``D[i, j]`` True when row i constraint-dominates row j: feasible beats infeasible, less violation beats
    more, two feasible rows compare by Pareto dominance."""
    F = np.asarray(F, float)
    N = F.shape[0]
    le = np.ones((N, N), bool)
    lt = np.zeros((N, N), bool)
    for column in F.T:  # one (N, N) comparison per objective: faster than reducing an (N, N, k) array
        le &= column[:, None] <= column[None, :]
        lt |= column[:, None] < column[None, :]
    D = le & lt
    if violation is None:
        return D
    cv = np.asarray(violation, float)
    feas = cv <= 0
    both_feasible = feas[:, None] & feas[None, :]
    return np.where(both_feasible, D, (feas[:, None] & ~feas[None, :]) | (~feas[:, None] & ~feas[None, :]
                                                                           & (cv[:, None] < cv[None, :])))


def _pareto_ranks(F: np.ndarray, stop: int | None = None) -> np.ndarray:
    """Front index (N,) under plain Pareto dominance, by peeling; with ``stop``, peeling ends once at least
    ``stop`` rows are ranked and the rest get the next rank (they are behind every ranked row)."""
    D = dominance_matrix(F)
    count = D.sum(axis=0)
    rank = np.full(F.shape[0], -1)
    current = np.nonzero(count == 0)[0]
    r = done = 0
    while current.size:
        rank[current] = r
        done += current.size
        r += 1
        if stop is not None and done >= stop:
            break
        count = count - D[current].sum(axis=0)
        count[rank >= 0] = -1
        current = np.nonzero(count == 0)[0]
    rank[rank < 0] = r
    return rank


def nondominated_ranks(F: np.ndarray, violation: np.ndarray | None = None, stop: int | None = None) -> np.ndarray:
    """Front index (N,) of every row under constraint domination, 0 first, as sorting by :func:`dominance_matrix`
    would give without building its (N, N) constraint part: the feasible rows by Pareto dominance, then one front
    per distinct violation value. ``stop`` as in :func:`_pareto_ranks`."""
    F = np.asarray(F, float)
    if violation is None:
        return _pareto_ranks(F, stop)
    cv = np.asarray(violation, float).reshape(-1)
    feas = cv <= 0
    rank = np.zeros(F.shape[0], dtype=int)
    offset = 0
    if feas.any():
        rank[feas] = _pareto_ranks(F[feas], stop)
        offset = rank[feas].max() + 1
    if not feas.all():
        rank[~feas] = offset + np.unique(cv[~feas], return_inverse=True)[1].reshape(-1)
    return rank


def crowding_distance(F: np.ndarray) -> np.ndarray:
    """Crowding distance (M,) of the points ``F`` (M, k) of one front (Deb 2002); extremes get inf."""
    M, k = F.shape
    if M <= 2:
        return np.full(M, np.inf)
    order = np.argsort(F, axis=0, kind="stable")
    Fs = np.take_along_axis(F, order, axis=0)
    span = Fs[-1] - Fs[0]
    gap = np.where(span > 0, (Fs[2:] - Fs[:-2]) / np.where(span > 0, span, 1.0), 0.0)
    dist_sorted = np.vstack([np.full((1, k), np.inf), gap, np.full((1, k), np.inf)])
    dist = np.zeros((M, k))
    np.put_along_axis(dist, order, dist_sorted, axis=0)
    return dist.sum(axis=1)


def survival(F: np.ndarray, violation: np.ndarray | None, size: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """NSGA-II's elitist survival: indices of the ``size`` survivors (whole fronts in rank order, the overflowing one
    cut by crowding distance), with their ranks and crowding distances."""
    rank = nondominated_ranks(F, violation, stop=size)
    order = np.argsort(rank, kind="stable")
    last = rank[order[min(size, len(order)) - 1]]
    cd = np.zeros(F.shape[0])
    fronts, starts = np.unique(rank[order], return_index=True)
    ends = np.append(starts[1:], len(order))
    for r, a, b in zip(fronts, starts, ends, strict=True):
        if r > last:
            break
        members = order[a:b]
        cd[members] = np.inf if b - a <= 2 else crowding_distance(F[members])
    whole = order[rank[order] < last]
    cut = order[rank[order] == last]
    if cut.size > size - whole.size:
        cut = cut[np.argsort(-cd[cut], kind="stable")[: size - whole.size]]
    keep = np.concatenate([whole, cut])
    return keep, rank[keep], cd[keep]


def _tournament_pairs(size: int, count: int, rng: np.random.Generator) -> np.ndarray:
    """``count`` tournament pairs (count, 2) over ``size`` individuals, read off consecutive random
    permutations as in Deb's reference code: for ``count = size`` (even) every individual enters exactly
    two tournaments and never meets itself."""
    perms = np.argsort(rng.random((-(-2 * count // size), size)), axis=1).reshape(-1)
    return perms[: 2 * count].reshape(count, 2)


def _tournament(rank: np.ndarray, cd: np.ndarray, pairs: np.ndarray, rng: np.random.Generator) -> np.ndarray:
    """Binary tournaments with Deb's crowded comparison: lower rank wins, then larger crowding distance;
    a full tie (same rank and distance, e.g. two boundary points) is a fair coin toss from ``rng``."""
    a, b = pairs[:, 0], pairs[:, 1]
    b_wins = (rank[b] < rank[a]) | ((rank[b] == rank[a]) & (cd[b] > cd[a]))
    b_wins |= (rank[b] == rank[a]) & (cd[b] == cd[a]) & (rng.random(a.size) < 0.5)
    return np.where(b_wins, b, a)
