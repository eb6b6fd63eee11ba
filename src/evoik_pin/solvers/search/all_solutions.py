"""Every IK solution of one target (``memetic-all``, the default method of :func:`evoik_pin.solve_all`): batched LM
from q0, the seed table and uniform draws, the converged runs sorted into distinct solutions
(:mod:`.solution_classes`); every class of a finite set, ``count`` spread solutions on a redundant arm."""

from __future__ import annotations

import itertools
import time

import numpy as np

from ...errors import OptionError
from ...goals.stack import GoalArrays
from ...problem import IKProblem, shortfall_text
from ...result import Result
from .. import register
from ..lm import DEFAULT_ITERATIONS, ENGINES, LevenbergMarquardt, solve_pairs, wrapping_joints
from ..options import check_choice, check_int, check_positive
from .memetic import memetic, prepare
from .seed_table import default_table_size
from .solution_classes import (
    REFINE_ITERATIONS,
    SolutionClasses,
    class_representatives,
    farthest_point_selection,
    min_pairwise_distance,
)

__all__ = ["DEFAULT_CLASS_RADIUS", "DEFAULT_COUNT", "DEFAULT_TIMEOUT", "REFINE_TOLERANCE", "SolutionList",
           "goal_moving_joints", "memetic_all"]

#: Default time budget (s) of one search: a safety net (the stopping rule ends most searches first).
DEFAULT_TIMEOUT = 0.02
#: Default class radius (rad, wrapped joint distance): converged configurations closer than this are one solution.
DEFAULT_CLASS_RADIUS = 1e-3
#: Default bound on the LM starts of one search (128 kernel calls of 32).
DEFAULT_MAX_STARTS = 4096
#: Default number of solutions returned on redundant arms.
DEFAULT_COUNT = 8
#: Refinement of a run that opens a class: tolerance (m, rad) and a stall test that lets LM creep along a
#: near-singular valley (|e| must drop by 10 % every 20 steps, instead of halve every 4).
REFINE_TOLERANCE, REFINE_STALL = 1e-12, (20, 0.9)
#: Runs that stalled with an error (m + rad) below this are continued by the patient LM (:func:`_rescued`).
RESCUE_ERROR = 1e-3
#: Batches without any converged run, in units of ``patience``, before the differential-evolution fallback; also
#: the longest wait for the ``min_hits`` of a rare class, and for a new solution on a redundant arm.
EMPTY_PATIENCE_FACTOR = 4


class SolutionList(list):
    """What :func:`evoik_pin.solve_all` returns: a ``list`` of :class:`Result` (one per solution, best first)
    carrying the search's own Result as ``result`` (or None) and its ``message`` ("" without one). Slicing or copying
    gives a plain list."""

    def __init__(self, solutions=(), result: Result | None = None) -> None:
        super().__init__(solutions)
        self.result = result

    @property
    def message(self) -> str:
        return "" if self.result is None else self.result.message


def _check_options(*, count, timeout, max_starts, batch, patience, min_hits, class_radius, pool, table_size,
                   iterations, engine, n: int) -> tuple:
    """memetic-all's options (:func:`memetic_all`'s keywords; ``n`` the robot's joints) in the signature's order,
    ``table_size`` resolved; OptionError naming an option out of range."""
    count = None if count is None else check_int("count", count, 1)
    timeout = None if timeout is None else check_positive("timeout (s; or None)", timeout)
    max_starts = None if max_starts is None else check_int("max_starts", max_starts, 1)
    table_size = default_table_size(n) if table_size is None else check_int("table_size", table_size, 0)
    return (count, timeout, max_starts, check_int("batch", batch, 1), check_int("patience", patience, 1),
            check_int("min_hits", min_hits, 1), check_positive("class_radius", class_radius, unit="rad"),
            check_int("pool", pool, 1), table_size, check_int("iterations", iterations, 1),
            check_choice("engine", engine, ENGINES))


def _starts(problem: IKProblem, table, rng):
    """The endless stream of LM starts (n,): q0, the seed table's nearest first (several goals:
    :meth:`SeedTable.goal_starts`), then uniform draws from ``rng``."""
    if problem.q0 is not None:
        yield problem.q0
    if table is not None:
        size = table.Q.shape[0]
        ff = table.frame_search(problem)
        yield from (table.goal_starts(problem, size) if ff is None
                    else (table.Q[i] for i in table.ranked(ff, table.target_point(problem, ff), size)))
    while True:
        yield rng.uniform(problem.lower, problem.upper)


