"""An :class:`~evoik_pin.IKSolver`'s per-call path for one pose or position target, or a goal list of one goal on one
frame: memetic's compiled first runs with nothing around them but the target's and q0's checks and the Result.

A single target that one of memetic's guaranteed first runs solves (nearly every one) costs one compiled call,
:func:`~.first_runs.first_runs` (the table's ranking, q0's nearness, the LM runs: 12 us on UR10), and the Python
of the general path around it: a Target, an IKProblem copied from the solver's template with its objective, the
plan's look-ups (seed table, engine retargeted, compiled entry), the cost from an objective, the Result: about
11 us more, 15 us when the machine's caches were taken by other work between two calls (a control loop's other
tasks; TRAC-IK's calls in the latency benchmark). A lane does the part that changes from call to call only:

* the target's checks (:func:`~evoik_pin.target.pose_arrays`: those of :class:`~evoik_pin.Target`, on Python
  floats; a goal list's are :func:`~evoik_pin.goals.stack.bind`'s) and q0's (the solver's); any other form of
  target, or a target a check refuses, goes the general way, which accepts what the lane accepts and raises the
  error of what it refuses;
* the target written into its engine's own arrays, and the compiled entry called with the arguments it keeps;
* the cost from the objective the solver's options make (its ``from_errors``, as ``IKProblem.assess`` computes
  it), the tolerances tested, and the Result :func:`~.memetic.first_runs_result` makes for the general path.

The answer is the general path's: the same compiled call on the same numbers, the same Result (``setup_s`` is
0: the lane pays no set-up). When none of the first runs converges, the lane hands its runs' state to the general
path (:meth:`~.memetic.MemeticPlan.resume`), which goes on from there on the lane's clock, as memetic itself does
after its first runs.

A lane is made by :meth:`SingleTargetLane.of_plan` after the plan solved a target of its kind through the compiled
entry, and serves the thread that made it (its workspace is that thread's).
"""

from __future__ import annotations

import threading
import time

import numpy as np

from ...objectives import default_objective
from ...problem import goal_summary
from ...target import Target
from ..lm.layout import P_ITERATIONS
from . import memetic
from .memetic import GUARANTEED_TABLE_RUNS, first_runs_result, resumed_state
from .seed_table import DEFAULT_TABLE_SEEDS

__all__ = ["SingleTargetLane"]


