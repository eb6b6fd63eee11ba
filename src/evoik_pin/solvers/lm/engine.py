"""The Levenberg-Marquardt engine: every LM run in evoik_pin goes through :class:`LevenbergMarquardt`
(one target, one or several starts) or :func:`solve_pairs` (many (start, target) pairs).

The task error ``e(q)`` and its Jacobian ``E(q) = de/dq`` depend on the target:

* pose target (6 rows): ``e = log6(T_t^-1 T(q))``, the SE(3) logarithm (m, rad) of the tip pose seen from
  the target frame, and ``E = Jlog6(T_t^-1 T(q)) J_local(q)``: since ``T(q + dq) = T(q) exp(J_local dq)``,
  ``e(q + dq) = e + E dq + O(dq^2)``. Its rotational part is ``log3(R_t^T R)``, whose norm is the rotation
  angle, and it vanishes exactly at the target. (A decoupled error ``(R_t^T (p - p_t), log3(R_t^T R))`` was
  measured against it: slower and no better, docs/BENCHMARKS.md);
* position target (3 rows): ``e = p(q) - p_t`` in the base frame with the translational Jacobian rows;
* planar target (x, y[, yaw]): ``e = (p_x - x_t, p_y - y_t[, wrap(yaw(q) - yaw_t)])`` with the matching rows
  of the base-frame Jacobian.

One step solves the damped normal equations in task space (at most 6 x 6, whatever the number of joints)::

    (E E^T + lambda I) y = e,        dq = -E^T y  ( = -(E^T E + lambda I)^-1 E^T e )

with the step length capped at ``max_step`` (a trust region), accepted only when it lowers ``|e|^2``
(``lambda`` shrinks after a success, grows after a failure). Joint limits are respected exactly by a small
active set (held joints; joints a step carries past a bound fixed there and the step re-solved for the
others). Revolute joints whose range spans a full turn wrap instead of being clipped. A run gives up on a
stall (``|e|`` not halved in a few steps), so the caller can restart elsewhere; once it meets the
tolerances it takes one more, undamped step (about 1e-12 instead of just under the tolerance). Near-singular
targets get a geodesic acceleration (Transtrum & Sethna 2012) while a run creeps along a narrow valley.

Two engines run that one iteration: ``engine="compiled"`` (the default) calls the numba kernel
(:mod:`.kernel`, about 1 us per step, every target kind); ``engine="python"`` runs the reference loop
(:mod:`.reference`, about 30-40 us per step), which the tests hold the kernel to.
"""

from __future__ import annotations

import time

import numpy as np

from ...errors import OptionError
from ...problem import IKProblem, Target
from .layout import (
    DEFAULT_DAMPING,
    DEFAULT_ITERATIONS,
    DEFAULT_MAX_STEP,
    DEFAULT_STALL_RATIO,
    DEFAULT_STALL_WINDOW,
    KIND_PLANAR,
    KIND_PLANAR_YAW,
    KIND_POSE,
    KIND_POSITION,
    P_ITERATIONS,
    S_CONVERGED,
    S_EVALUATIONS,
    S_ITERATIONS,
    S_POS,
    S_ROT,
    STATS_SIZE,
    TargetArrays,
    box_constants,
    encode_target,
    kernel_params,
    target_kind,
)
from .outcome import LMOutcome, PairsOutcome

__all__ = ["ENGINES", "LevenbergMarquardt", "compiled_kernel", "solve_pairs"]

#: LM engines: "compiled" runs the numba kernel of :mod:`.kernel`; "python" the reference loop of
#: :mod:`.reference` over Pinocchio's kinematics.
ENGINES = ("compiled", "python")

_KERNEL: dict = {}


def compiled_kernel() -> dict:
    """The kernel's entry points (``lm_run``, ``lm_run_starts``, ``lm_run_pairs``), ready to run.

    The first call imports numba (~0.3 s) and runs each entry point once on a one-joint chain, so that numba
    loads the machine code from its on-disk cache (~0.5 s) or, the first time after an install, compiles it
    (~15 s) here, and not inside a solve's time budget. Later calls return at once. Solvers call it before
    starting their clock.
    """
    if not _KERNEL:
        from . import kernel

        # a one-joint chain: Robot.chain_constants() + Robot.chain_coupling()
        chain = (np.tile(np.eye(3), (2, 1, 1)), np.zeros((2, 3)), np.ones(1, dtype=bool), np.zeros(1, dtype=np.int64),
                 np.ones(1), np.zeros(1))
        box = np.array([[-1.0], [1.0], [-1.0], [1.0], [0.0]])
        params = kernel_params(1e-6, 1e-6, KIND_POSE, iterations=1)
        # the argument types the engine passes: C-contiguous float64 / int64 / bool arrays and a Python bool
        kernel.lm_run(np.zeros(1), *chain, box, False, np.zeros(3), np.eye(3), params, np.empty(1))
        stats = np.empty((1, STATS_SIZE))
        kernel.lm_run_starts(np.zeros((1, 1)), *chain, box, False, np.zeros(3), np.eye(3), params,
                             np.empty((1, 1)), stats)
        kernel.lm_run_pairs(np.zeros((1, 1)), *chain, box, False, np.zeros((1, 3)), np.eye(3)[None].copy(),
                            params, np.empty((1, 1)), stats)
        _KERNEL.update(lm_run=kernel.lm_run, lm_run_starts=kernel.lm_run_starts, lm_run_pairs=kernel.lm_run_pairs)
    return _KERNEL


