"""Paper 000's multi-objective differential evolution (``mode``, Pseudocode 1): minimized objectives (section IV)
``f1 = 1 - exp(-||P - P_e(q)|| / l)`` (l = ``length_scale``) and ``f2 = max_k |q_k - q_init,k|`` (rad; q_init =
``problem.q0`` or zeros), combined as ``w1 f1 + w2 f2`` with Gabli et al.'s equitable weights
(:func:`equitable_weights`) of the previous generation's individual closest to the target. Per individual: a draw
m; if ``m < P_m`` a trigonometric donor (``m <= Mt``) or DE/rand/1, crossed binomially (or whole, the "fixed"
variant) with probability ``P_c``; greedy selection under the current weights. ``P_c``, ``P_m`` adapt as in Zhao &
Qiao (:func:`adaptive_probability`). The paper gives no Mt: the default 0.125 is measured in docs/BENCHMARKS.md.
"""

from __future__ import annotations

import numpy as np

from ...objectives import MaxJointDisplacement
from ...problem import Evaluation, IKProblem
from ...result import Front, Result
from .. import register
from ..options import check_choice, check_fraction, check_int, check_nonnegative, check_positive
from .common import BOUND_HANDLING, SolverRun, enforce_bounds, initial_population
from .de_ops import binomial_crossover, distinct_indices, rand1, trigonometric
from .pareto_sorting import crowding_distance

__all__ = ["VARIANTS", "adaptive_probability", "equitable_weights", "nondominated_2d"]

#: Paper 000's three configurations (Figs. 3-6): (crossover, trigonometric mutation).
VARIANTS: dict[str, tuple[str, bool]] = {
    "fixed": ("fixed", False),  # (a) fixed crossover and normal (DE/rand/1) mutation
    "binomial": ("binomial", False),  # (b) binomial crossover, without trigonometric mutation
    "binomial-trigonometric": ("binomial", True),  # (c) binomial crossover and trigonometric mutation
}


def equitable_weights(f_best: np.ndarray, previous: np.ndarray | None = None) -> np.ndarray:
    """Gabli et al.'s equitable weights (H,) ``w_h = sum_{k != h} |f_k| / ((H - 1) sum_k |f_k|)`` of the previous
    best's objective values (H,); ``previous`` (or equal weights) when every |f_k| is 0."""
    f = np.abs(np.asarray(f_best, float))
    H = f.size
    total = f.sum()
    if not total > 0:
        return np.full(H, 1.0 / H) if previous is None else np.asarray(previous, float)
    return (total - f) / ((H - 1) * total)


def adaptive_probability(cost: np.ndarray, C: float) -> np.ndarray:
    """Zhao & Qiao's adaptive probability (N,) for minimized ``cost`` (N,): ``C (f - f_min) / (f_avg - f_min)``
    where ``f <= f_avg``, ``C`` elsewhere (everywhere when all costs are equal)."""
    f_min, f_avg = cost.min(), cost.mean()
    if not f_avg > f_min:
        return np.full(cost.shape, C)
    return np.where(cost <= f_avg, C * (cost - f_min) / (f_avg - f_min), C)


def nondominated_2d(F: np.ndarray) -> np.ndarray:
    """Indices of the non-dominated rows of ``F`` (M, 2) (both minimized) by the first objective, one per duplicate."""
    order = np.lexsort((F[:, 1], F[:, 0]))
    f2 = F[order, 1]
    prev_min = np.concatenate([[np.inf], np.minimum.accumulate(f2)[:-1]])
    return order[f2 < prev_min]


def _merge_front(front: tuple[np.ndarray, np.ndarray], Q: np.ndarray, F: np.ndarray, size: int):
    """The non-dominated rows of ``front`` (configurations (M, n), objectives (M, 2)) and the new ``Q``, ``F``, as
    such a pair of at most ``size`` rows (a crowded front thinned by crowding distance, Deb 2002, extremes kept)."""
    Q, F = np.concatenate([front[0], Q]), np.concatenate([front[1], F])
    keep = nondominated_2d(F)
    if keep.size > size:
        keep = keep[np.sort(np.argsort(-crowding_distance(F[keep]), kind="stable")[:size])]
    return Q[keep], F[keep]


@register("mode", "paper 000: multi-objective DE (position error and max joint displacement, equitable "
          "weights, trigonometric mutation, adaptive Pc/Pm)", multi_objective=True)
