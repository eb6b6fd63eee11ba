"""Paper 003's NSGA-II IK method (``nsga2``) on :func:`~.nsga2_minimizer.nsga2_minimize` (whose names and the
sorting's are re-exported here): objectives ``g = 1 / (Y + 1)`` (Yoshikawa manipulability of the task rows) and the
smoothness ``S``, the pose equality a constraint, new individuals repaired by :func:`~.task_repair.dls_repair`;
also for goal lists (:class:`GoalManipulability`, :func:`goal_task`)."""

from __future__ import annotations

import numpy as np

from ...errors import OptionError
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
from ..options import check_int, check_nonnegative_vector
from .common import SolverRun, diversity, initial_population
from .nsga2_minimizer import NSGA2Result, bounded_polynomial_mutation, nsga2_minimize, sbx
from .pareto_sorting import crowding_distance, dominance_matrix, nondominated_ranks, survival
from .task_repair import _movable_rows, _task_rows, dls_repair

__all__ = ["GoalManipulability", "NSGA2Result", "bounded_polynomial_mutation", "crowding_distance", "dls_repair",
           "dominance_matrix", "goal_task", "nondominated_ranks", "nsga2_minimize", "sbx", "survival"]


#: Names of the rows of a base-frame Jacobian.
ROW_NAMES = ("vx", "vy", "vz", "wx", "wy", "wz")


class GoalManipulability(Objective):
    """Paper 003's manipulability over several goal frames: Y, the product of the singular values of the stacked
    base-frame Jacobian rows ``rows[i]`` of ``frames[i]`` (``sqrt(det(J J^T))`` or ``sqrt(det(J^T J))``), in the
    ``form`` of :class:`ManipulabilityCost` (``"inverse"`` 1 / (Y + 1), ``"negative"`` -Y, ``"value"`` Y)."""

    def __init__(self, frames, rows, form: str = "inverse") -> None:
        self._form = ManipulabilityCost("translation", form).form  # the form's check
        self.frames, self.rows = list(frames), [list(r) for r in rows]

    def value(self, Q, kin):
        robot = kin.robot
        J = np.concatenate([robot.jacobian_batch(Q, validate=False, frame=f)[:, r]
                            for f, r in zip(self.frames, self.rows, strict=True)], axis=1)
        M = J @ J.transpose(0, 2, 1) if J.shape[1] <= J.shape[2] else J.transpose(0, 2, 1) @ J
        Y = np.sqrt(np.maximum(np.linalg.det(M), 0.0))
        return 1.0 / (Y + 1.0) if self._form == "inverse" else -Y if self._form == "negative" else Y

    def __repr__(self) -> str:
        return f"GoalManipulability(frames={self.frames!r}, rows={self.rows!r}, form={self._form!r})"


def _chosen_goals(problem: IKProblem, which) -> list[int]:
    """Indices of the goals ``which`` names (indices or frames of the goal list; None: all), or OptionError."""
    goals = problem.goals
    if which is None:
        return list(range(len(goals)))
    frames = [g.frame for g in goals]
    picked: list[int] = []
    listed = list(which) if np.iterable(which) and not isinstance(which, str) else [which]
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
    """A goal list's default manipulability objective, on the goals ``which`` picks, less the rows their frames
    never move (:func:`~.task_repair._movable_rows`); and the names of the rows left out, for the message."""
    frames, rows, fixed = [], [], []
    for goal in (problem.goals[i] for i in _chosen_goals(problem, which)):
        moving, still = _movable_rows(problem, [0, 1, 2, 3, 4, 5] if goal.has_orientation else [0, 1, 2], goal.frame)
        fixed += [f"{goal.frame}:{ROW_NAMES[r]}" for r in still]
        if moving:
            frames.append(goal.frame)
            rows.append(moving)
    if not frames:
        raise OptionError("no goal frame of the goal list moves along any of its rows; give objectives=[...]")
    return GoalManipulability(frames, rows), fixed


