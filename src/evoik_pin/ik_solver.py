"""The one solve pipeline: :class:`IKSolver`, a solver set up once for one robot, method and options.

A control loop, a planner sampling goal configurations or a grasp scorer solves one target at a time, thousands of
times, with the same robot and options. Checking the options, building the problem's constants and looking up the
method's set-up on every call would cost more than the solve; an ``IKSolver`` does that once:

* the method and every option are checked when the solver is made (the errors :func:`evoik_pin.solve` raises);
* the problem's constants (tolerances, search box, scene, objective settings) are checked into a template problem,
  and each call copies it with the new target (checked: a NaN pose, a 5-vector, a q0 of the wrong length get the
  errors they get from :func:`evoik_pin.solve`);
* for ``memetic`` (the default), its :class:`~evoik_pin.solvers.search.memetic.MemeticSetup`: the compiled kernel
  loaded, the seed table of the search box built, and one LM engine whose target arrays each call overwrites.

The pipeline of a call: the target (or goal list) checked and bound, its problem copied from the template, the
method run (for memetic: q0, the seed table, LM, the evolutionary search; :mod:`evoik_pin.solvers.search.choose` for
goal sets, ``prefer=`` and preferences), the goals' and the scene's verdicts. ``locked=`` makes it the pipeline of
the robot without those joints, its answers put back in the full layout.

Once memetic has solved a pose (a position, a one-goal list of some goal structure) this way, the next ones of that
kind take a lane (:mod:`evoik_pin.solvers.search.repeat_call`): the target's and q0's checks, memetic's
compiled first runs called directly, the Result; no problem copied, no look-up. The answers stay the pipeline's,
bit for bit; a target the first runs do not solve goes on in memetic from their state.

:func:`evoik_pin.solve` is an IKSolver's solve: the one kept per robot, method and options (per thread, the 8 made
last, which keep their robots alive) when the options are plain values (numbers, strings, a
:class:`~evoik_pin.Scene` or objective object, a ``locked`` dict), else one made for the call (a robot by name, a
scene file's path, array bounds).
"""

from __future__ import annotations

import math
import threading

import numpy as np

from .call_setup import (
    _PROBLEM_OPTIONS,
    DEFAULT_METHOD,
    _goal_method_problem,
    _rng,
    _robot,
    _with_goal_verdict,
    make_problem,
    split_options,
)
from .errors import ConfigurationError, EvoikError
from .goals import is_goal_list
from .goals.goal import Goal
from .goals.preferences import Preference
from .goals.stack import bind
from .objectives import default_objective
from .problem import NEAR_UNBOUNDED, IKProblem, Target, target_box
from .result import Result
from .robot import Robot
from .scene import Scene
from .solvers import get_solver
from .solvers.collision_verdict import with_collision_verdict
from .solvers.search.memetic import KEPT_ENGINES
from .target import pose_arrays

__all__ = ["IKSolver"]


