"""Differential evolution (Storn & Price) with the mutation schemes of papers 002, 004 and 000 (``de``): per
generation, donors by the chosen mutation (:mod:`.de_ops`), crossed with their targets, brought into the box,
evaluated in one kinematics pass, and kept when no worse than their target (:func:`greedy_selection`)."""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from ...errors import OptionError
from ...problem import Evaluation, IKProblem
from ...result import Result
from .. import register
from ..options import check_choice, check_fraction, check_int, check_positive
from .common import BOUND_HANDLING, SolverRun, enforce_bounds, initial_population, run_with_restarts
from .de_ops import (
    MUTATIONS,
    SCHEME_NUMBERS,
    binomial_crossover,
    either_or,
    exponential_crossover,
    exponential_lengths,
    indices_from_uniform,
    mutate,
    rand1,
    trigonometric,
)

__all__ = ["CROSSOVERS", "DE_MUTATIONS", "de", "greedy_selection", "parse_strategy"]

#: Mutations accepted by ``de``: paper 002's eight (also by number 1-8), paper 004's either-or, trigonometric.
DE_MUTATIONS = (*MUTATIONS, "eitheror", "trig")
CROSSOVERS = ("bin", "exp")


def _key(name) -> str:
    """``name`` lower-cased without a ``de/`` prefix and ``/``, ``-``, ``_`` separators (``DE/best/1`` -> best1)."""
    return str(name).lower().replace("de/", "").replace("/", "").replace("-", "").replace("_", "")


def parse_strategy(strategy: str) -> tuple[str, str]:
    """(mutation, crossover) of a scipy-style strategy name: any of :data:`DE_MUTATIONS` followed by ``bin`` or
    ``exp`` (``best1bin``, ``randtobest1exp``, ``trigbin``, ``DE/best/1/bin``, ...)."""
    if not isinstance(strategy, str):
        raise OptionError(f"strategy must be a string such as 'best1bin', got {strategy!r}")
    key = _key(strategy)
    for cx in CROSSOVERS:
        if key.endswith(cx) and key[: -len(cx)] in DE_MUTATIONS:
            return key[: -len(cx)], cx
    names = [m + c for m in DE_MUTATIONS for c in CROSSOVERS]
    raise OptionError(f"unknown DE strategy {strategy!r}; accepted: {', '.join(names)}")


def _mutation_name(mutation) -> str:
    if isinstance(mutation, (int, np.integer)) and not isinstance(mutation, bool):
        if int(mutation) not in SCHEME_NUMBERS:
            raise OptionError(f"mutation scheme number must be 1-8 (paper 002, eq. 12), got {mutation}")
        return SCHEME_NUMBERS[int(mutation)]
    key = _key(mutation)
    if key not in DE_MUTATIONS:
        raise OptionError(f"unknown mutation {mutation!r}; accepted: {', '.join(DE_MUTATIONS)} or 1-8")
    return key


@register("de", "differential evolution: paper 002's eight schemes (default best/1, F 0.5, CR 0.9), paper 004's "
                "either-or, trigonometric mutation; binomial or exponential crossover")
