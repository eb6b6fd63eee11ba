"""Levenberg-Marquardt polish: Newton-type IK steps on the task error, one configuration or a batch.

The task error ``e(q)`` and its Jacobian ``E(q) = de/dq`` depend on the target:

* pose target (6 rows): ``e = log6(T_t^-1 T(q))``, the SE(3) logarithm (m, rad) of the tip pose seen from
  the target frame, and ``E = Jlog6(T_t^-1 T(q)) J_local(q)`` (Pinocchio's ``pin.log6`` / ``pin.Jlog6``
  and the tip-frame Jacobian): since ``T(q + dq) = T(q) exp(J_local dq)``, ``e(q + dq) = e + E dq + O(dq^2)``.
  Its rotational part is ``log3(R_t^T R)``, whose norm is the rotation angle, and it vanishes exactly at
  the target. (A decoupled error ``(R_t^T (p - p_t), log3(R_t^T R))``, whose parts are exactly the two
  judged errors, was measured against it: slower in the Python loop and no better, docs/BENCHMARKS.md);
* position target (3 rows): ``e = p(q) - p_t`` in the base frame, ``E = R(q) J_local[:3]``;
* planar target (x, y[, yaw]): ``e = (p_x - x_t, p_y - y_t[, wrap(yaw(q) - yaw_t)])`` with the matching rows
  of the base-frame Jacobian.

One step solves the damped normal equations in task space (at most 6 x 6, whatever the number of
joints n)::

    (E E^T + lambda I) y = e,        dq = -E^T y  ( = -(E^T E + lambda I)^-1 E^T e )

with the step length capped at ``max_step`` (a trust region), and is accepted only when it lowers
``|e|^2`` (Levenberg-Marquardt: ``lambda`` shrinks after a success, grows after a failure). Joint limits
are respected exactly, by a small active set: joints resting on a bound that the descent direction pushes
outward are held there, and joints a step would carry past a bound are fixed at it while the step is
re-solved once for the others, so the free joints compensate instead of the whole step being cut.
Revolute joints whose range spans at least 2 pi (continuous joints, UR-style +-2 pi joints) are wrapped
back into their range instead of being clipped, so a step across +-pi is never blocked. A run gives up
on a stall (``|e|`` not halved in a few steps: a limit or a local minimum holds it), so the caller can
restart elsewhere; once it meets the tolerances it takes one more, undamped step (quadratic convergence:
about 1e-12 instead of just under the tolerance, for one iteration). Near-singular targets (smallest
singular value of E around 1e-3 at the solution) put a run in a narrow curved valley where the linear model
holds only for short steps: it reaches |e| ~ 1e-4 quickly, then creeps for 30-80 steps. There, and only
there (an accepted step that did not halve ``|e|`` while ``|e| < 1e-2``), the step gets a geodesic
acceleration (Transtrum & Sethna 2012: the error's second directional derivative from one extra FK),
which bends it along the valley and cuts those runs to about a third of the steps.

:class:`LevenbergMarquardt` has two engines for one iteration. ``engine="compiled"`` (the default, pose and
position targets) runs a whole LM run in one call of the numba kernel :func:`.lm_kernel.lm_run` (about 1-2 us
per step); ``engine="python"`` (:meth:`LevenbergMarquardt.run_python`, and every planar target) works
through Pinocchio one configuration at a time (``Robot.tip_pose_seen_from_unchecked`` for pose targets,
``Robot.fk_unchecked``, ``Robot.jacobian_local_unchecked``): a handful of C++ calls and small NumPy
products per step, about 30 us. The tests hold the two to the same steps from the same starts.
:func:`compiled_pairs` runs the kernel on many (start, target) pairs in one call, for
:func:`evoik_pin.solve_many`.
:meth:`LevenbergMarquardt.run_many` runs K starts in lockstep (per-configuration kinematics, one batched
NumPy pass for the linear algebra of all K). :func:`batch_levenberg_marquardt` runs the iteration on many
(configuration, target) pairs at once with the NumPy batch kinematics (``Robot.fk_jacobian_batch``), for
:func:`evoik_pin.solve_many`.
"""

from __future__ import annotations

import math
import time
import weakref
from dataclasses import dataclass

import numpy as np
import pinocchio as pin
from scipy.linalg.lapack import dposv

from ..errors import OptionError
from ..problem import IKProblem, Target

__all__ = ["ENGINES", "BatchOutcome", "LMOutcome", "LevenbergMarquardt", "batch_levenberg_marquardt", "compiled_kernel",
           "compiled_pairs", "wrapping_joints"]

