"""An :class:`~evoik_pin.IKSolver`'s prepared velocity-box step (:class:`BoxStep`): the goal structure its
:class:`~.velocity_box.VelocityBoxStage` solved once, bound to the stage's engine, so that each later
:meth:`~evoik_pin.IKSolver.solve_within` of that structure (a Tracker's step, a trajectory's point) only writes the new
targets and box into the engine's own arrays and calls the compiled LM entry; the stage's answers, bit for bit, and
the stage itself whenever this path cannot give them (a run that misses)."""

from __future__ import annotations

import threading
import time

import numpy as np
import pinocchio as pin
from numba import njit

from ...result import Result
from ...target import Target, pose_arrays
from ..lm.compiling import compiled_entry
from ..lm.layout import B_HI, B_LO, P_ITERATIONS, wrapping_joints
from ..lm.run_outcome import LMOutcome
from .velocity_box import BOX_ITERATIONS, NOT_MET, VelocityBoxStage, write_step

__all__ = ["PREPARED", "BoxStep", "settle", "step_key", "write_step"]

#: Whether an IKSolver's solve_within takes a structure's prepared step (the tests turn it off to compare with the
#: general path).
PREPARED = True

_ENTRIES: dict = {}  # write_step's and settle's compiled entries, once found


def _entry(function, args: tuple):
    """``function``'s compiled entry for the argument signature of ``args`` (its one: float64 C arrays, bool masks),
    compiled or loaded on first use (:func:`~..lm.compiling.compiled_entry`; the dispatcher where there is none)."""
    hit = _ENTRIES.get(function)
    if hit is None:
        function(*args)
        hit = _ENTRIES[function] = compiled_entry(function, args) or function
    return hit


@njit(cache=True, nogil=True)
def settle(q, box, g_err, checks, orientation_weight):  # pragma: no cover - compiled
    """Clip the run's answer ``q`` (n,) into the box rows B_LO, B_HI of ``box`` (5, n) (``np.minimum(np.maximum(q,
    lo), hi)``: a NaN stays) and judge each goal's row (position m, angle rad) of ``g_err`` (G, 2) against its
    ``checks`` row (reports a position 0/1, reports an angle 0/1, tolerance m, rotation_tolerance rad, weight): the
    Python of Goal.reported, Goal.met and :func:`~evoik_pin.problem.goal_summary` in their operations and order.

    Returns:
        (every goal met, the largest position error m (0 for none; NaN stays), the largest angle rad, whether some
        goal reports an angle, the cost: the sum of weight x (position error + orientation_weight x angle))."""
    for k in range(q.shape[0]):
        v = q[k]
        if not (v >= box[B_LO, k] or v != v):
            v = box[B_LO, k]
        if not (v <= box[B_HI, k] or v != v):
            v = box[B_HI, k]
        q[k] = v
    met = True
    largest = 0.0
    angle = 0.0
    angled = False
    cost = 0.0
    for g in range(g_err.shape[0]):
        has_p, has_r = checks[g, 0] != 0.0, checks[g, 1] != 0.0
        p, r = g_err[g, 0], g_err[g, 1]
        met = met and (not has_p or p <= checks[g, 2]) and (not has_r or r <= checks[g, 3])
        p0 = p if has_p and p != 0.0 else 0.0  # ``p or 0.0``: None, 0.0 and -0.0 give 0.0
        r0 = r if has_r and r != 0.0 else 0.0
        if largest == largest:
            largest = p0 if p0 != p0 else (p0 if p0 > largest else largest)  # max(largest, p0)
        cost += (p0 + orientation_weight * r0) * checks[g, 4]
        if has_r:
            angle = r if not angled or r > angle else angle  # max(angle, r)
            angled = True
    return met, largest, angle, angled, cost


