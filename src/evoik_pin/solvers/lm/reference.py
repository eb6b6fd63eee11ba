"""The reference Levenberg-Marquardt loop: the iteration of :mod:`.kernel` in Python over Pinocchio.

The one Python LM loop in evoik_pin. It states the algorithm readably and is what the compiled kernel is tested
against (tests/test_lm.py: the same steps from the same starts); ``engine="python"`` runs it in production
(about 30-40 us per step against about 1 us compiled). Kinematics come from the robot layer
(``Robot.tip_pose_seen_from_unchecked``, ``fk_unchecked``, ``jacobian_local_unchecked``), the error's
logarithm and its Jacobian from Pinocchio (``pin.log6``, ``pin.Jlog6``).

The iteration (see :mod:`.engine` for the task errors): one step solves the damped normal equations in task
space, ``(E E^T + lambda I) y = e, dq = -E^T y``, capped at ``max_step`` (a trust region), accepted only when
it lowers ``|e|^2`` (lambda shrinks after a success, grows after a failure). Joint limits are an active set
(:meth:`ReferenceLM._step`); full-turn joints wrap; a stall test gives up on a lost cause; near-singular
targets get a geodesic acceleration; a converged run takes one finishing, undamped step.
"""

from __future__ import annotations

import math
import time

import numpy as np
import pinocchio as pin
from scipy.linalg.lapack import dposv

from ...lie import wrap_angle, yaw
from ...problem import IKProblem
from .layout import (
    DEFAULT_DAMPING,
    DEFAULT_MAX_STEP,
    DEFAULT_STALL_RATIO,
    DEFAULT_STALL_WINDOW,
    FINISHED,
    GEO_ALPHA,
    GEO_H,
    GEO_NEAR,
    GEO_SLOW,
    GROW,
    LAMBDA_MAX,
    LAMBDA_MIN,
    SHRINK,
    TWO_PI,
    box_constants,
)
from .outcome import LMOutcome

__all__ = ["ReferenceLM"]

_EYES = {m: np.eye(m) for m in (2, 3, 6)}


def _log6_error(X: pin.SE3):
    """(``log6(X)`` (6,), X, position error m, orientation error rad) of the tip seen from the target, X."""
    e = pin.log6(X).vector
    t = X.translation
    w = e[3:]
    return e, X, math.sqrt(t.dot(t)), math.sqrt(w.dot(w))