TWO_PI = 2.0 * np.pi
#: LM engines: "compiled" runs pose and position targets in the numba kernel of :mod:`.lm_kernel` (planar
#: targets always take the Python loop); "python" runs the Python loop over Pinocchio's kinematics.
ENGINES = ("compiled", "python")
#: Initial damping lambda (m^2, rad^2): small against the entries of E E^T (about reach^2 ~ 0.1-1 m^2).
DEFAULT_DAMPING = 1e-2
#: Steps allowed to one LM run started from a seed (converging runs need about 5-15).
DEFAULT_ITERATIONS = 30
#: Stall test: a run stops when |e| has not dropped below DEFAULT_STALL_RATIO times its value
#: DEFAULT_STALL_WINDOW accepted steps earlier.
DEFAULT_STALL_WINDOW, DEFAULT_STALL_RATIO = 4, 0.5
#: Largest length |dq| of one step (rad or m, Euclidean); longer steps are scaled down (trust region).
DEFAULT_MAX_STEP = 1.0
_LAMBDA_MIN, _LAMBDA_MAX = 1e-12, 1e4
_SHRINK, _GROW = 0.2, 8.0
_BATCH_STALL_WINDOW = 6
#: |e|^2 below which a converged run needs no finishing step (|e| = 1e-12: about FK round-off for 1 m arms).
_FINISHED = 1e-24
#: Geodesic acceleration (see :meth:`LevenbergMarquardt._geodesic`): used after an accepted step that left
#: |e|^2 above _GEO_SLOW times its value (|e| not halved) while |e|^2 < _GEO_NEAR (|e| < 1 cm + rad: a
#: run creeping along a narrow curved valley, the signature of a near-singular target), so the fast,
#: quadratic phase pays nothing; kept when |a| <= _GEO_ALPHA |v| / 2; _GEO_H is the finite-difference step.
_GEO_SLOW, _GEO_NEAR, _GEO_ALPHA, _GEO_H = 0.25, 1e-4, 0.75, 0.1
#: Layout of the compiled kernel's ``params`` vector (:func:`.lm_kernel.lm_run`) and rows of its ``box``.
_P_TOL, _P_RTOL, _P_DAMPING, _P_MAX_STEP, _P_STALL_WINDOW, _P_STALL_RATIO, _P_FINISH, _P_ITERATIONS, _P_POSE = range(9)
_B_LO, _B_HI, _B_CLO, _B_CHI, _B_WRAP = range(5)


def wrapping_joints(robot, lower: np.ndarray, upper: np.ndarray) -> np.ndarray:
    """(n,) bool: revolute joints whose search range spans a full turn, so wrapping by 2 pi keeps them inside.

    Every continuous joint qualifies (its range is [-pi, pi]), and so does a UR-style [-2 pi, 2 pi] joint.
    """
    return robot.revolute & ((upper - lower) >= TWO_PI - 1e-9)


_EYES = {m: np.eye(m) for m in (2, 3, 6)}
_BOX_CACHE: dict = {}


def _box_constants(robot, lower: np.ndarray, upper: np.ndarray):
    """(wrap mask, any wrap, clip lower, clip upper, kernel box) of a box, cached: the same box recurs every solve.

    The clip bounds are the box with +-inf for wrapping joints, which are never clipped. The kernel box is
    the (5, n) array of :func:`.lm_kernel.lm_run`: lower, upper, clip lower, clip upper, wrap (0/1).
    """
    key = (id(robot), lower.tobytes(), upper.tobytes())
    hit = _BOX_CACHE.get(key)
    if hit is None or hit[0]() is not robot:  # a weak reference: the cache must not keep robots alive
        wrap = wrapping_joints(robot, lower, upper)
        clip = (np.where(wrap, -np.inf, lower), np.where(wrap, np.inf, upper))
        box = np.empty((5, robot.n))
        box[[_B_LO, _B_HI, _B_CLO, _B_CHI, _B_WRAP]] = lower, upper, *clip, wrap
        hit = (weakref.ref(robot), (wrap, bool(wrap.any()), *clip, box))
        if len(_BOX_CACHE) > 64:
            _BOX_CACHE.clear()
        _BOX_CACHE[key] = hit
    return hit[1]


def _kernel_params(tolerance: float, rotation_tolerance: float, pose: bool, iterations: int = 0,
                   damping: float = DEFAULT_DAMPING, max_step: float = DEFAULT_MAX_STEP,
                   stall_window: int = DEFAULT_STALL_WINDOW, stall_ratio: float = DEFAULT_STALL_RATIO,
                   finish: bool = True) -> np.ndarray:
    """The (9,) ``params`` vector of :func:`.lm_kernel.lm_run` (layout: the ``_P_*`` indices)."""
    params = np.empty(9)
    params[[_P_TOL, _P_RTOL, _P_DAMPING, _P_MAX_STEP, _P_STALL_WINDOW, _P_STALL_RATIO, _P_FINISH, _P_ITERATIONS,
            _P_POSE]] = (tolerance, rotation_tolerance, damping, max_step, stall_window, stall_ratio, float(finish),
                         iterations, float(pose))
    return params


_KERNEL = []


def compiled_kernel():
    """:func:`.lm_kernel.lm_run`, ready to run: the first call imports numba (~0.3 s) and runs the kernel (and
    :func:`.lm_kernel.lm_run_pairs`) once on a one-joint chain, so that numba loads the machine code from its
    on-disk cache (~0.5 s) or, the first time after an install, compiles it (~15 s) here, and not inside a
    solve's time budget. Later calls return at once. :func:`~evoik_pin.solvers.memetic.memetic` calls it
    before starting its clock."""
    if not _KERNEL:
        from .lm_kernel import lm_run, lm_run_pairs

        FR, Fp = np.tile(np.eye(3), (2, 1, 1)), np.zeros((2, 3))
        box = np.zeros((5, 1))
        box[[_B_LO, _B_CLO]], box[[_B_HI, _B_CHI]] = -1.0, 1.0
        params = _kernel_params(1e-6, 1e-6, pose=True, iterations=1)
        # the argument types of LevenbergMarquardt.run and compiled_pairs (C-contiguous float64 / bool arrays,
        # a Python bool)
        rev = np.ones(1, dtype=bool)
        lm_run(np.zeros(1), FR, Fp, rev, box, False, np.zeros(3), np.eye(3), params, np.empty(1))
        lm_run_pairs(np.zeros((1, 1)), FR, Fp, rev, box, False, np.zeros((1, 3)), np.eye(3)[None].copy(), params,
                     np.empty((1, 1)), np.empty((1, 5)))
        _KERNEL.extend((lm_run, lm_run_pairs))
    return _KERNEL[0]


