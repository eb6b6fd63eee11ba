"""An :class:`~evoik_pin.IKSolver`'s per-call path (:class:`RepeatCall`) for problems its memetic set-up solved
before: memetic's compiled guaranteed runs (:mod:`.guaranteed_runs`) on the engine's own target arrays, with nothing
around them but the checks and the Result; the general path's answer, and when no guaranteed run converges its state
goes on in :meth:`~.memetic.MemeticSetup.resume`."""

from __future__ import annotations

import threading
import time

import numpy as np

from ...goals.stack import free_entries
from ...result import Result
from ..lm.layout import P_ITERATIONS
from . import memetic
from .answer_choice import member_distances
from .guaranteed_runs import REFUSED
from .memetic import GUARANTEED_TABLE_RUNS, guaranteed_runs_result, resumed_state
from .seed_table import DEFAULT_TABLE_SEEDS, one_frame

__all__ = ["SET_MEMBERS", "RepeatCall"]

#: A goal set's members tried on the compiled guaranteed runs (the nearest the seed table first) before the goal-set
#: search takes the set over: as many as that search's last stage takes (its nearest variants).
SET_MEMBERS = 3


class RepeatCall:
    """The per-call path of one :class:`~.memetic.MemeticSetup` for problems like the one it was made from: a tip
    pose or position target, or a one-goal list on one frame bound to its goal stack, in that problem's box, tolerances
    and objective; in the thread that made it.

    Args:
        setup: the memetic setup. problem: a problem the setup has just solved through the compiled guaranteed runs (no
            scene). lm: the setup's engine for it. table: the setup's seed table. entry: the compiled entry of
            :func:`~.guaranteed_runs.guaranteed_runs` for ``lm``'s arguments. ff: the table's features of the problem's
            frame (:meth:`~.seed_table.SeedTable.frame_search`).

    Attributes:
        key: what it serves: True (poses), False (positions), or the goal stack a one-goal list is bound to.
    """

    @classmethod
    def of_setup(cls, setup, problem) -> RepeatCall | None:
        """A path for problems like ``problem``, which the setup has just solved; None when such problems do not take
        the compiled guaranteed runs (a scene, a planar target, several goals, a goal set, options that change the first
        runs), when the compiled entry is not known yet, or while the engine's target arrays are not its own."""
        table_size, table_seeds, table_offset, batch, _, engine = setup.options[5:]
        lm, table = setup._lm, setup._table
        args, kept_table, entry = setup._entry
        if not (memetic.COMPILED_GUARANTEED_RUNS and problem.scene is None and engine == "compiled" and batch == 1
                and table_offset == 0 and table_size > 0 and table_seeds != 0 and table is not None
                and lm is not None and lm.problem is problem and lm._owned
                and args is lm._args and kept_table is table and entry is not None
                and not hasattr(entry, "overloads")  # a compiled entry, not numba's dispatcher
                and one_frame(problem)):
            return None
        ff = table.frame_search(problem)
        return None if ff.planar else cls(setup, problem, lm, table, entry, ff)

    def __init__(self, setup, problem, lm, table, entry, ff) -> None:
        self.setup = setup
        self.key = ff.oriented if problem.target is not None else problem.goal_stack()[0]
        # its problems' verdict and cost are the first one's (IKProblem.summary reads the goals' weights and the
        # objective, not the targets); a goal set bound to the same stack ranks its members by the frame's features
        goal = problem.goals[0]  # what the kernel's errors report and their tolerances (the stack's, every call's)
        self._summary, self._goal_list = problem.summary, problem.target is None
        self._reports = (goal.has_position, goal.reports_angle, goal.tolerance, goal.rotation_tolerance)
        self._ranking = (table, ff, table.goal_spec(problem.goals))
        self._iterations, table_seeds = setup.options[9], setup.options[6]
        self._lm, self._args, self._entry, self._n = lm, lm._args, entry, problem.n
        self._pt, self._Rt = lm._pt[0], lm._Rt[0]  # (3,) and (3, 3) views of the engine's own target arrays
        buffers, args, self._params = lm.kernel_arguments(self._iterations)
        self._errors, self._g_out, self._zeros, self._best_q, self._best = setup._scratch
        self._head = tuple(buffers)
        table_runs = min(GUARANTEED_TABLE_RUNS, DEFAULT_TABLE_SEEDS if table_seeds is None else table_seeds)
        self._box = (ff.gap, table.Q, ff.FT, ff.sq, ff.sp, ff.sr, lm.oriented, table_runs, *args, self._params)
        self._thread = threading.get_ident()
        #: the q entries no goal depends on (None: none) and the box (lower, upper): IKSolver settles them
        #: (call_setup.settle_free's rule; a repeat call's objective is the errors' own)
        self.free = free_entries(problem.robot, problem.goal_stack()[0])
        self.box = (problem.lower, problem.upper)

    def usable(self) -> bool:
        """Whether the engine's arguments still hold, in the thread that made the path."""
        return self._lm._args is self._args and threading.get_ident() == self._thread

    def solve(self, position: np.ndarray, rotation: np.ndarray | None, q0: np.ndarray | None,
              rotation_checked: bool = True):
        """Solve a problem like the path's (a tip target, or a one-goal list bound to its stack) whose one target is
        ``position`` (3,) m and ``rotation`` (3, 3) or None (checked; with ``rotation_checked=False`` the compiled
        guaranteed runs check the rotation before anything runs), from ``q0`` (n,) float (checked; None: none); the goal
        is judged on the kernel's errors, as memetic judges them.

        Returns:
            The Result when a guaranteed run met the tolerances; else (clock start, the runs' state) for
            :meth:`~.memetic.MemeticSetup.resume`, or None when a run converged by the kernel's test but not by the
            tolerances, or the rotation is not a rotation matrix (the general path then solves the problem from the
            start, or refuses its target).
        """
        t0 = time.perf_counter()
        self._pt[:] = position
        if rotation is not None:
            self._Rt[:] = rotation
        self._params[P_ITERATIONS] = self._iterations  # another path may have run the engine with another budget
        q = np.empty(self._n)
        stage, runs, evaluations, pos, rot, _ = self._entry(
            *self._head, self._zeros if q0 is None else np.array(q0, dtype=float), q0 is not None,
            not rotation_checked and rotation is not None, *self._box, q, self._g_out, self._errors, self._best_q,
            self._best)
        if stage < 0:
            return None if stage == REFUSED else (t0, resumed_state(self.setup, self._box[6], runs, evaluations,
                                                                    self._box[7]))
        positioned, angled, tol, rtol = self._reports  # Goal.reported and Goal.met, inline
        errors = [(float(pos) if positioned else None, float(rot) if angled else None)]
        if not ((not positioned or errors[0][0] <= tol) and (not angled or errors[0][1] <= rtol)):
            return None
        pos, rot, cost = self._summary(q, errors)
        result = guaranteed_runs_result(q, pos, rot, cost, stage, runs, evaluations, self._errors,
                                        time.perf_counter() - t0, 0.0, errors if self._goal_list else None)
        if self._goal_list:
            result.chosen = [None]
        return result

    def solve_set(self, goal, q0: np.ndarray | None):
        """Solve the one-goal list ``[goal]`` of a goal set bound to the path's stack from ``q0`` (n,) float (checked;
        None: none): the member nearest the seed table (:func:`~.answer_choice.member_distances`, the goal-set search's
        first choice), then the next nearest, up to :data:`SET_MEMBERS`, each on the compiled guaranteed runs as
        :meth:`solve` solves it alone.

        Returns:
            The Result, ``chosen`` the member met, when a guaranteed run met one (its time and evaluations those of the
            members tried before too); else None (the goal-set search then solves the set from the start)."""
        t0 = time.perf_counter()
        P, R = goal.member_targets
        order = [0] if len(P) == 1 else np.argsort(  # equals: the first member first
            member_distances(*self._ranking, P[:, None], R[:, None])[1], kind="stable")[:SET_MEMBERS].tolist()
        spent = 0  # the evaluations of the members tried before
        for m in order:
            out = self.solve(P[m], R[m], q0)
            if type(out) is Result:
                out.chosen = [m]
                out.evaluations += spent
                out.time_s = time.perf_counter() - t0
                return out
            if out is not None:  # (clock start, resumed_state): the runs made and their evaluations
                spent += out[1][1]
        return None