def _check_engine(engine: str) -> None:
    if engine not in ENGINES:
        raise OptionError(f"LM engine {engine!r} unknown; use one of {list(ENGINES)}")


class LevenbergMarquardt:
    """Levenberg-Marquardt on the task error of one :class:`~evoik_pin.problem.IKProblem` (see the module
    docstring for the error and the iteration).

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
        engine: ``"compiled"`` (numba kernel) or ``"python"`` (the reference loop).
    """

    def __init__(self, problem: IKProblem, damping: float = DEFAULT_DAMPING, max_step: float = DEFAULT_MAX_STEP,
                 stall_window: int = DEFAULT_STALL_WINDOW, stall_ratio: float = DEFAULT_STALL_RATIO,
                 finish: bool = True, engine: str = "compiled") -> None:
        _check_engine(engine)
        self.engine = engine
        self.problem = problem
        robot = problem.robot
        self.robot = robot
        self.n = robot.n
        self.kind = target_kind(problem.target)
        self.oriented = problem.target.has_orientation
        if engine == "python":
            from .reference import ReferenceLM

            self._reference = ReferenceLM(problem, damping, max_step, stall_window, stall_ratio, finish)
            return
        self._reference = None
        self._kernel = compiled_kernel()
        self._chain = robot.chain_constants() + robot.chain_coupling()  # folded chain, how it follows q
        _, self._any_wrap, _, _, self._box = box_constants(robot, problem.lower, problem.upper)
        self._pt, self._Rt = encode_target(problem.target)
        self._params = kernel_params(float(problem.tolerance), float(problem.rotation_tolerance), self.kind, 0,
                                     damping, max_step, stall_window, stall_ratio, finish)

    def run(self, q: np.ndarray, max_iterations: int, deadline: float | None = None) -> LMOutcome:
        """One LM run from ``q`` (n,) (clipped / wrapped into the box first), at most ``max_iterations`` steps.

        Stops as soon as the problem's tolerances are met, when the damping saturates, on a stall or at
        ``deadline`` (a ``time.perf_counter()`` value). The compiled engine checks ``deadline`` only before
        the run starts (a run is at most ``max_iterations`` steps of about 1 us); when it has passed, the
        start is evaluated and no step is taken. Returns the last accepted configuration (the best met).
        """
        if self._reference is not None:
            return self._reference.run(q, max_iterations, deadline)
        if deadline is not None and time.perf_counter() >= deadline:
            max_iterations = 0
        params = self._params
        params[P_ITERATIONS] = max_iterations
        out = np.empty(self.n)
        pos, rot, converged, it, evaluations = self._kernel["lm_run"](
            np.ascontiguousarray(q, dtype=float), *self._chain, self._box, self._any_wrap, self._pt, self._Rt,
            params, out)
        return LMOutcome(out, pos, rot if self.oriented else None, converged, it, evaluations)

    def run_many(self, Q: np.ndarray, max_iterations: int, deadline: float | None = None
                 ) -> tuple[LMOutcome, int]:
        """LM runs from the starts ``Q`` (K, n), in order, until one meets the tolerances: one kernel call
        for all K (compiled engine), so a group of starts that mostly fail costs little more than its steps.

        ``deadline`` is checked before the group starts (compiled) or before every step (python).

        Returns:
            (outcome of the converged run, or of the run with the lowest error; index of that start).
            ``iterations`` and ``evaluations`` count every run made.
        """
        Q = np.ascontiguousarray(np.array(Q, dtype=float, ndmin=2))
        if self._reference is not None:
            outs = []
            for k in range(Q.shape[0]):
                outs.append(self._reference.run(Q[k], max_iterations, deadline))
                if outs[-1].converged:
                    break
            best = len(outs) - 1 if outs[-1].converged else int(np.argmin([o.error for o in outs]))
            o = outs[best]
            return LMOutcome(o.q, o.position_error, o.orientation_error, o.converged,
                             sum(x.iterations for x in outs), sum(x.evaluations for x in outs)), best
        if deadline is not None and time.perf_counter() >= deadline:
            max_iterations = 0
        params = self._params
        params[P_ITERATIONS] = max_iterations
        K = Q.shape[0]
        Q_out = np.empty_like(Q)
        stats = np.empty((K, STATS_SIZE))
        k = self._kernel["lm_run_starts"](Q, *self._chain, self._box, self._any_wrap, self._pt, self._Rt, params,
                                          Q_out, stats)
        runs = k + 1 if k >= 0 else -(k + 1)
        s = stats[:runs]
        if k < 0:
            k = int(np.argmin(s[:, S_POS] + (s[:, S_ROT] if self.oriented else 0.0)))
        rot = float(s[k, S_ROT]) if self.oriented else None
        return LMOutcome(Q_out[k], float(s[k, S_POS]), rot, bool(s[k, S_CONVERGED]),
                         int(s[:, S_ITERATIONS].sum()), int(s[:, S_EVALUATIONS].sum())), k