def step_key(target) -> tuple | None:
    """(key, targets) of a ``solve_within`` target for a :class:`BoxStep`. A goal list's key: per goal its class, frame,
    kind, weight, tolerances, aux row and whether it is a single target (not a goal set), what its goal stack depends
    on (:func:`~evoik_pin.goals.stack.structure`'s, which adds what goals beyond one frame pack: those are never
    prepared); its targets: the list. A tip pose or position given as a ``pin.SE3``, float (4, 4) or float (3,) array
    (or a :class:`~evoik_pin.Target`) that passes :class:`~evoik_pin.Target`'s checks but the rotation's, which
    :func:`write_step` makes (:func:`~evoik_pin.target.pose_arrays`): the key ``True`` / ``False``, the targets
    (position (3,) m, rotation (3, 3) or None). None for anything else (the general path then takes it, and refuses it
    if it is bad). Never raises."""
    kind = type(target)
    if kind is list or kind is tuple:
        try:
            return tuple([(type(g), g.frame, g.kind, g.weight, g.tolerance, g.rotation_tolerance,
                           g.alternatives is None, None if (aux := g.aux()) is None else aux.tobytes())
                          for g in target]), target
        except (AttributeError, TypeError):  # not goals: the general path's verdict
            return None
    if kind is pin.SE3 or kind is np.ndarray or kind is Target:
        arrays = pose_arrays(target, check_rotation=False)
        return None if arrays is None else (arrays[1] is not None, arrays)
    return None