def _wrap_into(q: np.ndarray, lower: np.ndarray, mask: np.ndarray) -> np.ndarray:
    """``q`` with the ``mask`` entries shifted by multiples of 2 pi into [lower, lower + 2 pi)."""
    q = q.copy()
    q[mask] = lower[mask] + np.mod(q[mask] - lower[mask], TWO_PI)
    return q


def _angle_wrap(a):
    return (a + np.pi) % TWO_PI - np.pi


def _log6_error(X: pin.SE3):
    """(``log6(X)`` (6,), X, position error m, orientation error rad) of the tip seen from the target, X."""
    e = pin.log6(X).vector
    t = X.translation
    w = e[3:]
    return e, X, math.sqrt(t.dot(t)), math.sqrt(w.dot(w))


@dataclass
class LMOutcome:
    """End state of one :meth:`LevenbergMarquardt.run`.

    Attributes:
        q: (n,) final configuration, inside the search box.
        position_error: m; orientation_error: rad (None when the target has no orientation).
        converged: the errors meet the problem's tolerances.
        iterations: steps tried; evaluations: forward-kinematics calls (one per step tried, plus one).
    """

    q: np.ndarray
    position_error: float
    orientation_error: float | None
    converged: bool
    iterations: int
    evaluations: int

    @property
    def error(self) -> float:
        """Position error + orientation error (m + rad): the score used to rank failed attempts."""
        return self.position_error + (self.orientation_error or 0.0)


