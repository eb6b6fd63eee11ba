"""ISADE (paper 002, section 3.3; ``isade``): DE whose strategy (eqs. 14-16, :func:`isade_donors`, SaDE's
:func:`strategy_probabilities`), scale factors (eqs. 17-19) and crossover rates (eq. 20, jDE-style, kept with a
surviving trial) adapt per individual. Paper 002's stop at 1e-17 m is below double precision: use 1e-15 m or more.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from ...problem import IKProblem
from ...result import Result
from .. import register
from ..options import check_choice, check_fraction, check_int, check_nonnegative, check_number, check_positive
from .common import BOUND_HANDLING, SolverRun, enforce_bounds, initial_population, run_with_restarts
from .de import greedy_selection
from .de_ops import binomial_crossover, permutation_indices

__all__ = ["ISADE_STRATEGIES", "adapt_crossover_rates", "isade", "isade_donors", "mean_scale_factor",
           "rank_scale_factors", "scale_factors", "sigmoid_by_rank", "strategy_probabilities"]

#: ISADE's candidate strategies, in the order of paper 002's eqs. 14-16.
ISADE_STRATEGIES = ("best1", "best2", "randtobest1")


def sigmoid_by_rank(N: int, alpha: float) -> np.ndarray:
    """Eq. 17 for ranks i = 1..N: ``F_i = 1 / (1 + exp(alpha (i - N/2) / N))``, shape (N,), decreasing in i."""
    return 1.0 / (1.0 + np.exp(alpha * (np.arange(1, N + 1) - N / 2) / N))


def rank_scale_factors(costs: np.ndarray, alpha: float, table: np.ndarray | None = None) -> np.ndarray:
    """Eq. 17 per individual (N,): the sigmoid of its fitness rank, best (i = 1, largest F) to worst, ties in
    index order; ``table`` = ``sigmoid_by_rank(N, alpha)`` may be passed to save its cost."""
    F = np.empty(costs.shape[0])
    F[np.argsort(costs, kind="stable")] = sigmoid_by_rank(costs.shape[0], alpha) if table is None else table
    return F


def mean_scale_factor(generation: int, max_generations: int, F_min: float, F_max: float, n_iter: float) -> float:
    """Eq. 18: ``F_mean = F_min + (F_max - F_min) ((iter_max - iter) / iter_max) ** n_iter`` for the generation being
    produced (1..max_generations)."""
    return F_min + (F_max - F_min) * (max(max_generations - generation, 0) / max(max_generations, 1)) ** n_iter


def scale_factors(F_rank: np.ndarray, F_mean: float) -> np.ndarray:
    """Eq. 19 as in the original ISADE: ``F_i^iter = (F_i + F_mean^iter) / 2`` (paper 002 prints a minus)."""
    return 0.5 * (F_rank + F_mean)


def adapt_crossover_rates(CR: np.ndarray, u1: np.ndarray, u2: np.ndarray, tau: float, CR_low: float = 0.0
                          ) -> np.ndarray:
    """Eq. 20: ``CR_i <- CR_low + (1 - CR_low) u2_i`` where ``u1_i <= tau``, else unchanged; u1, u2 (N,) uniform
    draws in [0, 1) (the paper: ``CR_low = 0``)."""
    return np.where(u1 <= tau, CR_low + (1.0 - CR_low) * u2, CR)


def strategy_probabilities(successes: np.ndarray, trials: np.ndarray, floor: float = 0.01) -> np.ndarray:
    """SaDE's strategy probabilities (K,): ``p_k`` proportional to ``successes_k / trials_k + floor`` over one
    learning period's counts (K,); a strategy not tried counts as fully successful, so it gets tried."""
    w = (np.asarray(successes, float) + 1e-12) / (np.asarray(trials, float) + 1e-12) + floor
    return w / w.sum()


# Columns of E = [r1, r2, r3, r4, best] forming (base, a, b, c, d) of V = X_base + F (X_a - X_b) + F (X_c - X_d)
# for each strategy; DE/best/1 uses X_c = X_d = X_r4 so its second difference is exactly zero.
_DONOR_TEMPLATE = np.array([
    [4, 0, 1, 3, 3],  # DE/best/1, eq. 14: X_best + F (X_r1 - X_r2)
    [4, 0, 1, 2, 3],  # DE/best/2, eq. 15: X_best + F (X_r1 - X_r2) + F (X_r3 - X_r4)
    [0, 4, 0, 1, 2],  # DE/rand-to-best/1, eq. 16: X_r1 + F (X_best - X_r1) + F (X_r2 - X_r3)
])


def isade_donors(X: np.ndarray, F: np.ndarray, E: np.ndarray, strategy: np.ndarray) -> np.ndarray:
    """Donors (N, D) of population ``X`` (N, D) with scale factors ``F`` (N,) and a per-individual ``strategy``
    (N,): 0 = DE/best/1 (eq. 14), 1 = DE/best/2 (eq. 15), 2 = DE/rand-to-best/1 (eq. 16). ``E`` (N, 5): distinct
    random others r1..r4 in columns 0-3, the best individual in column 4. All from one gather."""
    G = X[E[np.arange(X.shape[0])[:, None], _DONOR_TEMPLATE[strategy]]]  # (N, 5, D)
    return G[:, 0] + F[:, None] * ((G[:, 1] - G[:, 2]) + (G[:, 3] - G[:, 4]))


@register("isade", "ISADE (paper 002): DE with adaptive strategy choice among best/1, best/2, rand-to-best/1, "
                   "rank-sigmoid F blended with a decaying mean F, self-adapted CR")