class IKSolver:
    """One robot, method and set of options, checked and prepared once; :meth:`solve` per target.

    Args:
        robot: a :class:`~evoik_pin.Robot` or anything :func:`~evoik_pin.load_robot` accepts.
        method: a name from :func:`~evoik_pin.methods` (default ``"memetic"``).
        prefer: ``"first"`` (None: the same), ``"nearest"`` (q0 required) or ``"manipulability"``: which answer
            memetic returns among those it finds (:mod:`evoik_pin.solvers.search.choose`).
        locked: ``{joint: value}`` (rad or m): those joints held at their values; ``q0``, ``bounds`` and the answers
            stay in ``robot``'s layout.
        **options: what :func:`evoik_pin.solve` takes (``tolerance`` m, ``rotation_tolerance`` rad, ``bounds``,
            ``scene``, ``margin`` m, ``orientation_weight``, ``pose_metric``, ``objective``, ``polish``, the method's
            own: ``timeout`` s, ``max_restarts``, ...); a ``q0`` (n,) here is the start of every :meth:`solve` not
            given one.

    Raises:
        MethodError: an unknown method, ``prefer`` other than "first" with a method other than memetic. OptionError,
        BoundsError, ConfigurationError, SceneError, FrameError: an option :func:`evoik_pin.solve` would refuse (an
        unknown ``prefer``, a ``locked`` joint that does not exist), with its message.

    The robot's bounds (``bounds`` or the robot's own) are read when the solver is made. One solver is not to be
    shared by threads that solve at the same time (each call writes the solver's target buffers): make one per
    thread.

    Example::

        solver = IKSolver(panda, tolerance=1e-6)
        for T in targets:
            r = solver.solve(T, q0=q_now)     # a Result, as evoik_pin.solve returns
    """

    def __init__(self, robot, method: str = DEFAULT_METHOD, *, prefer: str | None = None, locked: dict | None = None,
                 **options) -> None:
        from .solvers.search.prefer import check_prefer, check_prefer_method

        robot = _robot(robot)
        self.robot = robot
        self.method = method
        # prefer= and locked= checked first (evoik_pin.solve's order): an unknown prefer, then an unknown joint or a
        # value beyond its limits
        self._prefer = check_prefer("first" if prefer is None else prefer)
        self._locked = None
        options = dict(options)
        if locked:
            self._locked = _Locked(robot, locked, method, self._prefer, options)
            return
        self._info = info = get_solver(method)
        self._polish = bool(options.pop("polish", False))
        q0 = options.pop("q0", None)
        self._problem_kw = problem_kw = split_options(options)
        # the template: every problem option checked once (a goal list's problems are made from the same options)
        self._template = IKProblem(robot, Target(np.zeros(3)), **problem_kw)
        self._q_shape = (robot.n,)
        self._q0 = None if q0 is None else self._checked_q0(q0)
        self._objective = problem_kw.get("objective")  # a custom objective serves every target; None: the default
        # near-unbounded joints searched in a box around each target (target_box) unless bounds were given
        self._target_box = "lower" not in problem_kw and "upper" not in problem_kw and bool(
            ((np.abs(robot.lower) >= NEAR_UNBOUNDED) | (np.abs(robot.upper) >= NEAR_UNBOUNDED)).any())
        # a goal list's box: the bounds given, else the robot's (IKProblem's for a goal list: no target box); the
        # template's own arrays whenever they hold those values, so that single targets and goal lists share one box
        # (the plan keeps one seed table per box arrays: a solver alternating them would look the table up anew)
        template = self._template
        given = "lower" in problem_kw or "upper" in problem_kw
        self._goal_box = ((template.lower, template.upper) if given or (
            np.array_equal(template.lower, robot.lower) and np.array_equal(template.upper, robot.upper))
                          else (robot.lower.copy(), robot.upper.copy()))
        self._options = options
        check_prefer_method(self._prefer, method)
        info.check_options(options, n=robot.n)
        self._plan = None
        if method == "memetic":
            from .solvers.search.memetic import MemeticSetup

            self._plan = MemeticSetup(robot, **options)
        # solve may call the plan directly (prefer= other than "first" chooses among answers: search.choose)
        self._plain = self._plan is not None and not self._polish and self._prefer == "first"
        # the per-call paths (memetic's compiled first runs and little else), one per kind (True: poses, False:
        # positions) and per one-goal list's goal stack (by id; the last _GOAL_REPEAT_CALLS), made after the general
        # path has solved a target of that kind: for the default objective in a box that does not move with the target
        # (a custom objective may need the Target; a target box is remade per target)
        self._repeat_calls: dict = {}
        self._repeat_calls_open = self._plain and not self._target_box and self._objective is None
        self._box_stage = None  # solve_within's stage (velocity_box), made on its first call

    def _checked_q0(self, q0) -> np.ndarray:
        arr = np.asarray(q0, dtype=float)
        # Robot.check_q's verdict for the usual q0 in a fraction of its microsecond: of shape (n,) and a finite sum
        # (a NaN or inf makes the sum NaN or inf); anything else, huge finite entries whose sum overflows too, gets
        # check_q itself, which accepts or raises its error
        if arr.shape == self._q_shape and math.isfinite(sum(arr.tolist())):
            return arr
        try:
            return self.robot.check_q(q0)
        except ConfigurationError as exc:
            raise ConfigurationError(f"q0: {exc}") from None

    def problem(self, target, q0=None) -> IKProblem:
        """The :class:`~evoik_pin.IKProblem` of one target (or goal list) and start ``q0`` (None: the solver's),
        as :func:`evoik_pin.make_problem` would make it with the solver's options, checked the same way."""
        template = self._template
        objective = self._objective
        if is_goal_list(target):
            if objective is not None:  # refused for a goal list: IKProblem raises its error
                kw = self._problem_kw
                q0 = self._q0 if q0 is None else q0
                return IKProblem(self.robot, list(target), **kw, **({} if q0 is None else {"q0": q0}))
            return self._goal_problem(bind(self.robot, target), q0)
        target = Target.coerce(target)
        p = object.__new__(IKProblem)
        # the template's fields with this call's: one dict built, no attribute set one by one
        p.__dict__ = {**template.__dict__, "target": target, "objective": default_objective(
            target, template.orientation_weight, template.pose_metric) if objective is None else objective,
            "q0": self._q0 if q0 is None else self._checked_q0(q0), "evaluations": 0}
        if self._target_box:
            p.lower, p.upper = target_box(self.robot, target, self.robot.lower, self.robot.upper)
        return p

    def _goal_problem(self, bound: tuple, q0) -> IKProblem:
        """:meth:`problem` of a goal list bound to the robot (``bound``: :func:`~evoik_pin.goals.stack.bind`'s
        (goals, stack, pt, Rt): the goals' checks made, the stack cached for equal goals), q0 checked; the box is the
        solver's own arrays, the same every call (the plan keeps its seed table and engine while the box arrays are
        the same)."""
        goals, stack, pt, Rt = bound
        p = object.__new__(IKProblem)
        lower, upper = self._goal_box
        p.__dict__ = {**self._template.__dict__, "target": None, "goals": goals, "_goal_stack": [stack, pt, Rt],
                      "objective": None, "q0": self._q0 if q0 is None else self._checked_q0(q0), "evaluations": 0,
                      "lower": lower, "upper": upper}
        return p

    def solve(self, target, q0=None, seed=None) -> Result:
        """Solve one target: a 3-vector position (m), a ``pin.SE3``, a (4, 4) matrix, a
        :class:`~evoik_pin.Target`, or a goal list (:mod:`evoik_pin.goals`); from ``q0`` (n,) when given; ``seed``:
        int, ``numpy.random.Generator`` or None. The :class:`~evoik_pin.Result` of :func:`evoik_pin.solve` with the
        solver's robot, method and options, the same for the same seed."""
        if self._locked is not None:
            return self._locked.solve(target, q0, seed)
        problem = None
        if self._repeat_calls:
            # a pose or a position on the lane of its kind (repeat_call), here rather than behind a call: the
            # lane's whole Python is a few us, and a control loop's calls are nearly all of this kind
            arrays = pose_arrays(target)
            if arrays is not None:
                lane = self._repeat_calls.get(arrays[1] is not None)
                if lane is not None and lane.usable():
                    q0 = self._repeat_call_q0(q0, seed)
                    out = lane.solve(arrays[0], arrays[1], q0)
                    return out if type(out) is Result else self._resume_general(self.problem(target, q0), seed, out)
            else:
                problem = self._goal_repeat_call(target, q0, seed)
                if type(problem) is Result:
                    return problem
        if problem is None:
            if type(target) in (list, tuple) and any(isinstance(x, Preference) for x in target):
                return self._solve_choosing(target, q0, seed)
            problem = self.problem(target, q0)
        if self._prefer != "first":
            return self._solve_choosing(problem, q0, seed)
        return self.run(problem, _rng(seed))

    def solve_within(self, target, q_prev, step, seed=None) -> Result:
        """Solve one target (or goal list) inside the velocity box of the last configuration ``q_prev`` (n,):
        ``[q_prev - step, q_prev + step]`` (``step`` (n,) rad or m: ``v_max dt``) within the solver's bounds,
        full-turn joints in unwrapped values around ``q_prev`` (:mod:`evoik_pin.solvers.search.velocity_box`).

        The answer is inside the box whatever the target: the one closest to meeting the goals, ``success=False`` and
        its goal errors when they cannot be met within it. Levenberg-Marquardt from ``q_prev``, then a few starts
        inside the box drawn from ``seed`` (int, Generator or None) when that run falls short; the solver's goals,
        tolerances, bounds and scene, whatever its method (a box this small holds one branch: no global search).
        The box is written into the stage's own engine per call: no seed table is built for it.

        Raises:
            OptionError: goal lists holding preferences (the box's stage meets goals only). The errors of
            :meth:`solve` for a bad target or ``q_prev``.
        """
        if self._locked is not None:
            return self._locked.solve_within(target, q_prev, step, seed)
        if type(target) in (list, tuple) and any(isinstance(x, Preference) for x in target):
            from .errors import OptionError

            raise OptionError("velocity limits meet goals only: a goal list with preferences (Posture, "
                              "JointLimitMargin, ...) is not accepted with velocity_limits; drop the preferences")
        q_prev = self._checked_q0(q_prev)
        problem = self.problem(target)  # its q0 is not read: the stage starts from q_prev
        stage = self._box_stage
        if stage is None:
            from .solvers.search.velocity_box import VelocityBoxStage

            stage = self._box_stage = VelocityBoxStage(self.robot)
        return stage.solve(problem, q_prev, step, None if seed is None else _rng(seed))

    def _goal_repeat_call(self, target, q0, seed) -> Result | IKProblem | None:
        """A one-goal list on the lane of its goal stack (repeat_call; :meth:`solve` puts poses and positions
        on theirs): the Result (memetic going on from the lane's first runs when none met the tolerances); the
        problem of a one-goal list without a lane (bound already); None for any other target."""
        if not (type(target) is list and len(target) == 1 and isinstance(target[0], Goal)
                and target[0].alternatives is None and self._objective is None):
            return None
        bound = bind(self.robot, target)  # the goal's checks; equal goals' stack (a goal set's may be too)
        lane = self._repeat_calls.get(id(bound[1]))
        if lane is None or lane.key is not bound[1] or not lane.usable():
            return self._goal_problem(bound, q0)
        q0 = self._repeat_call_q0(q0, seed)
        out = lane.solve(bound[2][0], bound[3][0], q0, bound[0])
        return out if type(out) is Result else self._resume_general(self._goal_problem(bound, q0), seed, out)

    def _solve_choosing(self, target, q0, seed) -> Result:
        """:meth:`solve` with ``prefer`` other than ``"first"`` or preferences among the goals (``target``: the goal
        list or target, or its problem already made). Preferences with ``prefer="first"`` (or another method than
        memetic) come after the method's own search: the same answers as without them, then refined in the goals'
        null space (a step kept only when every goal is still met), so they never cost success."""
        from .goals.preferences import split_preferences
        from .solvers.search.choose import choose
        from .solvers.search.prefer import bind_preferences, refine

        if isinstance(target, IKProblem):
            problem, prefs = target, []
        else:
            goals, prefs = split_preferences(target)
            problem = self.problem(goals, q0)
        rng = _rng(seed)
        if self._prefer != "first":  # memetic collecting answers (search.choose), the preferences among its terms
            result = choose(problem, rng, prefer=self._prefer, preferences=prefs, **self._options)
            if problem.goals is not None:
                result = _with_goal_verdict(problem, result)
            return with_collision_verdict(problem, result)
        criterion = bind_preferences(problem, prefs)  # bad preferences fail before the solve
        result = self.run(problem, rng)
        if not result.success:
            return result
        from .solvers.lm import LevenbergMarquardt

        refined = problem
        if problem.goals is not None and problem.goal_sets:  # refined on the members the answer meets
            choices, P, R = problem.variant_targets()
            k = choices.index(tuple(problem.chosen(result.q)))
            refined = problem.variant(choices[k], P[k], R[k])
        q, _, _ = refine(refined, LevenbergMarquardt(refined), result.q, criterion, None)
        result.q, result.position_error, result.orientation_error, result.cost = q, *problem.assess(q)
        result.goal_errors = None
        result.collision_free = None  # the search's verdict was on its answer, not the refined one
        if problem.goals is not None:
            result = _with_goal_verdict(problem, result)
        return with_collision_verdict(problem, result)

    def _repeat_call_q0(self, q0, seed):
        """A lane call's q0 (checked; None: the solver's own) after the seed's check: the general path's errors for
        a bad q0 or seed, in its order (the target's checks came first)."""
        q0 = self._q0 if q0 is None else self._checked_q0(q0)
        if seed is not None and not (type(seed) is int and seed >= 0):
            _rng(seed)  # a Generator passes; anything else raises the general path's error
        return q0

    def _resume_general(self, problem: IKProblem, seed, out) -> Result:
        """The general path after a lane's first runs none of which met the tolerances: memetic goes on from their
        state (``out``: the lane's), or solves ``problem`` from the start (``out`` None: a run converged by the
        kernel's test but not by the problem's tolerances)."""
        rng = _rng(seed)
        result = self._plan.solve(problem, rng) if out is None else self._plan.resume(problem, rng, out)
        if problem.goals is not None:
            result.chosen = [None] * len(problem.goals)
        return result

    def _open_repeat_call(self, problem: IKProblem) -> None:
        """After the plan solved ``problem`` (a single target or a one-goal list), make the lane of its kind (or goal
        stack) when there is none, or when the one kept no longer holds (its engine remade; another thread's). The
        lanes of goal stacks are the last few kept."""
        key = problem.target.rotation is not None if problem.goals is None else id(problem.goal_stack()[0])
        kept = self._repeat_calls.get(key)
        if kept is None or not kept.usable():
            from .solvers.search.repeat_call import RepeatCall

            lane = RepeatCall.of_setup(self._plan, problem)
            if lane is not None:
                if problem.goals is not None:
                    stacks = [k for k in self._repeat_calls if k is not True and k is not False]
                    if len(stacks) >= _GOAL_REPEAT_CALLS:
                        del self._repeat_calls[stacks[0]]
                self._repeat_calls[key] = lane

    def run(self, problem: IKProblem, rng) -> Result:
        """The method on a problem of this solver (:meth:`problem`), then what :func:`evoik_pin.solve` does
        after it: ``polish``, the goals' verdict, the scene's exact check."""
        goals = problem.goals
        if self._plain and problem.scene is None and (goals is None or not problem.goal_sets):
            # memetic's plan alone (no polish, no scene): memetic judged each goal by goals_met on the goal_errors it
            # returns, every goal with one target (chosen: None each), so the goals' verdict is its own
            result = self._plan.solve(problem, rng)
            if goals is not None:
                result.chosen = [None] * len(goals)
            if self._repeat_calls_open and (goals is None or len(goals) == 1):
                self._open_repeat_call(problem)
            return result
        goal_problem = problem if goals is not None else None
        if goal_problem is not None:  # the method's own problem of a goal list (the closed forms: one tip goal)
            problem = _goal_method_problem(self.method, problem)
        if self._plan is not None:
            result = self._plan.solve(problem, rng)
        else:
            result = self._info.func(problem, rng, **self._options)
        if self._polish:
            from .solvers.lm.polish import polish_result

            result = polish_result(problem, result, rng)
        if goal_problem is not None:
            result = _with_goal_verdict(goal_problem, result)
        return with_collision_verdict(problem, result)

    def __repr__(self) -> str:
        return f"IKSolver({self.robot.name!r}, method={self.method!r})"


