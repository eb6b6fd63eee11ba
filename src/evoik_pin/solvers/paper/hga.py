"""Paper 001's hybrid GA (``hga``): the niching GA finds the good regions, Nelder-Mead polishes them.

Exploration (section 3.1): :func:`~evoik_pin.solvers.paper.ga.run_niching_ga` for the paper's 12 generations.
Exploitation (section 3.2): every individual the GA evaluated is split into joint-space clusters (wrapped
distances, :mod:`~evoik_pin.solvers.paper.clustering`); the best member of each of the best ``max_starts`` clusters is
polished by ``scipy.optimize.minimize(method="Nelder-Mead")``, whose coefficients are exactly the paper's
(reflection 1, expansion 2, contraction 0.5, shrink 0.5), inside the search box. Polished points that
meet the tolerances are merged again (they often converge to the same solution) and returned as the
distinct IK solutions, best first.

A goal list (:mod:`evoik_pin.goals`) is searched the same way on its cost (``IKProblem.evaluate``: the goals'
weighted errors), and a polished point is a solution when it meets every goal within that goal's tolerances.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from ...problem import IKProblem
from ...result import Result
from .. import register
from ..options import check_callback, check_int, check_positive
from .analytic import solution_results
from .clustering import leader_clusters
from .ga import check_niching_ga_options, run_niching_ga, solution_leaders

__all__ = ["nelder_mead_polish"]


def nelder_mead_polish(problem: IKProblem, q: np.ndarray, simplex_size: float = 0.05, xatol: float = 1e-10,
                       fatol: float = 1e-13, max_evaluations: int = 2000) -> np.ndarray:
    """Nelder-Mead from ``q`` (n,) on the problem's cost, inside the search box; returns the polished q.

    Revolute joints whose box spans a full turn are searched unbounded and wrapped back into the box.

    The initial simplex is ``q`` plus ``simplex_size`` (rad or m) along each joint axis, stepping inwards
    at an upper bound, so it spans the GA's niche rather than scipy's default 5 % of |q|, which collapses
    for joints near zero. Evaluations count towards ``problem.evaluations``.
    """
    lo, hi = problem.lower, problem.upper
    q = np.clip(np.asarray(q, float), lo, hi)
    # A revolute joint whose box is a full turn has no real bound: -pi and +pi are the same angle. Leave it
    # unbounded for the simplex (a solution at -170 deg reached from +179 deg must not stop on +180) and
    # wrap the result back into the box.
    full_turn = problem.robot.revolute & (hi - lo >= 2 * np.pi - 1e-9)
    step = np.where(full_turn | (q + simplex_size <= hi), simplex_size, -simplex_size)
    simplex = np.vstack([q, q + np.diag(step)])
    simplex = np.where(full_turn, simplex, np.clip(simplex, lo, hi))
    bounds = [(None, None) if f else (a, b) for f, a, b in zip(full_turn, lo, hi, strict=True)]
    from scipy.optimize import minimize  # lazy: importing scipy.optimize costs ~0.4 s

    res = minimize(lambda x: float(problem.cost(x[None])[0]), q, method="Nelder-Mead", bounds=bounds,
                   options={"initial_simplex": simplex, "xatol": xatol, "fatol": fatol,
                            "maxfev": max_evaluations, "adaptive": False})
    x = np.where(full_turn, lo + np.mod(res.x - lo, 2 * np.pi), res.x)
    return np.clip(x, lo, hi)


@register("hga", "paper 001: niching GA + Nelder-Mead polish of every niche; all distinct IK solutions",
          multi_solution=True)
def hga(problem: IKProblem, rng: np.random.Generator, *, population: int = 750, max_generations: int = 12,
        niches: int = 2, niche_size: float | None = None, eta: float = 5.0, crossover_probability: float = 0.9,
        cluster_radius: float = 0.35, max_starts: int = 24, simplex_size: float = 0.05, xatol: float = 1e-10,
        fatol: float = 1e-13, max_polish_evaluations: int = 2000, solution_radius: float = 1e-4,
        callback: Callable | None = None) -> Result:
    """Paper 001's hybrid GA (section 3.2): every IK solution at once.

    Options: the GA's (``population``, ``max_generations``, ``niches``, ``niche_size``, ``eta``,
    ``crossover_probability``: see ``ga``; defaults are paper 001's 2R settings, Table 1; its PUMA
    settings are population 1000 and 4 niches), and:
        cluster_radius: joint-space radius (rad, wrapped) of the clusters whose leaders are polished.
        max_starts: polish at most this many cluster leaders, best first (24).
        simplex_size: initial Nelder-Mead simplex edge (rad or m) (0.05).
        xatol, fatol: Nelder-Mead stopping tolerances on the simplex (rad) and its costs (1e-10, 1e-13).
        max_polish_evaluations: cost evaluations allowed per polish (2000).
        solution_radius: polished solutions closer than this (rad, wrapped) are one solution (1e-4).
        callback: optional ``callback(generation, population)`` on the GA phase, as for ``ga`` (a copy of
            the population (N, n) after generation 0 and every generation; return value ignored).

    Returns:
        :class:`Result` with ``q`` the best solution and ``solutions`` every distinct polished solution
        that meets the tolerances (a goal list: every goal's, each solution with its ``goal_errors``), best first
        (empty, with a message, when none does, e.g. an unreachable target).
    """
    population, max_generations, niches, niche_size, eta, crossover_probability = check_niching_ga_options(
        population, max_generations, niches, niche_size, eta, crossover_probability)
    max_starts = check_int("max_starts", max_starts)
    max_polish_evaluations = check_int("max_polish_evaluations", max_polish_evaluations)
    simplex_size, xatol, fatol, solution_radius = (check_positive(k, v) for k, v in (
        ("simplex_size", simplex_size), ("xatol", xatol), ("fatol", fatol), ("solution_radius", solution_radius)))
    check_callback(callback)
    archive: list = []
    run, _, _ = run_niching_ga(problem, rng, population, max_generations, niches, niche_size, eta,
                               crossover_probability, archive=archive, callback=callback)
    # The good areas are taken from every individual the GA evaluated, not only the last generation: in
    # 12 generations the population may drift away from one of the solution families it had found
    # (on the PUMA targets, the last generation alone misses about a quarter of the solutions).
    Q = np.concatenate([a[0] for a in archive])
    cost = np.concatenate([a[1] for a in archive])
    starts = solution_leaders(problem, Q, cost, cluster_radius, max_clusters=max_starts)
    polished = np.array([nelder_mead_polish(problem, q, simplex_size, xatol, fatol, max_polish_evaluations)
                         for q in starts])
    before = problem.evaluations
    ev = problem.evaluate(polished)
    problem.evaluations = before  # bookkeeping, not search
    for i in range(len(polished)):
        rot = None if ev.orientation_error is None else float(ev.orientation_error[i])
        run.offer(polished[i], float(ev.cost[i]), float(ev.position_error[i]), rot)
    ok = problem.rows_met(polished)  # a goal list: every goal within its own tolerances
    good, good_cost = polished[ok], ev.cost[ok]
    if len(good):
        leaders, _ = leader_clusters(good, good_cost, solution_radius, problem.robot.revolute)
        good = good[leaders]
    message = (f"{len(good)} distinct solution(s) from {len(starts)} polished niche leader(s)" if len(good) else
               f"no polished niche leader (of {len(starts)}) reaches the target: it is out of reach, or "
               "the GA missed it")
    if not len(good) and problem.goals is not None and problem.n > 6:
        message += (f" (Nelder-Mead over {problem.n} joints rarely meets a goal list's tolerances; memetic-all finds "
                    "the solutions of whole robots)")
    result = run.result("hga", message)
    result.solutions = solution_results(problem, good, "hga", result.generations, result.evaluations,
                                        result.time_s)
    return result
