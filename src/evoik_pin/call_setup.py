"""One call's plumbing, shared by :mod:`evoik_pin.api` and :mod:`evoik_pin.ik_solver`: the robot and the random
generator of a call, its options split between the problem and the solver, the problem made, the solver run with
its goal-list and collision verdicts."""

from __future__ import annotations

import numpy as np

from .errors import MethodError, OptionError
from .goals import is_goal_list
from .goals.stack import free_entries
from .problem import IKProblem
from .result import Result
from .robot import Robot, load_robot
from .solvers import get_solver
from .solvers.collision_verdict import with_collision_verdict

__all__ = ["DEFAULT_ALL_METHOD", "DEFAULT_METHOD", "GOAL_METHODS", "make_problem", "split_options"]


#: Method used when none is named.
DEFAULT_METHOD = "memetic"
#: Method :func:`solve_all` uses when none is named (every target kind).
DEFAULT_ALL_METHOD = "memetic-all"

# Options consumed by the problem rather than by the solver.
_PROBLEM_OPTIONS = ("tolerance", "rotation_tolerance", "q0", "bounds", "objective", "orientation_weight",
                    "pose_metric", "scene", "margin")


class _DeferredGenerator:
    """A ``numpy.random.Generator`` for ``seed`` (the same draws), created on first use: seeding costs 10-50 us, a
    tenth of a memetic solve, whose deterministic stages usually need no random number."""

    __slots__ = ("_seed", "_generator")

    def __init__(self, seed) -> None:
        self._seed = seed
        self._generator = None

    def __getattr__(self, name):
        if self._generator is None:
            self._generator = np.random.default_rng(self._seed)
        return getattr(self._generator, name)


def _rng(seed) -> np.random.Generator:
    if isinstance(seed, (np.random.Generator, _DeferredGenerator)):
        return seed
    if seed is not None and (isinstance(seed, bool) or not isinstance(seed, (int, np.integer)) or seed < 0):
        raise OptionError(f"seed must be a non-negative integer, a numpy Generator or None, got {seed!r}")
    return _DeferredGenerator(seed)


def _robot(robot) -> Robot:
    return robot if isinstance(robot, Robot) else load_robot(robot)


def split_options(options: dict) -> dict:
    """The problem's keywords (:class:`IKProblem`'s: ``bounds`` as ``lower``, ``upper``) popped from ``options``,
    which keeps the solver's."""
    problem_kw = {k: options.pop(k) for k in _PROBLEM_OPTIONS if k in options}
    bounds = problem_kw.pop("bounds", None)
    if bounds is not None:
        try:
            lower, upper = bounds
        except (TypeError, ValueError):
            raise OptionError("bounds must be a pair (lower, upper) of arrays with one value per joint") from None
        problem_kw["lower"], problem_kw["upper"] = lower, upper
    return problem_kw


def make_problem(robot, target, **options) -> tuple[IKProblem, dict]:
    """Split ``options`` into an :class:`IKProblem` and the remaining solver options."""
    robot = _robot(robot)
    return IKProblem(robot, list(target) if is_goal_list(target) else target, **split_options(options)), options


#: Methods that solve goal lists (:mod:`evoik_pin.goals`); ``algebraic`` takes a goal list that is one Pose or
#: Position goal on the tip.
GOAL_METHODS = ("memetic", "memetic-all", "de", "isade", "pso", "mode", "ga", "ga-binary", "nsga2", "hga")


def settle_free(problem: IKProblem, result: Result) -> Result:
    """``result`` with the entries of q that no goal of a goal list depends on
    (:func:`~evoik_pin.goals.stack.free_entries`: another arm, the head) at q0's values, or without q0 at the box's
    point nearest the zero configuration, in place: they change no goal's error, and the values a start left there (a
    seed-table entry's, a DE member's) are arbitrary. A tip target is its one goal on the tip. Kept as found with a
    scene (they move collision geometry) and under an objective that reads more than the target's errors."""
    target = problem.target
    if problem.scene is None and (target is None or problem.objective.from_errors(
            target, 0.0, 0.0 if target.has_orientation else None) is not None):
        free = free_entries(problem.robot, problem.goal_stack()[0])
        if free is not None:
            settle(result.q, free, problem.q0, problem.lower, problem.upper)
    return result