class ReferenceLM:
    """Levenberg-Marquardt on the task error of one :class:`~evoik_pin.problem.IKProblem`, as a Python loop.

    Args: as :class:`.engine.LevenbergMarquardt`'s (damping, max_step, stall_window, stall_ratio, finish).
    """

    def __init__(self, problem: IKProblem, damping: float = DEFAULT_DAMPING, max_step: float = DEFAULT_MAX_STEP,
                 stall_window: int = DEFAULT_STALL_WINDOW, stall_ratio: float = DEFAULT_STALL_RATIO,
                 finish: bool = True) -> None:
        self.problem = problem
        self.robot = problem.robot
        target = problem.target
        self.target = target
        self.damping = float(damping)
        self.max_step = float(max_step)
        self.max_step2 = self.max_step**2
        self.stall_window = int(stall_window)
        self.stall_ratio = float(stall_ratio)
        self.finish = bool(finish)
        self.lower, self.upper = problem.lower, problem.upper
        self.wrap, self.any_wrap, self.clip_lo, self.clip_hi, _ = box_constants(self.robot, self.lower, self.upper)
        self.tol_p = float(problem.tolerance)
        self.tol_r = float(problem.rotation_tolerance)
        if target.planar:
            self.kind = "planar"
            self.m = 3 if target.yaw is not None else 2
        elif target.rotation is not None:
            self.kind = "pose"
            self.m = 6
            self.target_inv = pin.SE3(target.rotation, target.position).inverse()
            self.error_at = self._pose_error_at
        else:
            self.kind = "position"
            self.m = 3
        self.eye = _EYES[self.m]

    # ------------------------------------------------------------------ task error
    def _pose_error_at(self, q: np.ndarray):
        """:meth:`error_at` for pose targets: ``T_t^-1 T(q)`` straight from the robot, no intermediate copy."""
        return _log6_error(self.robot.tip_pose_seen_from_unchecked(q, self.target_inv))

    def error_at(self, q: np.ndarray):
        """:meth:`residual` of the tip pose at ``q`` (n,) (pose targets bind a faster twin in ``__init__``)."""
        return self.residual(self.robot.fk_unchecked(q))

    def residual(self, T: pin.SE3):
        """Task error ``e`` (m,), the extra object the Jacobian needs, position error (m), orientation error.

        ``T`` is the tip pose in the base frame.
        """
        target = self.target
        if self.kind == "pose":
            return _log6_error(self.target_inv * T)
        if self.kind == "position":
            e = T.translation - target.position
            return e, T, math.sqrt(e.dot(e)), None
        p = T.translation
        ex, ey = p[0] - target.position[0], p[1] - target.position[1]
        pos = math.hypot(ex, ey)
        if self.m == 2:
            return np.array([ex, ey]), T, pos, None
        eyaw = float(wrap_angle(yaw(T.rotation)[0] - target.yaw))
        return np.array([ex, ey, eyaw]), T, pos, abs(eyaw)

    def task_jacobian(self, q: np.ndarray, extra) -> np.ndarray:
        """``E = de/dq`` (m, n) at ``q``; ``extra`` is what :meth:`residual` returned for the same q."""
        J = self.robot.jacobian_local_unchecked(q)
        if self.kind == "pose":
            return pin.Jlog6(extra).dot(J)
        R = extra.rotation
        if self.kind == "position":
            return R.dot(J[:3])
        Jv = R[:2].dot(J[:3])
        if self.m == 2:
            return Jv
        return np.vstack([Jv, R[2].dot(J[3:])])

    # ------------------------------------------------------------------ the iteration
    def _step(self, q: np.ndarray, on_bound: bool, E: np.ndarray, EEt: np.ndarray, e: np.ndarray,
              lam: float) -> tuple[np.ndarray, bool]:
        """The next configuration and whether it rests on a bound: damped step, trust region, joint limits.

        Limits are an active set: joints resting on a bound (``on_bound`` says whether any does) that the
        descent direction ``-E^T e`` pushes further out are held there, their columns of E zeroed, so the
        free joints take the whole task error; if the step still carries joints past a bound, those are
        fixed at the bound they hit and the step is re-solved once for the others (with the task error
        the fixed joints' moves leave), so it keeps its effect instead of being cut by the clip. Wrapping
        joints are never clipped: they are shifted by 2 pi back into their range.
        """
        lo, hi = self.clip_lo, self.clip_hi
        eye = self.eye
        held = None
        if on_bound:
            g = E.T.dot(e)
            held = ((q <= lo) & (g > 0.0)) | ((q >= hi) & (g < 0.0))
            if np.count_nonzero(held):
                E = E * ~held
                EEt = E.dot(E.T)
            else:
                held = None
        dq = E.T.dot(dposv(EEt + lam * eye, e, overwrite_a=1)[1])  # the step is -dq
        s2 = dq.dot(dq)
        if s2 > self.max_step2:
            dq *= self.max_step / math.sqrt(s2)
        qn = q - dq
        qc = np.minimum(np.maximum(qn, lo), hi)
        fixed = qc != qn
        clipped = np.count_nonzero(fixed) > 0
        if clipped:
            if held is not None:
                fixed |= held
            dfix = np.where(fixed, qc - q, 0.0)
            Ef = E * ~fixed
            dq = Ef.T.dot(dposv(Ef.dot(Ef.T) + lam * eye, e + E.dot(dfix), overwrite_a=1)[1])
            s2 = dq.dot(dq)
            if s2 > self.max_step2:
                dq *= self.max_step / math.sqrt(s2)
            qc = np.minimum(np.maximum(q + dfix - dq, lo), hi)
        if self.any_wrap:
            qc = self._into_box(qc)
        return qc, bool(clipped)

    def run(self, q: np.ndarray, max_iterations: int, deadline: float | None = None) -> LMOutcome:
        """Iterate from ``q`` (n,) (clipped / wrapped into the box first) for at most ``max_iterations`` steps.

        Stops as soon as the problem's tolerances are met, when the damping saturates, on a stall or at
        ``deadline`` (a ``time.perf_counter()`` value, checked before every step). Returns the last accepted
        configuration (the best met).
        """
        q = self._into_box(np.asarray(q, dtype=float))
        on_bound = np.count_nonzero((q <= self.clip_lo) | (q >= self.clip_hi)) > 0
        error_at = self.error_at
        jacobian = self.task_jacobian
        step = self._step
        tol_p, tol_r = self.tol_p, self.tol_r
        e, extra, pos, rot = error_at(q)
        evaluations = 1
        c = e.dot(e)
        if pos <= tol_p and (rot is None or rot <= tol_r):
            return LMOutcome(q, pos, rot, True, 0, evaluations)
        lam = self.damping
        E = EEt = None
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
                E = jacobian(q, extra)
                EEt = E.dot(E.T)
            qn, on_bound_n = step(q, on_bound, E, EEt, e, lam)
            if creeping and not (on_bound or on_bound_n):
                v = self._delta(qn, q)
                a = self._geodesic(e, E, EEt, lam, v, error_at(q + GEO_H * v)[0])
                evaluations += 1
                if a is not None:
                    qn = self._into_box(q + v + 0.5 * a)
            en, extra_n, pos_n, rot_n = error_at(qn)
            evaluations += 1
            cn = en.dot(en)
            if cn < c:
                creeping = GEO_SLOW * c < cn < GEO_NEAR
                q, on_bound, e, extra, pos, rot, c = qn, on_bound_n, en, extra_n, pos_n, rot_n, cn
                if pos <= tol_p and (rot is None or rot <= tol_r):
                    if self.finish and c > FINISHED:
                        return self._finish(q, e, extra, pos, rot, c, it, evaluations)
                    return LMOutcome(q, pos, rot, True, it, evaluations)
                E = None
                lam *= SHRINK
                if lam < LAMBDA_MIN:
                    lam = LAMBDA_MIN
                history.append(c)
                if len(history) > window and c > stall * history[-1 - window]:
                    break
            else:
                lam *= GROW
                if lam > LAMBDA_MAX:
                    break
        return LMOutcome(q, pos, rot, False, it, evaluations)

    def _delta(self, qn: np.ndarray, q: np.ndarray) -> np.ndarray:
        """``qn - q`` with wrapping joints' differences taken on the circle (a wrapped step is no 2 pi jump)."""
        d = qn - q
        if self.any_wrap:
            d = np.where(self.wrap, wrap_angle(d), d)
        return d

    def _geodesic(self, e, E, EEt, lam, v, eh):
        """Geodesic acceleration (Transtrum & Sethna 2012) ``a`` (n,) of the step ``v`` (n,) taken from a
        configuration with task error ``e`` (m,), Jacobian ``E`` (m, n), ``EEt = E E^T`` and damping ``lam``,
        given the error ``eh`` (m,) at ``q + h v``; None when ``|a| > GEO_ALPHA |v| / 2`` (the second-order
        model is not trusted).

        The second directional derivative ``r'' = 2/h ((e(q + h v) - e) / h - E v)`` costs one FK; the
        acceleration ``a = -(E^T E + lam I)^-1 E^T r''`` bends the step ``v + a / 2`` along the valley's
        curvature, so a run creeping along a narrow curved valley (a near-singular target, where the linear
        model holds only for short steps) takes steps several times longer.
        """
        h = GEO_H
        rpp = (2.0 / h) * ((eh - e) / h - E.dot(v))
        a = -E.T.dot(dposv(EEt + lam * self.eye, rpp)[1])
        return a if 2.0 * math.sqrt(a.dot(a)) <= GEO_ALPHA * math.sqrt(v.dot(v)) else None

    def _into_box(self, q: np.ndarray) -> np.ndarray:
        """``q`` (n,) clipped into the box, wrapping joints wrapped into [lower, lower + 2 pi)."""
        q = np.minimum(np.maximum(q, self.clip_lo), self.clip_hi)
        if self.any_wrap:
            out = self.wrap & ((q < self.lower) | (q > self.upper))
            if np.count_nonzero(out):
                q = np.where(out, self.lower + np.mod(q - self.lower, TWO_PI), q)
        return q

    def _finish(self, q, e, extra, pos, rot, c, it, evaluations) -> LMOutcome:
        """One more step once the tolerances are met: at quadratic convergence it takes the error from
        about the tolerance to about 1e-12 or below for the price of one iteration (kept only if better)."""
        E = self.task_jacobian(q, extra)
        # (almost) undamped: any damping left would cap the gain at lambda / (sigma^2 + lambda) per step
        qn, _ = self._step(q, False, E, E.dot(E.T), e, LAMBDA_MIN)
        en, _, pos_n, rot_n = self.error_at(qn)
        if en.dot(en) < c:
            return LMOutcome(qn, pos_n, rot_n, True, it + 1, evaluations + 1)
        return LMOutcome(q, pos, rot, True, it + 1, evaluations + 1)
