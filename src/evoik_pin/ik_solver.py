"""The one solve pipeline: :class:`IKSolver`, a solver set up once for one robot, method and options;
:func:`evoik_pin.solve` is the solve of an IKSolver kept per robot, method and options (:func:`cached_solver`)."""

from __future__ import annotations

import math
import threading
from functools import partial

import numpy as np

from .call_setup import (
    _PROBLEM_OPTIONS,
    DEFAULT_METHOD,
    _rng,
    _robot,
    make_problem,
    run_with_verdicts,
    settle,
    settle_free,
    split_options,
    with_verdicts,
)
from .errors import EvoikError, OptionError
from .goals import is_goal_list
from .goals.goal import Goal
from .goals.preferences import Preference
from .goals.stack import bind, tip_goals
from .objectives import default_objective
from .problem import NEAR_UNBOUNDED, IKProblem, Target, check_q0, target_box
from .result import Result
from .robot import Robot
from .robot.locking import expand_result, kept_columns, locked_robot, shrink_q
from .scene import Scene
from .solvers import get_solver
from .solvers.search import box_step
from .solvers.search.box_step import step_key
from .solvers.search.memetic import KEPT_ENGINES
from .target import pose_arrays

__all__ = ["IKSolver"]


class IKSolver:
    """One robot, method and set of options, checked and prepared once; :meth:`solve` per target.

    The options are checked once into a template problem that each call copies with its target; memetic's set-up
    (kernel, seed table, engine) is made once. After memetic has solved a pose, a position or a one-goal list (or set),
    the next ones of that kind take a repeat call (:mod:`evoik_pin.solvers.search.repeat_call`): the same answers.

    Args:
        robot: a :class:`~evoik_pin.Robot` or anything :func:`~evoik_pin.load_robot` accepts.
        method: a name from :func:`~evoik_pin.methods` (default ``"memetic"``).
        prefer: ``"first"`` (or None), ``"nearest"`` (q0 required) or ``"manipulability"`` (method memetic).
        locked: ``{joint: value}`` (rad or m) held fixed; ``q0``, ``bounds`` and answers stay in ``robot``'s layout.
        **options: what :func:`evoik_pin.solve` takes; a ``q0`` (n,) here starts every solve not given one.

    Raises:
        The errors :func:`evoik_pin.solve` raises for the same method and options (MethodError, OptionError,
        BoundsError, ConfigurationError, SceneError, FrameError).

    Not to be shared by threads solving at the same time (each call writes the solver's target buffers).
    """

    def __init__(self, robot, method: str = DEFAULT_METHOD, *, prefer: str | None = None, locked: dict | None = None,
                 **options) -> None:
        from .solvers.search.prefer import check_prefer, check_prefer_method

        robot = _robot(robot)
        self.robot = robot
        self.method = method
        # evoik_pin.solve's order of checks: prefer=, then locked=
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
        given = "lower" in problem_kw or "upper" in problem_kw
        # near-unbounded joints searched in a box around each target (target_box) unless bounds were given
        self._target_box = not given and bool(
            ((np.abs(robot.lower) >= NEAR_UNBOUNDED) | (np.abs(robot.upper) >= NEAR_UNBOUNDED)).any())
        # a goal list's box (no target box): the template's arrays when they hold its values, so that targets and goal
        # lists share the plan's one seed table per box arrays
        template = self._template
        self._goal_box = ((template.lower, template.upper) if given or (
            np.array_equal(template.lower, robot.lower) and np.array_equal(template.upper, robot.upper))
                          else (robot.lower.copy(), robot.upper.copy()))
        self._options = options
        check_prefer_method(self._prefer, method)
        info.check_options(options, n=robot.n)
        self._memetic = None
        if method == "memetic":
            from .solvers.search.memetic import MemeticSetup

            self._memetic = MemeticSetup(robot, **options)
        # solve may call the plan directly (prefer= other than "first" chooses among answers: search.answer_choice)
        self._plain = self._memetic is not None and not self._polish and self._prefer == "first"
        # the repeat calls: True (poses), False (positions), id(goal stack) (the last _GOAL_REPEAT_CALLS); only for
        # the default objective in a box that does not move with the target
        self._repeat_calls: dict = {}
        self._repeat_calls_open = self._plain and not self._target_box and self._objective is None
        self._box_stage = None  # solve_within's stage (velocity_box), made on its first call
        self._box_steps: dict = {}  # solve_within's prepared steps: box_step.step_key's key -> BoxStep or None

    def _checked_q0(self, q0) -> np.ndarray:
        arr = np.asarray(q0, dtype=float)
        # Robot.check_q's verdict, faster: shape (n,) and a finite sum (NaN, inf and overflow make it non-finite)
        return arr if arr.shape == self._q_shape and math.isfinite(sum(arr.tolist())) else check_q0(self.robot, q0)

    def problem(self, target, q0=None) -> IKProblem:
        """The :class:`~evoik_pin.IKProblem` of one target (or goal list) and ``q0`` (None: the solver's)."""
        template = self._template
        objective = self._objective
        if is_goal_list(target):
            if objective is not None:  # refused for a goal list: IKProblem raises its error
                return IKProblem(self.robot, list(target), **self._problem_kw)
            return self._goal_problem(bind(self.robot, target), q0)
        target = Target.coerce(target)
        goals, *stack = tip_goals(self.robot, target, template.tolerance, template.rotation_tolerance)
        p = template.copy_with(target=target, goals=goals, _goal_stack=stack, objective=default_objective(
            target, template.orientation_weight, template.pose_metric) if objective is None else objective,
            q0=self._q0 if q0 is None else self._checked_q0(q0))
        if self._target_box:
            p.lower, p.upper = target_box(self.robot, target, self.robot.lower, self.robot.upper)
        return p

    def _goal_problem(self, bound: tuple, q0) -> IKProblem:
        """:meth:`problem` of a goal list bound to the robot (``bound``: :func:`~evoik_pin.goals.stack.bind`'s
        (goals, stack, pt, Rt)); the box is the solver's own arrays, so the plan keeps its seed table and engine."""
        goals, stack, pt, Rt = bound
        lower, upper = self._goal_box
        return self._template.copy_with(target=None, goals=goals, _goal_stack=[stack, pt, Rt], objective=None,
                                        q0=self._q0 if q0 is None else self._checked_q0(q0), lower=lower, upper=upper)

    def solve(self, target, q0=None, seed=None) -> Result:
        """The :class:`~evoik_pin.Result` of :func:`evoik_pin.solve` for ``target`` (any form it takes), ``q0`` (n,)
        and ``seed`` (int, Generator or None) with the solver's robot, method and options."""
        if self._locked is not None:
            return self._locked.solve(target, q0, seed)
        problem = None
        if self._repeat_calls:
            # a pose or a position on the repeat call of its kind, inline: its whole Python is a few us
            arrays = pose_arrays(target, check_rotation=False)  # the rotation checked in the compiled guaranteed runs
            if arrays is not None:
                repeat = self._repeat_calls.get(arrays[1] is not None)
                if repeat is not None and repeat.usable():
                    q0 = self._repeat_call_q0(q0, seed)
                    out = repeat.solve(arrays[0], arrays[1], q0, rotation_checked=False)
                    if type(out) is not Result:
                        return self._resume_general(self.problem(target, q0), seed, out)
                    if repeat.free is not None:  # settle_free's rule (call_setup), its mask kept on the repeat call
                        settle(out.q, repeat.free, q0, *repeat.box)
                    return out
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
        """Solve one target (or goal list) inside the velocity box ``[q_prev - step, q_prev + step]`` (``step`` (n,)
        rad or m: ``v_max dt``) within the bounds (:mod:`evoik_pin.solvers.search.velocity_box`): the answer closest
        to meeting the goals inside it, ``success=False`` when they cannot be met there. After the first call of a
        goal structure (or tip-target kind), the next ones take its prepared step
        (:mod:`evoik_pin.solvers.search.box_step`), with the same answers.

        Raises:
            OptionError: goal lists holding preferences, a ``step`` not (n,) finite and >= 0. :meth:`solve`'s errors
            for a bad target or ``q_prev``.
        """
        if self._locked is not None:
            return self._locked.solve_within(target, q_prev, step, seed)
        # C-contiguous float64 arrays: the prepared step hands them to compiled code as they are
        return self._within(target, np.ascontiguousarray(self._checked_q0(q_prev)), self._checked_step(step),
                            None if seed is None else _rng(seed))

    def _within(self, target, q_prev: np.ndarray, step: np.ndarray, rng) -> Result:
        """:meth:`solve_within` on arguments checked already: ``q_prev`` and ``step`` float64 (n,) (rad or m), ``rng``
        a Generator or None (a :class:`~evoik_pin.Tracker`'s step: its configuration, ``v_max dt`` and generator,
        checked once); the target is checked here."""
        if self._locked is not None:
            return self._locked.solve_within(target, q_prev, step, rng)
        keyed = step_key(target)
        if keyed is not None and box_step.PREPARED:
            prepared = self._box_steps.get(keyed[0])
            if prepared is not None and prepared.usable():
                return prepared.solve(target, keyed[1], q_prev, step, rng)
        check_no_preferences(target)
        problem = self.problem(target)  # its q0 is not read: the stage starts from q_prev
        stage = self._box_stage
        if stage is None:
            stage = self._box_stage = box_step.VelocityBoxStage(self.robot)
        result = stage.solve(problem, q_prev, step, rng)
        if keyed is not None and box_step.PREPARED and self._box_steps.get(keyed[0], False) is not None:
            # the structure's prepared step (None where it has none: not sought again)
            if len(self._box_steps) >= _KEPT_BOX_STEPS and keyed[0] not in self._box_steps:
                self._box_steps.pop(next(iter(self._box_steps)))
            self._box_steps[keyed[0]] = box_step.BoxStep.prepare(self, target)
        return result

    def _checked_step(self, step) -> np.ndarray:
        """``step`` (n,) as float64, finite and >= 0 (rad or m); OptionError naming what is accepted."""
        if type(step) is np.ndarray and step.dtype == np.float64 and step.shape == self._q_shape and (
                step.flags.c_contiguous):
            values = step.tolist()
            if math.isfinite(sum(values)) and min(values) >= 0.0:
                return step
        try:
            arr = np.ascontiguousarray(step, dtype=float)
        except (TypeError, ValueError):
            arr = None
        if arr is None or arr.shape != self._q_shape or not (np.isfinite(arr).all() and (arr >= 0.0).all()):
            raise OptionError(f"step must be {self.robot.n} finite half-widths >= 0 (rad or m: v_max dt), got "
                              f"{step!r}")
        return arr

    def _goal_repeat_call(self, target, q0, seed) -> Result | IKProblem | None:
        """A one-goal list (a goal set too: its members nearest the seed table) on the repeat call of its goal stack:
        the Result; the problem (bound) when it has none; None for any other target."""
        if not (type(target) is list and len(target) == 1 and isinstance(target[0], Goal) and self._objective is None):
            return None
        bound = bind(self.robot, target)  # the goal's checks; equal goals' stack (a goal set's members' too)
        repeat = self._repeat_calls.get(id(bound[1]))
        if repeat is None or repeat.key is not bound[1] or not repeat.usable():
            return self._goal_problem(bound, q0)
        q0 = self._repeat_call_q0(q0, seed)
        if target[0].alternatives is not None:  # a goal set: the goal-set search when none of those members is met
            out = repeat.solve_set(target[0], q0)
            if out is None:
                return self._goal_problem(bound, q0)
        else:
            out = repeat.solve(bound[2][0], bound[3][0], q0)
            if type(out) is not Result:
                return self._resume_general(self._goal_problem(bound, q0), seed, out)
        if repeat.free is not None:  # settle_free's rule (call_setup), its mask kept on the repeat call
            settle(out.q, repeat.free, q0, *repeat.box)
        return out

    def _solve_choosing(self, target, q0, seed) -> Result:
        """:meth:`solve` with ``prefer`` other than ``"first"`` or preferences among the goals (``target``: the goals
        or their problem). With ``prefer="first"`` the preferences refine the method's answer in the goals' null
        space, a step kept only while every goal is still met."""
        from .goals.preferences import split_preferences
        from .solvers.search.answer_choice import choose
        from .solvers.search.prefer import bind_preferences, refine

        if isinstance(target, IKProblem):
            problem, prefs = target, []
        else:
            goals, prefs = split_preferences(target)
            problem = self.problem(goals, q0)
        rng = _rng(seed)
        if self._prefer != "first":
            # memetic collecting answers (search.answer_choice), the preferences among its terms; the solver's memetic
            # set-up lends its LM engine (retargeted, not made anew every call)
            result = choose(problem, rng, prefer=self._prefer, preferences=prefs, setup=self._memetic, **self._options)
            # the free joints at q0 (settle_free) unless preferences among the terms placed them
            return with_verdicts(problem, result if prefs else settle_free(problem, result))
        criterion = bind_preferences(problem, prefs)  # bad preferences fail before the solve
        result = self.run(problem, rng)
        if not result.success:
            return result
        from .solvers.lm import LevenbergMarquardt

        refined = problem
        if problem.goal_sets:  # refined on the members the answer meets
            choices, P, R = problem.variant_targets()
            k = choices.index(tuple(problem.chosen(result.q)))
            refined = problem.variant(choices[k], P[k], R[k])
        q, _, _ = refine(refined, LevenbergMarquardt(refined), result.q, criterion, None)
        result.q, result.position_error, result.orientation_error, result.cost = q, *problem.assess(q)
        result.goal_errors = None
        result.collision_free = None  # the search's verdict was on its answer, not the refined one
        return with_verdicts(problem, result)

    def _repeat_call_q0(self, q0, seed):
        """A repeat call's q0 (checked; None: the solver's), then the seed's check, as the general path orders them."""
        q0 = self._q0 if q0 is None else self._checked_q0(q0)
        if seed is not None and not (type(seed) is int and seed >= 0):
            _rng(seed)  # a Generator passes; anything else raises the general path's error
        return q0

    def _resume_general(self, problem: IKProblem, seed, out) -> Result:
        """Memetic after a repeat call's guaranteed runs met no tolerance: going on from their state ``out``, or from
        the start (``out`` None)."""
        rng = _rng(seed)
        result = self._memetic.solve(problem, rng) if out is None else self._memetic.resume(problem, rng, out)
        result.chosen = problem.reported([None] * len(problem.goals))
        return settle_free(problem, result)

    def _open_repeat_call(self, problem: IKProblem) -> None:
        """Make the repeat call of ``problem``'s kind (or goal stack) after memetic solved it, unless a usable one is
        kept."""
        key = problem.target.rotation is not None if problem.target is not None else id(problem.goal_stack()[0])
        kept = self._repeat_calls.get(key)
        if kept is None or not kept.usable():
            from .solvers.search.repeat_call import RepeatCall

            repeat = RepeatCall.of_setup(self._memetic, problem)
            if repeat is not None:
                if problem.target is None:
                    stacks = [k for k in self._repeat_calls if k is not True and k is not False]
                    if len(stacks) >= _GOAL_REPEAT_CALLS:
                        del self._repeat_calls[stacks[0]]
                self._repeat_calls[key] = repeat

    def run(self, problem: IKProblem, rng) -> Result:
        """The method on this solver's problem (:meth:`problem`), then ``polish``, the goals' and scene's verdicts."""
        goals = problem.goals
        if self._plain and problem.scene is None and not problem.goal_sets:
            # memetic's plan alone: without goal sets, scene or polish its verdict is the goals' verdict
            result = self._memetic.solve(problem, rng)
            result.chosen = problem.reported([None] * len(goals))
            if self._repeat_calls_open and len(goals) == 1:
                self._open_repeat_call(problem)
            return settle_free(problem, result)
        solve = self._memetic.solve if self._memetic is not None else partial(self._info.func, **self._options)
        result = run_with_verdicts(problem, self.method, solve, self._polish, rng)
        if (self._repeat_calls_open and problem.target is None and len(goals) == 1 and problem.scene is None
                and result.success and result.chosen[0] is not None):
            self._open_set_repeat_call(problem, result)
        return result

    def _open_set_repeat_call(self, problem: IKProblem, result: Result) -> None:
        """After the goal-set search met a one-goal set: the repeat call of its goal stack (its members' too), opened
        by memetic solving the member met from the answer (one LM evaluation), unless a usable one is kept."""
        goal = problem.goals[0]
        kept = self._repeat_calls.get(id(problem.goal_stack()[0]))
        if kept is not None and kept.usable():
            return
        member = self._goal_problem(bind(self.robot, [goal.alternatives[result.chosen[0]]]), result.q)
        if member.goal_stack()[0] is problem.goal_stack()[0]:
            self.run(member, _rng(0))  # a plain one-goal list: run opens its repeat call (no draw: q0 meets it)

    def __repr__(self) -> str:
        return f"IKSolver({self.robot.name!r}, method={self.method!r})"