class LevenbergMarquardt:
    """Levenberg-Marquardt on the task error of one :class:`~evoik_pin.problem.IKProblem`.

    Args:
        problem: robot, target, search box and tolerances (``tolerance`` m, ``rotation_tolerance`` rad).
        damping: initial lambda (m^2 / rad^2 scale), adapted per step.
        max_step: largest length ``|dq|`` of one step (rad or m, Euclidean norm over the joints).
        stall_window, stall_ratio: give up when ``|e|`` has not dropped below ``stall_ratio`` times its value
            ``stall_window`` accepted steps earlier (a limit or a local minimum holds the arm), so the
            caller can restart elsewhere instead of spending iterations on a lost cause.
        finish: once the tolerances are met, take one more step (kept if it lowers the error): near the
            solution LM converges quadratically, so one step takes an answer just inside a 1e-6 tolerance to
            about 1e-12, for the price of one iteration.
    """

    def __init__(self, problem: IKProblem, damping: float = DEFAULT_DAMPING, max_step: float = DEFAULT_MAX_STEP,
                 stall_window: int = DEFAULT_STALL_WINDOW, stall_ratio: float = DEFAULT_STALL_RATIO,
                 finish: bool = True, engine: str = "compiled") -> None:
        if engine not in ENGINES:
            raise OptionError(f"LM engine {engine!r} unknown; use one of {list(ENGINES)}")
        self.engine = engine
        self.finish = bool(finish)
        self.problem = problem
        robot = problem.robot
        self.robot = robot
        self.n = robot.n
        target: Target = problem.target
        self.target = target
        self.damping = float(damping)
        self.max_step = float(max_step)
        self.max_step2 = self.max_step**2
        self.stall_window = int(stall_window)
        self.stall_ratio = float(stall_ratio)
        lo, hi = problem.lower, problem.upper
        self.lower, self.upper = lo, hi
        self.wrap, self.any_wrap, self.clip_lo, self.clip_hi, box = _box_constants(robot, lo, hi)
        self.tol_p = float(problem.tolerance)
        self.tol_r = float(problem.rotation_tolerance)
        if target.planar:
            self.kind = "planar"
            self.m = 3 if target.yaw is not None else 2
            self.target_xy = target.position.copy()
            self.target_yaw = None if target.yaw is None else float(target.yaw)
        elif target.rotation is not None:
            self.kind = "pose"
            self.m = 6
            self.residual = self._residual_pose
            self.error_at = self._pose_error_at
            self.target_se3 = pin.SE3(target.rotation, target.position)
            self.target_inv = self.target_se3.inverse()
        else:
            self.kind = "position"
            self.m = 3
            self.target_p = target.position.copy()
        self.eye = _EYES[self.m]
        self._kernel = None
        if engine == "compiled" and self.kind != "planar":
            self._kernel = compiled_kernel()
            FR, Fp, rev = robot.chain_constants()
            self._chain = (FR, Fp, rev)
            self._box = box
            self._pt = np.ascontiguousarray(target.position, dtype=float)
            self._Rt = np.ascontiguousarray(target.rotation if target.rotation is not None else _EYES[3], dtype=float)
            self._params = _kernel_params(self.tol_p, self.tol_r, self.kind == "pose", 0, self.damping,
                                          self.max_step, self.stall_window, self.stall_ratio, self.finish)

    # ------------------------------------------------------------------ task error
    def _residual_pose(self, T: pin.SE3):
        """:meth:`residual` for pose targets (bound as ``self.residual``: the hot path skips the dispatch)."""
        return _log6_error(self.target_se3.actInv(T))

    def _pose_error_at(self, q: np.ndarray):
        """:meth:`error_at` for pose targets: ``T_t^-1 T(q)`` straight from the robot, no intermediate copy."""
        return _log6_error(self.robot.tip_pose_seen_from_unchecked(q, self.target_inv))

    def error_at(self, q: np.ndarray):
        """:meth:`residual` of the tip pose at ``q`` (n,) (bound per target kind in ``__init__``)."""
        return self.residual(self.robot.fk_unchecked(q))

    def residual(self, T: pin.SE3):
        """Task error ``e`` (m,), the extra object the Jacobian needs, position error (m), orientation error.

        ``T`` is the tip pose in the base frame.
        """
        if self.kind == "pose":
            return self._residual_pose(T)
        if self.kind == "position":
            e = T.translation - self.target_p
            return e, T, math.sqrt(e.dot(e)), None
        p = T.translation
        ex, ey = p[0] - self.target_xy[0], p[1] - self.target_xy[1]
        pos = math.hypot(ex, ey)
        if self.m == 2:
            return np.array([ex, ey]), T, pos, None
        R = T.rotation
        eyaw = float(_angle_wrap(math.atan2(R[1, 0], R[0, 0]) - self.target_yaw))
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

    def converged(self, pos: float, rot: float | None) -> bool:
        return pos <= self.tol_p and (rot is None or rot <= self.tol_r)

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
            if np.count_nonzero(held):  # (count_nonzero: a C call; ndarray.any() costs ~1 us of Python here)
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
            lower, upper = self.lower, self.upper
            out = self.wrap & ((qc < lower) | (qc > upper))
            if np.count_nonzero(out):
                qc = _wrap_into(qc, lower, out)
        return qc, bool(clipped)

    def run(self, q: np.ndarray, max_iterations: int, deadline: float | None = None) -> LMOutcome:
        """Iterate from ``q`` (n,) (clipped / wrapped into the box first) for at most ``max_iterations`` steps.

        Stops as soon as the problem's tolerances are met, when the damping saturates, on a stall (see
        the class docstring) or at ``deadline`` (a ``time.perf_counter()`` value). Returns the last accepted
        configuration (the best met). The compiled engine (pose and position targets) runs the whole
        iteration in one call of :func:`.lm_kernel.lm_run` and checks ``deadline`` only before it starts (a
        run is at most ``max_iterations`` steps of about 1-2 us); the Python engine is :meth:`run_python`.
        """
        if self._kernel is None:
            return self.run_python(q, max_iterations, deadline)
        if deadline is not None and time.perf_counter() >= deadline:
            max_iterations = 0  # as run_python: the start is evaluated, no step taken
        params = self._params
        params[_P_ITERATIONS] = max_iterations
        out = np.empty(self.n)
        FR, Fp, rev = self._chain
        q = np.ascontiguousarray(q, dtype=float)
        pos, rot, converged, it, evaluations = self._kernel(q, FR, Fp, rev, self._box, self.any_wrap, self._pt,
                                                            self._Rt, params, out)
        return LMOutcome(out, pos, rot if self.kind == "pose" else None, converged, it, evaluations)

    def run_python(self, q: np.ndarray, max_iterations: int, deadline: float | None = None) -> LMOutcome:
        """:meth:`run` as a Python loop over Pinocchio's kinematics (the reference the compiled kernel is tested
        against, and the engine of planar targets)."""
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
                a = self._geodesic_one(e, E, EEt, lam, v, error_at(q + _GEO_H * v)[0])
                evaluations += 1
                if a is not None:
                    qn = self._into_box(q + v + 0.5 * a)
            en, extra_n, pos_n, rot_n = error_at(qn)
            evaluations += 1
            cn = en.dot(en)
            if cn < c:
                creeping = _GEO_SLOW * c < cn < _GEO_NEAR
                q, on_bound, e, extra, pos, rot, c = qn, on_bound_n, en, extra_n, pos_n, rot_n, cn
                if pos <= tol_p and (rot is None or rot <= tol_r):
                    if self.finish and c > _FINISHED:
                        return self._finish(q, e, extra, pos, rot, c, lam, it, evaluations)
                    return LMOutcome(q, pos, rot, True, it, evaluations)
                E = None
                lam *= _SHRINK
                if lam < _LAMBDA_MIN:
                    lam = _LAMBDA_MIN
                history.append(c)
                if len(history) > window and c > stall * history[-1 - window]:
                    break
            else:
                lam *= _GROW
                if lam > _LAMBDA_MAX:
                    break
        return LMOutcome(q, pos, rot, False, it, evaluations)

    def _delta(self, qn: np.ndarray, q: np.ndarray) -> np.ndarray:
        """``qn - q`` with wrapping joints' differences taken on the circle (a wrapped step is no 2 pi jump)."""
        d = qn - q
        if self.any_wrap:
            d = np.where(self.wrap, _angle_wrap(d), d)
        return d

    def _geodesic_one(self, e, E, EEt, lam, v, eh):
        """:meth:`_geodesic` for one configuration (``e`` (m,), ``E`` (m, n), ``EEt``, ``v`` (n,), ``eh``
        (m,)), with one Cholesky solve: the hot path of :meth:`run`. Returns ``a`` (n,) or None."""
        h = _GEO_H
        rpp = (2.0 / h) * ((eh - e) / h - E.dot(v))
        a = -E.T.dot(dposv(EEt + lam * self.eye, rpp)[1])
        return a if 2.0 * math.sqrt(a.dot(a)) <= _GEO_ALPHA * math.sqrt(v.dot(v)) else None

    def _geodesic(self, q, e, E, EEt, lam, v, eh):
        """Geodesic accelerations (Transtrum & Sethna 2012) of K steps ``v`` (K, n) taken from one or K
        configurations ``q`` with task errors ``e``, Jacobians ``E``, ``EEt = E E^T`` and dampings ``lam``
        (one configuration: (n,), (m, n), (m, m), float; or K: leading K axes, ``EEt`` None to compute it),
        given the errors ``eh`` (K, m) at ``q + h v``.

        The second directional derivative ``r'' = 2/h ((e(q + h v) - e) / h - E v)`` costs one FK; the
        acceleration ``a = -(E^T E + lam I)^-1 E^T r''`` bends the step ``v + a / 2`` along the valley's
        curvature, so a run creeping along a narrow curved valley (a near-singular target, where the linear
        model holds only for short steps) takes steps several times longer. Returns a list: ``a`` (n,) per
        step, or None where ``|a| > _GEO_ALPHA |v| / 2`` (the second-order model is not trusted).
        """
        h = _GEO_H
        E = np.asarray(E)
        if E.ndim == 2:
            E, EEt, e, lam = E[None], EEt[None], np.asarray(e)[None], np.array([lam])
        elif EEt is None:
            EEt = E @ E.transpose(0, 2, 1)
        rpp = (2.0 / h) * ((eh - e) / h - (E @ v[:, :, None])[:, :, 0])
        y = np.linalg.solve(EEt + np.asarray(lam)[:, None, None] * self.eye, rpp[:, :, None])
        a = -(E.transpose(0, 2, 1) @ y)[:, :, 0]
        ok = 2.0 * np.sqrt((a * a).sum(axis=1)) <= _GEO_ALPHA * np.sqrt((v * v).sum(axis=1))
        return [a[k] if ok[k] else None for k in range(a.shape[0])]

    def _into_box(self, q: np.ndarray) -> np.ndarray:
        """``q`` (n,) or (K, n) clipped into the box, wrapping joints wrapped into their range."""
        q = np.minimum(np.maximum(q, self.clip_lo), self.clip_hi)
        if self.any_wrap:
            out = self.wrap & ((q < self.lower) | (q > self.upper))
            if np.count_nonzero(out):
                q = np.where(out, self.lower + np.mod(q - self.lower, TWO_PI), q)
        return q

    def _finish(self, q, e, extra, pos, rot, c, lam, it, evaluations) -> LMOutcome:
        """One more step once the tolerances are met: at quadratic convergence it takes the error from
        about the tolerance to about 1e-12 or below for the price of one iteration (kept only if better)."""
        E = self.task_jacobian(q, extra)
        # (almost) undamped: any damping left would cap the gain at lambda / (sigma^2 + lambda) per step
        qn, _ = self._step(q, False, E, E.dot(E.T), e, _LAMBDA_MIN)
        en, _, pos_n, rot_n = self.error_at(qn)
        if en.dot(en) < c:
            return LMOutcome(qn, pos_n, rot_n, True, it + 1, evaluations + 1)
        return LMOutcome(q, pos, rot, True, it + 1, evaluations + 1)

    def run_many(self, Q: np.ndarray, max_iterations: int, deadline: float | None = None
                 ) -> tuple[LMOutcome, int]:
        """LM from K starts ``Q`` (K, n) in lockstep; stops as soon as one start meets the tolerances.

        The kinematics stay per configuration (Pinocchio), but the linear algebra of all K runs (limits,
        damped normal equations, trust region) is one batched NumPy pass per iteration, so K runs cost far
        less than K sequential :meth:`run` calls when most of them fail (hard targets, restarts).
        Each run keeps its own lambda and is dropped on a stall (``|e|`` not halved over
        ``stall_window`` iterations) or a saturated lambda; all stop at ``deadline`` (as in :meth:`run`).

        Returns:
            (outcome of the converged run, or of the run with the lowest error; index of that start).
            ``iterations`` and ``evaluations`` count all K runs.
        """
        Q = self._into_box(np.array(Q, dtype=float, ndmin=2))
        K, n = Q.shape
        error_at, jacobian = self.error_at, self.task_jacobian
        tol_p, tol_r = self.tol_p, self.tol_r
        m = self.m
        e = np.empty((K, m))
        E = np.empty((K, m, n))
        extra: list = [None] * K
        pos = np.empty(K)
        rot = np.empty(K) if self.target.has_orientation else None
        for k in range(K):
            e[k], extra[k], pos[k], r = error_at(Q[k])
            if rot is not None:
                rot[k] = r
        evaluations = K

        def outcome(k, converged, it):
            return LMOutcome(Q[k].copy(), float(pos[k]), None if rot is None else float(rot[k]), converged, it,
                             evaluations), k

        done = (pos <= tol_p) if rot is None else (pos <= tol_p) & (rot <= tol_r)
        if done.any():
            return outcome(int(done.argmax()), True, 0)
        c = (e * e).sum(axis=1)
        lam = np.full(K, self.damping)
        alive = np.ones(K, dtype=bool)
        need_J = np.ones(K, dtype=bool)
        creeping = np.zeros(K, dtype=bool)  # as in run: geodesic acceleration for the next step
        checkpoint = np.full(K, np.inf)
        eye = self.eye
        lo, hi = self.clip_lo, self.clip_hi
        ms, ms2 = self.max_step, self.max_step2
        it = 0
        while it < max_iterations:
            idx = np.nonzero(alive)[0]
            if idx.size == 0 or (deadline is not None and time.perf_counter() >= deadline):
                break
            it += 1
            for k in idx[need_J[idx]]:
                E[k] = jacobian(Q[k], extra[k])
            need_J[idx] = False
            q, Ea, ea, la = Q[idx], E[idx], e[idx], lam[idx]
            g = (Ea.transpose(0, 2, 1) @ ea[:, :, None])[:, :, 0]  # E^T e: -g is the descent direction
            held = ((q <= lo) & (g > 0.0)) | ((q >= hi) & (g < 0.0))
            Eh = Ea * ~held[:, None, :]
            EhT = Eh.transpose(0, 2, 1)
            dq = (EhT @ np.linalg.solve(Eh @ EhT + la[:, None, None] * eye, ea[:, :, None]))[:, :, 0]
            s2 = (dq * dq).sum(axis=1)
            dq *= np.where(s2 > ms2, ms / np.sqrt(np.maximum(s2, 1e-300)), 1.0)[:, None]
            qn = q - dq
            qc = np.minimum(np.maximum(qn, lo), hi)
            fixed = qc != qn
            redo = fixed.any(axis=1)
            if redo.any():  # the joints that hit a bound stay there; the others re-solve (see _step)
                r = np.nonzero(redo)[0]
                fx = fixed[r] | held[r]
                dfix = np.where(fx, qc[r] - q[r], 0.0)
                Ef = Ea[r] * ~fx[:, None, :]
                EfT = Ef.transpose(0, 2, 1)
                rhs = ea[r] + (Ea[r] @ dfix[:, :, None])[:, :, 0]
                d2 = (EfT @ np.linalg.solve(Ef @ EfT + la[r, None, None] * eye, rhs[:, :, None]))[:, :, 0]
                s2 = (d2 * d2).sum(axis=1)
                d2 *= np.where(s2 > ms2, ms / np.sqrt(np.maximum(s2, 1e-300)), 1.0)[:, None]
                qc[r] = np.minimum(np.maximum(q[r] + dfix - d2, lo), hi)
            if self.any_wrap:
                qc = self._into_box(qc)
            geo = creeping[idx] & ~(held.any(axis=1) | redo)
            if geo.any():
                f = np.nonzero(geo)[0]
                v = self._delta(qc[f], q[f])
                eh = np.array([error_at(q[j] + _GEO_H * v[i])[0] for i, j in enumerate(f)])
                evaluations += f.size
                for i, a in enumerate(self._geodesic(q[f], ea[f], Ea[f], None, la[f], v, eh)):
                    if a is not None:
                        qc[f[i]] = self._into_box(q[f[i]] + v[i] + 0.5 * a)
            for j, k in enumerate(idx):
                en, xn, pn, rn = error_at(qc[j])
                evaluations += 1
                cn = en.dot(en)
                if cn < c[k]:
                    creeping[k] = _GEO_SLOW * c[k] < cn < _GEO_NEAR
                    Q[k], e[k], extra[k], pos[k], c[k] = qc[j], en, xn, pn, cn
                    if rot is not None:
                        rot[k] = rn
                    if pn <= tol_p and (rn is None or rn <= tol_r):
                        if self.finish and cn > _FINISHED:
                            out = self._finish(Q[k].copy(), e[k], extra[k], pn, rn, cn, lam[k], it, evaluations)
                            return out, k
                        return outcome(k, True, it)
                    need_J[k] = True
                    lam[k] = max(lam[k] * _SHRINK, _LAMBDA_MIN)
                else:
                    lam[k] *= _GROW
            alive &= lam <= _LAMBDA_MAX
            if it % self.stall_window == 0:
                alive &= c < (self.stall_ratio**2) * checkpoint
                checkpoint = c.copy()
        err = pos + (0.0 if rot is None else rot)
        return outcome(int(err.argmin()), False, it)


