"""The reference Levenberg-Marquardt loop (``engine="python"``): :mod:`.engine`'s iteration in Python over Pinocchio
(``pin.log6``, ``pin.Jlog6``), step for step what :mod:`.kernel` compiles (tests/test_lm.py holds the two equal)."""

from __future__ import annotations

import math
import time
from typing import TYPE_CHECKING

import numpy as np
import pinocchio as pin
from scipy.linalg.lapack import dposv

from ...goals.registry import LOG6, POINT
from ...goals.stack import G_RTOL, G_TOL, G_WEIGHT, KIND_PLANAR_YAW
from ...lie import wrap_angle, yaw
from . import layout
from .layout import DEFAULT_DAMPING, DEFAULT_MAX_STEP, DEFAULT_STALL_RATIO, DEFAULT_STALL_WINDOW, LAMBDA_MIN
from .run_outcome import LMOutcome

if TYPE_CHECKING:
    from ...problem import IKProblem

__all__ = ["ReferenceLM"]


def _log6_error(X: pin.SE3):
    """(``log6(X)`` (6,), X, position error m, orientation error rad) of a frame seen from its target, X."""
    e = pin.log6(X).vector
    t = X.translation
    w = e[3:]
    return e, X, math.sqrt(t.dot(t)), math.sqrt(w.dot(w))


class _Goal:
    """One goal of the stack, as the Python loop reads it: its kind, frame, weight, tolerances and target."""

    def __init__(self, robot, kind: int, frame: str, weight: float, tol: float, rtol: float, pt, Rt) -> None:
        self.kind = kind
        self.frame_id = robot.frame_id(frame)
        self.sw = float(weight)  # the square root of the goal's weight
        self.tol, self.rtol = float(tol), float(rtol)
        self.position = np.array(pt, dtype=float)
        if kind == LOG6:
            self.target_inv = pin.SE3(np.array(Rt, dtype=float), self.position).inverse()

    def residual(self, T: pin.SE3):
        """(error rows (m,) unweighted, the extra object its Jacobian needs, position error m, orientation error rad
        or None) for the goal frame's pose ``T`` in the base frame."""
        if self.kind == LOG6:
            return _log6_error(self.target_inv * T)
        if self.kind == POINT:
            e = T.translation - self.position
            return e, T, math.sqrt(e.dot(e)), None
        p = T.translation
        ex, ey = p[0] - self.position[0], p[1] - self.position[1]
        pos = math.hypot(ex, ey)
        if self.kind != KIND_PLANAR_YAW:
            return np.array([ex, ey]), T, pos, None
        eyaw = float(wrap_angle(yaw(T.rotation)[0] - self.position[2]))
        return np.array([ex, ey, eyaw]), T, pos, abs(eyaw)

    def jacobian(self, J: np.ndarray, extra) -> np.ndarray:
        """The goal's rows (m, n), unweighted, from its frame's local Jacobian J (6, n) and :meth:`residual`'s
        extra."""
        if self.kind == LOG6:
            return pin.Jlog6(extra).dot(J)
        R = extra.rotation
        if self.kind == POINT:
            return R.dot(J[:3])
        Jv = R[:2].dot(J[:3])
        if self.kind != KIND_PLANAR_YAW:
            return Jv
        return np.vstack([Jv, R[2].dot(J[3:])])