def settle(q: np.ndarray, free: np.ndarray, q0: np.ndarray | None, lower: np.ndarray, upper: np.ndarray) -> None:
    """``q``'s ``free`` entries ((n,) bool) set to q0's, or without q0 to the point of [lower, upper] nearest 0."""
    q[free] = (np.minimum(np.maximum(0.0, lower), upper) if q0 is None else q0)[free]


def _run(problem: IKProblem, method: str, rng: np.random.Generator, options: dict) -> Result:
    """The registered ``method`` with ``options`` (``polish`` among them) on ``problem``, with its verdicts
    (:func:`run_with_verdicts`)."""
    info = get_solver(method)
    polish = options.pop("polish", False)
    info.check_options(options)
    return run_with_verdicts(problem, method, lambda p, r: info.func(p, r, **options), polish, rng)


def run_with_verdicts(problem: IKProblem, method: str, solve, polish: bool, rng) -> Result:
    """``solve(problem, rng)`` (a goal list: on ``method``'s own problem of it, :func:`_goal_method_problem`), then
    the LM ``polish`` when asked, :func:`settle_free` and the verdicts (:func:`with_verdicts`)."""
    solved = problem if problem.target is not None else _goal_method_problem(method, problem)
    result = solve(solved, rng)
    if polish:
        from .solvers.lm.polish import polish_result

        result = polish_result(solved, result, rng)
    return with_verdicts(problem, settle_free(problem, result))


def with_verdicts(problem: IKProblem, result: Result) -> Result:
    """``result`` judged goal by goal (a goal list: :func:`_with_goal_verdict`), then against the scene
    (:func:`~evoik_pin.solvers.collision_verdict.with_collision_verdict`)."""
    if problem.target is None:
        result = _with_goal_verdict(problem, result)
    return with_collision_verdict(problem, result)


def _check_goal_method(method: str) -> None:
    """MethodError unless ``method`` solves goal lists (:data:`GOAL_METHODS`; ``algebraic`` passes here, its goal
    lists are checked one by one in :func:`_goal_method_problem`)."""
    if method not in GOAL_METHODS and method != "algebraic":
        raise MethodError(f"method {method!r} solves one target for the tip; goal lists are solved by "
                          f"{', '.join(repr(m) for m in GOAL_METHODS)}")


def _goal_method_problem(method: str, problem: IKProblem) -> IKProblem:
    """The problem ``method`` solves for a goal list: the list itself (:data:`GOAL_METHODS`), or, for the closed forms
    (``algebraic``), the one target on the tip that a single Pose or Position goal on the tip stands for; MethodError
    naming the methods that take goal lists otherwise."""
    if method == "algebraic":
        from .solvers.paper.analytic import tip_target_problem

        single = tip_target_problem(problem)
        if single is not None:
            return single
        raise MethodError(f"method 'algebraic' solves one target for the tip (a closed form of one arm): a goal list "
                          f"only when it is one Pose or Position goal on the tip {problem.robot.tip!r}; goal lists "
                          f"are solved by {', '.join(repr(m) for m in GOAL_METHODS)}")
    _check_goal_method(method)
    return problem


def _with_goal_verdict(problem: IKProblem, result: Result) -> Result:
    """A goal problem's result with each goal's errors at its ``q`` (``goal_errors``) and ``success`` judged goal by
    goal, each within its own tolerances (the evolutionary methods compare the largest errors with the problem's
    tolerance, and a polish makes a new Result); a scene's verdict comes after (:func:`with_collision_verdict`)."""
    if result.goal_errors is None:  # goal sets: which member each goal meets, from the same pass
        result.goal_errors, result.chosen = problem.goal_errors_and_chosen(result.q)
    elif result.chosen is None:  # the method gave the errors at its q, not the members
        result.chosen = problem.chosen(result.q)
    met = problem.goals_met(result.goal_errors)
    if result.success and not met:
        unmet = [g.label for g, e in zip(problem.goals, result.goal_errors, strict=True) if not g.met(*e)]
        result.message += f"; goals not met within their own tolerances: {', '.join(unmet)}"
    result.success = met
    return result
