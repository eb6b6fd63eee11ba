"""Memetic IK: Levenberg-Marquardt from good starting points, differential evolution when they fail.

Registered as ``memetic``, the default method of :func:`evoik_pin.solve`. It pairs a global search that
proposes starting configurations with a local Newton-type search that takes them to machine precision
(:class:`~evoik_pin.solvers.polish.LevenbergMarquardt`, on the SE(3) error ``log6(T_t^-1 T(q))`` for pose
targets, the position for position targets, (x, y[, yaw]) for planar ones, within the joint limits; each
run of a pose or position target is one call of a numba-compiled function, :mod:`.lm_kernel`, about 1-2 us
per step). Stages, each tried only when the previous ones have not met the tolerances:

1. **Warm start**: LM from ``q0`` when it is given (a previous solution usually converges in a few steps),
   first when its tip pose is within the table's typical spacing of the target or nearer than the table's
   nearest entry; a farther ``q0`` (a random guess) goes right after that entry.
2. **Seed table**: LM from the configurations whose tip poses are nearest to the target in a table of
   ``table_size`` configurations spread over the search box (a deterministic Halton sequence, so no random
   numbers are drawn; its forward kinematics is computed once per robot and box and cached). Nearness is
   ``|p - p_t|^2 + w^2 |R - R_t|_F^2`` with ``w`` a quarter of the arm's reach (m per unit of the
   Frobenius distance, which is ``2 sqrt(2) sin(angle / 2)``). The nearest entry is polished alone (it
   converges for most targets); then the next ones, one LM run after the other (``batch=k`` runs them k at
   a time in lockstep instead, :meth:`~evoik_pin.solvers.polish.LevenbergMarquardt.run_many`: measured
   slower, as a lockstep iteration carries ~0.1 ms of fixed NumPy cost and a group runs until its slowest
   useful member; docs/BENCHMARKS.md). One-time costs do not count against the budget: the table's
   construction, and loading (or, once after an install, compiling) the compiled LM kernel.
3. **Memetic restarts** until the tolerances, the time budget ``timeout`` or ``max_restarts`` are reached:
   a population of ``population`` configurations (uniform in the box, drawn from ``rng``, plus ``q0`` and
   the best configuration met so far) evolves for ``generations`` generations of differential evolution
   (DE/current-to-best/1/bin from :mod:`.de_ops`, dithered F in [0.5, 1], CR = 0.9, greedy selection on
   the problem's objective), and its ``polish_count`` best members are polished by LM, best first.

Determinism: every random draw comes from ``rng``, and stages 1-2 draw none. The time budget is checked
between LM runs and generations, so two runs with the same seed give identical results whenever the
budget is not what stops them (every reachable target in practice); ``timeout=None`` with
``max_restarts=k`` gives a fully deterministic budget.
"""

from __future__ import annotations

import itertools
import time
import weakref

import numpy as np
import pinocchio as pin

from ..errors import OptionError
from ..objectives import (
    OrientationError,
    PopulationKinematics,
    PoseDistance,
    PositionError,
    WeightedSum,
    orientation_errors,
    position_errors,
)
from ..problem import IKProblem, Target
from ..result import Result
from . import register
from .common import check_positive, check_positive_int, diversity
from .de_ops import binomial_crossover, distinct_indices, mutate
from .polish import DEFAULT_ITERATIONS, LevenbergMarquardt, LMOutcome, compiled_kernel, wrapping_joints

__all__ = ["DEFAULT_TIMEOUT", "SeedTable", "memetic", "polish_result", "seed_table"]

#: Default time budget (s): TRAC-IK's default.
DEFAULT_TIMEOUT = 0.005
#: Steps allowed when polishing another solver's answer (already close: it converges or stalls quickly).
POLISH_ITERATIONS = 100


