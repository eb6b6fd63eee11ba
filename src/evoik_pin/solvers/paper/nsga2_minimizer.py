"""NSGA-II (Deb et al. 2002) as a generic box-constrained multi-objective minimizer (:func:`nsga2_minimize`), with
its variation operators as in Deb's reference code, vectorized: bounded SBX and bounded polynomial mutation."""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from ...errors import BoundsError, OptionError
from ..options import check_fraction, check_int, check_nonnegative
from .pareto_sorting import _tournament, _tournament_pairs, survival

__all__ = ["NSGA2Result", "bounded_polynomial_mutation", "nsga2_minimize", "sbx"]


def sbx(P1: np.ndarray, P2: np.ndarray, lower: np.ndarray, upper: np.ndarray, eta: float, rng: np.random.Generator,
        crossover_probability: float = 0.9, variable_probability: float = 0.5) -> tuple[np.ndarray, np.ndarray]:
    """Bounded simulated binary crossover (Deb's NSGA-II code) of parents (M, n): each pair crosses with
    ``crossover_probability``, each variable with ``variable_probability``; children stay inside the bounds."""
    M, n = P1.shape
    y1, y2 = np.minimum(P1, P2), np.maximum(P1, P2)
    diff = y2 - y1
    active = ((rng.random((M, 1)) < crossover_probability) & (rng.random((M, n)) < variable_probability)
              & (diff > 1e-14))
    safe = np.where(diff > 1e-14, diff, 1.0)
    u = rng.random((M, n))
    e1 = 1.0 / (eta + 1.0)

    def betaq(beta):
        alpha = 2.0 - beta ** -(eta + 1.0)
        return np.where(u <= 1.0 / alpha, (u * alpha) ** e1, (1.0 / np.maximum(2.0 - u * alpha, 1e-300)) ** e1)

    c1 = 0.5 * (y1 + y2 - betaq(1.0 + 2.0 * (y1 - lower) / safe) * diff)
    c2 = 0.5 * (y1 + y2 + betaq(1.0 + 2.0 * (upper - y2) / safe) * diff)
    c1, c2 = np.clip(c1, lower, upper), np.clip(c2, lower, upper)
    swap = rng.random((M, n)) < 0.5
    c1, c2 = np.where(swap, c2, c1), np.where(swap, c1, c2)
    return np.where(active, c1, P1), np.where(active, c2, P2)


def bounded_polynomial_mutation(X: np.ndarray, lower: np.ndarray, upper: np.ndarray, eta: float,
                                probability: float, rng: np.random.Generator) -> np.ndarray:
    """Bounded polynomial mutation (Deb's NSGA-II code, pymoo) of each entry of ``X`` (N, n) with ``probability``:
    the spread shrinks towards the bounds, and the result is clipped into them."""
    width = np.where(upper > lower, upper - lower, 1.0)
    mask = rng.random(X.shape) < probability
    u = rng.random(X.shape)
    d1, d2 = (X - lower) / width, (upper - X) / width
    power = 1.0 / (eta + 1.0)
    left = (2.0 * u + (1.0 - 2.0 * u) * (1.0 - d1) ** (eta + 1.0)) ** power - 1.0
    right = 1.0 - (2.0 * (1.0 - u) + 2.0 * (u - 0.5) * (1.0 - d2) ** (eta + 1.0)) ** power
    return np.clip(np.where(mask, X + np.where(u < 0.5, left, right) * width, X), lower, upper)


def _duplicate_rows(X: np.ndarray, Y: np.ndarray) -> np.ndarray:
    """Mask (len(Y),) of the rows of ``Y`` equal (bit for bit, -0.0 = 0.0) to a row of ``X`` or an earlier row."""
    Z = np.ascontiguousarray(np.concatenate([X, Y]) + 0.0)
    keys = Z.view(np.dtype((np.void, Z.dtype.itemsize * Z.shape[1]))).reshape(-1)
    first = np.unique(keys, return_index=True)[1]  # first occurrences (numpy sorts stably for return_index)
    unique = np.zeros(Z.shape[0], bool)
    unique[first] = True
    return ~unique[X.shape[0]:]


@dataclass
class NSGA2Result:
    """Outcome of :func:`nsga2_minimize`: final population ``X`` (N, n), objectives ``F`` (N, k), ``violation``
    (N,), ``rank`` (N,) (0 = first front), and ``history`` per generation (0 = initial): ``front_size``,
    ``feasible_fraction``, ``min_violation``."""

    X: np.ndarray
    F: np.ndarray
    violation: np.ndarray
    rank: np.ndarray
    generations: int
    evaluations: int
    time_s: float
    history: dict[str, np.ndarray] = field(default_factory=dict)

    @property
    def front(self) -> np.ndarray:
        """Indices of the first front (feasible non-dominated points when any is feasible)."""
        return np.nonzero(self.rank == 0)[0]


