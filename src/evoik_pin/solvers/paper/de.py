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
from ..options import check_callback, check_choice, check_fraction, check_int, check_positive
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
#: Crossovers: binomial (``bin``) and exponential (``exp``).
CROSSOVERS = ("bin", "exp")


def parse_strategy(strategy: str) -> tuple[str, str]:
    """(mutation, crossover) of a scipy-style strategy name such as ``best1bin`` or ``randtobest1exp``.

    Accepted: any of :data:`DE_MUTATIONS` followed by ``bin`` or ``exp`` (``currenttobest1bin``,
    ``rand2exp``, ``eitherorbin``, ``trigbin``, ...). ``either-or`` and ``/`` or ``-`` separators are tolerated
    (``DE/best/1/bin``).
    """
    if not isinstance(strategy, str):
        raise OptionError(f"strategy must be a string such as 'best1bin', got {strategy!r}")
    key = strategy.lower().replace("de/", "").replace("/", "").replace("-", "").replace("_", "")
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
    key = str(mutation).lower().replace("de/", "").replace("/", "").replace("-", "").replace("_", "")
    if key not in DE_MUTATIONS:
        raise OptionError(f"unknown mutation {mutation!r}; accepted: {', '.join(DE_MUTATIONS)} or 1-8")
    return key


@register("de", "differential evolution: paper 002's eight schemes (default best/1, F 0.5, CR 0.9), paper 004's "
                "either-or, trigonometric mutation; binomial or exponential crossover")
def de(
    problem: IKProblem,
    rng: np.random.Generator,
    *,
    population: int = 30,
    max_generations: int = 600,
    stall_generations: int | None = None,
    cost_tolerance: float | None = None,
    strategy: str | None = None,
    mutation: str | int = "best1",
    crossover: str = "bin",
    F: float = 0.5,
    CR: float = 0.9,
    p_F: float = 0.5,
    K: float | None = None,
    trig_probability: float = 0.05,
    bound_handling: str = "clip",
    runs: int = 10,
    callback: Callable | None = None,
) -> Result:
    """Differential evolution over the joint vector, vectorized over the population.

    Defaults follow paper 002 (Table 2): scheme 2 of eq. 12 (DE/best/1), F = 0.5, CR = 0.9, binomial
    crossover (eq. 13), 600 generations. Paper 004's settings are ``mutation="rand1"``, ``F=0.9``,
    ``CR=0.95``, ``bound_handling="clip"``.

    Args:
        problem: the IK problem (its tolerances stop the run; ``q0`` seeds the population).
        rng: the only source of randomness.
        population: number of individuals N (>= 3, and >= the mutation's indices + 1).
        max_generations: generation budget (paper 002: 600).
        stall_generations: stop after this many generations without improvement of the best cost.
        cost_tolerance: also stop once the best cost is at most this value.
        strategy: scipy-style name (``best1bin``, ``rand1exp``, ``currenttobest1bin``, ``randtobest1bin``,
            ``best2bin``, ``rand2bin``, ``eitherorbin``, ``trigbin``, ...); overrides ``mutation`` and
            ``crossover``.
        mutation: one of paper 002's eq. 12 schemes by name or number (1 ``rand1``, 2 ``best1``, 3 ``rand2``,
            4 ``best2``, 5 ``currenttobest1``, 6 ``currenttobest2``, 7 ``randtobest1``, 8 ``currenttorand1``),
            ``eitheror`` (paper 004) or ``trig`` (paper 000: trigonometric mutation with probability
            ``trig_probability``, DE/rand/1 otherwise).
        crossover: ``bin`` (binomial, paper 002 eq. 13 / paper 004) or ``exp`` (exponential, paper 004 Alg. 2).
        F: scale factor (> 0, at most 2).
        CR: crossover rate in [0, 1].
        p_F: either-or probability of using DE/rand/1 (paper 004's p_f).
        K: either-or recombination factor; default 0.5 (F + 1) (Price, Storn & Lampinen 2005).
        trig_probability: probability Mt of the trigonometric donor for ``mutation="trig"`` (Fan & Lampinen
            suggest 0.05).
        bound_handling: ``clip`` (paper 004), ``reflect`` or ``resample`` (see ``common.enforce_bounds``).
        runs: paper 002's rho: up to this many independent runs until the tolerances are met (see
            ``common.run_with_restarts``; totals are reported).
        callback: ``callback(generation, population)`` after the initial population (generation 0) and after
            every generation, with the (N, n) population (rad or m); a truthy return value stops the run.

    Returns:
        A :class:`Result`; ``history`` adds nothing beyond best/mean cost and diversity.
    """
    if strategy is not None:
        mutation, crossover = parse_strategy(strategy)
    scheme = _mutation_name(mutation)
    check_choice("crossover", crossover, CROSSOVERS)
    check_choice("bound_handling", bound_handling, BOUND_HANDLING)
    k = MUTATIONS.get(scheme, 3)
    N = check_int("population", population, k + 1)
    F = check_positive("F", F, 2.0)
    CR = check_fraction("CR", CR)
    p_F = check_fraction("p_F", p_F)
    K = 0.5 * (F + 1.0) if K is None else check_positive("K", K, 2.0)
    trig_probability = check_fraction("trig_probability", trig_probability)
    check_callback(callback)
    check_int("runs", runs)
    SolverRun(problem, max_generations, stall_generations, cost_tolerance)  # validates the stopping options
    D = problem.n

    def once() -> Result:
        run = SolverRun(problem, max_generations, stall_generations, cost_tolerance)

        X = initial_population(problem, rng, N)
        ev = problem.evaluate(X)
        best = run.record(X, ev)
        reason = "stopped by callback" if callback is not None and callback(0, X.copy()) else None
        while reason is None and (reason := run.stop_reason()) is None:
            # one uniform draw per generation: indices (N x N), crossover (N x D), its start/forced coordinate
            # and the either-or / trigonometric choice (2 x N); fewer calls keep the generation cheap
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
            if crossover == "bin":
                U = binomial_crossover(X, V, CR, u[:, N:N + D], j)
            else:
                U = exponential_crossover(X, V, j, exponential_lengths(CR, u[:, N:N + D]))
            U = enforce_bounds(U, problem, rng, bound_handling)
            X, ev = greedy_selection(X, ev, U, problem.evaluate(U))
            run.generation += 1
            best = run.record(X, ev)
            if callback is not None and callback(run.generation, X.copy()):
                reason = "stopped by callback"
        return run.result("de", reason)

    return run_with_restarts(once, problem, runs)


def greedy_selection(X: np.ndarray, ev: Evaluation, U: np.ndarray, ev_u: Evaluation) -> tuple[np.ndarray, Evaluation]:
    """DE's one-to-one selection: each trial U_i replaces its target X_i when its cost is no larger.

    Accepting ties lets the population drift across flat regions (Storn & Price). Returns the new
    population (N, n) and its evaluation.
    """
    better = ev_u.cost <= ev.cost
    X = np.where(better[:, None], U, X)
    cost = np.where(better, ev_u.cost, ev.cost)
    pos = np.where(better, ev_u.position_error, ev.position_error)
    rot = None if ev.orientation_error is None else np.where(better, ev_u.orientation_error, ev.orientation_error)
    return X, Evaluation(cost, pos, rot)
