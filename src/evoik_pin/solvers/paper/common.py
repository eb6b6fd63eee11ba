"""Pieces every population solver shares: the initial population, bound handling, diversity, and a
:class:`SolverRun` that keeps time, history and the stopping rules and builds the :class:`Result`."""

from __future__ import annotations

import time

import numpy as np

from ...problem import Evaluation, IKProblem, shortfall_text
from ...result import Result
from ..options import check_callback, check_choice, check_int, check_number

__all__ = ["BOUND_HANDLING", "SolverRun", "diversity", "enforce_bounds", "halton", "initial_population",
           "run_with_restarts"]

BOUND_HANDLING = ("clip", "reflect", "resample")


def halton(dimensions: int, count: int, skip: int = 0) -> np.ndarray:
    """Points ``skip .. skip + count - 1`` (count, dimensions) in [0, 1) of the unscrambled Halton sequence,
    as ``scipy.stats.qmc.Halton(d, scramble=False)`` gives them, without importing the slow scipy.stats."""
    primes = [p for p in range(2, 20 * dimensions + 20) if all(p % d for d in range(2, int(p**0.5) + 1))][:dimensions]
    index = np.arange(skip, skip + count, dtype=np.int64)
    out = np.zeros((count, dimensions))
    for d, base in enumerate(primes):
        i = index.copy()
        f = 1.0
        while i.any():
            f /= base
            out[:, d] += f * (i % base)
            i //= base
    return out


def initial_population(problem: IKProblem, rng: np.random.Generator, size: int) -> np.ndarray:
    """(size, n) configurations uniform in the search box; ``problem.q0`` (clipped) is the first one."""
    Q = rng.uniform(problem.lower, problem.upper, size=(size, problem.n))
    if problem.q0 is not None:
        Q[0] = np.clip(problem.q0, problem.lower, problem.upper)
    return Q


def enforce_bounds(trial: np.ndarray, problem: IKProblem, rng: np.random.Generator, method: str = "clip") -> np.ndarray:
    """A population (N, n) brought back into the search box: ``"clip"`` onto the violated bound, ``"reflect"``
    mirrored back inside, ``"resample"`` violating entries re-drawn uniformly in the box."""
    lo, hi = problem.lower, problem.upper
    if method == "clip":
        return np.minimum(np.maximum(trial, lo), hi)  # = np.clip, with less call overhead
    check_choice("bound_handling", method, BOUND_HANDLING)
    if method == "reflect":
        width = hi - lo
        safe = np.where(width > 0, width, 1.0)
        y = np.mod(trial - lo, 2 * safe)
        y = np.where(y > safe, 2 * safe - y, y)
        return np.where(width > 0, lo + y, lo)
    bad = (trial < lo) | (trial > hi)
    if bad.any():
        trial = trial.copy()
        trial[bad] = rng.uniform(lo, hi, size=trial.shape)[bad]
    return trial


def diversity(Q: np.ndarray, lower: np.ndarray, upper: np.ndarray) -> float:
    """Mean distance of the individuals to the population centroid, each joint scaled by its range (0 for a
    collapsed population, about 0.29 sqrt(n) for a uniform one)."""
    return float(_diversities(np.asarray(Q, dtype=float)[None], lower, upper)[0])


def _diversities(Qs: np.ndarray, lower: np.ndarray, upper: np.ndarray) -> np.ndarray:
    """:func:`diversity` of a stack of equally sized populations (G, N, n), shape (G,), in one pass."""
    Z = Qs / np.where(upper > lower, upper - lower, 1.0)
    Z -= Z.mean(axis=1, keepdims=True)
    return np.sqrt((Z * Z).sum(axis=2)).mean(axis=1)