def goal_task(problem: IKProblem, Q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The task error ``e`` (N, rows) and Jacobian ``J`` (N, rows, n) of a goal list at ``Q`` (N, n) for
    :func:`dls_repair`: :meth:`~evoik_pin.problem.IKProblem.goal_rows` with the sign it reads, ``e = target - f(q)``."""
    e, E = problem.goal_rows(Q)
    return -e, E


@register("nsga2", "paper 003: NSGA-II with constraint domination; Pareto front of manipulability and "
          "weighted joint displacement under the pose constraint (every goal of a goal list)", multi_objective=True)
def nsga2(problem: IKProblem, rng: np.random.Generator, *, population: int = 200, max_generations: int = 100,
          gains=None, manipulability_rows=None, manipulability_goals=None, objectives: list[Objective] | None = None,
          pick: int = -1, repair_steps: int = 3, eta_c: float = 15.0, eta_m: float = 20.0,
          crossover_probability: float = 0.9, mutation_probability: float | None = None) -> Result:
    """Paper 003's NSGA-II IK (section 3): a Pareto front under the constraint ``f(q) = x_d`` (a goal list: every
    goal within its own tolerances, :meth:`~evoik_pin.problem.IKProblem.goal_violation`).

    Options:
        population, max_generations: offspring generations, always all run.
        gains: K (n,) of the smoothness ``S = sqrt(sum K_i (q_i - q_prev,i)^2)`` (default ones); q_prev is
            ``problem.q0`` (zeros when none).
        manipulability_rows: one target: Jacobian rows of ``Y = sqrt(det(J J^T))`` (default the task's rows, less
            those along which the chain never moves its tip; the message names them).
        manipulability_goals: a goal list: the goals (indices or frames) whose rows Y reads (default all).
        objectives: replace the default ``[ManipulabilityCost(rows, "inverse"), WeightedJointDisplacement]`` by
            any list of :class:`~evoik_pin.objectives.Objective` (all minimized).
        pick: objective index minimized when choosing ``q`` from the front (-1: the last, S).
        repair_steps: damped-least-squares steps (weighted by 1 / K) applied to every new individual (the initial
            population gets four times as many); 0 runs the plain algorithm.
        eta_c, eta_m, crossover_probability, mutation_probability: SBX / polynomial mutation (default 1/n).

    Returns:
        :class:`Result` whose ``front`` holds the first front sorted by the first objective (violation = errors
        above the tolerances, m + rad) and whose ``q`` is its feasible member with the least objective ``pick``
        (else the least violation). History adds ``front_size``, ``feasible_fraction``, ``min_violation``.
    """
    robot = problem.robot
    repair_steps = check_int("repair_steps", repair_steps, 0)
    q_prev = np.zeros(problem.n) if problem.q0 is None else problem.q0
    goals = problem.target is None
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
            rows = manipulability_rows
            if rows is None:
                rows, fixed_rows = _movable_rows(problem, _task_rows(problem))
                if not rows:
                    raise OptionError("the chain cannot move its tip along any row of the task; give "
                                      "manipulability_rows=[...] or objectives=[...]")
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

    def callback(g, X, F, cv):
        ok = cv <= 0
        run.history["best_cost"].append(float(F[ok, pick].min()) if ok.any() else np.nan)
        run.history["mean_cost"].append(float(np.mean(F[:, pick])))
        run.history["diversity"].append(diversity(X, problem.lower, problem.upper))

    out = nsga2_minimize(
        f, problem.lower, problem.upper, k, rng, population=population, generations=max_generations, eta_c=eta_c,
        eta_m=eta_m, crossover_probability=crossover_probability, mutation_probability=mutation_probability,
        initial=init if repair_steps == 0 else repair(init, 4 * repair_steps),
        repair=None if repair_steps == 0 else (lambda Y: repair(Y, repair_steps)), callback=callback)
    run.generation = out.generations
    order = out.front[np.argsort(out.F[out.front, 0], kind="stable")]
    feasible = order[out.violation[order] <= 0]
    chosen = feasible[np.argmin(out.F[feasible, pick])] if feasible.size else order[np.argmin(out.violation[order])]
    run.best_q = out.X[chosen].copy()
    run.history.update({key: list(v) for key, v in out.history.items()})
    message = f"{max_generations} generations; " + (
        f"{len(order)} point(s) on the front, all feasible" if feasible.size
        else "no individual meets " + ("every goal" if goals else "the pose constraint"))
    if fixed_rows:
        names = ", ".join(ROW_NAMES[r] for r in fixed_rows)
        message += f"; manipulability on Jacobian rows {rows}: the chain never moves its tip along {names}"
    if fixed_goal_rows:
        message += f"; manipulability without the rows no joint moves ({', '.join(fixed_goal_rows)})"
    return run.result("nsga2", message,
                      front=Front(q=out.X[order], objectives=out.F[order], violation=out.violation[order]))