# ---------------------------------------------------------------------- many pairs, compiled
def compiled_pairs(robot, Q: np.ndarray, targets: list[Target], lower: np.ndarray, upper: np.ndarray,
                   tolerance: float, rotation_tolerance: float, max_iterations: int = DEFAULT_ITERATIONS,
                   damping: float = DEFAULT_DAMPING, max_step: float = DEFAULT_MAX_STEP) -> BatchOutcome:
    """:meth:`LevenbergMarquardt.run` (compiled engine) on many (configuration, target) pairs in one call of
    :func:`.lm_kernel.lm_run_pairs`: what :func:`batch_levenberg_marquardt` does for ``solve_many``, with the
    full iteration (limit re-solve, stall test, finishing step) at about 1-2 us per step and pair.

    Args:
        robot: the chain. Q: (N, n) start configurations. targets: N targets, all pose or all position
            (planar targets: :func:`batch_levenberg_marquardt`). lower, upper: (n,) box. tolerance (m),
            rotation_tolerance (rad): success thresholds. max_iterations: steps per pair.
    """
    compiled_kernel()
    lm_run_pairs = _KERNEL[1]
    N = Q.shape[0]
    pose = targets[0].rotation is not None
    P = np.ascontiguousarray([t.position for t in targets], dtype=float)
    Rts = np.ascontiguousarray([t.rotation for t in targets] if pose else np.broadcast_to(np.eye(3), (N, 3, 3)),
                               dtype=float)
    _, any_wrap, _, _, box = _box_constants(robot, lower, upper)
    params = _kernel_params(tolerance, rotation_tolerance, pose, max_iterations, damping, max_step)
    FR, Fp, rev = robot.chain_constants()
    Q_out = np.empty((N, robot.n))
    stats = np.empty((N, 5))
    lm_run_pairs(np.ascontiguousarray(Q, dtype=float), FR, Fp, rev, box, any_wrap, P, Rts, params, Q_out, stats)
    return BatchOutcome(Q_out, stats[:, 0].copy(), stats[:, 1].copy() if pose else None, stats[:, 2] != 0.0,
                        stats[:, 4].astype(np.int64))