@register("memetic-all", "Every distinct IK solution: batched Levenberg-Marquardt from q0 and the seed table "
          "(nearest first), clustered modulo 2 pi; count spread solutions on redundant arms", multi_solution=True,
          check=_check_options)
def memetic_all(problem: IKProblem, rng: np.random.Generator, *, count: int | None = None,
                timeout: float | None = DEFAULT_TIMEOUT, max_starts: int | None = DEFAULT_MAX_STARTS, batch: int = 32,
                patience: int = 2, min_hits: int = 3, class_radius: float = DEFAULT_CLASS_RADIUS, pool: int = 4,
                table_size: int | None = None, iterations: int = DEFAULT_ITERATIONS,
                engine: str = "compiled") -> Result:
    """Every distinct IK solution of ``problem`` (``Result.solutions``): batched LM from q0, the seed table (nearest
    first) and uniform draws, the converged runs sorted into classes; every class of a finite set, ``count`` spread
    by farthest-point selection on a redundant arm; each its class's representative nearest ``q0`` (re-checked,
    nearest first). When no run converges, memetic's DE restarts look for one.

    Args:
        problem: the IK problem; its tolerances decide which runs converged.
        rng: uniform starts once the table runs out, and the DE fallback.
        count: redundant arms: spread solutions returned (>= 1; default 8); finite sets: at most this many.
        timeout: budget (s; default 0.02; None: none), checked between batches, after the one-time set-up.
        max_starts: LM starts at most (>= 1; None: no limit).
        batch: LM starts per kernel call. patience: quiet batches before a finite set's search stops.
        min_hits: runs each class needs before that stop. class_radius: wrapped joint distance (rad; m on prismatic
            joints) within which two answers are one solution. pool: redundant arms: solutions collected per one
            returned. table_size: seed-table size (default memetic's; 0: uniform starts).
        iterations: LM steps per start. engine: ``"compiled"`` or ``"python"``.

    Returns:
        A :class:`Result`: ``q`` the first solution (or the best approximation), ``success`` when there is one,
        ``solutions`` (each a Result), ``generations`` the batches; ``history`` per batch: ``starts``, ``solutions``,
        ``best_cost`` (m + rad), and ``min_pairwise_distance`` (rad) on redundant arms."""
    t_setup = time.perf_counter()
    robot = problem.robot
    count, timeout, max_starts, batch, patience, min_hits, class_radius, pool, table_size, iterations, engine = \
        _check_options(count=count, timeout=timeout, max_starts=max_starts, batch=batch, patience=patience,
                       min_hits=min_hits, class_radius=class_radius, pool=pool, table_size=table_size,
                       iterations=iterations, engine=engine, n=robot.n)
    lo, hi = problem.lower, problem.upper
    if engine != "compiled" and problem.target is None:  # the Python engine's pairs are tip targets
        raise OptionError("memetic-all solves goal lists on the compiled LM engine only (engine='compiled')")
    stack, pt, Rt = problem.goal_stack()
    moving = goal_moving_joints(robot, stack)
    redundant = int(moving.sum()) > stack.rows  # more joints moving the goals than task rows
    wanted = (DEFAULT_COUNT if count is None else count) if redundant else count
    table, _ = prepare(robot, lo, hi, table_size, engine)  # the kernel and the seed table, outside the clock
    if table is not None and table.frame_search(problem) is None:
        table.prepare_goals(problem.goals)  # the goal frames' poses over the table, once per frame list
    wrap = wrapping_joints(robot, lo, hi)
    reference = np.zeros(robot.n) if problem.q0 is None else problem.q0
    # joints that move no goal frame stay where LM leaves them: put them at the reference instead
    still = np.flatnonzero(~moving)
    rest_at = np.minimum(np.maximum(reference, lo), hi)[still]
    patient = LevenbergMarquardt(problem.tightened(REFINE_TOLERANCE), stall_window=REFINE_STALL[0],
                                 stall_ratio=REFINE_STALL[1], engine=engine)
    t0 = time.perf_counter()
    deadline = None if timeout is None else t0 + timeout
    # A finite set: isolate each solution by refinement (redundant arms have no isolated solutions).
    classes = SolutionClasses(problem, wrap, class_radius, None if redundant else patient)
    starts = _starts(problem, table, rng)
    history: dict[str, list[float]] = {"starts": [], "solutions": [], "best_cost": []}
    evaluations = started = batches = quiet = 0
    best = (np.inf, None)  # the lowest error (m + rad) met and its q
    fallback = ""
    while True:
        k = batch if max_starts is None else min(batch, max_starts - started)
        if k <= 0:
            stop = f"max_starts ({max_starts}) reached"
            break
        pairs = (GoalArrays(stack, np.repeat(pt[None], k, axis=0), np.repeat(Rt[None], k, axis=0))
                 if engine == "compiled" else [problem.target] * k)
        out = solve_pairs(robot, np.array(list(itertools.islice(starts, k))), pairs, lo, hi, problem.tolerance,
                          problem.rotation_tolerance, iterations, engine=engine)
        if still.size:
            out.q[:, still] = rest_at
        started += k
        batches += 1
        evaluations += int(out.evaluations.sum())
        rot = np.zeros(k) if out.orientation_error is None else out.orientation_error
        err = out.position_error + rot
        i = int(err.argmin())
        if err[i] < best[0]:
            best = (float(err[i]), out.q[i].copy())
        Q, E, work = _rescued(problem, patient, out.q, err, out.converged)
        evaluations += work
        quiet = 0 if classes.add(Q, E) else quiet + 1
        history["starts"].append(started)
        history["solutions"].append(len(classes))
        history["best_cost"].append(best[0])
        if redundant and len(classes) >= pool * wanted:
            stop = f"{len(classes)} distinct solutions pooled"
            break
        if len(classes) and quiet >= patience and (
                (not redundant and min(classes.hits) >= min_hits) or quiet >= EMPTY_PATIENCE_FACTOR * patience):
            stop = f"no new {'distinct ' if redundant else ''}solution in the last {quiet} batch(es) of {batch} starts"
            break
        if not len(classes) and quiet >= EMPTY_PATIENCE_FACTOR * patience and not fallback:
            fallback = _fallback(problem, rng, classes, deadline, iterations, engine)
            if not len(classes):
                stop = f"no LM start converged, {fallback}"
                break
            quiet = 0
        if deadline is not None and time.perf_counter() >= deadline:
            stop = f"time budget ({timeout:g} s) exhausted"
            break
    evaluations += classes.evaluations
    pooled = len(classes)
    Q = class_representatives(np.array(classes.reps).reshape(-1, robot.n), reference, lo, hi, wrap)
    if still.size:  # the fallback's answers too
        Q[:, still] = rest_at
    collided = 0
    if problem.scene is not None and Q.shape[0]:  # with a scene, only collision-free solutions are candidates
        free = ~problem.scene.collides(Q, problem.margin)
        collided = int(np.count_nonzero(~free))
        Q = Q[free]
    if redundant and Q.shape[0]:
        Q = Q[farthest_point_selection(Q, wanted, int(np.linalg.norm(Q - reference, axis=1).argmin()), wrap)]
    solutions = _checked_solutions(problem, Q, reference, evaluations, time.perf_counter() - t0, batches)
    if count is not None:
        solutions = solutions[:count]
    spread = None
    if redundant and solutions:
        spread = min_pairwise_distance(np.array([s.q for s in solutions]), wrap)
        history["min_pairwise_distance"] = [spread]
    if solutions:
        first = solutions[0]
        q, pos, rot, cost = first.q, first.position_error, first.orientation_error, first.cost
        message = (f"{len(solutions)} solution(s) spread over the self-motion manifold, smallest pairwise joint "
                   f"distance {spread:.3g} rad, chosen among {pooled} distinct converged solutions from {started} "
                   f"LM start(s) ({stop})" if redundant
                   else f"{len(solutions)} distinct solution(s) from {started} LM start(s) ({stop})")
        if collided:
            message += f"; {collided} solution(s) in collision left out"
    else:
        q = best[1] if best[1] is not None else np.minimum(np.maximum(reference, lo), hi)
        pos, rot, cost = problem.assess(q)
        shortfall = shortfall_text(problem, pos, rot, problem.goal_errors(q))
        message = (f"no solution after {started} LM start(s) ({stop}); {shortfall}: the "
                   f"{'target is' if problem.target is not None else 'goals are'} out of reach (or reachable only "
                   "where no start led)")
        if collided:
            message = (f"all {collided} solution(s) found after {started} LM start(s) are in collision; "
                       f"the nearest to q0 is returned")
            q = class_representatives(np.array(classes.reps).reshape(-1, robot.n), reference, lo, hi, wrap)[0]
            pos, rot, cost = problem.assess(q)
    return Result(q=q.copy(), position_error=pos, orientation_error=rot, cost=cost, success=bool(solutions),
                  generations=batches, evaluations=evaluations, time_s=time.perf_counter() - t0,
                  history={k: np.asarray(v, dtype=float) for k, v in history.items()}, message=message,
                  method="memetic-all", solutions=solutions, setup_s=t0 - t_setup)


