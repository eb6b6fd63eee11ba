"""Paper 001's hybrid GA (``hga``): the niching GA (:func:`~.ga.run_niching_ga`) finds the good regions among
every individual it evaluated, clustered in joint space; Nelder-Mead (the paper's coefficients) polishes each
cluster's best member, and the polished points within tolerance, merged, are the distinct IK solutions.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from ...problem import IKProblem
from ...result import Result
from .. import register
from ..options import check_int, check_positive
from .analytic import solution_results
from .clustering import leader_rows
from .ga import run_niching_ga

__all__ = ["nelder_mead_polish"]


def nelder_mead_polish(problem: IKProblem, q: np.ndarray, simplex_size: float = 0.05, xatol: float = 1e-10,
                       fatol: float = 1e-13, max_evaluations: int = 2000) -> np.ndarray:
    """Nelder-Mead from ``q`` (n,) on the problem's cost, inside the search box; returns the polished q. The
    initial simplex is ``q`` plus ``simplex_size`` (rad or m) along each joint axis (inwards at an upper bound): it
    spans the GA's niche, where scipy's default 5 % of |q| collapses for joints near zero."""
    lo, hi = problem.lower, problem.upper
    q = np.clip(np.asarray(q, float), lo, hi)
    # A revolute joint whose box is a full turn has no real bound (a solution at -170 deg reached from +179 deg
    # must not stop on +180): unbounded for the simplex, the result wrapped back into the box.
    full_turn = problem.robot.revolute & (hi - lo >= 2 * np.pi - 1e-9)
    simplex = np.vstack([q, q + np.diag(np.where(full_turn | (q + simplex_size <= hi), simplex_size, -simplex_size))])
    simplex = np.where(full_turn, simplex, np.clip(simplex, lo, hi))
    bounds = [(None, None) if f else (a, b) for f, a, b in zip(full_turn, lo, hi, strict=True)]
    from scipy.optimize import minimize  # lazy: scipy.optimize is slow to import

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

    Options: the GA's and ``callback`` (see :func:`~.ga.ga`), and
        cluster_radius: joint-space radius (rad, wrapped) of the clusters whose leaders are polished.
        max_starts: polish at most this many cluster leaders, best first.
        simplex_size, xatol, fatol: Nelder-Mead's initial simplex edge (rad or m) and stopping tolerances.
        max_polish_evaluations: cost evaluations allowed per polish.
        solution_radius: polished solutions closer than this (rad, wrapped) are one solution.

    Returns:
        :class:`Result` with ``q`` the best solution and ``solutions`` every distinct polished solution that
        meets the tolerances (a goal list: every goal's), best first; empty, with a message, when none does.
    """
    max_starts = check_int("max_starts", max_starts)
    max_polish_evaluations = check_int("max_polish_evaluations", max_polish_evaluations)
    simplex_size, xatol, fatol, solution_radius = (check_positive(k, v) for k, v in (
        ("simplex_size", simplex_size), ("xatol", xatol), ("fatol", fatol), ("solution_radius", solution_radius)))
    archive: list = []
    run, _, _ = run_niching_ga(problem, rng, population, max_generations, niches, niche_size, eta,
                               crossover_probability, archive=archive, callback=callback)
    # every individual the GA evaluated, not only the last generation, which may have drifted away from a family
    Q, cost = (np.concatenate(part) for part in zip(*archive, strict=True))
    starts = leader_rows(Q, cost, cluster_radius, problem.robot.revolute, max_clusters=max_starts)
    polished = np.array([nelder_mead_polish(problem, q, simplex_size, xatol, fatol, max_polish_evaluations)
                         for q in starts])
    ev = problem.evaluate(polished, count=False)
    for i in range(len(polished)):
        run.offer(polished[i], ev, i)
    ok = problem.rows_met(polished)  # a goal list: every goal within its own tolerances
    good = leader_rows(polished[ok], ev.cost[ok], solution_radius, problem.robot.revolute)
    message = (f"{len(good)} distinct solution(s) from {len(starts)} polished niche leader(s)" if len(good) else
               f"no polished niche leader (of {len(starts)}) reaches the target: it is out of reach, or "
               "the GA missed it")
    if not len(good) and problem.target is None and problem.n > 6:
        message += (f" (Nelder-Mead over {problem.n} joints rarely meets a goal list's tolerances; memetic-all finds "
                    "the solutions of whole robots)")
    result = run.result("hga", message)
    result.solutions = solution_results(problem, good, "hga", result.generations, result.evaluations, result.time_s)
    return result