# ---------------------------------------------------------------------- batched version
def _skew_sq_terms(phi: np.ndarray):
    """Angle (N,), skew matrices (N, 3, 3) and their squares for rotation vectors ``phi`` (N, 3)."""
    theta = np.sqrt((phi * phi).sum(axis=1))
    K = np.zeros((phi.shape[0], 3, 3))
    K[:, 0, 1], K[:, 0, 2] = -phi[:, 2], phi[:, 1]
    K[:, 1, 0], K[:, 1, 2] = phi[:, 2], -phi[:, 0]
    K[:, 2, 0], K[:, 2, 1] = -phi[:, 1], phi[:, 0]
    return theta, K, K @ K


def _log3_batch(R: np.ndarray) -> np.ndarray:
    """Rotation vectors (N, 3) (rad) of rotations (N, 3, 3): the batched ``pin.log3``, stable near 0 and pi."""
    trace = R[:, 0, 0] + R[:, 1, 1] + R[:, 2, 2]
    axis = np.stack([R[:, 2, 1] - R[:, 1, 2], R[:, 0, 2] - R[:, 2, 0], R[:, 1, 0] - R[:, 0, 1]], axis=1)
    s = 0.5 * np.sqrt((axis * axis).sum(axis=1))
    theta = np.arctan2(s, 0.5 * (trace - 1.0))
    # theta / (2 sin theta) with its series 1/2 + theta^2/12 near 0
    small = s < 1e-8
    coef = np.where(small, 0.5 + theta * theta / 12.0, theta / (2.0 * np.where(small, 1.0, s)))
    phi = coef[:, None] * axis
    near_pi = theta > np.pi - 1e-4
    if near_pi.any():  # the antisymmetric part vanishes: recover the axis from the symmetric part
        for i in np.nonzero(near_pi)[0]:
            phi[i] = pin.log3(R[i])
    return phi