# ---------------------------------------------------------------------- seed table
class SeedTable:
    """Configurations spread over a search box and their tip poses, searchable by nearness to a target.

    Attributes:
        Q: (size, n) configurations (a Halton sequence mapped onto the box; deterministic).
        positions: (size, 3) tip positions (m); rotations: (size, 3, 3).
        weight: m per unit of rotation-matrix (Frobenius) distance in the pose metric.
    """

    def __init__(self, robot, lower: np.ndarray, upper: np.ndarray, size: int) -> None:
        # Halton point 0 is the box's lower corner (often a singular, limit-bound pose): skip it.
        from scipy.stats import qmc  # lazy: scipy.stats costs ~0.4 s to import, paid on first table only

        u = qmc.Halton(robot.n, scramble=False).random(size + 1)[1:]
        self.Q = lower + u * (upper - lower)
        self.positions, self.rotations = robot.fk_batch(self.Q, validate=False)
        reach = float(np.sqrt((self.positions**2).sum(axis=1)).max()) if size else 1.0
        self.weight = 0.25 * max(reach, 1e-3)
        self._features: dict[str, tuple[np.ndarray, np.ndarray]] = {}
        self._trees: dict = {}  # feature key -> scipy.spatial.cKDTree
        self._gaps: dict[str, float] = {}  # feature key -> typical_gap_sq

    def _pose_features(self, key: str, P: np.ndarray, R: np.ndarray) -> np.ndarray:
        """Features (N, d) of tip poses (positions P (N, 3) m, rotations R (N, 3, 3)) for one target kind."""
        if key == "pose":
            return np.concatenate([P, self.weight * R.reshape(-1, 9)], axis=1)
        if key == "position":
            return P
        if key == "planar":
            return P[:, :2]
        return np.concatenate([P[:, :2], self.weight * R[:, :2, 0]], axis=1)  # heading, scaled like rotations

    def _table_features(self, key: str) -> tuple[np.ndarray, np.ndarray]:
        """(features (size, d), squared norms (size,)) of the table for one target kind, built once."""
        if key not in self._features:
            F = np.array(self._pose_features(key, self.positions, self.rotations), order="C")  # a copy
            self._features[key] = (F, (F * F).sum(axis=1))
        return self._features[key]

    def target_features(self, targets: list[Target]) -> tuple[str, np.ndarray]:
        """(kind key, features (N, d)) of targets that are all of one kind."""
        t0 = targets[0]
        if t0.planar:
            xy = np.array([t.position for t in targets])
            if t0.yaw is None:
                return "planar", xy
            yaw = np.array([t.yaw for t in targets])
            return "planar_yaw", np.concatenate([xy, self.weight * np.stack([np.cos(yaw), np.sin(yaw)], 1)], 1)
        P = np.array([t.position for t in targets])
        if t0.rotation is None:
            return "position", P
        R = np.array([t.rotation for t in targets])
        return "pose", np.concatenate([P, self.weight * R.reshape(-1, 9)], axis=1)

    def ranked(self, target: Target, k: int):
        """Indices of the (up to) k table entries nearest to one target, nearest first, lazily: the nearest
        costs one matrix-vector product and an argmin; the others are ranked only if asked for."""
        if k <= 0:
            return
        key, f = self.target_features([target])
        F, sq = self._table_features(key)
        d = sq - 2.0 * (F @ f[0])
        first = int(d.argmin())
        yield first
        k = min(k, d.shape[0])
        if k > 1:
            part = np.argpartition(d, k - 1)[:k]
            for i in part[d[part].argsort()]:
                if i != first:
                    yield int(i)

    def distance_sq(self, target: Target, T: pin.SE3) -> float:
        """Squared nearness metric between a target and a tip pose ``T`` (the one :meth:`ranked` sorts by)."""
        key, f = self.target_features([target])
        d = f[0] - self._pose_features(key, T.translation[None], T.rotation[None])[0]
        return float(d.dot(d))

    def typical_gap_sq(self, target: Target) -> float:
        """Median squared distance (in the metric of ``target``'s kind) from a table entry to its nearest
        other entry, over 64 sampled entries, cached: a start nearer the target than this is as good a guess
        as the table's nearest entry usually is."""
        key = self.target_features([target])[0]
        gap = self._gaps.get(key)
        if gap is None:
            F, sq = self._table_features(key)
            sample = np.linspace(0, F.shape[0] - 1, min(64, F.shape[0])).astype(int)
            D = sq[sample, None] + sq[None, :] - 2.0 * F[sample] @ F.T
            D[np.arange(sample.size), sample] = np.inf
            gap = self._gaps[key] = float(np.median(D.min(axis=1)))
        return gap

    def nearest(self, targets: list[Target], k: int) -> np.ndarray:
        """Indices (N, k) of the k table entries nearest to each target, nearest first.

        Many targets at once go through a k-d tree of the table's features (built once per target kind):
        O(N log size), against O(N size) for the distance matrix that :meth:`ranked` uses for one target.
        """
        key, f = self.target_features(targets)
        tree = self._trees.get(key)
        if tree is None:
            from scipy.spatial import cKDTree

            tree = self._trees[key] = cKDTree(self._table_features(key)[0])
        k = min(k, tree.n)
        _, idx = tree.query(f, k=k)
        return np.asarray(idx, dtype=np.intp).reshape(len(targets), k)