class _Locked:
    """An :class:`IKSolver`'s joints held fixed (``locked``: {joint: value}, rad or m): the solver of the robot without
    them (:meth:`Robot.locked`), ``q0``, ``bounds`` and the answers in the full robot's layout, the locked joints at
    their values."""

    def __init__(self, robot, locked: dict, method: str, prefer: str, options: dict) -> None:
        from .robot.locking import locked_robot, shrink_q

        self.robot = robot
        self.sub = sub = locked_robot(robot, locked)
        self.values = {k: float(v) for k, v in locked.items()}
        if options.get("q0") is not None:
            options["q0"] = shrink_q(robot, sub, options["q0"])
        if options.get("bounds") is not None:
            lower, upper = options["bounds"]
            options["bounds"] = (shrink_q(robot, sub, lower), shrink_q(robot, sub, upper))
        self.solver = IKSolver(sub, method, prefer=prefer, **options)

    def solve(self, target, q0, seed) -> Result:
        from .robot.locking import expand_result, shrink_q

        if q0 is not None:
            q0 = shrink_q(self.robot, self.sub, q0)
        return expand_result(self.robot, self.sub, self.values, self.solver.solve(target, q0, seed))

    def solve_within(self, target, q_prev, step, seed) -> Result:
        from .robot.locking import expand_result, kept_columns, shrink_q

        step = np.asarray(step, dtype=float)[kept_columns(self.robot, self.sub)]
        return expand_result(self.robot, self.sub, self.values, self.solver.solve_within(
            target, shrink_q(self.robot, self.sub, q_prev), step, seed))