def batch_levenberg_marquardt(robot, Q: np.ndarray, targets: list[Target], lower: np.ndarray, upper: np.ndarray,
                              tolerance: float, rotation_tolerance: float, max_iterations: int = DEFAULT_ITERATIONS,
                              damping: float = DEFAULT_DAMPING, max_step: float = DEFAULT_MAX_STEP) -> BatchOutcome:
    """Levenberg-Marquardt on many (configuration, target) pairs at once, all targets of one kind.

    Every iteration runs one batched forward-kinematics-and-Jacobian pass over the pairs still unsolved
    (``Robot.fk_jacobian_batch``), solves their damped normal equations with one batched
    ``np.linalg.solve``, evaluates every trial step with one batched FK and accepts, per pair, the steps
    that lower the error (per-pair lambda). The error is expressed in the base frame,
    ``e = (p - p_t, log3(R R_t^T))`` with ``E = (J_v, Jl^-1(log3(R R_t^T)) J_w)`` (``Jl^-1`` the inverse
    left Jacobian of SO(3)); its parts have exactly the norms of the position and orientation errors.
    Limits: joints on a bound pushed outward are held (columns zeroed), the step is clipped onto the
    box, wrapping joints are wrapped (no re-solve: a pair stuck on a limit is left to the caller).

    Args:
        robot: the chain. Q: (N, n) start configurations. targets: N targets, all pose, all position or all
            planar (planar: x, y and yaw when given). lower, upper: (n,) box. tolerance (m),
            rotation_tolerance (rad): success thresholds. max_iterations: steps tried per pair.
    """
    N, n = Q.shape
    kind = "planar" if targets[0].planar else ("pose" if targets[0].rotation is not None else "position")
    pt = np.array([t.position for t in targets])
    yaw_t = None
    if kind == "pose":
        Rt = np.array([t.rotation for t in targets])
        rows = slice(0, 6)
    elif kind == "planar":
        if targets[0].yaw is not None:
            yaw_t = np.array([t.yaw for t in targets], dtype=float)
        rows = [0, 1] if yaw_t is None else [0, 1, 5]
    else:
        rows = slice(0, 3)
    wrap = wrapping_joints(robot, lower, upper)
    clip_lo, clip_hi = np.where(wrap, -np.inf, lower), np.where(wrap, np.inf, upper)

    def residuals(p, R, idx):
        """e (M, m), position error (M,), orientation error (M,) or None, rotation vectors (M, 3) or None."""
        if kind == "pose":
            dp = p - pt[idx]
            phi = _log3_batch(R @ Rt[idx].transpose(0, 2, 1))
            e = np.concatenate([dp, phi], axis=1)
            return e, np.sqrt((dp * dp).sum(1)), np.sqrt((phi * phi).sum(1)), phi
        if kind == "position":
            dp = p - pt[idx]
            return dp, np.sqrt((dp * dp).sum(1)), None, None
        dp = p[:, :2] - pt[idx]
        pos = np.sqrt((dp * dp).sum(1))
        if yaw_t is None:
            return dp, pos, None, None
        dyaw = _angle_wrap(np.arctan2(R[:, 1, 0], R[:, 0, 0]) - yaw_t[idx])
        return np.concatenate([dp, dyaw[:, None]], axis=1), pos, np.abs(dyaw), None

    def into_box(Qx):
        Qx = np.minimum(np.maximum(Qx, clip_lo), clip_hi)
        if wrap.any():
            out = (Qx < lower) | (Qx > upper)
            Qx = np.where(out & wrap, lower + np.mod(Qx - lower, TWO_PI), Qx)
        return Qx

    def converged(pos, rot):
        ok = pos <= tolerance
        return ok if rot is None else ok & (rot <= rotation_tolerance)

    Q = into_box(np.array(Q, dtype=float))
    p, R = robot.fk_batch(Q, validate=False)
    _, pos, rot, _ = residuals(p, R, np.arange(N))
    evaluations = np.ones(N, dtype=np.int64)
    ok = converged(pos, rot)
    lam = np.full(N, float(damping))
    alive = ~ok
    cost = np.full(N, np.inf)
    checkpoint = np.full(N, np.inf)
    for it in range(max_iterations):
        if it and it % _BATCH_STALL_WINDOW == 0:
            # a pair whose |e| has not halved over the last window is stuck (a limit, a local minimum)
            alive &= cost < 0.25 * checkpoint
            checkpoint = cost.copy()
        idx = np.nonzero(alive)[0]
        if idx.size == 0:
            break
        Qa = Q[idx]
        pa, Ra, J = robot.fk_jacobian_batch(Qa, validate=False)
        ea, _, _, phi = residuals(pa, Ra, idx)
        if kind == "pose":
            theta, K, K2 = _skew_sq_terms(phi)
            # Jl^-1(phi) = I - K/2 + (1/theta^2 - (1 + cos theta) / (2 theta sin theta)) K^2 (-> 1/12 at 0)
            small = theta < 1e-6
            th = np.where(small, 1.0, theta)
            b = np.where(small, 1.0 / 12.0, 1.0 / th**2 - (1.0 + np.cos(th)) / (2.0 * th * np.sin(th)))
            E = J.copy()
            E[:, 3:] = (np.eye(3) - 0.5 * K + b[:, None, None] * K2) @ J[:, 3:]
        else:
            E = J[:, rows, :]
        g = (E.transpose(0, 2, 1) @ ea[:, :, None])[:, :, 0]  # E^T e: -g is the descent direction
        held = ((Qa <= clip_lo) & (g > 0.0)) | ((Qa >= clip_hi) & (g < 0.0))
        E = E * ~held[:, None, :]
        m = E.shape[1]
        A = E @ E.transpose(0, 2, 1) + lam[idx, None, None] * np.eye(m)
        dq = (E.transpose(0, 2, 1) @ np.linalg.solve(A, ea[:, :, None]))[:, :, 0]
        s = np.sqrt((dq * dq).sum(axis=1))
        dq *= np.where(s > max_step, max_step / np.maximum(s, 1e-300), 1.0)[:, None]
        Qn = into_box(Qa - dq)
        pn, Rn = robot.fk_batch(Qn, validate=False)
        en, posn, rotn, _ = residuals(pn, Rn, idx)
        evaluations[idx] += 2
        cn, ca = (en * en).sum(1), (ea * ea).sum(1)
        better = cn < ca
        cost[idx] = np.where(better, cn, ca)
        acc = idx[better]
        Q[acc] = Qn[better]
        pos[acc] = posn[better]
        if rot is not None:
            rot[acc] = rotn[better]
        lam[acc] = np.maximum(lam[acc] * _SHRINK, _LAMBDA_MIN)
        rej = idx[~better]
        lam[rej] = lam[rej] * _GROW
        done = converged(pos[idx], None if rot is None else rot[idx])
        ok[idx] = done
        alive[idx] = ~done & (lam[idx] <= _LAMBDA_MAX)
    return BatchOutcome(Q, pos, rot, ok, evaluations)


@dataclass
class BatchOutcome:
    """End state of :func:`batch_levenberg_marquardt`: configurations (N, n), position errors (N,) m,
    orientation errors (N,) rad or None, converged (N,) bool, forward-kinematics evaluations (N,) per pair."""

    q: np.ndarray
    position_error: np.ndarray
    orientation_error: np.ndarray | None
    converged: np.ndarray
    evaluations: np.ndarray