class ReferenceLM:
    """Levenberg-Marquardt on the task error of one :class:`~evoik_pin.problem.IKProblem` (its goals, or its
    single target on the tip), as a Python loop.

    Args: as :class:`.engine.LevenbergMarquardt`'s (damping, max_step, stall_window, stall_ratio, finish).
    """

    def __init__(self, problem: IKProblem, damping: float = DEFAULT_DAMPING, max_step: float = DEFAULT_MAX_STEP,
                 stall_window: int = DEFAULT_STALL_WINDOW, stall_ratio: float = DEFAULT_STALL_RATIO,
                 finish: bool = True) -> None:
        robot = self.robot = problem.robot
        self.damping, self.max_step, self.finish = float(damping), float(max_step), bool(finish)
        self.max_step2 = self.max_step**2
        self.stall_window, self.stall_ratio = int(stall_window), float(stall_ratio)
        self.lower, self.upper = problem.lower, problem.upper
        self.wrap, self.any_wrap, self.clip_lo, self.clip_hi, _ = layout.box_constants(robot, self.lower, self.upper)
        stack, pt, Rt = problem.goal_stack()
        spec = stack.spec
        self.goals = [_Goal(robot, stack.kinds[g], stack.frames[g], spec[g, G_WEIGHT], spec[g, G_TOL],
                            spec[g, G_RTOL], pt[g], Rt[g]) for g in range(len(stack))]
        self.frame_ids = [g.frame_id for g in self.goals]
        # one goal on the tip: the robot's tip fast paths (for a pose goal, the tip seen from the target directly)
        self._tip = len(self.goals) == 1 and self.frame_ids[0] == robot.frame_id(None) and self.goals[0].sw == 1.0
        self.task_space = stack.rows <= robot.n  # solve the smaller normal equations
        self.eye = np.eye(min(stack.rows, robot.n))

    def error_at(self, q: np.ndarray):
        """(e (rows,), extras (per goal), errors (per goal: (position m, orientation rad or None))) at ``q`` (n,)."""
        if self._tip:
            goal = self.goals[0]
            if goal.kind == LOG6:
                e, X, pos, rot = _log6_error(self.robot.tip_pose_seen_from_unchecked(q, goal.target_inv))
            else:
                e, X, pos, rot = goal.residual(self.robot.fk_unchecked(q))
            return e, (X,), ((pos, rot),)
        parts, extras, errors = [], [], []
        for goal, T in zip(self.goals, self.robot.frame_poses_unchecked(q, self.frame_ids), strict=True):
            e, extra, pos, rot = goal.residual(T)
            parts.append(e if goal.sw == 1.0 else goal.sw * e)
            extras.append(extra)
            errors.append((pos, rot))
        return np.concatenate(parts), extras, errors

    def task_jacobian(self, q: np.ndarray, extras) -> np.ndarray:
        """``E = de/dq`` (rows, n) at ``q``; ``extras``: :meth:`error_at`'s (or one goal's residual's) for that q."""
        if self._tip:
            extra = extras[0] if isinstance(extras, (tuple, list)) else extras
            return self.goals[0].jacobian(self.robot.jacobian_local_unchecked(q), extra)
        blocks = []
        for goal, extra in zip(self.goals, extras, strict=True):
            E = goal.jacobian(self.robot.jacobian_local_unchecked(q, goal.frame_id), extra)
            blocks.append(E if goal.sw == 1.0 else goal.sw * E)
        return np.vstack(blocks)

    def within(self, errors) -> bool:
        """Every goal's errors within its tolerances."""
        return all(pos <= g.tol and (rot is None or rot <= g.rtol) for g, (pos, rot) in zip(self.goals, errors,
                                                                                            strict=True))

    def outcome(self, q, errors, converged: bool, it: int, evaluations: int, c: float) -> LMOutcome:
        """The :class:`LMOutcome` of a run ending at ``q`` with per-goal ``errors`` and cost ``c``."""
        pos = max(p for p, _ in errors)
        rot = max((r for _, r in errors if r is not None), default=None)
        g_err = np.array([(p, np.nan if r is None else r) for p, r in errors]) if len(errors) > 1 else None
        return LMOutcome(q, pos, rot, converged, it, evaluations, g_err, float(c))

    def _normal(self, E: np.ndarray) -> np.ndarray:
        """The normal matrix of the damped step: E E^T (task space) or E^T E (joint space)."""
        return E.dot(E.T) if self.task_space else E.T.dot(E)

    def _solve(self, E: np.ndarray, N: np.ndarray, rhs: np.ndarray, lam: float) -> np.ndarray:
        """dq (n,) = E^T (E E^T + lam I)^-1 rhs = (E^T E + lam I)^-1 E^T rhs, ``N`` being :meth:`_normal` of E."""
        if self.task_space:
            return E.T.dot(dposv(N + lam * self.eye, rhs, overwrite_a=1)[1])
        return dposv(N + lam * self.eye, E.T.dot(rhs), overwrite_a=1)[1]

    def _trust_step(self, E: np.ndarray, N: np.ndarray, rhs: np.ndarray, lam: float) -> np.ndarray:
        """:meth:`_solve`'s dq, scaled down to length ``max_step`` when longer (the trust region)."""
        dq = self._solve(E, N, rhs, lam)
        s2 = dq.dot(dq)
        if s2 > self.max_step2:
            dq *= self.max_step / math.sqrt(s2)
        return dq

    def _step(self, q: np.ndarray, on_bound: bool, E: np.ndarray, N: np.ndarray, e: np.ndarray,
              lam: float) -> tuple[np.ndarray, bool]:
        """The next configuration and whether it rests on a bound (``N``: :meth:`_normal` of ``E``): the damped step
        in the trust region; joints on a bound (``on_bound``: any is) that ``-E^T e`` pushes out are held, joints the
        step carries past one fixed at it and the step re-solved for the others; wrapping joints wrapped instead."""
        lo, hi = self.clip_lo, self.clip_hi
        held = None
        if on_bound:
            g = E.T.dot(e)
            held = ((q <= lo) & (g > 0.0)) | ((q >= hi) & (g < 0.0))
            if np.count_nonzero(held):
                E = E * ~held
                N = self._normal(E)
            else:
                held = None
        qn = q - self._trust_step(E, N, e, lam)
        qc = np.minimum(np.maximum(qn, lo), hi)
        fixed = qc != qn
        clipped = np.count_nonzero(fixed) > 0
        if clipped:
            if held is not None:
                fixed |= held
            dfix = np.where(fixed, qc - q, 0.0)
            Ef = E * ~fixed
            dq = self._trust_step(Ef, self._normal(Ef), e + E.dot(dfix), lam)
            qc = np.minimum(np.maximum(q + dfix - dq, lo), hi)
        if self.any_wrap:
            qc = self._into_box(qc)
        return qc, bool(clipped)

    def run(self, q: np.ndarray, max_iterations: int, deadline: float | None = None) -> LMOutcome:
        """:meth:`.engine.LevenbergMarquardt.run`, ``deadline`` checked before every step."""
        q = self._into_box(np.asarray(q, dtype=float))
        on_bound = np.count_nonzero((q <= self.clip_lo) | (q >= self.clip_hi)) > 0
        e, extras, errors = self.error_at(q)
        evaluations = 1
        c = e.dot(e)
        if self.within(errors):
            return self.outcome(q, errors, True, 0, evaluations, c)
        lam = self.damping
        E = N = None
        window = self.stall_window
        stall = self.stall_ratio**2  # compared on |e|^2
        history = [c]
        it = 0
        creeping = False  # the last accepted step did not halve |e| near the target: accelerate the next
        while it < max_iterations:
            if deadline is not None and time.perf_counter() >= deadline:
                break
            it += 1
            if E is None:
                E = self.task_jacobian(q, extras)
                N = self._normal(E)
            qn, on_bound_n = self._step(q, on_bound, E, N, e, lam)
            if creeping and not (on_bound or on_bound_n):
                v = qn - q
                if self.any_wrap:  # wrapping joints' differences on the circle (a wrapped step is no 2 pi jump)
                    v = np.where(self.wrap, wrap_angle(v), v)
                a = self._geodesic(e, E, N, lam, v, self.error_at(q + layout.GEO_H * v)[0])
                evaluations += 1
                if a is not None:
                    qn = self._into_box(q + v + 0.5 * a)
            en, extras_n, errors_n = self.error_at(qn)
            evaluations += 1
            cn = en.dot(en)
            if cn < c:
                creeping = layout.GEO_SLOW * c < cn < layout.GEO_NEAR
                q, on_bound, e, extras, errors, c = qn, on_bound_n, en, extras_n, errors_n, cn
                if self.within(errors):
                    if self.finish and c > layout.FINISHED:  # one more, (almost) undamped step, kept if better
                        E = self.task_jacobian(q, extras)  # and every goal stays met (the kernel's rule)
                        qn, _ = self._step(q, False, E, self._normal(E), e, LAMBDA_MIN)
                        en, _, errors_n = self.error_at(qn)
                        it, evaluations, cn = it + 1, evaluations + 1, en.dot(en)
                        if cn < c and self.within(errors_n):
                            q, errors, c = qn, errors_n, cn
                    return self.outcome(q, errors, True, it, evaluations, c)
                E = None
                lam = max(lam * layout.SHRINK, LAMBDA_MIN)
                history.append(c)
                if len(history) > window and c > stall * history[-1 - window]:
                    break
            else:
                lam *= layout.GROW
                if lam > layout.LAMBDA_MAX:
                    break
        return self.outcome(q, errors, False, it, evaluations, c)

    def _geodesic(self, e, E, N, lam, v, eh):
        """Geodesic acceleration (Transtrum & Sethna 2012) ``a = -(E^T E + lam I)^-1 E^T r''`` (n,) of the step v
        (n,) from a configuration with error e, Jacobian E, its normal matrix N and damping lam, given the error eh
        at ``q + h v``: ``r'' = 2/h ((eh - e) / h - E v)``; the step ``v + a / 2`` bends along a narrow curved valley
        (a near-singular target). None when ``|a| > GEO_ALPHA |v| / 2``.
        """
        h = layout.GEO_H
        rpp = (2.0 / h) * ((eh - e) / h - E.dot(v))
        a = -self._solve(E, N, rpp, lam)
        return a if 2.0 * math.sqrt(a.dot(a)) <= layout.GEO_ALPHA * math.sqrt(v.dot(v)) else None

    def _into_box(self, q: np.ndarray) -> np.ndarray:
        """``q`` (n,) clipped into the box, wrapping joints wrapped into [lower, lower + 2 pi)."""
        q = np.minimum(np.maximum(q, self.clip_lo), self.clip_hi)
        if self.any_wrap:
            out = self.wrap & ((q < self.lower) | (q > self.upper))
            if np.count_nonzero(out):
                q = np.where(out, self.lower + np.mod(q - self.lower, layout.TWO_PI), q)
        return q
