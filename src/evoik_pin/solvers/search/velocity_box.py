"""One solve inside a velocity box ``[q_prev - step, q_prev + step]`` (``step = v_max dt``, rad or m) clipped to the
bounds, wrapping joints unclipped (:class:`VelocityBoxStage`): a step a robot can follow, never a jump; the closest
answer inside the box when the goals are unmet there."""

from __future__ import annotations

import time

import numpy as np
from numba import njit

from ...lie.compiled import is_rotation_entries
from ...result import Result
from ..lm.engine import LevenbergMarquardt
from ..lm.layout import B_CHI, B_CLO, B_HI, B_LO, wrapping_joints
from ..lm.run_outcome import LMOutcome
from .memetic_runs import kernel_goal_errors

__all__ = ["EXTRA_STARTS", "NOT_MET", "VelocityBoxStage", "write_step"]

#: Starts drawn inside the box after the run from q_prev did not meet the goals.
EXTRA_STARTS = 4
#: LM steps per run: the box is small, the warm start close.
BOX_ITERATIONS = 30
#: LM's initial damping in the box (the engine's default: 1e-2): the warm start is a control step from the answer.
BOX_DAMPING = 1e-6
#: Bisection steps pulling a colliding answer back towards q_prev (2^-8 of the segment).
COLLISION_BISECTIONS = 8
#: Goal stacks whose engines a stage keeps (a tracker alternating a few goal structures).
_KEPT = 8
#: The message's end when the goals are unmet.
NOT_MET = "; the goals are not met within the velocity box (the answer closest to them inside it)"


@njit(cache=True, nogil=True)
def write_step(box, q_prev, step, lower, upper, wrap, poses, posed, pt, Rt, check_rt):  # pragma: no cover - compiled
    """Write one step's box and targets into the LM kernel's arrays. The velocity box of ``q_prev`` (n,) with
    half-widths ``step`` (n,) (rad or m) into ``box`` (5, n) rows B_LO, B_CLO and B_HI, B_CHI: clipped into ``lower``,
    ``upper`` (n,), joints where ``wrap`` (n,) bool is set unclipped (:meth:`VelocityBoxStage.box`). The targets of the
    goals where ``posed`` (G,) bool is set from their homogeneous poses ``poses`` (G, 4, 4) (m) into ``pt`` (G, 3) and
    ``Rt`` (G, 3, 3) (the others' rows untouched).

    Returns:
        Whether ``Rt[0]`` is a rotation matrix (:func:`~evoik_pin.lie.so3.is_rotation_entries`) when ``check_rt`` (a
        tip pose :func:`~.box_step.step_key` left unchecked); True otherwise."""
    for k in range(q_prev.shape[0]):
        lo = q_prev[k] - step[k]
        hi = q_prev[k] + step[k]
        if not wrap[k]:
            lo, hi = min(max(lo, lower[k]), hi), max(min(hi, upper[k]), lo)
        box[B_LO, k] = lo
        box[B_CLO, k] = lo
        box[B_HI, k] = hi
        box[B_CHI, k] = hi
    for i in range(posed.shape[0]):
        if posed[i]:
            for r in range(3):
                pt[i, r] = poses[i, r, 3]
                for c in range(3):
                    Rt[i, r, c] = poses[i, r, c]
    if not check_rt:
        return True
    T = Rt[0]
    return is_rotation_entries(T[0, 0], T[0, 1], T[0, 2], T[1, 0], T[1, 1], T[1, 2], T[2, 0], T[2, 1], T[2, 2])


# write_step's targets when it writes a box only
_NO_POSES, _NO_POSED = np.zeros((0, 4, 4)), np.zeros(0, dtype=bool)
_NO_PT, _NO_RT = np.zeros((0, 3)), np.zeros((0, 3, 3))


