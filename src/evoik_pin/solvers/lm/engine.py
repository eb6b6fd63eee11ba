"""The Levenberg-Marquardt engine: every LM run in evoik_pin goes through :class:`LevenbergMarquardt` (one problem,
one or several starts) or :func:`solve_pairs` (many (start, target) pairs).

The task error ``e(q)`` stacks each goal's rows scaled by the square root of its weight; ``E = de/dq``. A pose goal's
rows are ``log6(T_t^-1 T_f(q))`` (m, rad), with ``E = Jlog6(T_t^-1 T_f) J_local``; a position goal's ``p_f(q) - p_t``
(base frame); the other kinds' are in :mod:`.axes` and :mod:`.balance`. One step solves the damped normal equations
in the smaller space, ``(E E^T + lambda I) y = e, dq = -E^T y`` (rows <= joints) or ``(E^T E + lambda I) dq = -E^T e``,
its length capped at ``max_step`` (trust region), accepted only when it lowers ``|e|^2`` (lambda shrinks after a
success, grows after a failure). Joint limits are an active set (joints a step carries past a bound are fixed there,
the step re-solved for the others); full-turn revolute joints wrap instead. A run gives up on a stall so the caller
can restart elsewhere, takes one undamped finishing step once every goal meets its tolerances, and near-singular
targets get a geodesic acceleration (Transtrum & Sethna 2012).

``engine="compiled"`` (the default) runs the numba kernel (:mod:`.kernel`); ``engine="python"`` the reference loop
(:mod:`.reference`) the tests hold the kernel to.
"""

from __future__ import annotations

import threading
import time
from dataclasses import replace
from typing import TYPE_CHECKING

import numpy as np

from ...errors import OptionError
from ...goals.bands import AUX_SIZE
from ...goals.registry import BANDED_LOG6, FAMILY_FRAME, KINDS, LOG6, POINT
from ...goals.stack import KIND_PLANAR, KIND_PLANAR_YAW, GoalArrays, GoalStack, TargetArrays, owned, spec_row
from . import layout
from .compiling import compiled_entry
from .layout import DEFAULT_DAMPING, DEFAULT_ITERATIONS, DEFAULT_MAX_STEP, DEFAULT_STALL_RATIO, DEFAULT_STALL_WINDOW
from .run_outcome import LMOutcome, PairsOutcome

if TYPE_CHECKING:  # the problem module imports goals, which import this package's layout
    from ...problem import IKProblem, Target

__all__ = ["ENGINES", "LevenbergMarquardt", "compiled_kernel", "later_kinds", "solve_pairs"]

#: LM engines: the numba kernel of :mod:`.kernel`, the reference loop of :mod:`.reference`.
ENGINES = ("compiled", "python")

#: About how long (s, one core) compiling a variant's entries takes from an empty cache (scripts/compile_time.py).
KERNEL_COMPILE_SECONDS = {False: 20.0, True: 35.0}
#: The loaded kernels: per variant (False: one-frame goals only, True: any stack), compiled_kernel's dict.
_KERNELS: dict = {}
_LOADING = threading.Lock()


def warmup_problem() -> tuple:
    """(kin, box, goals, pt, Rt) of a one-joint tree with one pose goal: the kernels' arguments of the types the
    engine passes, for compiling or loading them outside any time budget."""
    tree = (np.full(1, -1, dtype=np.int64), np.eye(3)[None].copy(), np.zeros((1, 3)), np.ones(1, dtype=bool),
            np.zeros(1, dtype=np.int64), np.ones(1), np.zeros(1))
    spec = spec_row(LOG6, 0, 1.0, 1e-6, 1e-6, 0)[None]
    goals = (spec, np.eye(3)[None].copy(), np.zeros((1, 3)), np.ones((1, 1), dtype=bool), np.zeros((1, 1)))
    box = np.array([[-1.0], [1.0], [-1.0], [1.0], [0.0]])
    return tree, box, goals, np.zeros((1, 3)), np.eye(3)[None].copy()