def check_no_preferences(target) -> None:
    """OptionError for a goal list holding preferences: a velocity box meets goals only."""
    if type(target) in (list, tuple) and any(isinstance(x, Preference) for x in target):
        raise OptionError("velocity limits meet goals only: a goal list with preferences (Posture, "
                          "JointLimitMargin, ...) is not accepted with velocity_limits; drop the preferences")


class _Locked:
    """An :class:`IKSolver` of the robot without its ``locked`` joints (:meth:`Robot.locked`), in the full layout."""

    def __init__(self, robot, locked: dict, method: str, prefer: str, options: dict) -> None:
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
        if q0 is not None:
            q0 = shrink_q(self.robot, self.sub, q0)
        return expand_result(self.robot, self.sub, self.values, self.solver.solve(target, q0, seed))

    def solve_within(self, target, q_prev, step, seed) -> Result:
        step = np.asarray(step, dtype=float)[kept_columns(self.robot, self.sub)]
        return expand_result(self.robot, self.sub, self.values, self.solver.solve_within(
            target, shrink_q(self.robot, self.sub, q_prev), step, seed))


# ---------------------------------------------------------------------- evoik_pin.solve's solvers
#: Goal structures whose prepared velocity-box step an IKSolver keeps (as many as its velocity-box stage keeps engines).
_KEPT_BOX_STEPS = 8
#: One-goal lists' repeat calls an IKSolver keeps (the last made): as many as memetic's set-up keeps engines.
_GOAL_REPEAT_CALLS = KEPT_ENGINES
_LOCAL = threading.local()
#: IKSolvers evoik_pin.solve keeps per thread (the last made; each keeps its robot, seed table and scene alive).
_CACHED = 8
#: Option values keyed by value (by type too: population=32.0 must still be refused where 32 is accepted).
_PLAIN = (bool, int, float, str, type(None), np.integer, np.floating)


