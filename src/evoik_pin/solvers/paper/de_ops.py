"""Differential-evolution operators on whole populations, vectorized, their random draws taken as arguments:
paper 002's eq. 12 mutations (:data:`MUTATIONS`), paper 004's :func:`either_or`, paper 000's :func:`trigonometric`,
binomial and exponential crossovers, index sampling. Shapes: a population ``X`` is (N, D); index matrices are
(N, k) integers into it; ``F`` is a scalar or (N,)."""

from __future__ import annotations

import numpy as np

from ...errors import OptionError

__all__ = ["MUTATIONS", "SCHEME_NUMBERS", "binomial_crossover", "distinct_indices", "either_or",
           "exponential_crossover", "exponential_lengths", "indices_from_uniform", "mutate", "permutation_indices",
           "rand1", "trigonometric"]

#: Paper 002's eq. 12 schemes, numbered 1-8 in this order: ``(base, (a, b), ...)`` for the donor
#: ``base + F (a - b) + ...``, where an int j is X_r(j+1), ``"best"`` X_best and ``"self"`` X.
_SCHEMES: dict[str, tuple] = {
    "rand1": (0, (1, 2)),
    "best1": ("best", (0, 1)),
    "rand2": (0, (1, 2), (3, 4)),
    "best2": ("best", (0, 1), (2, 3)),
    "currenttobest1": ("self", (0, 1), ("best", "self")),
    "currenttobest2": ("self", (0, 1), (2, 3), ("best", "self")),
    "randtobest1": (0, (1, 2), ("best", 0)),
    "currenttorand1": ("self", (1, 2), (0, "self")),
}
#: The schemes with the number of random indices each needs.
MUTATIONS: dict[str, int] = {name: 1 + max(v for t in terms for v in (t if isinstance(t, tuple) else (t,))
                                           if isinstance(v, int)) for name, terms in _SCHEMES.items()}
#: Paper 002's scheme numbers (1-8) -> names.
SCHEME_NUMBERS: dict[int, str] = {i + 1: name for i, name in enumerate(MUTATIONS)}


def distinct_indices(rng: np.random.Generator, size: int, k: int) -> np.ndarray:
    """(size, k) indices: row i holds k distinct members of {0..size-1}, none equal to i, in random order
    (:func:`indices_from_uniform` of a uniform matrix drawn here)."""
    if size < k + 1:
        raise OptionError(f"this mutation needs a population of at least {k + 1} individuals, got {size}")
    return indices_from_uniform(rng.random((size, size)), k)


def indices_from_uniform(R: np.ndarray, k: int) -> np.ndarray:
    """k distinct indices per row, none equal to the row, from a uniform (N, N) matrix ``R`` (overwritten): the
    argsort of iid uniforms is a random permutation, and a diagonal of 2 puts the row itself last."""
    np.fill_diagonal(R, 2.0)
    return np.argsort(R, axis=1)[:, :k]


def permutation_indices(u_perm: np.ndarray, u_offsets: np.ndarray, k: int) -> np.ndarray:
    """(N, k) distinct indices per individual, none equal to it, in O(N log N) from uniform ``u_perm`` (N,)
    and ``u_offsets`` (N - 1,): the individual at position j of the permutation P = argsort(u_perm) gets
    ``P[(j + o_m) mod N]`` for the k offsets o_m = the first k of argsort(u_offsets) + 1. Each tuple is
    uniform as with :func:`indices_from_uniform`, but each column is a permutation of the population."""
    N = u_perm.shape[0]
    P = np.argsort(u_perm)
    offsets = np.argsort(u_offsets)[:k] + 1
    idx = np.empty((N, k), dtype=np.intp)
    idx[P] = P[(np.arange(N)[:, None] + offsets) % N]
    return idx


def _as_column(F) -> np.ndarray | float:
    F = np.asarray(F, dtype=float)
    return F[:, None] if F.ndim == 1 else float(F)


def mutate(X: np.ndarray, scheme: str, F, idx: np.ndarray, best: int) -> np.ndarray:
    """Donors (N, D) of paper 002's eq. 12 ``scheme`` (one of :data:`MUTATIONS`) for population ``X`` (N, D), scale
    factor ``F``, distinct random indices ``idx`` (N, >= the scheme's count; column j is r_(j+1)), best row ``best``."""
    if scheme not in MUTATIONS:
        raise OptionError(f"unknown mutation scheme {scheme!r}; known: {', '.join(MUTATIONS)}")
    n_needed = MUTATIONS[scheme]
    if idx.ndim != 2 or idx.shape[0] != X.shape[0] or idx.shape[1] < n_needed:
        raise OptionError(f"mutation {scheme!r} needs an index matrix of shape ({X.shape[0]}, >={n_needed}), "
                          f"got {idx.shape}")
    f = _as_column(F)

    def term(t):
        return X if t == "self" else X[best] if t == "best" else X[idx[:, t]]

    base, *pairs = _SCHEMES[scheme]
    V = term(base)
    for a, b in pairs:
        V = V + f * (term(a) - term(b))
    return V