_TABLES: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()
_TABLES_PER_ROBOT = 4


def default_table_size(n: int) -> int:
    """Seed-table size for an n-joint chain: 2^(n+5), clamped to [256, 4096] (about 1-5 ms to build)."""
    return int(min(4096, max(256, 2 ** (n + 5))))


def seed_table(robot, lower: np.ndarray, upper: np.ndarray, size: int) -> SeedTable:
    """The cached :class:`SeedTable` of ``robot`` over the box [lower, upper] (built on first use).

    A few boxes are kept per robot (the most recent ones), so a trajectory solved in narrow moving boxes
    does not grow the cache.
    """
    per_robot = _TABLES.setdefault(robot, {})
    key = (lower.tobytes(), upper.tobytes(), int(size))
    table = per_robot.get(key)
    if table is None:
        table = SeedTable(robot, lower, upper, size)
        if len(per_robot) >= _TABLES_PER_ROBOT:
            per_robot.pop(next(iter(per_robot)))
        per_robot[key] = table
    return table


# ---------------------------------------------------------------------- option checks
def _check_timeout(timeout) -> float | None:
    return None if timeout is None else check_positive("timeout (s; or None)", timeout)


def _check_restarts(max_restarts) -> int | None:
    if max_restarts is None:
        return None
    return check_positive_int("max_restarts", max_restarts, 0)


# ---------------------------------------------------------------------- results
def _final_errors(problem: IKProblem, q: np.ndarray, known: LMOutcome | None = None
                  ) -> tuple[float, float | None, float]:
    """(position error m, orientation error rad or None, objective cost) of ``q``.

    ``known``: an LM outcome at this very ``q``, whose errors (computed from one Pinocchio FK as the norms of
    the task error's parts, equal to ``IKProblem.evaluate``'s up to rounding) are reused. The cost is
    ``position + w * orientation`` when the objective is the default one; any other objective is evaluated
    on a kinematics object filled from the single-configuration FK, so no batch pass is run.
    """
    target = problem.target
    if known is not None:
        pos, rot = known.position_error, known.orientation_error
        cost = _default_cost(problem, pos, rot)
        if cost is not None:
            return pos, rot, cost
    T = problem.robot.fk_unchecked(q)
    Q = q[None]
    kin = PopulationKinematics.from_poses(problem.robot, Q, np.array(T.translation)[None], np.array(T.rotation)[None])
    if known is None:
        pos = float(position_errors(target, kin)[0])
        rot = float(orientation_errors(target, kin)[0]) if target.has_orientation else None
    return pos, rot, float(problem.objective(Q, kin)[0])


def _default_cost(problem: IKProblem, pos: float, rot: float | None) -> float | None:
    """The objective value from the errors when the objective is the default one (else None).

    Recognized structurally: ``PositionError(target)`` alone, or ``1 * PositionError(target) +
    w * OrientationError(target)`` or ``PoseDistance(target, w)`` for the problem's own target (what
    ``default_objective`` builds).
    """
    obj, target = problem.objective, problem.target
    if isinstance(obj, PositionError):
        return pos if obj.target is target else None
    if isinstance(obj, PoseDistance):
        return float(np.hypot(pos, obj.orientation_weight * rot)) if obj.target is target and rot is not None else None
    if not isinstance(obj, WeightedSum) or rot is None or len(obj.terms) != 2:
        return None
    (w1, t1), (w2, t2) = obj.terms
    if (isinstance(t1, PositionError) and isinstance(t2, OrientationError) and w1 == 1.0
            and t1.target is target and t2.target is target):
        return pos + w2 * rot
    return None


def _errors_text(pos: float, rot: float | None) -> str:
    return f"position error {pos:.3g} m" + ("" if rot is None else f", orientation error {rot:.3g} rad")