def mode(problem: IKProblem, rng: np.random.Generator, *, population: int = 150, max_generations: int = 200,
         variant: str = "binomial-trigonometric", mutation_probability: float = 0.2, crossover_rate: float = 0.8,
         scale_factor: float = 0.2, trigonometric_probability: float = 0.125, adaptive: bool = True,
         bound_handling: str = "clip", front_size: int = 100, length_scale: float = 1.0) -> Result:
    """Paper 000's multi-objective DE (Pseudocode 1; defaults are its parameters).

    Options:
        population: Np. max_generations: g_max (the run also stops when the best meets the tolerances).
        variant: ``"binomial-trigonometric"`` (c, the paper's method), ``"binomial"`` (b) or ``"fixed"`` (a: the
            whole DE/rand/1 donor taken with probability Cr).
        mutation_probability: M. crossover_rate: Cr. scale_factor: F. trigonometric_probability: Mt.
        adaptive: Zhao & Qiao's adaptive P_c and P_m; False keeps P_c = Cr and P_m = M.
        bound_handling: ``"clip"``, ``"reflect"`` or ``"resample"`` for donors outside the bounds.
        front_size: at most this many points kept in the non-dominated archive. length_scale: l (m) of ``f1``.

    Returns:
        :class:`Result` with ``q`` the final generation's best weighted individual (the paper's ``argmax f``),
        ``front`` the non-dominated (position error m, max displacement rad) met in the run, and history series
        ``w1``, ``w2``, ``best_fitness`` (least weighted cost), ``best_position_error`` m, ``best_displacement`` rad.
    """
    population = check_int("population", population, 5)
    check_choice("variant", variant, tuple(VARIANTS))
    M = check_fraction("mutation_probability", mutation_probability)
    Cr = check_fraction("crossover_rate", crossover_rate)
    F = check_nonnegative("scale_factor", scale_factor, 2.0)
    Mt = check_fraction("trigonometric_probability", trigonometric_probability)
    check_choice("bound_handling", bound_handling, BOUND_HANDLING)
    front_size = check_int("front_size", front_size, 2)
    length_scale = check_positive("length_scale", length_scale, unit="m")
    crossover, use_trig = VARIANTS[variant]

    displacement = MaxJointDisplacement(np.zeros(problem.n) if problem.q0 is None else problem.q0)

    def objectives(Q):
        """Evaluation, objectives (N, 2) f1, f2, and the front's (position error m, f2 rad)."""
        ev = problem.evaluate(Q)
        raw = np.column_stack([ev.position_error, displacement(Q, robot=problem.robot)])
        return ev, np.column_stack([1.0 - np.exp(-raw[:, 0] / length_scale), raw[:, 1]]), raw

    run = SolverRun(problem, max_generations)
    X = initial_population(problem, rng, population)
    ev, Fx, raw = objectives(X)
    pos, rot, disp = ev.position_error, ev.orientation_error, raw[:, 1]
    archive = _merge_front((X[:0], raw[:0]), X, raw, front_size)  # the non-dominated points met in the run
    w = np.array([0.5, 0.5])  # Pseudocode 1, step 2
    cost = Fx @ w
    best = int(np.argmin(pos))

    def record():
        run.record(X, Evaluation(cost, pos, rot), w1=w[0], w2=w[1], best_fitness=cost.min(),
                   best_position_error=pos[best], best_displacement=disp[best])

    record()
    while (reason := run.stop_reason()) is None:
        w = equitable_weights(Fx[best], w)
        cost = Fx @ w
        P_m, P_c = (adaptive_probability(cost, c) if adaptive else np.full(population, c) for c in (M, Cr))
        m = rng.random(population)
        mutated = m < P_m
        idx = distinct_indices(rng, population, 3)
        V = rand1(X, F, idx)
        if use_trig:
            trig = mutated & (m <= Mt)
            if trig.any():
                V[trig] = trigonometric(X, cost, idx[trig])
        u, jrand = rng.random(X.shape), rng.integers(0, problem.n, population)
        U = (binomial_crossover(X, V, P_c, u, jrand) if crossover == "binomial"
             else np.where((u[:, 0] < P_c)[:, None], V, X))  # "fixed": the whole donor
        changed = mutated & np.any(U != X, axis=1)
        if changed.any():
            trial = enforce_bounds(U[changed], problem, rng, bound_handling)
            ev_t, F_t, raw_t = objectives(trial)
            archive = _merge_front(archive, trial, raw_t, front_size)
            better = F_t @ w <= cost[changed]
            rows = np.nonzero(changed)[0][better]
            X[rows], Fx[rows] = trial[better], F_t[better]
            pos[rows], disp[rows] = ev_t.position_error[better], raw_t[better, 1]
            if rot is not None:
                rot[rows] = ev_t.orientation_error[better]
            cost = Fx @ w
        best = int(np.argmin(pos))
        run.generation += 1
        record()
    # The paper's answer is the best weighted individual of the last generation (argmax f), not the best
    # ever met under other weights: reset the run's best to it.
    final = int(np.argmin(cost))
    run.best_cost = np.inf
    run.offer(X[final], Evaluation(cost, pos, rot), final)
    order = np.argsort(archive[1][:, 0], kind="stable")
    return run.result("mode", reason,
                      front=Front(q=archive[0][order], objectives=archive[1][order], violation=np.zeros(len(order))))