def _rescued(problem: IKProblem, patient: LevenbergMarquardt, Q: np.ndarray, E: np.ndarray, converged: np.ndarray
             ) -> tuple[np.ndarray, np.ndarray, int]:
    """The converged runs of a batch (configurations, errors m + rad), plus the near misses (stalled below
    ``RESCUE_ERROR``) a patient LM run takes within the tolerances (near-singular solutions with tiny basins), and the
    kinematics evaluations spent."""
    near = np.flatnonzero(~converged & (E < RESCUE_ERROR))
    if not near.size:
        return Q[converged], E[converged], 0
    work = 0
    Q, E, ok = Q.copy(), E.copy(), converged.copy()
    for i in near:
        out = patient.run(Q[i], REFINE_ITERATIONS)
        work += out.evaluations
        Q[i], E[i] = out.q, out.error
        ok[i] = bool(problem.rows_met(out.q[None])[0])
    return Q[ok], E[ok], work


def _fallback(problem: IKProblem, rng, classes: SolutionClasses, deadline: float | None, iterations: int,
              engine: str) -> str:
    """No start converged: memetic's DE restarts (no table stage) look for one solution with the budget left (20
    restarts without a timeout); a solution opens the first class. Returns what happened, for the message."""
    remaining = None if deadline is None else max(deadline - time.perf_counter(), 1e-4)
    res = memetic(problem, rng, timeout=remaining, max_restarts=None if remaining else 20, table_seeds=0,
                  iterations=iterations, engine=engine)
    classes.evaluations += res.evaluations
    what = f"memetic's differential-evolution restarts ({res.generations} generations, {res.time_s * 1e3:.3g} ms)"
    if res.success:
        classes.add(res.q[None], np.array([res.position_error + (res.orientation_error or 0.0)]))
        return f"{what} found one"
    return f"nor did {what}"