# ---------------------------------------------------------------------- the solver
class _Search:
    """State of one memetic solve: the LM engine, the best configuration met, counters and the clock."""

    def __init__(self, problem: IKProblem, t0: float, deadline: float | None, iterations: int,
                 batch: int = 1, engine: str = "compiled") -> None:
        self.problem = problem
        self.batch = batch
        self.lm = LevenbergMarquardt(problem, engine=engine)
        self.t0 = t0
        self.deadline = deadline
        self.iterations = iterations
        self.best: LMOutcome | None = None
        self.evaluations = 0
        self.attempts = 0
        self.attempt_errors: list[float] = []

    def out_of_time(self) -> bool:
        return self.deadline is not None and time.perf_counter() >= self.deadline

    def _keep(self, out: LMOutcome, runs: int) -> bool:
        self.evaluations += out.evaluations
        self.attempts += runs
        self.attempt_errors.append(out.error)
        if self.best is None or out.converged or out.error < self.best.error:
            self.best = out
        return out.converged

    def polish(self, q: np.ndarray, iterations: int | None = None) -> bool:
        """One LM run from ``q`` (n,); keeps the best outcome; True when it meets the tolerances."""
        return self._keep(self.lm.run(q, iterations or self.iterations, self.deadline), 1)

    def polish_many(self, Q: np.ndarray) -> bool:
        """LM runs from the rows of ``Q`` (K, n), in order, ``batch`` at a time (in lockstep when > 1, see
        ``LevenbergMarquardt.run_many``), until one meets the tolerances or the time is up."""
        for s in range(0, Q.shape[0], self.batch):
            if s and self.out_of_time():
                return False
            chunk = Q[s:s + self.batch]
            if chunk.shape[0] == 1:
                solved = self.polish(chunk[0])
            else:
                solved = self._keep(self.lm.run_many(chunk, self.iterations, self.deadline)[0], chunk.shape[0])
            if solved:
                return True
        return False


@register("memetic", "Memetic IK: Levenberg-Marquardt on the SE(3) error from q0 and a seed table, then DE "
          "populations polished by LM until the tolerance or the time budget (default 5 ms)")