class VelocityBoxStage:
    """Levenberg-Marquardt inside a per-call box, one engine per goal stack kept from call to call, its box and targets
    written in place every call.

    Args:
        robot: the :class:`~evoik_pin.Robot` the problems are of."""

    def __init__(self, robot) -> None:
        self.robot = robot
        self._engines: dict = {}  # id(goal stack) -> (stack, engine)
        self._wrap_for = None  # (lower, upper) arrays the wrap mask is of
        self._wrap = np.zeros(robot.n, dtype=bool)

    def box(self, q_prev: np.ndarray, step: np.ndarray, lower: np.ndarray, upper: np.ndarray
            ) -> tuple[np.ndarray, np.ndarray]:
        """(lo, hi) (n,) of the velocity box around ``q_prev`` (n,) with half-widths ``step`` (n,) inside the bounds
        ``lower``, ``upper`` (n,); full-turn joints unclipped (unwrapped values around q_prev). A ``q_prev`` more than
        ``step`` beyond a bound (not on a full-turn joint) gets the box's one point nearest that bound: the speed
        limit holds first, the joint returns towards its range at full speed."""
        if self._wrap_for is None or self._wrap_for[0] is not lower or self._wrap_for[1] is not upper:
            self._wrap = wrapping_joints(self.robot, lower, upper)
            self._wrap_for = (lower, upper)
        box = np.empty((5, q_prev.shape[0]))
        write_step(box, q_prev, step, lower, upper, self._wrap, _NO_POSES, _NO_POSED, _NO_PT, _NO_RT, False)
        return box[B_LO], box[B_HI]

    def _engine(self, problem, free: bool = False) -> LevenbergMarquardt:
        """The engine of ``problem``'s goal stack, its targets written in: the boxed one (``confine`` per call), or
        with ``free`` the one searching the problem's bounds (its box fixed: the solver's arrays)."""
        stack, pt, Rt = problem.goal_stack()
        key = (id(stack), free)
        kept = self._engines.get(key)
        if kept is None or kept[0] is not stack or (free and (kept[2] is not problem.lower
                                                               or kept[3] is not problem.upper)):
            if len(self._engines) >= _KEPT:
                self._engines.pop(next(iter(self._engines)))
            engine = LevenbergMarquardt(problem, damping=BOX_DAMPING)
            kept = self._engines[key] = (stack, engine, problem.lower, problem.upper)
        engine = kept[1]
        engine.set_targets(pt, Rt)
        return engine

    def solve(self, problem, q_prev: np.ndarray, step: np.ndarray, rng: np.random.Generator | None,
              first: LMOutcome | None = None, t0: float | None = None) -> Result:
        """The answer to ``problem`` (an :class:`~evoik_pin.IKProblem`: its goals or target, tolerances, bounds and
        scene) inside the velocity box of ``q_prev`` (n,) and ``step`` (n,) (rad or m): LM from ``q_prev``; when it
        misses, LM in the full bounds, its share inside the box, it clipped and :data:`EXTRA_STARTS` drawn by ``rng``
        (None: none) run in the box, the best winning. With a scene an answer in collision is pulled back towards
        ``q_prev``. ``first``: that LM run from ``q_prev``, made already by the caller on this stage's boxed engine
        (:mod:`.box_step`), then not made again; ``t0``: the ``time.perf_counter()`` the solve's
        clock starts at (None: now).
        A :class:`Result` whose ``q`` is inside the box, ``success`` when every goal is met (and, with a scene, the
        answer collision-free)."""
        t0 = time.perf_counter() if t0 is None else t0
        lo, hi = self.box(q_prev, step, problem.lower, problem.upper)
        engine = self._engine(problem)
        engine.confine(lo, hi)
        out = engine.run(q_prev, BOX_ITERATIONS) if first is None else first
        evaluations = out.evaluations
        runs = 1
        if not out.converged:
            # the run pinned a joint at the box early (LM's active set only grows) or the box is too small: the
            # unboxed answer nearest q_prev (LM from q_prev in the bounds) shows where the goals are met; its
            # part inside the box along the straight line, and it clipped, start runs in the box, then random ones
            free = self._engine(problem, free=True).run(q_prev, BOX_ITERATIONS)
            evaluations += free.evaluations
            move = free.q - q_prev
            move = np.where(self._wrap, (move + np.pi) % (2 * np.pi) - np.pi, move)  # the short way round
            reach = q_prev + move
            if free.converged and ((reach >= lo) & (reach <= hi)).all():
                out = LMOutcome(reach, free.position_error, free.orientation_error, True, free.iterations,
                                free.evaluations, free.goal_errors, free.cost)
            else:
                share = float(np.min(np.where(np.abs(move) > 0.0, step / np.maximum(np.abs(move), 1e-300), np.inf)))
                starts = [q_prev + min(1.0, share) * move, np.minimum(np.maximum(reach, lo), hi)]
                if rng is not None:
                    starts.extend(lo + (hi - lo) * rng.random((EXTRA_STARTS, self.robot.n)))
                more, _ = engine.run_many(np.array(starts), BOX_ITERATIONS)
                evaluations += more.evaluations
                runs += len(starts)
                if more.converged or more.rank < out.rank:
                    out = more
        q = np.minimum(np.maximum(out.q, lo), hi)  # the kernel keeps q inside; this makes "by construction" literal
        message = f"velocity box: {runs} LM run(s)"
        collision_free = None
        scene = problem.scene
        kernel_errors = True  # the kernel's errors are q's (memetic trusts them the same way)
        if scene is not None:
            collision_free = not scene.in_collision(q, problem.margin)
            if not collision_free:
                q = _pulled_back(scene, problem.margin, q_prev, q, lo, hi)
                collision_free = not scene.in_collision(q, problem.margin)
                kernel_errors = False
                message += "; the answer collided: pulled back towards the previous configuration"
        goals = problem.goals
        if kernel_errors and not problem.goal_sets:
            goal_errors, chosen = kernel_goal_errors(goals, out), [None] * len(goals)
        else:  # a pulled-back answer, goal sets: the errors from one kinematics pass (and the members met)
            goal_errors, chosen = problem.goal_errors_and_chosen(q)
        pos, rot, cost = problem.summary(q, goal_errors)
        met = problem.goals_met(goal_errors)
        success = bool(met and collision_free is not False)
        if not met:
            message += NOT_MET
        return Result(q=q, position_error=float(pos), orientation_error=None if rot is None else float(rot),
                      cost=float(cost), success=success, generations=0, evaluations=int(evaluations),
                      time_s=time.perf_counter() - t0, message=message, method="velocity-box",
                      collision_free=collision_free,
                      goal_errors=problem.reported(goal_errors), chosen=problem.reported(chosen))


def _pulled_back(scene, margin: float, q_prev: np.ndarray, q: np.ndarray, lo: np.ndarray, hi: np.ndarray
                 ) -> np.ndarray:
    """The point of the segment ``q_prev`` -> ``q`` farthest from ``q_prev`` that the exact check passes (bisection;
    ``q_prev`` itself when none does), clipped into the box (q_prev may lie outside it only on a bound)."""
    good, bad = 0.0, 1.0
    for _ in range(COLLISION_BISECTIONS):
        mid = 0.5 * (good + bad)
        if scene.in_collision(q_prev + mid * (q - q_prev), margin):
            bad = mid
        else:
            good = mid
    return np.minimum(np.maximum(q_prev + good * (q - q_prev), lo), hi)
