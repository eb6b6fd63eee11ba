"""Paper 003's NSGA-II IK method (``nsga2``): a Pareto front under the pose constraint, vectorized over the population.

The registered method (:func:`nsga2`) builds paper 003's problem on the generic minimizer
:func:`~.nsga2_minimizer.nsga2_minimize` (NSGA-II with constraint domination, Deb et al. 2002; its sorting and
selection in :mod:`.pareto_sorting`): objectives ``g = 1 / (Y + 1)`` (Yoshikawa manipulability Y of the task rows)
and the smoothness ``S = sqrt(sum_i K_i (q_i - q_prev,i)^2)``, the equality ``f(q) = x_d`` as a constraint whose
violation is the error above the tolerances, every new individual repaired by damped-least-squares steps
(:mod:`.task_repair`), and the first-front member with the best S as the answer. Here too: the goal-list form of
the problem (:class:`GoalManipulability`, :func:`goal_task`). The minimizer's and the sorting's public names are
re-exported, as they were defined here before.
"""

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
from .common import SolverRun, diversity, halton, initial_population
from .nsga2_minimizer import NSGA2Result, bounded_polynomial_mutation, nsga2_minimize, sbx
from .pareto_sorting import crowding_distance, dominance_matrix, nondominated_ranks, survival
from .task_repair import _movable_rows, _task_rows, dls_repair

__all__ = [
    "GoalManipulability",
    "NSGA2Result",
    "bounded_polynomial_mutation",
    "crowding_distance",
    "dls_repair",
    "dominance_matrix",
    "goal_task",
    "goal_rows",
    "nondominated_ranks",
    "nsga2_minimize",
    "sbx",
    "survival",
]


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