def nsga2_minimize(f: Callable, lower, upper, n_obj: int, rng: np.random.Generator, *, population: int = 100,
                   generations: int = 250, eta_c: float = 15.0, eta_m: float = 20.0,
                   crossover_probability: float = 0.9, mutation_probability: float | None = None,
                   initial: np.ndarray | None = None, repair: Callable | None = None,
                   callback: Callable | None = None, eliminate_duplicates: bool = True) -> NSGA2Result:
    """Minimize ``n_obj`` objectives over the box [lower, upper] with NSGA-II (Deb et al. 2002): crowded-comparison
    tournaments, SBX, polynomial mutation, then :func:`~.pareto_sorting.survival` of N among parents and offspring.

    Args:
        f: vectorized ``f(X)`` for a population X (N, n): objectives (N, n_obj), or a pair
            ``(objectives, violation)`` with violation (N,) >= 0 (0 = feasible) for constrained problems.
        lower, upper: (n,) finite bounds. population: N (even numbers pair up exactly).
        eta_c, eta_m: distribution indices of SBX and polynomial mutation (15, 20: pymoo's defaults).
        crossover_probability: per pair. mutation_probability: per variable (default 1/n).
        initial: (N0, n) points for the first population (the rest uniform in the box).
        repair: ``repair(X) -> X`` applied to every new point before evaluation (and to the initial
            population), e.g. projecting onto an equality constraint.
        callback: ``callback(generation, X, F, violation)`` with the survivors of every generation (0: initial).
        eliminate_duplicates: breed again (up to 10 rounds, before ``repair`` and evaluation) the offspring that
            duplicate a population member or each other, as pymoo does.

    Returns:
        :class:`NSGA2Result`: the final population, its ranks, and per-generation history.
    """
    lower = np.asarray(lower, float).reshape(-1)
    upper = np.asarray(upper, float).reshape(-1)
    if lower.shape != upper.shape or not (np.all(np.isfinite(lower)) and np.all(np.isfinite(upper))):
        raise BoundsError("nsga2_minimize needs finite lower and upper bounds of equal length")
    if np.any(lower > upper):
        raise BoundsError("nsga2_minimize: some lower bound exceeds its upper bound")
    n = lower.size
    population = check_int("population", population, 4)
    generations = check_int("generations", generations, 0)
    n_obj = check_int("n_obj", n_obj, 1)
    crossover_probability = check_fraction("crossover_probability", crossover_probability)
    p_m = 1.0 / n if mutation_probability is None else check_fraction("mutation_probability", mutation_probability)
    eta_c = check_nonnegative("eta_c (SBX distribution index)", eta_c)
    eta_m = check_nonnegative("eta_m (mutation distribution index)", eta_m)
    t0 = time.perf_counter()
    evaluations = 0

    def evaluate(X):
        nonlocal evaluations
        out = f(X)
        F, cv = out if isinstance(out, tuple) else (out, np.zeros(X.shape[0]))
        F = np.asarray(F, float).reshape(X.shape[0], -1)
        if F.shape[1] != n_obj:
            raise OptionError(f"f returned {F.shape[1]} objectives per point, n_obj is {n_obj}")
        evaluations += X.shape[0]
        return F, np.maximum(np.asarray(cv, float).reshape(-1), 0.0)

    X = rng.uniform(lower, upper, size=(population, n))
    if initial is not None:
        init = np.clip(np.atleast_2d(np.asarray(initial, float)), lower, upper)[:population]
        X[: init.shape[0]] = init
    if repair is not None:
        X = np.clip(repair(X), lower, upper)
    F, cv = evaluate(X)
    keep, rank, cd = survival(F, cv, population)
    X, F, cv = X[keep], F[keep], cv[keep]
    history: dict[str, list[float]] = {"front_size": [], "feasible_fraction": [], "min_violation": []}

    def log(generation: int) -> None:
        history["front_size"].append(float(np.sum(rank == 0)))
        history["feasible_fraction"].append(float(np.mean(cv <= 0)))
        history["min_violation"].append(float(cv.min()))
        if callback is not None:
            callback(generation, X, F, cv)

    log(0)

    def breed(m):
        half = (m + 1) // 2
        winners = _tournament(rank, cd, _tournament_pairs(X.shape[0], 2 * half, rng), rng)
        C1, C2 = sbx(X[winners[:half]], X[winners[half:]], lower, upper, eta_c, rng, crossover_probability)
        return bounded_polynomial_mutation(np.concatenate([C1, C2])[:m], lower, upper, eta_m, p_m, rng)

    for g in range(generations):
        Y = breed(population)
        if eliminate_duplicates:
            for _ in range(10):
                dup = _duplicate_rows(X, Y)
                if not dup.any():
                    break
                Y[dup] = breed(int(dup.sum()))
        if repair is not None:
            Y = np.clip(repair(Y), lower, upper)
        FY, cvY = evaluate(Y)
        XA, FA, cvA = np.concatenate([X, Y]), np.concatenate([F, FY]), np.concatenate([cv, cvY])
        keep, rank, cd = survival(FA, cvA, population)
        X, F, cv = XA[keep], FA[keep], cvA[keep]
        log(g + 1)
    return NSGA2Result(X=X, F=F, violation=cv, rank=rank, generations=generations, evaluations=evaluations,
                       time_s=time.perf_counter() - t0, history={k: np.asarray(v) for k, v in history.items()})