class SolverRun:
    """Time, history and stopping rules of one population-solver run.

    Stopping rules, checked by :meth:`stop_reason` after every generation: ``callback(generation, population)``
    (given the (N, n) population after every :meth:`record`) returned a truthy value; the best individual meets
    the problem's tolerances; its cost is at most ``cost_tolerance``; ``max_generations`` reached; no improvement
    of the best cost for ``stall_generations`` generations. ``history["diversity"]`` (computed in batches) is
    complete in :meth:`result`."""

    #: Populations kept before their diversities are computed in one vectorized pass.
    _DIVERSITY_BATCH = 64

    def __init__(self, problem: IKProblem, max_generations: int, stall_generations: int | None = None,
                 cost_tolerance: float | None = None, callback=None) -> None:
        self.problem = problem
        self.callback = check_callback(callback)
        self._stopped_by_callback = False
        self.max_generations = check_int("max_generations", max_generations, 0)
        self.stall_generations = None if stall_generations is None else check_int(
            "stall_generations", stall_generations)
        self.cost_tolerance = None if cost_tolerance is None else check_number("cost_tolerance", cost_tolerance)
        self.t0 = time.perf_counter()
        self.generation = 0
        self.best_q: np.ndarray | None = None
        self.best_cost = np.inf
        self._stall = 0
        self.history: dict[str, list[float]] = {"best_cost": [], "mean_cost": [], "diversity": []}
        self._pending: list[np.ndarray] = []  # populations whose diversity is not computed yet

    def record(self, Q: np.ndarray, ev: Evaluation, **extra: float) -> int:
        """Log one generation's population ``Q`` (N, n), its evaluation and ``extra`` history series; the best index."""
        i = int(ev.cost.argmin())
        self._stall = 0 if ev.cost[i] < self.best_cost else self._stall + 1
        self.offer(Q[i], ev, i)
        self.history["best_cost"].append(self.best_cost)
        self.history["mean_cost"].append(float(ev.cost.sum() / ev.cost.shape[0]))
        if self._pending and (len(self._pending) >= self._DIVERSITY_BATCH or Q.shape != self._pending[0].shape):
            self._flush_diversity()
        self._pending.append(np.array(Q, dtype=float))
        for key, value in extra.items():
            self.history.setdefault(key, []).append(float(value))
        if self.callback is not None and self.callback(self.generation, Q.copy()):
            self._stopped_by_callback = True
        return i

    def _flush_diversity(self) -> None:
        if self._pending:
            values = _diversities(np.stack(self._pending), self.problem.lower, self.problem.upper)
            self.history["diversity"].extend(values.tolist())
            self._pending = []

    def offer(self, q: np.ndarray, ev: Evaluation, i: int) -> None:
        """Consider configuration ``q`` (n,), whose cost and errors are row ``i`` of ``ev``, for the best."""
        if ev.cost[i] < self.best_cost:
            self.best_cost, self.best_q = float(ev.cost[i]), np.asarray(q, float).copy()
            self._best_pos = float(ev.position_error[i])
            self._best_rot = None if ev.orientation_error is None else float(ev.orientation_error[i])

    def stop_reason(self) -> str | None:
        """Why to stop now, or None to go on."""
        if self._stopped_by_callback:
            return "stopped by callback"
        problem, q = self.problem, self.best_q
        if q is not None and (problem.rows_met(q[None])[0] if problem.target is None  # every goal's own tolerances
                              else problem.succeeded(self._best_pos, self._best_rot)):
            return "tolerance reached"
        if self.cost_tolerance is not None and self.best_cost <= self.cost_tolerance:
            return f"cost <= cost_tolerance ({self.cost_tolerance:g})"
        if self.generation >= self.max_generations:
            return f"max_generations ({self.max_generations}) reached"
        if self.stall_generations is not None and self._stall >= self.stall_generations:
            return f"no improvement for {self.stall_generations} generations"
        return None

    def result(self, method: str, message: str, **fields) -> Result:
        """The :class:`Result` of the best configuration met (errors recomputed from one FK)."""
        problem = self.problem
        self._flush_diversity()
        q = np.clip(self.best_q, problem.lower, problem.upper)
        ev = problem.evaluate(q[None], count=False)
        pos = float(ev.position_error[0])
        rot = None if ev.orientation_error is None else float(ev.orientation_error[0])
        goal_errors = None if problem.target is not None else problem.goal_errors(q)  # each within its own tolerances
        success = bool(problem.succeeded(pos, rot)) if goal_errors is None else problem.goals_met(goal_errors)
        if not success:  # "tolerance reached" by the best's errors, not by "cost <= cost_tolerance (...)"
            message = ("stopped" if message == "tolerance reached" else message) + "; " + shortfall_text(
                problem, pos, rot, goal_errors)
        return Result(
            q=q, position_error=pos, orientation_error=rot, cost=float(ev.cost[0]), success=success,
            generations=self.generation, evaluations=problem.evaluations, time_s=time.perf_counter() - self.t0,
            history={k: np.asarray(v) for k, v in self.history.items()}, message=message, method=method,
            goal_errors=goal_errors, **fields,
        )


def run_with_restarts(solve_once, problem: IKProblem, runs: int, max_generations: int,
                      stall_generations: int | None = None, cost_tolerance: float | None = None,
                      callback=None) -> Result:
    """Paper 002's rho (section 3.4): up to ``runs`` runs of ``solve_once(run)``, each on a fresh
    :class:`SolverRun` of the stopping options, until one meets the tolerances or is stopped by its callback;
    the best run's Result, with ``generations``, ``evaluations`` and ``time_s`` totals over the runs and
    ``history`` their series concatenated, plus ``run`` (the run index of each entry)."""
    runs = check_int("runs", runs)
    results = []
    for _ in range(runs):
        res = solve_once(SolverRun(problem, max_generations, stall_generations, cost_tolerance, callback))
        results.append(res)
        if res.success or res.message.startswith("stopped by callback"):
            break
    if len(results) == 1:
        return results[0]
    k = min(range(len(results)), key=lambda i: (not results[i].success, results[i].cost))
    best = results[k]
    history = {key: np.concatenate([r.history[key] for r in results if key in r.history]) for key in best.history}
    history["run"] = np.concatenate([np.full(len(r.history["best_cost"]), float(i)) for i, r in enumerate(results)])
    best.history = history
    best.generations = sum(r.generations for r in results)
    best.evaluations = problem.evaluations
    best.time_s = sum(r.time_s for r in results)
    best.message = f"{best.message} (run {k + 1} of {len(results)})"
    return best