# ---------------------------------------------------------------------- evoik_pin.solve's solvers
#: One-goal lists' lanes an IKSolver keeps (one per goal stack: frame, kind, weight, tolerances; the last made): as
#: many as the plan keeps engines (a lane opens at its engine's second problem).
_GOAL_REPEAT_CALLS = KEPT_ENGINES
_LOCAL = threading.local()
#: IKSolvers evoik_pin.solve keeps per thread (the last ones made; each keeps its robot, seed table and scene alive,
#: so the number is small).
_CACHED = 8
#: Option values keyed by value (by type too: population=32.0 must still be refused where 32 is accepted).
_PLAIN = (bool, int, float, str, type(None), np.integer, np.floating)


def _key(robot, method: str, options: dict):
    """A hashable key of (robot, its bounds, method, options), or None when an option is not a plain value (a
    scene file's path: the file may change between calls; arrays)."""
    parts = []
    for name, value in options.items():
        if name == "q0":
            continue
        if isinstance(value, _PLAIN) and not (name == "scene" and isinstance(value, str)):
            if isinstance(value, float) and math.isnan(value):  # NaN != NaN: such a key would never hit
                return None
            parts.append((name, type(value), value))
        elif name == "locked" and isinstance(value, dict) and all(
                type(k) is str and isinstance(v, _PLAIN) for k, v in value.items()):
            parts.append((name, None, tuple(sorted((k, type(v), v) for k, v in value.items()))))
        elif name == "objective" or (name == "scene" and isinstance(value, Scene)):
            # an object, by identity: the cached solver keeps it alive, so its id is not reused while cached (a
            # scene file's path is read into a Scene anew on every call, as before: the file may change)
            parts.append((name, None, id(value)))
        else:
            return None
    parts.sort(key=lambda part: part[0])
    return (id(robot), robot.lower.tobytes(), robot.upper.tobytes(), method, tuple(parts))


