"""Particle swarm optimization with a linearly varying inertia weight (paper 002, section 3.1, eq. 11): ``pso``.

``v_i <- w v_i + c1 r1 (p_i - x_i) + c2 r2 (g - x_i)``, ``x_i <- x_i + v_i`` for all particles at once, with
velocities clamped per joint (the paper gives no clamp).
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from ...objectives import PoseDistance
from ...problem import IKProblem
from ...result import Result
from .. import register
from ..options import check_choice, check_int, check_nonnegative, check_positive
from .common import BOUND_HANDLING, SolverRun, enforce_bounds, initial_population, run_with_restarts

__all__ = ["RANDOM_FACTORS", "TOPOLOGIES", "inertia_weight", "pso", "pso_step", "ring_best"]

TOPOLOGIES = ("global", "ring")
#: Accepted ``random_factors`` values: how r1, r2 of eq. 11 are drawn.
RANDOM_FACTORS = ("per-coordinate", "per-particle")


def inertia_weight(iteration: int, max_iterations: int, w_start: float, w_end: float) -> float:
    """Paper 002 (Table 2): ``w = w_start + (iter / iter_max)(w_end - w_start)``, iter = 1..iter_max."""
    return w_start + (iteration / max(max_iterations, 1)) * (w_end - w_start)


def pso_step(X: np.ndarray, V: np.ndarray, P: np.ndarray, g: np.ndarray, w: float, c1: float, c2: float,
             r1: np.ndarray, r2: np.ndarray, v_max: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """One update (eq. 11) of positions ``X``, velocities ``V`` given personal bests ``P`` (N, D), the guide
    ``g`` (D,) or (N, D), uniform draws ``r1``, ``r2`` (N, D) or (N, 1) and the velocity limit ``v_max`` (D,)
    (rad or m per iteration); returns the new positions and velocities (N, D), before bound handling."""
    V = w * V + c1 * r1 * (P - X) + c2 * r2 * (g - X)
    V = np.minimum(np.maximum(V, -v_max), v_max)
    return X + V, V


def ring_best(p_cost: np.ndarray) -> np.ndarray:
    """Index (N,) of the best personal best among particle i and its ring neighbours i - 1 and i + 1."""
    N = p_cost.shape[0]
    i = np.arange(N)
    cand = np.stack([(i - 1) % N, i, (i + 1) % N])  # (3, N)
    return cand[p_cost[cand].argmin(axis=0), i]


@register("pso", "particle swarm (paper 002): inertia weight linear from w_start to w_end, c1 = c2 = 1.5, "
                 "velocity clamping")
def pso(problem: IKProblem, rng: np.random.Generator, *, population: int = 30, max_generations: int = 600,
        stall_generations: int | None = None, cost_tolerance: float | None = None, w_start: float = 0.9,
        w_end: float = 0.4, c1: float = 1.5, c2: float = 1.5, velocity_clamp: float = 0.2, topology: str = "global",
        random_factors: str = "per-coordinate", reinit_stagnant: int | None = None, bound_handling: str = "clip",
        runs: int = 10, callback: Callable | None = None) -> Result:
    """Particle swarm optimization over the joint vector, vectorized over the swarm (paper 002, eq. 11).

    Args:
        population: N (>= 2). max_generations, stall_generations, cost_tolerance, callback: the stopping rules of
            :class:`~.common.SolverRun`; ``max_generations`` also sets the inertia schedule.
        w_start, w_end: inertia weight at the first and the last iteration (linear in between); c1, c2: cognitive
            and social coefficients; velocity_clamp: velocity limit as a fraction of each joint's range, (0, 1].
        topology: ``global`` (paper 002: the swarm's best guides) or ``ring`` (the best personal best among a
            particle and its two ring neighbours guides it, which slows the swarm's collapse).
        random_factors: ``per-coordinate`` (r1, r2 per particle and joint, eq. 11) or ``per-particle`` (one
            each per particle: the step stays in the plane of (p_i - x_i) and (g - x_i), so the swarm follows
            curved valleys; what 6-D pose targets need, with ``pose_metric="euclidean"``).
        reinit_stagnant: re-initialise a particle whose personal best has not improved for this many
            iterations (never the swarm's best); default off.
        bound_handling: ``clip`` (a particle stops at the bound and loses that velocity component),
            ``reflect`` or ``resample`` (:func:`~.common.enforce_bounds`).
        runs: paper 002's rho (:func:`~.common.run_with_restarts`).

    Returns a :class:`Result` whose ``history`` adds the inertia weight ``w`` per iteration.
    """
    N = check_int("population", population, 2)
    w_start, w_end = (check_nonnegative(k, v, 2.0) for k, v in (("w_start", w_start), ("w_end", w_end)))
    c1, c2 = (check_nonnegative(k, v, 10.0) for k, v in (("c1", c1), ("c2", c2)))
    velocity_clamp = check_positive("velocity_clamp", velocity_clamp, 1.0)
    check_choice("bound_handling", bound_handling, BOUND_HANDLING)
    check_choice("topology", topology, TOPOLOGIES)
    check_choice("random_factors", random_factors, RANDOM_FACTORS)
    r_shape = (2, N, problem.n) if random_factors == "per-coordinate" else (2, N, 1)
    reinit_stagnant = None if reinit_stagnant is None else check_int("reinit_stagnant", reinit_stagnant)

    def once(run: SolverRun) -> Result:
        D = problem.n
        v_max = velocity_clamp * (problem.upper - problem.lower)
        X = initial_population(problem, rng, N)
        V = rng.uniform(-v_max, v_max, size=(N, D))
        ev = problem.evaluate(X)
        P, p_cost = X.copy(), ev.cost.copy()
        stagnant = np.zeros(N, dtype=int)  # iterations since each personal best last improved
        run.record(X, ev, w=w_start)
        g_best = run.best_q
        while (reason := run.stop_reason()) is None:
            it = run.generation + 1
            w = inertia_weight(it, run.max_generations, w_start, w_end)
            r = rng.random(r_shape)
            guide = g_best if topology == "global" else P[ring_best(p_cost)]
            X_new, V = pso_step(X, V, P, guide, w, c1, c2, r[0], r[1], v_max)
            X = enforce_bounds(X_new, problem, rng, bound_handling)
            if bound_handling == "clip":
                V = np.where(X == X_new, V, 0.0)  # absorbing walls: a particle stopped at a bound loses that speed
            if reinit_stagnant is not None:
                reset = stagnant >= reinit_stagnant
                reset[p_cost.argmin()] = False  # the particle holding the swarm's best keeps it
                if reset.any():
                    k = int(reset.sum())
                    X[reset] = rng.uniform(problem.lower, problem.upper, size=(k, D))
                    V[reset] = rng.uniform(-v_max[None, :], v_max[None, :], size=(k, D))
            ev = problem.evaluate(X)
            improved = ev.cost < p_cost
            if reinit_stagnant is not None:
                improved |= reset  # a re-initialised particle's personal best restarts at its new position
                stagnant = np.where(improved, 0, stagnant + 1)
            P = np.where(improved[:, None], X, P)
            p_cost = np.where(improved, ev.cost, p_cost)
            run.generation = it
            run.record(X, ev, w=w)
            g_best = run.best_q  # the best position any particle has visited
        return run.result("pso", reason)

    result = run_with_restarts(once, problem, runs, max_generations, stall_generations, cost_tolerance, callback)
    if (not result.success and problem.target is not None and problem.target.rotation is not None
            and not (random_factors == "per-particle" and isinstance(problem.objective, PoseDistance))):
        result.message += ("; on 6-D pose targets PSO is reliable with pose_metric='euclidean' and "
                           "random_factors='per-particle' (docs/BENCHMARKS.md)")
    return result
