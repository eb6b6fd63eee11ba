"""The LM runs of one memetic solve (:class:`LMRuns`: their bookkeeping, the clock, a scene's exact check) and its
stage 3, differential-evolution restarts polished by LM (:func:`de_restart`)."""

from __future__ import annotations

import itertools
import time

import numpy as np

from ...problem import IKProblem
from ..lm import LevenbergMarquardt, LMOutcome
from ..paper.common import diversity
from ..paper.de_ops import binomial_crossover, distinct_indices, mutate

__all__ = ["BOUND_SHARE", "LMRuns", "de_restart", "kernel_goal_errors"]

#: Share of the coordinates of memetic's DE populations drawn on a bound instead of inside the box.
BOUND_SHARE = 0.4


def kernel_goal_errors(goals, out: LMOutcome) -> list:
    """Each goal's errors (:meth:`~evoik_pin.goals.Goal.reported`) from the kernel's at an LM outcome's q (its
    success test's numbers, trusted as the answer's: no kinematics pass in Python)."""
    errors = [(out.position_error, out.orientation_error)] if out.goal_errors is None else out.goal_errors.tolist()
    return [g.reported(p, r) for g, (p, r) in zip(goals, errors, strict=True)]


class LMRuns:
    """The LM runs of one memetic solve: its engine, the best outcome met, counters and the clock (``deadline``, s of
    ``perf_counter``; the first ``guaranteed`` runs are made whatever it says)."""

    def __init__(self, problem: IKProblem, lm: LevenbergMarquardt, deadline: float | None, iterations: int,
                 batch: int, guaranteed: int) -> None:
        self.problem, self.scene, self.lm, self.deadline = problem, problem.scene, lm, deadline
        self.iterations, self.batch, self.guaranteed = iterations, batch, guaranteed
        self.best: LMOutcome | None = None
        self.evaluations = self.attempts = 0
        self.attempt_errors: list[float] = []
        self.rejected = 0  # converged LM answers rejected by the scene's exact check
        self.rejected_pairs: list[tuple[str, str]] = []  # the pairs in contact at the last one

    def out_of_time(self) -> bool:
        return (self.deadline is not None and self.attempts >= self.guaranteed
                and time.perf_counter() >= self.deadline)

    def _deadline(self) -> float | None:
        """The next LM run's deadline: none while the guaranteed runs are made."""
        return None if self.attempts < self.guaranteed else self.deadline

    def _keep(self, out: LMOutcome, runs: int) -> bool:
        self.evaluations += out.evaluations
        self.attempts += runs
        self.attempt_errors.append(out.error)
        if out.converged and out.goal_errors is not None and not self.problem.goals_met(
                kernel_goal_errors(self.problem.goals, out)):
            # the kernel tests the goals before its finishing step, which may trade one goal past its tolerance for
            # a lower |e|^2 (a sole's angle for the CoM row): not met at q, the search goes on (as the guaranteed runs')
            out.converged = False
        if out.converged and self.scene is not None:
            margin = self.problem.margin
            if self.scene.in_collision(out.q, margin):  # the exact check, ~90 us
                # it reaches the target in collision: rejected; the search goes on from other starts
                self.rejected += 1
                self.rejected_pairs = self.scene.colliding_pairs(out.q, margin)
                out.converged = False
                if self.best is None:
                    self.best = out
                return False
        if self.best is None or out.converged or out.rank < self.best.rank:
            self.best = out
        return out.converged

    def polish(self, q: np.ndarray) -> bool:
        """One LM run from ``q`` (n,); keeps the best outcome; True when it meets the tolerances."""
        return self._keep(self.lm.run(q, self.iterations, self._deadline()), 1)

    def polish_many(self, starts) -> bool:
        """LM runs from ``starts`` (an iterable of (n,) configurations, drawn lazily) in order, ``batch`` per engine
        call, until one meets the tolerances or the time is up (checked between groups)."""
        it = iter(starts)
        for g in itertools.count():
            chunk = list(itertools.islice(it, self.batch))
            if not chunk or (g and self.out_of_time()):
                return False
            if len(chunk) == 1:
                solved = self.polish(chunk[0])
            else:
                out, k = self.lm.run_many(np.array(chunk), self.iterations, self._deadline())
                solved = self._keep(out, k + 1 if out.converged else len(chunk))
            if solved:
                return True


def de_restart(problem, rng, search: LMRuns, population: int, generations: int, polish_count: int,
               wrap: np.ndarray, history: dict, n_gen: int, best_cost: float) -> tuple[bool, int, float]:
    """One stage-3 restart: a DE population (uniform in the box, a share on its bounds, the best met and ``q0``),
    ``generations`` generations, then its ``polish_count`` best members (the elite excepted) polished by LM. Returns
    (solved, generations so far, best cost)."""
    lo, hi = problem.lower, problem.upper
    X = rng.uniform(lo, hi, size=(population, problem.n))
    # a share of the coordinates sits on a bound: targets whose solutions rest on joint limits (several at once
    # near a corner of the box) are rare under uniform draws, and LM from the interior is held off by the limits
    on_bound = rng.random(X.shape) < BOUND_SHARE
    X = np.where(on_bound, np.where(rng.random(X.shape) < 0.5, lo, hi), X)
    X[0] = search.best.q
    if problem.q0 is not None:
        X[1] = np.minimum(np.maximum(problem.q0, lo), hi)
    costs = problem.cost(X)
    for _ in range(generations):
        best = int(costs.argmin())
        F = rng.uniform(0.5, 1.0, size=population)
        V = mutate(X, "currenttobest1", F, distinct_indices(rng, population, 2), best)
        U = binomial_crossover(X, V, 0.9, rng.random(X.shape), rng.integers(0, problem.n, population))
        U = np.where(wrap, lo + np.mod(U - lo, 2 * np.pi), np.minimum(np.maximum(U, lo), hi))
        cu = problem.cost(U)
        better = cu <= costs
        X[better], costs[better] = U[better], cu[better]
        n_gen += 1
        best_cost = min(best_cost, float(costs.min()))
        history["best_cost"].append(best_cost)
        history["mean_cost"].append(float(costs.mean()))
        history["diversity"].append(diversity(X, lo, hi))
        if search.out_of_time():
            break
    order = np.argsort(costs)
    elite = search.best.q
    order = [i for i in order if not np.array_equal(X[i], elite)][:polish_count]
    if not order:
        return False, n_gen, best_cost
    return search.polish_many(X[order]), n_gen, best_cost