def _checked_solutions(problem: IKProblem, Q: np.ndarray, reference: np.ndarray, evaluations: int, time_s: float,
                       batches: int) -> list[Result]:
    """One Result per row of ``Q`` (M, n) in the box and within the tolerances by fresh forward kinematics (not
    counted as evaluations), nearest ``reference`` first."""
    if not Q.shape[0]:
        return []
    Q = Q[np.argsort(np.linalg.norm(Q - reference, axis=1), kind="stable")]
    ev = problem.evaluate(Q, count=False)
    ok = problem.rows_met(Q)
    ok &= np.all((Q >= problem.lower) & (Q <= problem.upper), axis=1)
    return [Result(q=Q[i].copy(), position_error=float(ev.position_error[i]),
                   orientation_error=None if ev.orientation_error is None else float(ev.orientation_error[i]),
                   cost=float(ev.cost[i]), success=True, generations=batches, evaluations=evaluations, time_s=time_s,
                   message="distinct IK solution", method="memetic-all",
                   goal_errors=None if problem.target is not None else problem.goal_errors(Q[i]))
            for i in np.flatnonzero(ok)]


def goal_moving_joints(robot, stack) -> np.ndarray:
    """(n,) bool: the entries of q that move some goal frame of goal ``stack``."""
    index, scale = robot.tree_constants()[4:6]
    moving = np.zeros(robot.n, dtype=bool)
    moving[index[stack.support.any(axis=0) & (scale != 0.0)]] = True
    return moving