class SingleTargetLane:
    """The per-call path of one plan (:class:`~.memetic.MemeticPlan`) for single targets of one kind (poses, or
    positions), or for goal lists of one goal on one frame bound to one goal stack (:func:`~.memetic.one_frame_goal`:
    a Pose with or without free axes or bands, a Position, an Orientation), in the search box, tolerances and
    objective settings of the problem it was made from.

    Args:
        plan: the memetic plan. problem: a problem the plan has just solved (its box, tolerances, goal stack,
            ``orientation_weight`` and ``pose_metric`` are the lane's; no scene). lm: the plan's engine for it.
            table: the plan's seed table. entry: :func:`~.first_runs.first_runs`' compiled entry for ``lm``'s
            arguments.

    Attributes:
        key: what the lane serves: True (poses), False (positions), or the goal stack a one-goal list is bound to
            (:func:`~evoik_pin.goals.stack.bind`).
    """

    @classmethod
    def of_plan(cls, plan, problem) -> SingleTargetLane | None:
        """A lane for problems like ``problem`` (a pose, a position, or a one-goal list bound to the same stack):
        ``problem`` is the one the plan has just solved through the compiled first runs, with their compiled entry
        found. None when such problems do not take the compiled first runs (a scene, a planar target, several goals,
        a goal set, options that change the first runs), when the entry is not known yet (a plan's first solve), or
        while the engine's target arrays may still be the first problem's own (a lane writes into them)."""
        (_, _, _, _, _, table_size, table_seeds, table_offset, batch, _, engine) = plan.options
        lm, table = plan._lm, plan._table
        args, kept_table, entry = plan._entry
        goals = problem.goals
        if not (memetic.FIRST_RUNS and problem.scene is None and engine == "compiled" and batch == 1
                and table_offset == 0 and table_size > 0 and table_seeds != 0 and table is not None
                and lm is not None and lm.problem is problem and lm._owned
                and args is lm._args and kept_table is table and entry is not None
                and not hasattr(entry, "overloads")  # a compiled entry, not numba's dispatcher
                and (not problem.target.planar if goals is None else
                     memetic.one_frame_goal(problem) and not problem.goal_sets)):
            return None
        return cls(plan, problem, lm, table, entry)

    def __init__(self, plan, problem, lm, table, entry) -> None:
        self.plan = plan
        goals = problem.goals
        if goals is None:
            self.key = self.oriented = problem.target.rotation is not None
            key = "pose" if self.oriented else "position"
            F, FT, sq = table.compiled_features(key)
            gap, sp, sr = table._gap(key), 1.0, table.weight
            # the cost of the lane's answers: the objective the solver's options make for a target of this kind,
            # asked for its value from the errors (as IKProblem.assess asks it) with the target it was made for
            dummy = Target(np.zeros(3), np.eye(3) if self.oriented else None)
            self._objective = default_objective(dummy, problem.orientation_weight, problem.pose_metric)
            self._dummy = dummy
        else:
            self.key = problem.goal_stack()[0]
            self.oriented = None
            F, FT, sq, gap, sp, sr = table.one_goal_features(goals[0])
        options = plan.options
        self._iterations = options[9]
        self._tolerance = problem.tolerance
        self._rotation_tolerance = problem.rotation_tolerance
        self._orientation_weight = problem.orientation_weight
        self._lm = lm
        self._args = lm._args
        self._pt, self._Rt = lm._pt[0], lm._Rt[0]  # (3,) and (3, 3) views of the engine's own target arrays
        buffers, args, params = lm.kernel_arguments(self._iterations)
        self._params = params
        lower, upper = plan._bounds
        self._errors, self._g_out, self._zeros, self._best_q, self._best = plan._scratch
        self._head = tuple(buffers)
        table_runs = min(GUARANTEED_TABLE_RUNS, DEFAULT_TABLE_SEEDS if options[6] is None else options[6])
        self._box = (lower, upper, gap, table.Q, F, FT, sq, sp, sr, lm.oriented, table_runs, *args, params)
        self._entry = entry
        self._thread = threading.get_ident()
        self._n = problem.n

    def usable(self) -> bool:
        """Whether the lane's engine and compiled entry still hold (the engine's arguments not remade) in the thread
        that made it."""
        return self._lm._args is self._args and threading.get_ident() == self._thread

    def _runs(self, q0: np.ndarray | None) -> tuple:
        """The compiled first runs from ``q0`` (n,) or none, towards the target written into the engine's arrays:
        (stage, runs, evaluations, position error, rotation error, the answer (n,))."""
        self._params[P_ITERATIONS] = self._iterations  # another path may have run the engine with another budget
        q_out = np.empty(self._n)
        has_q0 = q0 is not None
        stage, runs, evaluations, pos, rot, _ = self._entry(
            *self._head, np.array(q0, dtype=float) if has_q0 else self._zeros, has_q0, *self._box, q_out,
            self._g_out, self._errors, self._best_q, self._best)
        return stage, runs, evaluations, pos, rot, q_out

    def solve(self, position: np.ndarray, rotation: np.ndarray | None, q0: np.ndarray | None, goals=None):
        """Solve one checked target of the lane's kind (``position`` (3,) m, ``rotation`` (3, 3) or None), or the
        one-goal list ``goals`` bound to the lane's stack (:func:`~evoik_pin.goals.stack.bind`'s list, its target
        ``position`` and ``rotation``), from ``q0`` (n,) float (checked; None: none). A goal's errors are the kernel's
        (``Goal.reported``), judged by ``Goal.met``, as memetic judges them; ``chosen`` is ``[None]``.

        Returns:
            The Result when a first run met the tolerances; else (when the clock started, the runs' state) for
            :meth:`~.memetic.MemeticPlan.resume`, or None when a run converged by the kernel's test but not by the
            tolerances (the general path then solves the problem from the start, as memetic does).
        """
        t0 = time.perf_counter()
        self._pt[:] = position
        if rotation is not None:
            self._Rt[:] = rotation
        stage, runs, evaluations, pos, rot, q = self._runs(q0)
        if stage < 0:
            return t0, resumed_state(self.plan, self._box[9], runs, evaluations, self._box[10])
        if goals is not None:
            goal = goals[0]
            goal_errors = [goal.reported(pos, rot)]
            pos, rot, cost = goal_summary(goals, goal_errors, self._orientation_weight)
            if not goal.met(*goal_errors[0]):
                return None
            result = first_runs_result(q, pos, rot, cost, stage, runs, evaluations, self._errors,
                                       time.perf_counter() - t0, 0.0, goal_errors)
            result.chosen = [None]
            return result
        if not self.oriented:
            rot = None
        elif not rot <= self._rotation_tolerance:
            return None
        if not pos <= self._tolerance:
            return None
        cost = self._objective.from_errors(self._dummy, pos, rot)
        return first_runs_result(q, pos, rot, float(cost), stage, runs, evaluations, self._errors,
                                 time.perf_counter() - t0, 0.0)