def cached_solver(robot, method: str, options: dict) -> IKSolver | None:
    """The IKSolver :func:`evoik_pin.solve` uses for these arguments (made on first use, then kept), or None when
    they take the general path: a robot given by name, options that are no plain values, or options the solver
    refuses (the general path then raises the error :func:`evoik_pin.solve` always raised, in its order)."""
    if type(robot) is not Robot and not isinstance(robot, Robot):
        return None
    key = _key(robot, method, options)
    if key is None:
        return None
    cache = getattr(_LOCAL, "solvers", None)
    if cache is None:
        cache = _LOCAL.solvers = {}
    solver = cache.get(key)
    if solver is not None and solver.robot is robot:
        return solver
    try:
        solver = IKSolver(robot, method, **{k: v for k, v in options.items() if k != "q0"})
    except EvoikError:
        return None
    if len(cache) >= _CACHED:
        cache.pop(next(iter(cache)))
    cache[key] = solver
    return solver



def solver_for(robot, method: str, options: dict, target) -> IKSolver:
    """The IKSolver that solves ``target`` for :func:`evoik_pin.solve` with these arguments: the one kept for them
    (:func:`cached_solver`), else a new one (a robot by name, a scene file's path, array bounds: options that are no
    plain values). Bad arguments raise solve's errors in its order: the target's own checks (a NaN, a 5-vector) come
    before the options'."""
    solver = cached_solver(robot, method, options)
    if solver is not None:
        return solver
    robot = _robot(robot)
    try:
        return IKSolver(robot, method, **{k: v for k, v in options.items() if k != "q0"})
    except EvoikError:
        # solve's order: prefer=, locked=, the target's own checks (a goal list's bound to the robot), the options
        from .goals.preferences import split_preferences
        from .robot.locking import locked_robot
        from .solvers.search.prefer import check_prefer

        check_prefer("first" if options.get("prefer") is None else options["prefer"])
        goals = split_preferences(target)[0]
        if options.get("locked"):
            robot = locked_robot(robot, options["locked"])
            if not is_goal_list(goals):
                Target.coerce(goals)
            elif options.get("objective") is None:  # an objective with a goal list: the options' error
                bind(robot, goals)
        else:  # the problem's checks in their order: the target, tolerances, bounds, q0, margin, scene
            make_problem(robot, goals, **{k: v for k, v in options.items() if k in _PROBLEM_OPTIONS})
        raise
