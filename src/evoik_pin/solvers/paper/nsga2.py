"""NSGA-II (Deb et al. 2002) with constraint domination, vectorized over the population (paper 003).

:func:`nsga2_minimize` is a generic box-constrained multi-objective minimizer (usable on test problems such as
ZDT1), built from :func:`dominance_matrix`, :func:`nondominated_ranks`, :func:`crowding_distance`, :func:`sbx` and
:func:`bounded_polynomial_mutation` as in Deb's reference implementation, each one call over the whole population.
The registered ``nsga2`` IK method (:func:`nsga2`) builds paper 003's problem on top of it: objectives
``g = 1 / (Y + 1)`` (Yoshikawa manipulability Y of the task rows) and the smoothness
``S = sqrt(sum_i K_i (q_i - q_prev,i)^2)``, the equality ``f(q) = x_d`` as a constraint whose violation is the error
above the tolerances, and the first-front member with the best S as the answer.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from ... import lie
from ...errors import BoundsError, OptionError
from ...objectives import (
    ManipulabilityCost,
    Objective,
    PopulationKinematics,
    WeightedJointDisplacement,
    orientation_errors,
    position_errors,
)
from ...problem import IKProblem
from ...result import Front, Result
from .. import register
from ..options import check_fraction, check_int, check_nonnegative, check_nonnegative_vector
from .common import SolverRun, diversity, halton, initial_population

__all__ = [
    "GoalManipulability",
    "NSGA2Result",
    "bounded_polynomial_mutation",
    "crowding_distance",
    "dominance_matrix",
    "goal_task",
    "goal_rows",
    "nondominated_ranks",
    "nsga2_minimize",
    "sbx",
    "survival",
]


# ---------------------------------------------------------------------------------------------- operators
def dominance_matrix(F: np.ndarray, violation: np.ndarray | None = None) -> np.ndarray:
    """``D[i, j]`` True when row i constraint-dominates row j; ``F`` (N, k) minimized, ``violation`` (N,) >= 0.

    Feasible (violation 0) beats infeasible; two infeasible rows compare by violation; two feasible rows
    by Pareto dominance (no worse in every objective, better in one).
    """
    F = np.asarray(F, float)
    N = F.shape[0]
    le = np.ones((N, N), bool)
    lt = np.zeros((N, N), bool)
    for column in F.T:  # one (N, N) comparison per objective: faster than reducing an (N, N, k) array
        le &= column[:, None] <= column[None, :]
        lt |= column[:, None] < column[None, :]
    D = le & lt
    if violation is None:
        return D
    cv = np.asarray(violation, float)
    feas = cv <= 0
    both_feasible = feas[:, None] & feas[None, :]
    return np.where(both_feasible, D, (feas[:, None] & ~feas[None, :]) | (~feas[:, None] & ~feas[None, :]
                                                                           & (cv[:, None] < cv[None, :])))


def _pareto_ranks(F: np.ndarray, stop: int | None = None) -> np.ndarray:
    """Front index (N,) under plain Pareto dominance, by peeling; with ``stop``, peeling ends once at least
    ``stop`` rows are ranked and the rest get the next rank (they are behind every ranked row)."""
    D = dominance_matrix(F)
    count = D.sum(axis=0)
    rank = np.full(F.shape[0], -1)
    current = np.nonzero(count == 0)[0]
    r = done = 0
    while current.size:
        rank[current] = r
        done += current.size
        r += 1
        if stop is not None and done >= stop:
            break
        count = count - D[current].sum(axis=0)
        count[rank >= 0] = -1
        current = np.nonzero(count == 0)[0]
    rank[rank < 0] = r
    return rank


def _ranks(F: np.ndarray, violation: np.ndarray | None, stop: int | None = None) -> np.ndarray:
    """Constraint-domination ranks without the (N, N) constraint matrix: the feasible rows are sorted by
    Pareto dominance, the infeasible ones follow, one front per distinct violation value (a row with less
    violation dominates one with more). ``stop`` as in :func:`_pareto_ranks`."""
    if violation is None:
        return _pareto_ranks(F, stop)
    cv = np.asarray(violation, float).reshape(-1)
    feas = cv <= 0
    rank = np.zeros(F.shape[0], dtype=int)
    offset = 0
    if feas.any():
        rank[feas] = _pareto_ranks(F[feas], stop)
        offset = rank[feas].max() + 1
    if not feas.all():
        rank[~feas] = offset + np.unique(cv[~feas], return_inverse=True)[1].reshape(-1)
    return rank


def nondominated_ranks(F: np.ndarray, violation: np.ndarray | None = None) -> np.ndarray:
    """Fast non-dominated sorting under constraint domination: front index (N,) of every row, 0 first.

    The feasible rows are sorted by peeling (count each row's dominators, take the rows with none,
    subtract what they dominate, repeat: one vectorized pass per front); the infeasible rows follow, one
    front per distinct violation value in increasing order. This equals sorting by
    :func:`dominance_matrix` (``violation`` given), without building its constraint part.
    """
    return _ranks(np.asarray(F, float), violation)


def crowding_distance(F: np.ndarray) -> np.ndarray:
    """Crowding distance (M,) of the points ``F`` (M, k) of one front; extremes get inf (Deb 2002).

    For each objective the points are sorted and each gets the gap between its two neighbours divided
    by the objective's range; the distances add up over the objectives.
    """
    M, k = F.shape
    if M <= 2:
        return np.full(M, np.inf)
    order = np.argsort(F, axis=0, kind="stable")
    Fs = np.take_along_axis(F, order, axis=0)
    span = Fs[-1] - Fs[0]
    gap = np.where(span > 0, (Fs[2:] - Fs[:-2]) / np.where(span > 0, span, 1.0), 0.0)
    dist_sorted = np.vstack([np.full((1, k), np.inf), gap, np.full((1, k), np.inf)])
    dist = np.zeros((M, k))
    np.put_along_axis(dist, order, dist_sorted, axis=0)
    return dist.sum(axis=1)


def sbx(P1: np.ndarray, P2: np.ndarray, lower: np.ndarray, upper: np.ndarray, eta: float, rng: np.random.Generator,
        crossover_probability: float = 0.9, variable_probability: float = 0.5) -> tuple[np.ndarray, np.ndarray]:
    """Bounded simulated binary crossover (Deb & Agrawal 1995; Deb's NSGA-II code) of parents (M, n).

    Each pair crosses with ``crossover_probability``, each variable with ``variable_probability``; the
    spread factor's distribution is truncated so children stay inside [lower, upper]; children are
    swapped with probability 1/2 per variable.
    """
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
    """Bounded polynomial mutation (Deb & Goyal 1996 as in Deb's NSGA-II code and pymoo) of each entry of ``X``
    (N, n) with ``probability``, drawing from ``rng``; the result is clipped into [lower, upper].

    The spread depends on the distances ``d1 = (x - lower) / (upper - lower)`` and ``d2 = (upper - x) /
    (upper - lower)`` to the bounds: an entry on a bound is never pushed across it. Paper 001's GA uses
    the basic form instead (:func:`~evoik_pin.solvers.paper.ga.basic_polynomial_mutation`), whose spread ignores
    the bounds; the two give different children.
    """
    width = np.where(upper > lower, upper - lower, 1.0)
    mask = rng.random(X.shape) < probability
    u = rng.random(X.shape)
    d1, d2 = (X - lower) / width, (upper - X) / width
    power = 1.0 / (eta + 1.0)
    left = (2.0 * u + (1.0 - 2.0 * u) * (1.0 - d1) ** (eta + 1.0)) ** power - 1.0
    right = 1.0 - (2.0 * (1.0 - u) + 2.0 * (u - 0.5) * (1.0 - d2) ** (eta + 1.0)) ** power
    delta = np.where(u < 0.5, left, right)
    return np.clip(np.where(mask, X + delta * width, X), lower, upper)


def survival(F: np.ndarray, violation: np.ndarray | None, size: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """NSGA-II's elitist survival: indices of the ``size`` survivors, with their ranks and crowding distances.

    Whole fronts are taken in rank order; the front that overflows is cut by crowding distance.
    """
    rank = _ranks(F, violation, stop=size)
    order = np.argsort(rank, kind="stable")
    last = rank[order[min(size, len(order)) - 1]]
    cd = np.zeros(F.shape[0])
    fronts, starts = np.unique(rank[order], return_index=True)
    ends = np.append(starts[1:], len(order))
    for r, a, b in zip(fronts, starts, ends, strict=True):
        if r > last:
            break
        members = order[a:b]
        cd[members] = np.inf if b - a <= 2 else crowding_distance(F[members])
    whole = order[rank[order] < last]
    cut = order[rank[order] == last]
    if cut.size > size - whole.size:
        cut = cut[np.argsort(-cd[cut], kind="stable")[: size - whole.size]]
    keep = np.concatenate([whole, cut])
    return keep, rank[keep], cd[keep]


def _tournament_pairs(size: int, count: int, rng: np.random.Generator) -> np.ndarray:
    """``count`` tournament pairs (count, 2) over ``size`` individuals, read off consecutive random
    permutations as in Deb's reference code: for ``count = size`` (even) every individual enters exactly
    two tournaments and never meets itself."""
    k = -(-2 * count // size)
    perms = np.argsort(rng.random((k, size)), axis=1).reshape(-1)
    return perms[: 2 * count].reshape(count, 2)


def _tournament(rank: np.ndarray, cd: np.ndarray, pairs: np.ndarray, rng: np.random.Generator | None = None
                ) -> np.ndarray:
    """Binary tournaments with Deb's crowded comparison: lower rank wins, then larger crowding distance;
    a full tie (same rank and distance, e.g. two boundary points) is a fair coin toss from ``rng`` (the
    first contestant without one)."""
    a, b = pairs[:, 0], pairs[:, 1]
    b_wins = (rank[b] < rank[a]) | ((rank[b] == rank[a]) & (cd[b] > cd[a]))
    if rng is not None:
        b_wins |= (rank[b] == rank[a]) & (cd[b] == cd[a]) & (rng.random(a.size) < 0.5)
    return np.where(b_wins, b, a)


def _duplicate_rows(X: np.ndarray, Y: np.ndarray) -> np.ndarray:
    """Mask (len(Y),) of the rows of ``Y`` equal (bit for bit, -0.0 = 0.0) to a row of ``X`` or to an
    earlier row of ``Y``; one sort of the rows viewed as byte strings."""
    Z = np.ascontiguousarray(np.concatenate([X, Y]) + 0.0)
    keys = Z.view(np.dtype((np.void, Z.dtype.itemsize * Z.shape[1]))).reshape(-1)
    first = np.unique(keys, return_index=True)[1]  # first occurrences (numpy sorts stably for return_index)
    unique = np.zeros(Z.shape[0], bool)
    unique[first] = True
    return ~unique[X.shape[0]:]


# ---------------------------------------------------------------------------------------------- generic loop
@dataclass
class NSGA2Result:
    """Outcome of :func:`nsga2_minimize`.

    Attributes: final population ``X`` (N, n), objectives ``F`` (N, k), ``violation`` (N,), ``rank`` (N,)
    (0 = first front); ``generations``, ``evaluations``, ``time_s``; ``history`` per generation (index 0 =
    initial population): ``front_size``, ``feasible_fraction``, ``min_violation``.
    """

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
    """Minimize ``n_obj`` objectives over the box [lower, upper] with NSGA-II (Deb et al. 2002).

    Each generation: binary tournaments with the crowded comparison (rank, then crowding distance, then a
    coin), the contestants read off two random permutations of the population as in Deb's reference
    code; SBX on consecutive winners; polynomial mutation; then the N offspring join the N parents and
    :func:`survival` keeps N (constraint domination, fronts in order, the last one cut by crowding).
    With ``eliminate_duplicates`` (as pymoo does), an offspring equal to a parent or to another offspring
    (mostly parents copied when neither crossover nor mutation changed them) is bred again, for at most
    10 rounds, before anything is evaluated: each generation still costs exactly N evaluations, and
    (unless 10 rounds do not suffice, when the last copies are kept) none is spent on a known point.

    Args:
        f: vectorized ``f(X)`` for a population X (N, n): objectives (N, n_obj), or a pair
            ``(objectives, violation)`` with violation (N,) >= 0 (0 = feasible) for constrained problems.
        lower, upper: (n,) finite bounds.
        n_obj: number of objectives.
        rng: the only source of randomness.
        population: N (even numbers pair up exactly). generations: offspring generations.
        eta_c, eta_m: distribution indices of SBX and polynomial mutation (15, 20: pymoo's defaults).
        crossover_probability: per pair (0.9). mutation_probability: per variable (default 1/n).
        initial: optional (N0, n) points for the first population (the rest uniform in the box).
        repair: optional ``repair(X) -> X`` applied to every new point before evaluation (and to the
            initial population), e.g. projecting onto an equality constraint.
        callback: optional ``callback(generation, X, F, violation)`` with the survivors of every generation
            (generation 0: the initial population).
        eliminate_duplicates: breed again the offspring that duplicate a population member or each other
            (checked before ``repair``; True).

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

    def log():
        history["front_size"].append(float(np.sum(rank == 0)))
        history["feasible_fraction"].append(float(np.mean(cv <= 0)))
        history["min_violation"].append(float(cv.min()))

    log()
    if callback is not None:
        callback(0, X, F, cv)

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
        log()
        if callback is not None:
            callback(g + 1, X, F, cv)
    return NSGA2Result(X=X, F=F, violation=cv, rank=rank, generations=generations, evaluations=evaluations,
                       time_s=time.perf_counter() - t0, history={k: np.asarray(v) for k, v in history.items()})


# ---------------------------------------------------------------------------------------------- IK method
def _task_rows(problem: IKProblem) -> list[int]:
    """Jacobian rows of the task: planar (vx, vy[, wz]); 3-D (vx, vy, vz[, wx, wy, wz])."""
    t = problem.target
    if t.planar:
        return [0, 1, 5] if t.yaw is not None else [0, 1]
    return [0, 1, 2, 3, 4, 5] if t.rotation is not None else [0, 1, 2]


def _movable_rows(problem: IKProblem, rows: list[int]) -> tuple[list[int], list[int]]:
    """Split Jacobian ``rows`` into those the chain can move its tip along and those it never can (a row of
    zeros at 64 configurations spread over the box, e.g. vz for a planar chain): a zero row makes
    ``det(J J^T)`` 0 for every configuration, so the manipulability objective would be constant."""
    Q = problem.lower + halton(problem.n, 64, skip=1) * (problem.upper - problem.lower)
    J = problem.robot.jacobian_batch(Q, validate=False)[:, rows]
    moving = np.abs(J).max(axis=(0, 2)) > 1e-12
    return [r for r, m in zip(rows, moving, strict=True) if m], [r for r, m in zip(rows, moving, strict=True) if not m]


def _task_errors(problem: IKProblem, Q: np.ndarray) -> np.ndarray:
    """Task-space error vectors (N, m) target - current, in the rows of :func:`_task_rows` (m, rad)."""
    t = problem.target
    p, R = problem.robot.fk_batch(Q)
    if t.planar:
        e = [t.position[0] - p[:, 0], t.position[1] - p[:, 1]]
        if t.yaw is not None:
            e.append(lie.wrap_angle(t.yaw - lie.yaw(R)))
        return np.stack(e, axis=1)
    e = t.position - p
    if t.rotation is None:
        return e
    # Rotation error: the world-frame rotation vector of R_target R^T.
    return np.concatenate([e, lie.log3(np.einsum("ij,nkj->nik", t.rotation, R))], axis=1)


def dls_repair(problem: IKProblem, Q: np.ndarray, steps: int, damping: float = 1e-4,
               weights: np.ndarray | None = None, task=None) -> np.ndarray:
    """``steps`` damped-least-squares Newton steps (N, n) towards the target, all individuals at once.

    ``dq = W J^T (J W J^T + damping^2 I)^-1 e`` on the task rows of the base-frame Jacobian, then clipped
    into the box: the step of least ``dq^T W^-1 dq``. ``weights`` W (n,) default ones; ``nsga2`` passes
    1 / K so the repair, like the smoothness S, moves high-gain joints (the vehicle) least. Each step
    costs one batched FK and Jacobian and counts N evaluations. ``task(Q) -> (e (N, m), J (N, m, n))``: the
    errors and Jacobian rows the steps zero (default the target's task rows; :func:`goal_task` for a goal list).
    """
    if task is None:
        rows = _task_rows(problem)

        def task(Q):
            return _task_errors(problem, Q), problem.robot.jacobian_batch(Q)[:, rows]

    W = np.ones(problem.n) if weights is None else np.asarray(weights, float)
    lam2 = None
    for _ in range(steps):
        e, J = task(Q)
        problem.evaluations += Q.shape[0]
        if lam2 is None:
            lam2 = damping ** 2 * np.eye(J.shape[1])
        JW = J * W
        y = np.linalg.solve(JW @ J.transpose(0, 2, 1) + lam2, e[:, :, None])[..., 0]
        Q = np.clip(Q + np.einsum("nji,nj->ni", JW, y), problem.lower, problem.upper)
    return Q


# ---------------------------------------------------------------------------------------------- goal lists
def goal_rows(goal) -> list[int]:
    """Rows (of the frame's base-frame Jacobian: vx, vy, vz, wx, wy, wz) a goal constrains, as its manipulability
    reads them: the translation rows, and the rotation rows too for a goal that constrains orientation (a Pose)."""
    return [0, 1, 2, 3, 4, 5] if goal.has_orientation else [0, 1, 2]


class GoalManipulability(Objective):
    """Paper 003's manipulability cost over several goal frames (a goal list): Y is the product of the singular
    values of the stacked Jacobian rows ``rows[i]`` of ``frames[i]`` (base frame, (sum of rows, n)), that is
    ``sqrt(det(J J^T))`` while there are at most as many rows as joints (the tip's :class:`ManipulabilityCost` for one
    frame) and ``sqrt(det(J^T J))`` otherwise. ``form`` as :class:`ManipulabilityCost`'s: ``"inverse"`` 1 / (Y + 1)
    (minimized), ``"negative"`` -Y, ``"value"`` Y. Y has the units of the rows' product (m per rad for translation
    rows, 1 for rotation rows)."""

    def __init__(self, frames, rows, form: str = "inverse") -> None:
        self._form = ManipulabilityCost("translation", form).form  # the form's check
        self.frames, self.rows = list(frames), [list(r) for r in rows]

    def value(self, Q, kin):
        robot = kin.robot
        J = np.concatenate([robot.jacobian_batch(Q, validate=False, frame=f)[:, r]
                            for f, r in zip(self.frames, self.rows, strict=True)], axis=1)
        M = J @ J.transpose(0, 2, 1) if J.shape[1] <= J.shape[2] else J.transpose(0, 2, 1) @ J
        Y = np.sqrt(np.maximum(np.linalg.det(M), 0.0))
        if self._form == "inverse":
            return 1.0 / (Y + 1.0)
        return -Y if self._form == "negative" else Y

    def __repr__(self) -> str:
        return f"GoalManipulability(frames={self.frames!r}, rows={self.rows!r}, form={self._form!r})"


def _chosen_goals(problem: IKProblem, which) -> list[int]:
    """Indices of the goals whose rows the manipulability reads: every goal (``which`` None), or ``which``: goal
    indices or frame names of the goal list; OptionError otherwise."""
    goals = problem.goals
    if which is None:
        return list(range(len(goals)))
    frames = [g.frame for g in goals]
    picked: list[int] = []
    try:
        listed = [which] if isinstance(which, (str, int, np.integer)) else list(which)
    except TypeError:
        listed = [which]  # refused below, by name
    for w in listed:
        if isinstance(w, str) and w in frames:
            picked.append(frames.index(w))
        elif isinstance(w, (int, np.integer)) and not isinstance(w, bool) and -len(goals) <= w < len(goals):
            picked.append(int(w) % len(goals))
        else:
            raise OptionError(f"manipulability_goals names the goals whose Jacobian rows the manipulability reads: "
                              f"goal indices 0..{len(goals) - 1} or the goals' frames {frames}; got {w!r}")
    if not picked or len(set(picked)) != len(picked):
        raise OptionError(f"manipulability_goals must name distinct goals (indices or frames of {frames}), got "
                          f"{which!r}")
    return picked


def _goal_manipulability(problem: IKProblem, which) -> tuple[GoalManipulability, list[str]]:
    """The default manipulability objective of a goal list (the goals ``which`` picks, :func:`_chosen_goals`) less
    the rows its frames never move (zero at 64 configurations spread over the box: they would make Y 0 everywhere,
    as :func:`_movable_rows` for one target); and the names of the rows left out, for the message."""
    goals = problem.goals
    Q = problem.lower + halton(problem.n, 64, skip=1) * (problem.upper - problem.lower)
    frames, rows, fixed = [], [], []
    for i in _chosen_goals(problem, which):
        J = problem.robot.jacobian_batch(Q, validate=False, frame=goals[i].frame)
        moving = [r for r in goal_rows(goals[i]) if np.abs(J[:, r]).max() > 1e-12]
        fixed += [f"{goals[i].frame}:{('vx', 'vy', 'vz', 'wx', 'wy', 'wz')[r]}"
                  for r in goal_rows(goals[i]) if r not in moving]
        if moving:
            frames.append(goals[i].frame)
            rows.append(moving)
    if not frames:
        raise OptionError("no goal frame of the goal list moves along any of its rows; give objectives=[...]")
    return GoalManipulability(frames, rows), fixed


def goal_task(problem: IKProblem, Q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The task error ``e`` (N, rows) and Jacobian ``J`` (N, rows, n) of a goal list at ``Q`` (N, n), for
    :func:`dls_repair`: the LM kernel's own rows of every goal kind (:meth:`~evoik_pin.problem.IKProblem.goal_rows`:
    pose, position, bands and free axes, orientation, direction, look-at, centre of mass, support polygon, relative
    pose; each goal's rows scaled by the square root of its weight, zero inside dead-zone bands; a goal set's those
    of the member each configuration is nearest to) with the sign :func:`dls_repair` reads, target minus current:
    ``e = -(f(q) - target)``, ``J = d(f(q) - target)/dq``."""
    e, E = problem.goal_rows(Q)
    return -e, E


@register("nsga2", "paper 003: NSGA-II with constraint domination; Pareto front of manipulability and "
          "weighted joint displacement under the pose constraint (every goal of a goal list)", multi_objective=True)
def nsga2(problem: IKProblem, rng: np.random.Generator, *, population: int = 200, max_generations: int = 100,
          gains=None, manipulability_rows=None, manipulability_goals=None, objectives: list[Objective] | None = None,
          pick: int = -1, repair_steps: int = 3, eta_c: float = 15.0, eta_m: float = 20.0,
          crossover_probability: float = 0.9, mutation_probability: float | None = None) -> Result:
    """Paper 003's NSGA-II IK (section 3): a Pareto front under the constraint ``f(q) = x_d``.

    A goal list (:mod:`evoik_pin.goals`, several frames) is the same problem with ``f(q) = x_d`` for every goal:
    the constraint's violation is the sum over the goals of each one's error beyond its own tolerances
    (:meth:`~evoik_pin.problem.IKProblem.goal_violation`), so a feasible point meets every goal; the objectives stay
    the paper's two, manipulability and smoothness, the manipulability Y taken over the stacked Jacobian rows of
    every goal frame (:class:`GoalManipulability`: the translation rows of each goal, the rotation rows of a Pose
    too; ``manipulability_goals`` picks fewer goals), and the repair steps zero every goal's rows at once
    (:func:`goal_task`: the LM kernel's rows of every goal kind, each goal's rows scaled by the square root of its
    weight; a goal set's those of the member each individual is nearest to).

    Options:
        population: 200 (paper). max_generations: offspring generations (100), always all run.
        gains: K (n,) of the smoothness ``S = sqrt(sum K_i (q_i - q_prev,i)^2)`` (default ones); q_prev is
            ``problem.q0`` (``solve_trajectory`` passes the previous solution), zeros when none.
        manipulability_rows: Jacobian rows of ``Y = sqrt(det(J J^T))`` (default the task's rows:
            "planar" (vx, vy, wz) for planar yaw targets, translation for 3-D positions, all six for poses,
            less the rows along which the chain can never move its tip, such as vz for a planar arm given a
            3-D target: those would make ``Y`` 0 everywhere; the message names them). One target only.
        manipulability_goals: a goal list: the goals (indices into the list, or their frames) whose rows the
            manipulability reads (default every goal), less the rows their frames never move.
        objectives: replace the default ``[ManipulabilityCost(rows, "inverse"), WeightedJointDisplacement]``
            with any list of :class:`~evoik_pin.objectives.Objective` (all minimized).
        pick: objective index minimized when choosing ``q`` from the front (-1: the last, S).
            (Custom objectives of a goal list receive the kinematics of the robot's tip: terms of ``q`` alone,
            such as :class:`~evoik_pin.objectives.WeightedJointDisplacement`, or :class:`GoalManipulability`.)
        repair_steps: damped-least-squares steps towards the target applied to every new individual
            (3; the initial population gets four times as many, as the paper starts from a feasible
            population), weighted by 1 / K so they too spare the high-gain joints. 0 runs the plain
            algorithm, whose random individuals almost never meet a tight
            equality tolerance: then loosen ``tolerance``.
        eta_c, eta_m, crossover_probability, mutation_probability: SBX / polynomial mutation (15, 20, 0.9,
            1/n).

    Returns:
        :class:`Result` whose ``front`` holds the first front (q (M, n), objectives (M, k), violation (M,)
        with violation = position error above ``tolerance`` (m) + orientation error above
        ``rotation_tolerance`` (rad)), sorted by the first objective, and whose ``q`` is its member with the
        least objective ``pick`` among the feasible ones (the least violation when none is feasible).
        History per generation: ``best_cost`` (least objective ``pick`` among feasible survivors, NaN when
        none), ``mean_cost`` (its mean), ``diversity``, ``front_size``, ``feasible_fraction``,
        ``min_violation``.
    """
    robot = problem.robot
    repair_steps = check_int("repair_steps", repair_steps, 0)
    q_prev = np.zeros(problem.n) if problem.q0 is None else problem.q0
    goals = problem.goals is not None
    repair_weights = None
    fixed_rows: list[int] = []
    fixed_goal_rows: list[str] = []
    if goals and manipulability_rows is not None:
        raise OptionError("manipulability_rows selects rows of the tip's Jacobian for one target; for a goal list "
                          "give manipulability_goals=[...] (goal indices or frames: their rows count)")
    if not goals and manipulability_goals is not None:
        raise OptionError("manipulability_goals picks goals of a goal list; for one target give "
                          "manipulability_rows=[...]")
    if objectives is None:
        if gains is not None:
            gains = check_nonnegative_vector("gains", gains, problem.n)
            repair_weights = 1.0 / np.maximum(gains, 1e-12)
        if goals:
            manipulability, fixed_goal_rows = _goal_manipulability(problem, manipulability_goals)
        else:
            if manipulability_rows is None:
                rows, fixed_rows = _movable_rows(problem, _task_rows(problem))
                if not rows:
                    raise OptionError("the chain cannot move its tip along any row of the task; give "
                                      "manipulability_rows=[...] or objectives=[...]")
            else:
                rows = manipulability_rows
            robot.task_rows(rows)  # validates names and indices with a clear error
            manipulability = ManipulabilityCost(rows, "inverse")
        objectives = [manipulability, WeightedJointDisplacement(q_prev, gains)]
    elif gains is not None or manipulability_rows is not None or manipulability_goals is not None:
        raise OptionError("gains, manipulability_rows and manipulability_goals shape the default objectives; with "
                          "objectives=[...] put them into your own objective terms")
    objectives = list(objectives)
    if not objectives or not all(isinstance(o, Objective) for o in objectives):
        raise OptionError("objectives must be a non-empty list of evoik_pin.objectives.Objective terms")
    k = len(objectives)
    pick = check_int("pick (objective index)", pick, -k, k - 1)
    target = problem.target
    run = SolverRun(problem, max_generations)

    def f(Q):
        kin = PopulationKinematics(robot, Q)
        F = np.column_stack([obj(Q, kin) for obj in objectives])
        if goals:  # every goal within its own tolerances (counts the evaluations)
            return F, problem.goal_violation(Q)
        problem.evaluations += Q.shape[0]
        cv = np.maximum(position_errors(target, kin) - problem.tolerance, 0.0)
        if target.has_orientation:
            cv = cv + np.maximum(orientation_errors(target, kin) - problem.rotation_tolerance, 0.0)
        return F, cv

    def repair(Y, steps):
        return dls_repair(problem, Y, steps, weights=repair_weights,
                          task=(lambda Q: goal_task(problem, Q)) if goals else None)

    init = initial_population(problem, rng, population)
    best_pick: list[float] = []

    def callback(g, X, F, cv):
        ok = cv <= 0
        best_pick.append(float(F[ok, pick].min()) if ok.any() else np.nan)
        run.history["mean_cost"].append(float(np.mean(F[:, pick])))
        run.history["diversity"].append(diversity(X, problem.lower, problem.upper))

    first_repair = None if repair_steps == 0 else 4 * repair_steps
    out = nsga2_minimize(
        f, problem.lower, problem.upper, k, rng, population=population, generations=max_generations, eta_c=eta_c,
        eta_m=eta_m, crossover_probability=crossover_probability, mutation_probability=mutation_probability,
        initial=init if first_repair is None else repair(init, first_repair),
        repair=None if repair_steps == 0 else (lambda Y: repair(Y, repair_steps)),
        callback=callback)
    run.generation = out.generations
    front = out.front
    order = front[np.argsort(out.F[front, 0], kind="stable")]
    feasible = order[out.violation[order] <= 0]
    chosen = (feasible[np.argmin(out.F[feasible, pick])] if feasible.size
              else order[np.argmin(out.violation[order])])
    run.best_q = out.X[chosen].copy()
    run.history["best_cost"] = best_pick
    run.history.update({key: list(v) for key, v in out.history.items()})
    if feasible.size:
        message = f"{max_generations} generations; {len(order)} point(s) on the front, all feasible"
    else:
        message = (f"{max_generations} generations; no individual meets "
                   + ("every goal" if goals else "the pose constraint"))
    if fixed_rows:
        names = ", ".join(("vx", "vy", "vz", "wx", "wy", "wz")[r] for r in fixed_rows)
        message += f"; manipulability on Jacobian rows {rows}: the chain never moves its tip along {names}"
    if fixed_goal_rows:
        message += f"; manipulability without the rows no joint moves ({', '.join(fixed_goal_rows)})"
    result = run.result("nsga2", message,
                        front=Front(q=out.X[order], objectives=out.F[order], violation=out.violation[order]))
    return result