def rand1(X: np.ndarray, F, idx: np.ndarray) -> np.ndarray:
    """DE/rand/1 donors (N, D): ``X_r1 + F (X_r2 - X_r3)``, idx (N, >=3)."""
    f = _as_column(F)
    return X[idx[:, 0]] + f * (X[idx[:, 1]] - X[idx[:, 2]])


def either_or(X: np.ndarray, F, K, idx: np.ndarray, use_rand1: np.ndarray) -> np.ndarray:
    """Paper 004's "either-or" donors (N, D): DE/rand/1 where ``use_rand1`` (N,) is True, elsewhere the
    recombinant ``X_r1 + K (X_r2 - X_r1 + X_r3 - X_r1)`` (Price, Storn & Lampinen 2005)."""
    a, b, c = X[idx[:, 0]], X[idx[:, 1]], X[idx[:, 2]]
    v_f = a + _as_column(F) * (b - c)
    v_k = a + _as_column(K) * (b + c - 2.0 * a)
    return np.where(np.asarray(use_rand1, bool)[:, None], v_f, v_k)


def trigonometric(X: np.ndarray, costs: np.ndarray, idx: np.ndarray) -> np.ndarray:
    """Fan & Lampinen's (2003) trigonometric donors (N, D), as in paper 000:
    ``V = (X_r1 + X_r2 + X_r3) / 3 + (p2 - p1)(X_r1 - X_r2) + (p3 - p2)(X_r2 - X_r3) + (p1 - p3)(X_r3 - X_r1)``
    with ``p_k = |f(X_rk)| / sum_j |f(X_rj)|`` (1/3 where all three costs are 0)."""
    i1, i2, i3 = idx[:, 0], idx[:, 1], idx[:, 2]
    x1, x2, x3 = X[i1], X[i2], X[i3]
    f = np.abs(np.stack([costs[i1], costs[i2], costs[i3]], axis=1))
    total = f.sum(axis=1, keepdims=True)
    p = np.divide(f, total, out=np.full_like(f, 1.0 / 3.0), where=total > 0)
    p1, p2, p3 = p[:, 0:1], p[:, 1:2], p[:, 2:3]
    return (x1 + x2 + x3) / 3.0 + (p2 - p1) * (x1 - x2) + (p3 - p2) * (x2 - x3) + (p1 - p3) * (x3 - x1)


def binomial_crossover(X: np.ndarray, V: np.ndarray, CR, u: np.ndarray, jrand: np.ndarray) -> np.ndarray:
    """Binomial crossover of targets ``X`` and donors ``V`` (N, D): ``U[i, j] = V[i, j]`` where ``u[i, j] <= CR_i``
    (u (N, D) uniform, CR scalar or (N,)) or ``j == jrand_i`` (jrand (N,): one donor coordinate always taken)."""
    take = u <= _as_column(CR)
    take[np.arange(X.shape[0]), jrand] = True
    return np.where(take, V, X)


def exponential_lengths(CR, u: np.ndarray) -> np.ndarray:
    """Lengths L (N,) of paper 004's Algorithm 2: ``L = 1``, then ``L += 1`` while ``u < CR`` and ``L < D``, from
    uniform draws ``u`` (N, D) (its first D - 1 columns)."""
    D = u.shape[1]
    stopped = ~(u[:, : D - 1] < _as_column(CR))  # L - 1 = the number of leading draws below CR
    return np.where(stopped.any(axis=1), stopped.argmax(axis=1), D - 1) + 1


def exponential_crossover(X: np.ndarray, V: np.ndarray, start: np.ndarray, length: np.ndarray) -> np.ndarray:
    """Exponential crossover: the trial takes ``length_i`` consecutive donor coordinates from ``start_i``
    (circularly), the rest from the target. ``start`` (N,) in [0, D), ``length`` (N,) in [1, D]."""
    D = X.shape[1]
    offset = (np.arange(D)[None, :] - np.asarray(start)[:, None]) % D
    return np.where(offset < np.asarray(length)[:, None], V, X)