def later_kinds(stack: GoalStack) -> bool:
    """Whether ``stack`` holds a goal of a compiled family beyond the frame family's (pose, position, planar), which
    only the kernel's ``lm_run_all`` variant runs."""
    return any(KINDS[k].family != FAMILY_FRAME for k in stack.kinds)


def compiled_kernel(extra: bool = False) -> dict:
    """The kernel's entries for one variant of the run, loaded: ``extra`` False for stacks of one-frame goals
    (``lm_run_basic``), True for any (``lm_run_all``; :func:`later_kinds`). The dict holds ``lm_run_buffers``,
    ``lm_runs_buffers`` (:data:`.kernel.Entries`), ``lm_runs`` and ``workspace_size``.

    The first call per variant runs each entry once on a one-joint robot, so that numba loads (or, once per install,
    compiles, with a notice: :mod:`.compiling`) its machine code before any solver starts its clock. Thread-safe.
    """
    if extra in _KERNELS:
        return _KERNELS[extra]
    from . import kernel as K
    from .compiling import load

    with _LOADING:  # threads wanting it at once (solve_many's workers): one loads it, one notice
        if extra in _KERNELS:
            return _KERNELS[extra]
        tree, box, goals, pt, Rt = warmup_problem()
        params = layout.kernel_params(iterations=1)
        entries = K.ALL if extra else K.BASIC
        buffers = K._buffers(1, tree, goals[0], params)
        calls = [(entries.run, (*buffers, np.zeros(1), tree, box, False, goals, pt, Rt, params, np.empty(1),
                                np.empty((1, 2)))),
                 (entries.runs, (*buffers, np.zeros((1, 1)), tree, box, False, goals, pt[None], Rt[None], params,
                                 np.empty((1, 1)), np.empty((1, layout.STATS_SIZE)), np.empty((1, 1, 2)), True))]
        if extra:
            # Goal.errors' compiled errors (.axes, read-only aux row) are first called mid-search: load them here
            # too, outside any time budget
            from .axes import axes_error

            aux = np.zeros(AUX_SIZE)
            aux.setflags(write=False)
            calls.append((axes_error, (BANDED_LOG6, np.eye(3), np.zeros(3), np.zeros(3), np.eye(3), aux,
                                       np.empty((3, 3)), np.empty(3), np.empty(6))))
        load("the LM kernel for " + ("every goal kind" if extra else "pose, position and planar goals"), calls,
             KERNEL_COMPILE_SECONDS[extra])
        _KERNELS[extra] = dict(lm_runs=K.lm_runs, lm_run_buffers=entries.run, lm_runs_buffers=entries.runs,
                               workspace_size=K.workspace_size)
    return _KERNELS[extra]


def _check_engine(engine: str) -> None:
    if engine not in ENGINES:
        raise OptionError(f"LM engine {engine!r} unknown; use one of {list(ENGINES)}")