def memetic(
    problem: IKProblem,
    rng: np.random.Generator,
    *,
    timeout: float | None = DEFAULT_TIMEOUT,
    max_restarts: int | None = None,
    population: int = 32,
    generations: int = 3,
    polish_count: int = 8,
    table_size: int | None = None,
    table_seeds: int = 17,
    table_offset: int = 0,
    batch: int = 1,
    iterations: int = DEFAULT_ITERATIONS,
    engine: str = "compiled",
) -> Result:
    """Solve ``problem`` with LM from q0 and the seed table, then DE populations polished by LM.

    Args:
        problem: the IK problem; its tolerances (``tolerance`` m, ``rotation_tolerance`` rad; default 1e-6,
            reachable down to about 1e-12) decide success.
        rng: source of every random draw (stage 3 only).
        timeout: wall-clock budget in s (default 0.005, TRAC-IK's default), checked between LM runs and
            generations; None for no time limit (then ``max_restarts`` bounds the work).
        max_restarts: number of DE populations (stage 3) at most; None for no limit (then ``timeout``
            bounds the work); 0 runs stages 1-2 only.
        population: DE population size (>= 4). generations: DE generations per population (>= 0).
        polish_count: members of each population polished by LM, best first (1..population).
        table_size: seed-table size (0 disables stage 2); default 2^(n+5) clamped to [256, 4096].
        table_seeds: table entries tried in stage 2, nearest first: the nearest alone (it usually converges),
            the next ones one by one (``batch`` at a time).
        table_offset: skip the nearest ``table_offset`` entries (already tried, e.g. by ``solve_many``).
        batch: LM runs polished together in lockstep (stages 2 and 3; >= 1); 1 (default): one after the
            other, stopping at the first that meets the tolerances.
        iterations: LM steps allowed per run (>= 1).
        engine: ``"compiled"`` (default): each LM run is one call of the numba kernel
            (:mod:`.lm_kernel`, about 1-2 us per step); ``"python"``: the same iteration as a Python loop
            over Pinocchio's kinematics (about 30 us per step). Planar targets always use the Python loop.

    Returns:
        A :class:`Result`. ``generations`` counts DE generations; ``evaluations`` counts forward-kinematics
        evaluations (LM steps and DE individuals; the cached seed table is not counted); ``history`` holds
        ``best_cost`` / ``mean_cost`` / ``diversity`` with one entry for stages 1-2 and one per DE
        generation, and ``attempt_error`` (m + rad) after each LM run (or lockstep group). An unreachable
        target gives the best approximation met, ``success=False`` and a message.
    """
    t0 = time.perf_counter()
    timeout = _check_timeout(timeout)
    max_restarts = _check_restarts(max_restarts)
    if timeout is None and max_restarts is None:
        raise OptionError("memetic needs a finite budget: give timeout (s) or max_restarts (or both)")
    population = check_positive_int("population", population, 4)
    generations = check_positive_int("generations", generations, 0)
    polish_count = check_positive_int("polish_count", polish_count, 1)
    if polish_count > population:
        raise OptionError(f"polish_count ({polish_count}) cannot exceed population ({population})")
    robot = problem.robot
    table_size = default_table_size(robot.n) if table_size is None else check_positive_int("table_size",
                                                                                           table_size, 0)
    table_seeds = check_positive_int("table_seeds", table_seeds, 0)
    table_offset = check_positive_int("table_offset", table_offset, 0)
    batch = check_positive_int("batch", batch, 1)
    iterations = check_positive_int("iterations", iterations, 1)

    t_setup = time.perf_counter()
    if engine == "compiled" and not problem.target.planar:
        compiled_kernel()  # one-time: numba's import and the kernel's load (or compilation), outside the budget
    setup = time.perf_counter() - t_setup
    search = _Search(problem, t0, None if timeout is None else t0 + setup + timeout, iterations, batch, engine)
    history: dict[str, list[float]] = {"best_cost": [], "mean_cost": [], "diversity": []}
    stage = ""
    n_gen = 0
    restarts = 0
    solved = False
    # Stages 1-2: LM from q0 and from the seed table's entries nearest to the target. Every single run gets
    # the full step budget: a start in the basin of a solution converges in about 5-10 steps, one held by a
    # limit or a local minimum is dropped by LM's stall test within a few, and one still gaining after 15 is
    # mostly creeping towards a near-singular solution (LM's geodesic acceleration), cheaper to finish than
    # to replace. The table is built once per robot and box; building it does not count against the budget.
    table = ranked = first = None
    if table_size > 0 and table_seeds > 0:
        t_build = time.perf_counter()
        table = seed_table(robot, problem.lower, problem.upper, table_size)
        if search.deadline is not None:
            search.deadline += time.perf_counter() - t_build
        ranked = table.ranked(problem.target, table_offset + table_seeds)  # lazy: ranks on the first next()
        if table_offset:
            ranked = itertools.islice(ranked, table_offset, None)
    q0 = problem.q0
    q0_first = q0 is not None
    if q0 is not None and table is not None:
        # A q0 farther from the target than the table's nearest entry (a random guess rather than a previous
        # solution) goes second: a failed LM run from it costs as much as a converging one.
        d0 = table.distance_sq(problem.target, robot.fk_unchecked(np.minimum(np.maximum(q0, problem.lower),
                                                                            problem.upper)))
        if d0 > table.typical_gap_sq(problem.target):
            first = next(ranked, None)
            q0_first = first is None or d0 <= table.distance_sq(
                problem.target, pin.SE3(table.rotations[first], table.positions[first]))
    if q0_first:
        stage = "q0"
        solved = search.polish(q0)
    if not solved and table is not None and not search.out_of_time():
        if first is None:
            first = next(ranked, None)
        stage = "seed table"
        solved = first is not None and search.polish(table.Q[first])
        if not solved and q0 is not None and not q0_first and not search.out_of_time():
            stage = "q0"
            solved = search.polish(q0)
        if not solved and not search.out_of_time():
            rest = list(ranked)
            stage = "seed table"
            solved = bool(rest) and search.polish_many(table.Q[rest])
    # Stage 3: DE populations, their best members polished by LM, best first.
    if not solved and not search.out_of_time() and max_restarts != 0:
        if search.best is None:  # no q0 and no table: start from the box centre
            solved = search.polish(0.5 * (problem.lower + problem.upper))
        cost = _final_errors(problem, search.best.q, search.best)[2]
        history["best_cost"].append(cost)
        history["mean_cost"].append(cost)
        history["diversity"].append(0.0)
        wrap = wrapping_joints(robot, problem.lower, problem.upper)
        while not solved and not search.out_of_time() and (max_restarts is None or restarts < max_restarts):
            stage = "memetic restarts"
            restarts += 1
            solved, n_gen, cost = _memetic_restart(problem, rng, search, population, generations, polish_count,
                                                   wrap, history, n_gen, cost)
    if search.best is None:  # every stage disabled
        search.polish(0.5 * (problem.lower + problem.upper))
    q = search.best.q
    pos, rot, cost = _final_errors(problem, q, search.best)
    if not history["best_cost"]:
        history["best_cost"].append(cost)
        history["mean_cost"].append(cost)
        history["diversity"].append(0.0)
    success = pos <= problem.tolerance and (rot is None or rot <= problem.rotation_tolerance)
    if success:
        message = f"tolerance reached by LM from {stage} ({search.attempts} LM run(s), {restarts} restart(s))"
    else:
        why = (f"time budget ({timeout:g} s) exhausted" if search.out_of_time()
               else f"max_restarts ({max_restarts}) reached")
        message = (f"{why} after {search.attempts} LM run(s) and {restarts} restart(s); best {_errors_text(pos, rot)}"
                   f" exceeds the tolerance ({problem.tolerance:g} m, {problem.rotation_tolerance:g} rad)")
    history["attempt_error"] = search.attempt_errors
    return Result(
        q=q.copy(), position_error=pos, orientation_error=rot, cost=cost, success=bool(success), generations=n_gen,
        evaluations=search.evaluations + problem.evaluations, time_s=time.perf_counter() - t0,
        history={k: np.asarray(v, dtype=float) for k, v in history.items()}, message=message, method="memetic",
    )