def _key(robot, method: str, options: dict):
    """A hashable key of (robot, its bounds, method, options), or None for options that are no plain values."""
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
        elif name == "bounds" and (bounds := _bounds_key(value)) is not None:  # by value: a solver copies its bounds
            parts.append((name, None, bounds))
        elif name == "objective" or (name == "scene" and isinstance(value, Scene)):
            # by identity: the cached solver keeps the object alive, so its id is not reused while cached
            parts.append((name, None, id(value)))
        else:
            return None
    parts.sort(key=lambda part: part[0])
    return (id(robot), robot.lower.tobytes(), robot.upper.tobytes(), method, tuple(parts))


def _bounds_key(bounds) -> tuple | None:
    """(shape, lower's bytes, upper's bytes) of ``bounds`` given as two arrays or sequences of numbers (rad or m);
    None for anything else (the general path then raises solve's error)."""
    try:
        lower, upper = bounds
        lower, upper = np.asarray(lower, dtype=float), np.asarray(upper, dtype=float)
    except (TypeError, ValueError):
        return None
    return lower.shape, upper.shape, lower.tobytes(), upper.tobytes()


def cached_solver(robot, method: str, options: dict) -> IKSolver | None:
    """The IKSolver kept for these arguments (made on first use), or None: a robot by name, options that are no
    plain values or that the solver refuses (the general path then raises solve's error)."""
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
    """The IKSolver that solves ``target`` for :func:`evoik_pin.solve` (:func:`cached_solver`'s, else a new one);
    bad arguments raise solve's errors in its order: the target's own checks before the options'."""
    solver = cached_solver(robot, method, options)
    if solver is not None:
        return solver
    robot = _robot(robot)
    try:
        return IKSolver(robot, method, **{k: v for k, v in options.items() if k != "q0"})
    except EvoikError:
        # solve's order: prefer=, locked=, the target's own checks (a goal list's bound to the robot), the options
        from .goals.preferences import split_preferences
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