def isade(problem: IKProblem, rng: np.random.Generator, *, population: int = 60, max_generations: int = 130,
          stall_generations: int | None = None, cost_tolerance: float | None = None, F_min: float = 0.02,
          F_max: float = 0.3, n_iter: float = 6.0, alpha: float = 4.0, tau: float = 0.1, CR_init: float = 1.0,
          CR_low: float = 0.95, learning_period: int = 10, bound_handling: str = "clip", runs: int = 10,
          callback: Callable | None = None) -> Result:
    """ISADE over the joint vector, vectorized over the population (paper 002, eqs. 14-20). Defaults beyond the
    paper's 130 generations and rho = 10 are tuned for speed on reachable points; multimodal 6-D pose targets
    want a wider F (``F_max=0.9, F_min=0.3, n_iter=2``) and more generations.

    Args:
        population: N (>= 6).
        max_generations, stall_generations, cost_tolerance, callback: the stopping rules of
            :class:`~.common.SolverRun`; ``max_generations`` also sets the F schedule (eq. 18).
        F_min, F_max, n_iter: bounds (0 < F_min <= F_max <= 2) and modulation index (> 0) of eq. 18's mean F.
        alpha: gain of the rank sigmoid (eq. 17), >= 0 (0 gives F_i = 0.5 for everyone).
        tau, CR_init: probability of re-drawing an individual's CR (eq. 20); every CR at the start.
        CR_low: lower end of eq. 20's uniform re-draw (the paper: 0; low rates barely move a non-separable IK
            objective).
        learning_period: generations between updates of the strategy probabilities.
        bound_handling: ``clip``, ``reflect`` or ``resample`` (:func:`~.common.enforce_bounds`).
        runs: paper 002's rho (:func:`~.common.run_with_restarts`).

    Returns:
        A :class:`Result` whose ``history`` adds ``F_mean`` (eq. 18), ``CR_mean`` and the strategy
        probabilities ``p_best1``, ``p_best2``, ``p_randtobest1`` per generation.
    """
    N = check_int("population", population, 6)
    F_min = check_positive("F_min", F_min, 2.0)
    F_max = check_number("F_max", F_max, F_min, 2.0)
    n_iter = check_positive("n_iter", n_iter, 100.0)
    alpha = check_nonnegative("alpha", alpha, 1e3)
    tau, CR_init, CR_low = (check_fraction(k, v) for k, v in (("tau", tau), ("CR_init", CR_init), ("CR_low", CR_low)))
    learning_period = check_int("learning_period", learning_period)
    check_choice("bound_handling", bound_handling, BOUND_HANDLING)

    def once(run: SolverRun) -> Result:
        K = len(ISADE_STRATEGIES)
        counts = np.zeros(2 * K)  # trials that failed (0..K-1) and succeeded (K..2K-1) per strategy this period
        probs = np.full(K, 1.0 / K)
        cum_probs = np.cumsum(probs)[:-1]
        CR = np.full(N, CR_init)
        D = problem.n
        table = sigmoid_by_rank(N, alpha)
        X = initial_population(problem, rng, N)
        ev = problem.evaluate(X)
        best = run.record(X, ev, F_mean=F_max, CR_mean=CR_init, p_best1=probs[0], p_best2=probs[1],
                          p_randtobest1=probs[2])
        c_jrand, c_strategy, c_tau, c_cr, c_perm, c_offsets = D, D + 1, D + 2, D + 3, D + 4, D + 5
        while (reason := run.stop_reason()) is None:
            g = run.generation + 1
            # one uniform draw: crossover (N x D), its forced coordinate, strategy, CR (3 x N), indices (2 x N)
            u = rng.random((N, D + 6))
            E = np.empty((N, 5), dtype=np.intp)
            E[:, :4] = permutation_indices(u[:, c_perm], u[: N - 1, c_offsets], 4)
            E[:, 4] = best
            strategy = np.searchsorted(cum_probs, u[:, c_strategy], side="right")
            F_mean = mean_scale_factor(g, run.max_generations, F_min, F_max, n_iter)
            F = scale_factors(rank_scale_factors(ev.cost, alpha, table), F_mean)
            CR_trial = adapt_crossover_rates(CR, u[:, c_tau], u[:, c_cr], tau, CR_low)
            V = isade_donors(X, F, E, strategy)
            U = binomial_crossover(X, V, CR_trial, u[:, :D], (u[:, c_jrand] * D).astype(np.intp))
            U = enforce_bounds(U, problem, rng, bound_handling)
            ev_u = problem.evaluate(U)
            won = ev_u.cost < ev.cost  # strict improvement counts as a strategy success
            counts += np.bincount(strategy + K * won, minlength=2 * K)
            CR = np.where(ev_u.cost <= ev.cost, CR_trial, CR)  # a CR survives with its trial (jDE)
            X, ev = greedy_selection(X, ev, U, ev_u)
            if g % learning_period == 0:
                probs = strategy_probabilities(counts[K:], counts[:K] + counts[K:])
                cum_probs = np.cumsum(probs)[:-1]
                counts[:] = 0.0
            run.generation = g
            best = run.record(X, ev, F_mean=F_mean, CR_mean=CR.sum() / N, p_best1=probs[0], p_best2=probs[1],
                              p_randtobest1=probs[2])
        return run.result("isade", reason)

    return run_with_restarts(once, problem, runs, max_generations, stall_generations, cost_tolerance, callback)