def de(problem: IKProblem, rng: np.random.Generator, *, population: int = 30, max_generations: int = 600,
       stall_generations: int | None = None, cost_tolerance: float | None = None, strategy: str | None = None,
       mutation: str | int = "best1", crossover: str = "bin", F: float = 0.5, CR: float = 0.9, p_F: float = 0.5,
       K: float | None = None, trig_probability: float = 0.05, bound_handling: str = "clip", runs: int = 10,
       callback: Callable | None = None) -> Result:
    """Differential evolution over the joint vector, vectorized over the population. Defaults follow paper 002
    (Table 2): DE/best/1, F = 0.5, CR = 0.9, binomial crossover, 600 generations; paper 004's are
    ``mutation="rand1"``, ``F=0.9``, ``CR=0.95``.

    Args:
        population: N (>= the mutation's indices + 1).
        max_generations, stall_generations, cost_tolerance, callback: the stopping rules of
            :class:`~.common.SolverRun` (``callback(generation, population)``, population (N, n)).
        strategy: scipy-style name (:func:`parse_strategy`); overrides ``mutation`` and ``crossover``.
        mutation: one of paper 002's eq. 12 schemes by name or number 1-8 (:mod:`.de_ops`), ``eitheror``
            (paper 004) or ``trig`` (paper 000: trigonometric donor with probability ``trig_probability``,
            DE/rand/1 otherwise).
        crossover: ``bin`` (binomial) or ``exp`` (exponential, paper 004 Alg. 2).
        F: scale factor in (0, 2]. CR: crossover rate in [0, 1].
        p_F: either-or probability of DE/rand/1. K: either-or recombination factor (default 0.5 (F + 1)).
        bound_handling: ``clip``, ``reflect`` or ``resample`` (:func:`~.common.enforce_bounds`).
        runs: paper 002's rho (:func:`~.common.run_with_restarts`).
    """
    if strategy is not None:
        mutation, crossover = parse_strategy(strategy)
    scheme = _mutation_name(mutation)
    check_choice("crossover", crossover, CROSSOVERS)
    check_choice("bound_handling", bound_handling, BOUND_HANDLING)
    k = MUTATIONS.get(scheme, 3)
    N = check_int("population", population, k + 1)
    F = check_positive("F", F, 2.0)
    CR, p_F, trig_probability = (check_fraction(k, v) for k, v in (("CR", CR), ("p_F", p_F),
                                                                     ("trig_probability", trig_probability)))
    K = 0.5 * (F + 1.0) if K is None else check_positive("K", K, 2.0)
    D = problem.n

    def once(run: SolverRun) -> Result:
        X = initial_population(problem, rng, N)
        ev = problem.evaluate(X)
        best = run.record(X, ev)
        while (reason := run.stop_reason()) is None:
            # one uniform draw per generation: indices (N x N), crossover (N x D), its start/forced coordinate
            # and the either-or / trigonometric choice (2 x N)
            u = rng.random((N, N + D + 2))
            idx = indices_from_uniform(u[:, :N], k)
            if scheme in MUTATIONS:
                V = mutate(X, scheme, F, idx, best)
            elif scheme == "eitheror":
                V = either_or(X, F, K, idx, u[:, N + D + 1] < p_F)
            else:  # trig: Fan & Lampinen's trigonometric donor with probability Mt, DE/rand/1 otherwise
                use_trig = u[:, N + D + 1] < trig_probability
                V = np.where(use_trig[:, None], trigonometric(X, ev.cost, idx), rand1(X, F, idx))
            j = (u[:, N + D] * D).astype(np.intp)
            U = (binomial_crossover(X, V, CR, u[:, N:N + D], j) if crossover == "bin"
                 else exponential_crossover(X, V, j, exponential_lengths(CR, u[:, N:N + D])))
            U = enforce_bounds(U, problem, rng, bound_handling)
            X, ev = greedy_selection(X, ev, U, problem.evaluate(U))
            run.generation += 1
            best = run.record(X, ev)
        return run.result("de", reason)

    return run_with_restarts(once, problem, runs, max_generations, stall_generations, cost_tolerance, callback)


def greedy_selection(X: np.ndarray, ev: Evaluation, U: np.ndarray, ev_u: Evaluation) -> tuple[np.ndarray, Evaluation]:
    """DE's one-to-one selection: each trial U_i replaces its target X_i when its cost is no larger (ties let
    the population drift across flat regions); returns the new population (N, n) and its evaluation."""
    better = ev_u.cost <= ev.cost
    X = np.where(better[:, None], U, X)
    cost = np.where(better, ev_u.cost, ev.cost)
    pos = np.where(better, ev_u.position_error, ev.position_error)
    rot = None if ev.orientation_error is None else np.where(better, ev_u.orientation_error, ev.orientation_error)
    return X, Evaluation(cost, pos, rot)