class LevenbergMarquardt:
    """Levenberg-Marquardt on the task error of one :class:`~evoik_pin.problem.IKProblem` (its goals, or its single
    target on the tip; the module docstring states the iteration).

    Args:
        problem: robot, goals (or target), search box and tolerances (m, rad; or each goal's own).
        damping: initial lambda (m^2 / rad^2 scale), adapted per step.
        max_step: largest length ``|dq|`` of one step (rad or m, Euclidean norm over the joints).
        stall_window, stall_ratio: give up when ``|e|`` has not dropped below ``stall_ratio`` times its value
            ``stall_window`` accepted steps earlier.
        finish: once the tolerances are met, take one more step (kept if it lowers the error; quadratic
            convergence takes ~1e-6 to ~1e-12).
        engine: ``"compiled"`` (numba kernel) or ``"python"`` (the reference loop).
    """

    def __init__(self, problem: IKProblem, damping: float = DEFAULT_DAMPING, max_step: float = DEFAULT_MAX_STEP,
                 stall_window: int = DEFAULT_STALL_WINDOW, stall_ratio: float = DEFAULT_STALL_RATIO,
                 finish: bool = True, engine: str = "compiled") -> None:
        _check_engine(engine)
        self.engine = engine
        self.problem = problem
        robot = self.robot = problem.robot
        self.n = robot.n
        stack, pt, Rt = problem.goal_stack()
        self._pt, self._Rt = owned(pt, float), owned(Rt, float)
        self.goals = stack
        self.oriented = stack.any_oriented
        if engine == "python":
            from .reference import ReferenceLM

            if later_kinds(stack):  # bands, free axes, orientation, pointing, beyond a frame
                raise OptionError("the Python reference LM (engine='python') knows pose, position and planar goals "
                                  "only; goals with tolerance bands or free axes, Orientation, Direction, LookAt, "
                                  "CenterOfMass and RelativePose need the compiled engine (engine='compiled', the "
                                  "default)")
            self._reference = ReferenceLM(problem, damping, max_step, stall_window, stall_ratio, finish)
            return
        self._reference = None
        self._kernel = compiled_kernel(later_kinds(stack))  # this stack's variant, loaded before any clock
        self._tree = tuple(owned(a) for a in robot.tree_constants())  # the kernel's kin
        self._goal_arrays = tuple(owned(a) for a in stack.arrays)
        _, self._any_wrap, _, _, self._box = layout.box_constants(robot, problem.lower, problem.upper)
        self._params = layout.kernel_params(0, damping, max_step, stall_window, stall_ratio, finish)
        G = len(stack.kinds)
        self._one = G == 1
        self._g_scratch = np.empty((G, 2))  # one goal: its errors are the outcome's own
        self._buffers: tuple = ()  # the kernel's workspace (_workspace)
        self._buffers_for = -1  # the most steps those buffers hold
        self._buffers_thread = -1  # the thread whose buffers they are (threading.get_ident)
        self._set_args()
        self._owned = False  # whether _pt and _Rt are this engine's own arrays (retarget)
        self._direct = None  # lm_run_buffers's compiled overload, once the engine serves many problems (retarget)
        self._same_box = (problem.lower, problem.upper)  # box arrays known to give this engine's box constants
        self._own_box = False  # whether _box is this engine's own array (confine), no longer box_constants'

    def retarget(self, problem: IKProblem) -> bool:
        """Point this engine at ``problem`` when it differs from the current one only in its targets (an
        :class:`~evoik_pin.IKSolver`'s problems), written in place (:meth:`set_targets`). Returns False (the engine
        unchanged) when ``problem`` needs an engine of its own, and for the python engine."""
        if self._reference is not None or problem.robot is not self.robot or self._own_box:
            return False
        stack, pt, Rt = problem.goal_stack()
        same = problem.lower is self._same_box[0] and problem.upper is self._same_box[1]
        if stack is not self.goals or not (same or layout.box_constants(self.robot, problem.lower, problem.upper)[4]
                                           is self._box):
            return False
        self._same_box = (problem.lower, problem.upper)  # the box arrays checked last (an IKSolver's, every call)
        self.set_targets(pt, Rt)
        self.problem = problem
        return True

    def confine(self, lower: np.ndarray, upper: np.ndarray) -> None:
        """Run inside ``[lower, upper]`` (n,) (rad or m) from now on, no joint wrapping: a per-call box
        (:mod:`..search.velocity_box`) written in place into this engine's own box array; :meth:`retarget` then
        refuses other boxes. Compiled engine only."""
        if self._reference is not None:
            raise OptionError("a per-call box (velocity limits) runs on the compiled LM engine only "
                              "(engine='compiled')")
        box = self._box
        if not self._own_box:  # the first call: an array of our own (the cached one serves other engines)
            box = self._box = np.zeros_like(box)
            self._set_args()
            self._own_box = True
        box[layout.B_LO] = box[layout.B_CLO] = lower
        box[layout.B_HI] = box[layout.B_CHI] = upper  # the wrap row stays 0: the box is in unwrapped values

    def set_targets(self, pt: np.ndarray, Rt: np.ndarray) -> None:
        """Write the goals' targets ``pt`` (G, 3) m and ``Rt`` (G, 3, 3) into the kernel's argument arrays (the goal
        stack unchanged; a tracking loop's per-step update). Compiled engine only."""
        if self._reference is not None:
            raise OptionError("set_targets runs on the compiled LM engine only (engine='compiled')")
        if self._owned:
            self._pt[...] = pt
            self._Rt[...] = Rt
        else:  # the first problem's arrays may be its target's own: copies from now on, never written through
            self._pt, self._Rt = np.array(pt, dtype=float), np.array(Rt, dtype=float)
            self._set_args()
            self._owned = True
            self._direct = self._overload()  # an engine that serves many problems

    def _set_args(self) -> None:
        """The kernel's constant arguments, (kin, box, any_wrap, goals, pt, Rt) (:mod:`.kernel`'s groups), remade as one
        tuple whenever one of them is replaced: callers keep it, and test by identity that it still holds."""
        self._args = (self._tree, self._box, self._any_wrap, self._goal_arrays, self._pt, self._Rt)

    def _overload(self):
        """The compiled entry of :meth:`run`'s argument types, called without numba's dispatch (which types every
        argument on every call), or None where this numba does not expose it; for an engine that runs many problems
        (finding it costs more than a call)."""
        buffers = self._buffers or self._workspace(DEFAULT_ITERATIONS)
        g_err = self._g_scratch if self._one else np.empty((len(self.goals), 2))
        args = (*buffers, np.zeros(self.n), *self._args, self._params, np.empty(self.n), g_err)
        return compiled_entry(self._kernel["lm_run_buffers"], args)

    def _workspace(self, max_iterations: int) -> tuple[np.ndarray, np.ndarray]:
        """The kernel's buffers for runs of up to ``max_iterations`` steps: this thread's for this goal stack
        (:func:`_thread_buffers`; an engine kept from solve to solve may be handed to another thread)."""
        if max_iterations > self._buffers_for or self._buffers_thread != threading.get_ident():
            self._buffers = _thread_buffers(self._kernel, self.goals, self.n, self._tree[0].shape[0], max_iterations)
            self._buffers_for = max_iterations
            self._buffers_thread = threading.get_ident()
        return self._buffers

    def run(self, q: np.ndarray, max_iterations: int, deadline: float | None = None) -> LMOutcome:
        """One LM run from ``q`` (n,) (clipped / wrapped into the box first), at most ``max_iterations`` steps.

        Stops as soon as the problem's tolerances are met, when the damping saturates, on a stall or at ``deadline``
        (a ``time.perf_counter()`` value; the compiled engine checks it before the run only: when it has passed, the
        start is evaluated and no step taken). Returns the last accepted configuration (the best met).
        """
        if self._reference is not None:
            return self._reference.run(q, max_iterations, deadline)
        if deadline is not None and time.perf_counter() >= deadline:
            max_iterations = 0
        buffers, args, params = self.kernel_arguments(max_iterations)
        out = np.empty(self.n)
        g_err = self._g_scratch if self._one else np.empty((len(self.goals), 2))
        run = self._direct
        if run is None:
            run, q = self._kernel["lm_run_buffers"], owned(q, float)
        else:  # the overload's argument type exactly: a C-contiguous, writable float64 vector of our own
            q = np.array(q, dtype=float)
        pos, rot, converged, it, evaluations, cost = run(*buffers, q, *args, params, out, g_err)
        return LMOutcome(out, pos, rot if self.oriented else None, converged, it, evaluations,
                         None if self._one else g_err, cost)

    def kernel_arguments(self, max_iterations: int) -> tuple[tuple, tuple, np.ndarray]:
        """(workspace buffers, the kernel's constant arguments (kin, box, any_wrap, goals, pt, Rt), params with
        ``max_iterations`` steps) for compiled code that makes :meth:`run`'s runs itself
        (:mod:`..search.guaranteed_runs`). Compiled engine only."""
        self._params[layout.P_ITERATIONS] = max_iterations
        return self._workspace(max_iterations), self._args, self._params

    def run_many(self, Q: np.ndarray, max_iterations: int, deadline: float | None = None
                 ) -> tuple[LMOutcome, int]:
        """LM runs from the starts ``Q`` (K, n), in order, until one meets the tolerances (one kernel call for all K;
        ``deadline`` checked before the group starts, or before every step with the python engine).

        Returns:
            (outcome of the converged run, or of the run with the lowest error (one goal: position + orientation
            error; several: the weighted |e|^2); index of that start). ``iterations`` and ``evaluations`` count
            every run made.
        """
        Q = np.ascontiguousarray(np.array(Q, dtype=float, ndmin=2))
        if self._reference is not None:
            outs = []
            for k in range(Q.shape[0]):
                outs.append(self._reference.run(Q[k], max_iterations, deadline))
                if outs[-1].converged:
                    break
            best = len(outs) - 1 if outs[-1].converged else int(np.argmin([o.rank for o in outs]))
            return replace(outs[best], iterations=sum(o.iterations for o in outs),
                           evaluations=sum(o.evaluations for o in outs)), best
        if deadline is not None and time.perf_counter() >= deadline:
            max_iterations = 0
        buffers, args, params = self.kernel_arguments(max_iterations)
        K = Q.shape[0]
        Q_out, stats, g_stats = np.empty_like(Q), np.empty((K, layout.STATS_SIZE)), np.empty((K, len(self.goals), 2))
        k = self._kernel["lm_runs_buffers"](*buffers, Q, *args[:4], self._pt[None], self._Rt[None], params, Q_out,
                                            stats, g_stats, True)
        runs = k + 1 if k >= 0 else -(k + 1)
        s = stats[:runs]
        if k < 0:
            pos_rot = s[:, layout.S_POS] + (s[:, layout.S_ROT] if self.oriented else 0.0)
            k = int(np.argmin(pos_rot if self._one else s[:, layout.S_COST]))  # LMOutcome.rank
        rot = float(s[k, layout.S_ROT]) if self.oriented else None
        return LMOutcome(Q_out[k], float(s[k, layout.S_POS]), rot, bool(s[k, layout.S_CONVERGED]),
                         int(s[:, layout.S_ITERATIONS].sum()), int(s[:, layout.S_EVALUATIONS].sum()),
                         None if self._one else g_stats[k], float(s[k, layout.S_COST])), k