def _memetic_restart(problem, rng, search: _Search, population: int, generations: int, polish_count: int,
                     wrap: np.ndarray, history: dict, n_gen: int, best_cost: float) -> tuple[bool, int, float]:
    """One stage-3 restart: a DE population, ``generations`` generations, its best members polished by LM.

    The population is uniform in the box plus the best configuration met so far (elitism) and ``q0``.
    DE/current-to-best/1/bin (:mod:`.de_ops`) with a dithered scale factor F ~ U[0.5, 1] per individual
    and CR = 0.9; wrapping joints stay on their circle, the others are clipped; greedy selection on the
    problem's objective. Then the ``polish_count`` best members, except the elite (already polished), are
    polished by LM, best first (``batch`` at a time).
    """
    lo, hi = problem.lower, problem.upper
    X = rng.uniform(lo, hi, size=(population, problem.n))
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


def polish_result(problem: IKProblem, result: Result, rng: np.random.Generator | None = None,
                  iterations: int = POLISH_ITERATIONS, engine: str = "compiled") -> Result:
    """``result`` with its configuration polished by Levenberg-Marquardt (the ``polish=True`` of every method).

    LM runs from ``result.q`` for at most ``iterations`` steps on the problem's task error; the polished
    configuration replaces ``result.q`` only when its error (position + orientation, m + rad) is lower.
    The history is kept; ``evaluations`` and ``time_s`` grow by the polish's; the message says what the
    polish did. ``engine``: as memetic's. ``rng`` is accepted for the uniform hook signature; the polish draws
    no random numbers.
    """
    t0 = time.perf_counter()
    iterations = check_positive_int("iterations", iterations, 1)
    lm = LevenbergMarquardt(problem, engine=engine)
    out = lm.run(np.asarray(result.q, dtype=float), iterations)
    before = result.position_error + (result.orientation_error or 0.0)
    improved = out.error < before
    if improved:
        q = out.q
        pos, rot, cost = _final_errors(problem, q, out)
    else:
        q = np.asarray(result.q, dtype=float)
        pos, rot, cost = result.position_error, result.orientation_error, result.cost
    success = bool(problem.succeeded(pos, rot))
    if improved:
        note = f"polished by Levenberg-Marquardt ({out.iterations} steps): {_errors_text(pos, rot)}"
    else:
        note = f"polished by Levenberg-Marquardt ({out.iterations} steps): no improvement"
    message = (result.message + "; " if result.message else "") + note
    if success and not result.success:
        message += "; tolerance reached"
    return Result(
        q=q.copy(), position_error=pos, orientation_error=rot, cost=cost, success=success,
        generations=result.generations, evaluations=result.evaluations + out.evaluations,
        time_s=result.time_s + (time.perf_counter() - t0), history=result.history, message=message,
        method=result.method, solutions=result.solutions, front=result.front,
    )