def solve_pairs(robot, Q: np.ndarray, targets: list[Target] | TargetArrays, lower: np.ndarray, upper: np.ndarray,
                tolerance: float, rotation_tolerance: float, max_iterations: int = DEFAULT_ITERATIONS,
                damping: float = DEFAULT_DAMPING, max_step: float = DEFAULT_MAX_STEP,
                engine: str = "compiled") -> PairsOutcome:
    """One LM run per (start, target) pair: ``Q[i]`` towards ``targets[i]``, the run of
    :meth:`LevenbergMarquardt.run`; with the compiled engine one kernel call for all pairs.

    Args:
        robot: the chain. Q: (N, n) start configurations. targets: N targets, all of one kind (a list of
            :class:`~evoik_pin.problem.Target`, or their :class:`~.layout.TargetArrays`). lower, upper: (n,) box.
            tolerance (m), rotation_tolerance (rad): success thresholds. max_iterations: steps per pair.
            engine: as :class:`LevenbergMarquardt`'s.
    """
    _check_engine(engine)
    N = Q.shape[0]
    if engine == "python":
        from .reference import ReferenceLM

        listed = targets if not isinstance(targets, TargetArrays) else targets_of(targets)
        oriented = listed[0].has_orientation
        outs = [ReferenceLM(IKProblem(robot, t, lower=lower, upper=upper, tolerance=tolerance,
                                      rotation_tolerance=rotation_tolerance), damping, max_step
                            ).run(Q[i], max_iterations) for i, t in enumerate(listed)]
        return PairsOutcome(np.array([o.q for o in outs]), np.array([o.position_error for o in outs]),
                            np.array([o.orientation_error for o in outs]) if oriented else None,
                            np.array([o.converged for o in outs]), np.array([o.evaluations for o in outs]))
    arrays = targets if isinstance(targets, TargetArrays) else TargetArrays.of(targets)
    lm_run_pairs = compiled_kernel()["lm_run_pairs"]
    _, any_wrap, _, _, box = box_constants(robot, lower, upper)
    params = kernel_params(tolerance, rotation_tolerance, arrays.kind, max_iterations, damping, max_step)
    chain = robot.chain_constants() + robot.chain_coupling()
    Q_out = np.empty((N, robot.n))
    stats = np.empty((N, STATS_SIZE))
    lm_run_pairs(np.ascontiguousarray(Q, dtype=float), *chain, box, any_wrap, arrays.P, arrays.Rts, params, Q_out,
                 stats)
    return PairsOutcome(Q_out, stats[:, S_POS].copy(), stats[:, S_ROT].copy() if arrays.oriented else None,
                        stats[:, S_CONVERGED] != 0.0, stats[:, S_EVALUATIONS].astype(np.int64))


def targets_of(arrays: TargetArrays) -> list[Target]:
    """Target objects of :class:`~.layout.TargetArrays` (the reference engine works on them)."""
    P, Rts = arrays.P, arrays.Rts
    if arrays.kind in (KIND_PLANAR, KIND_PLANAR_YAW):
        return [Target(P[i, :2], planar=True, yaw=float(P[i, 2]) if arrays.kind == KIND_PLANAR_YAW else None)
                for i in range(len(arrays))]
    if arrays.kind == KIND_POSITION:
        return [Target(P[i]) for i in range(len(arrays))]
    return [Target(P[i], Rts[i]) for i in range(len(arrays))]