_LOCAL = threading.local()
#: Goal stacks whose buffers a thread keeps (the most recently used ones).
_BUFFERS_KEPT = 8


def _thread_buffers(kernel: dict, stack: GoalStack, n: int, m: int, max_iterations: int):
    """(float buffer, held (n,) bool) of the kernel's workspace for ``stack`` on this thread, for runs of up to
    ``max_iterations`` steps (at least the default): kept per thread for the last few goal stacks (the entry keeps
    its stack alive, so an id is never reused while it is cached)."""
    cache = getattr(_LOCAL, "buffers", None)
    if cache is None:
        cache = _LOCAL.buffers = {}
    key = (id(stack), n)
    hit = cache.get(key)
    if hit is None or hit[1] < max_iterations:
        steps = max(max_iterations, DEFAULT_ITERATIONS)
        size = int(kernel["workspace_size"](n, m, len(stack.kinds), stack.rows, steps))
        if len(cache) >= _BUFFERS_KEPT:
            cache.pop(next(iter(cache)))
        hit = cache[key] = ((np.empty(size), np.empty(n, dtype=bool)), steps, stack)
    return hit[0]


def solve_pairs(robot, Q: np.ndarray, targets: list[Target] | TargetArrays | GoalArrays, lower: np.ndarray,
                upper: np.ndarray, tolerance: float, rotation_tolerance: float,
                max_iterations: int = DEFAULT_ITERATIONS, damping: float = DEFAULT_DAMPING,
                max_step: float = DEFAULT_MAX_STEP, engine: str = "compiled") -> PairsOutcome:
    """One LM run per (start, target) pair: ``Q[i]`` towards ``targets[i]``, the run of
    :meth:`LevenbergMarquardt.run`; with the compiled engine one kernel call for all pairs.

    Args:
        robot: the chain or tree. Q: (N, n) start configurations. targets: N targets, all of one kind (a list of
            :class:`~evoik_pin.problem.Target`, or their :class:`~evoik_pin.goals.stack.TargetArrays`), or N goal
            lists of one structure (:class:`~evoik_pin.goals.stack.GoalArrays`: their stack's tolerances apply;
            compiled engine only).
            lower, upper: (n,) box. tolerance (m), rotation_tolerance (rad): success thresholds of single targets.
            max_iterations: steps per pair. engine: as :class:`LevenbergMarquardt`'s.
    """
    _check_engine(engine)
    N = Q.shape[0]
    if isinstance(targets, GoalArrays) and engine == "python":
        raise OptionError("solve_pairs runs goal stacks on the compiled engine only (engine='compiled')")
    if engine == "python":
        from ...problem import IKProblem
        from .reference import ReferenceLM

        listed = targets if not isinstance(targets, TargetArrays) else targets_of(targets)
        oriented = listed[0].has_orientation
        outs = [ReferenceLM(IKProblem(robot, t, lower=lower, upper=upper, tolerance=tolerance,
                                      rotation_tolerance=rotation_tolerance), damping, max_step
                            ).run(Q[i], max_iterations) for i, t in enumerate(listed)]
        return PairsOutcome(np.array([o.q for o in outs]), np.array([o.position_error for o in outs]),
                            np.array([o.orientation_error for o in outs]) if oriented else None,
                            np.array([o.converged for o in outs]), np.array([o.evaluations for o in outs]))
    if isinstance(targets, GoalArrays):  # N goal lists of one stack, each goal's errors kept
        arrays, stack, P, Rts = targets, targets.stack, targets.P, targets.Rts
        g_stats = np.empty((N, len(stack), 2))
    else:  # single targets: the tip's one-goal stack
        arrays = targets if isinstance(targets, TargetArrays) else TargetArrays.of(targets)
        stack = GoalStack.single(robot, arrays.kind, tolerance, rotation_tolerance)
        P, Rts, g_stats = arrays.P[:, None], arrays.Rts[:, None], None
    _, any_wrap, _, _, box = layout.box_constants(robot, lower, upper)
    Q_out, stats = np.empty((N, robot.n)), np.empty((N, layout.STATS_SIZE))
    compiled_kernel(later_kinds(stack))["lm_runs"](
        owned(Q, float), tuple(owned(a) for a in robot.tree_constants()), box, any_wrap,
        tuple(owned(a) for a in stack.arrays), owned(P, float), owned(Rts, float),
        layout.kernel_params(max_iterations, damping, max_step), Q_out, stats,
        np.empty((N, 1, 2)) if g_stats is None else g_stats)
    rot = stats[:, layout.S_ROT].copy() if arrays.oriented else None
    return PairsOutcome(Q_out, stats[:, layout.S_POS].copy(), rot, stats[:, layout.S_CONVERGED] != 0.0,
                        stats[:, layout.S_EVALUATIONS].astype(np.int64), g_stats)


def targets_of(arrays: TargetArrays) -> list[Target]:
    """Target objects of :class:`~evoik_pin.goals.stack.TargetArrays` (the reference engine works on them)."""
    from ...problem import Target

    P, Rts = arrays.P, arrays.Rts
    if arrays.kind in (KIND_PLANAR, KIND_PLANAR_YAW):
        return [Target(P[i, :2], planar=True, yaw=float(P[i, 2]) if arrays.kind == KIND_PLANAR_YAW else None)
                for i in range(len(arrays))]
    if arrays.kind == POINT:
        return [Target(P[i]) for i in range(len(arrays))]
    return [Target(P[i], Rts[i]) for i in range(len(arrays))]