class BoxStep:
    """A velocity-box solve prepared for one goal structure (or one tip-target kind): the stage's boxed engine for it,
    its box, targets and scratch arrays bound once; :meth:`solve` per step.

    Made by :meth:`prepare`; used in the thread that made it (the engine's workspace is that thread's).

    Attributes:
        key: the :func:`step_key` of the targets it takes."""

    @classmethod
    def prepare(cls, solver, target) -> BoxStep | None:
        """The per-call path of ``solver`` (an :class:`~evoik_pin.IKSolver`, after its ``solve_within`` took
        ``target``) for targets like ``target``; None where it would not give the stage's answers: locked joints, a
        scene, goal sets, goals beyond one frame or two on one frame, a target-dependent box or an objective other
        than the errors' (tip targets), or no :func:`step_key`."""
        keyed = step_key(target)
        if keyed is None or solver._locked is not None:  # a locked solver's stage is its inner solver's
            return None
        stage = solver._box_stage
        if not isinstance(stage, VelocityBoxStage):
            return None
        problem = solver.problem(target)
        if problem.scene is not None:
            return None
        goals = problem.goals
        if problem.target is None:  # a goal list
            frames = [g.frame for g in goals]
            # one frame per goal: bind's clash test of two goals on one frame reads the targets
            if problem.goal_sets or len(set(frames)) < len(frames) or not all(g.on_one_frame for g in goals):
                return None
        elif solver._target_box or solver._objective is not None or problem.objective.from_errors(
                problem.target, 0.0, 0.0 if problem.target.has_orientation else None) is None:
            return None  # the box or the cost would depend on the target itself
        engine = stage._engine(problem)
        if not (engine._owned and engine._own_box):  # the stage's run made both: else a path not taken yet
            return None
        return cls(keyed[0], solver, stage, problem, engine)

    def __init__(self, key, solver, stage: VelocityBoxStage, problem, engine) -> None:
        self.key = key
        self._solver, self._stage = solver, stage
        self._thread = threading.get_ident()
        self._problem, self._list = problem, problem.target is None
        # what each goal reports and meets (Goal.reported, Goal.met), fixed by its kind and tolerances: the structure's
        self._reports = [(g.has_position, g.reports_angle) for g in problem.goals]
        self._checks = np.array([(g.has_position, g.reports_angle, g.tolerance, g.rotation_tolerance, g.weight)
                                 for g in problem.goals], dtype=float)
        self._orientation_weight = float(problem.orientation_weight)
        self._one = len(problem.goals) == 1
        self._settle = _entry(settle, (np.zeros(1), np.zeros((5, 1)), np.zeros((1, 2)), np.zeros((1, 5)), 1.0))
        self._engine, self._args = engine, engine._args
        self._pt, self._Rt, self._box = engine._pt, engine._Rt, engine._box
        self._params = engine._params
        self._head = tuple(engine.kernel_arguments(BOX_ITERATIONS)[0])
        self._run = engine._direct or engine._kernel["lm_run_buffers"]
        self._g_err = np.empty((len(problem.goals), 2))
        self._n = problem.n
        # C float64 copies (the entry's one signature) of the bounds the stage clips to, and its wrap mask of them
        lower, upper = problem.lower, problem.upper
        self._bounds = (np.array(lower, dtype=float), np.array(upper, dtype=float),
                        np.array(wrapping_joints(problem.robot, lower, upper), dtype=bool))
        one, mask = np.zeros(1), np.zeros(1, dtype=bool)
        self._write_step = _entry(write_step, (np.zeros((5, 1)), one, one, one, one, mask, np.zeros((1, 4, 4)), mask,
                                               np.zeros((1, 3)), np.zeros((1, 3, 3)), True))
        # the goals whose target is a pin.SE3 (a Pose's always is): their poses go through one (G, 4, 4) array
        G = len(problem.goals)
        self._posed = np.array([self._list and type(g.target) is pin.SE3 for g in problem.goals], dtype=bool)
        self._posed_list = self._posed.tolist()
        self._all_posed = all(self._posed_list)
        self._poses = np.zeros((G, 4, 4))

    def usable(self) -> bool:
        """Whether the engine's arguments are still the ones bound, in the thread that prepared the path."""
        return self._engine._args is self._args and threading.get_ident() == self._thread

    def _write_targets(self, targets) -> None:
        """The step's targets (:func:`step_key`'s) into the engine's arrays: each goal's
        :meth:`~evoik_pin.goals.Goal.encode`, or a tip target's position and rotation (None for a position)."""
        pt, Rt = self._pt, self._Rt
        if not self._list:
            pt[0] = targets[0]
            if targets[1] is not None:
                Rt[0] = targets[1]
            return
        poses = self._poses  # copied into pt, Rt by the compiled write (one array write per goal here, not two)
        if self._all_posed:
            poses[:] = [g.target.homogeneous for g in targets]  # its length checked: the key's
            return
        for i, (g, posed) in enumerate(zip(targets, self._posed_list, strict=True)):
            if posed:
                poses[i] = g.target.homogeneous
            else:
                pt[i], Rt[i] = g.encode()

    def solve(self, target, targets, q_prev: np.ndarray, step: np.ndarray, rng: np.random.Generator | None) -> Result:
        """The stage's :class:`Result` for ``target`` (``targets``: its :func:`step_key`'s, of this path's key) inside
        the velocity box of ``q_prev`` (n,) with half-widths ``step`` (n,) (rad or m; both float64 and checked): the
        LM run from ``q_prev``, and when it misses the stage's search
        (:meth:`~.velocity_box.VelocityBoxStage.solve`, its extra starts drawn by ``rng``) on ``target``'s problem,
        that run not made again."""
        t0 = time.perf_counter()
        self._write_targets(targets)
        if not self._write_step(self._box, q_prev, step, *self._bounds, self._poses, self._posed, self._pt,
                                self._Rt, not self._list and targets[1] is not None):
            return self._stage.solve(self._solver.problem(target), q_prev, step, rng)  # its TargetError
        self._params[P_ITERATIONS] = BOX_ITERATIONS  # another run of the engine may have set another budget
        q = np.empty(self._n)
        g_err = self._g_err
        pos, rot, converged, it, evaluations, c = self._run(*self._head, q_prev, *self._args, self._params, q, g_err)
        if not converged:  # the stage's search from here: its problem, this run as its first
            first = LMOutcome(q, pos, rot if self._engine.oriented else None, False, it, evaluations,
                              None if self._one else g_err.copy(), c)
            return self._stage.solve(self._solver.problem(target), q_prev, step, rng, first, t0)
        if self._one:  # the kernel's errors of one goal are its returned ones (what the stage reads)
            g_err[0, 0], g_err[0, 1] = pos, rot
        # the stage's clip (the kernel keeps q inside) and each goal's verdict and the goal list's summary, compiled
        met, largest, angle, angled, cost = self._settle(q, self._box, g_err, self._checks, self._orientation_weight)
        errors = [(p if has_p else None, r if has_r else None)  # Goal.reported
                  for (has_p, has_r), (p, r) in zip(self._reports, g_err.tolist(), strict=True)]
        if self._list:
            pos, rot = largest, angle if angled else None
        else:  # a tip target's cost is its objective's (of the errors: BoxStep.prepare)
            pos, rot, cost = self._problem.summary(q, errors)
        message = "velocity box: 1 LM run(s)" + ("" if met else NOT_MET)
        return Result(q=q, position_error=float(pos), orientation_error=None if rot is None else float(rot),
                      cost=float(cost), success=bool(met), generations=0, evaluations=int(evaluations),
                      time_s=time.perf_counter() - t0, message=message, method="velocity-box",
                      goal_errors=errors if self._list else None,
                      chosen=[None] * len(errors) if self._list else None)
