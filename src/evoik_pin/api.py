"""The public surface: :func:`solve`, :func:`solve_trajectory`, :func:`solve_all`, :func:`methods`.

Every call builds an :class:`~evoik_pin.problem.IKProblem` from the robot, the target and the shared
options, draws all randomness from one ``numpy.random.Generator`` seeded by ``seed``, and hands the
problem to the registered solver.
"""

from __future__ import annotations

import numpy as np

from .errors import ConfigurationError, MethodError, OptionError
from .problem import DEFAULT_PRO_DELTA, IKProblem, Target
from .result import Result
from .robot import Robot, load_robot
from .solvers import get_solver, methods

__all__ = ["DEFAULT_METHOD", "make_problem", "methods", "solve", "solve_all", "solve_trajectory"]

#: Method used when none is named.
DEFAULT_METHOD = "memetic"

# Options consumed by the problem rather than by the solver.
_PROBLEM_OPTIONS = ("tolerance", "rotation_tolerance", "q0", "bounds", "objective", "orientation_weight")


def _rng(seed) -> np.random.Generator:
    if isinstance(seed, np.random.Generator):
        return seed
    if seed is not None and (isinstance(seed, bool) or not isinstance(seed, (int, np.integer)) or seed < 0):
        raise OptionError(f"seed must be a non-negative integer, a numpy Generator or None, got {seed!r}")
    return np.random.default_rng(seed)


def _robot(robot) -> Robot:
    return robot if isinstance(robot, Robot) else load_robot(robot)


def make_problem(robot, target, **options) -> tuple[IKProblem, dict]:
    """Split ``options`` into an :class:`IKProblem` and the remaining solver options."""
    robot = _robot(robot)
    problem_kw = {k: options.pop(k) for k in _PROBLEM_OPTIONS if k in options}
    bounds = problem_kw.pop("bounds", None)
    if bounds is not None:
        try:
            lower, upper = bounds
        except (TypeError, ValueError):
            raise OptionError("bounds must be a pair (lower, upper) of arrays with one value per joint") from None
        problem_kw["lower"], problem_kw["upper"] = lower, upper
    if "q0" in problem_kw and problem_kw["q0"] is None:
        problem_kw.pop("q0")
    return IKProblem(robot, Target.coerce(target), **problem_kw), options


def _run(problem: IKProblem, method: str, rng: np.random.Generator, options: dict) -> Result:
    info = get_solver(method)
    polish = options.pop("polish", False)
    info.check_options(options)
    result = info.func(problem, rng, **options)
    if polish:
        from .solvers.memetic import polish_result

        result = polish_result(problem, result, rng)
    return result


def solve(robot, target, method: str = DEFAULT_METHOD, seed=None, **options) -> Result:
    """Solve one IK problem.

    Args:
        robot: a :class:`Robot` or anything :func:`load_robot` accepts.
        target: a 3-vector position (m), a ``pin.SE3``, a (4, 4) matrix or a :class:`Target`.
        method: a name from :func:`methods` (default ``"memetic"``).
        seed: int or ``numpy.random.Generator``; the same seed gives the same result.
        **options: shared ones (``tolerance`` m, ``rotation_tolerance`` rad, ``q0`` (n,), ``bounds``
            (lower, upper), ``objective``, ``orientation_weight``, ``polish``) and the solver's own
            (``population``, ``max_generations``, ...; see each solver's docstring).

    Returns:
        A :class:`Result`; an unreachable target gives ``success=False``, the best approximation and a
        message, not an exception.
    """
    problem, solver_options = make_problem(robot, target, **options)
    return _run(problem, method, _rng(seed), solver_options)


def solve_all(robot, target, method: str = "hga", seed=None, **options) -> list[Result]:
    """Every distinct IK solution a multi-solution method finds, best first (may be empty)."""
    info = get_solver(method)
    if not info.multi_solution:
        capable = [m for m in methods() if get_solver(m).multi_solution]
        raise MethodError(
            f"method {method!r} returns one solution; solve_all needs one of: {', '.join(capable) or '(none)'}"
        )
    problem, solver_options = make_problem(robot, target, **options)
    result = _run(problem, method, _rng(seed), solver_options)
    return list(result.solutions or [])


def solve_trajectory(robot, targets, method: str = DEFAULT_METHOD, q0=None, pro: bool = False,
                     delta: float = DEFAULT_PRO_DELTA, seed=None, **options) -> list[Result]:
    """Solve a sequence of targets, each warm-started from the previous solution.

    With ``pro=True`` (paper 002's "Pro-" variants) the search box of every point after the first is the
    previous solution +- ``delta`` rad, intersected with the bounds. One random generator serves the
    whole trajectory, so a seed fixes every point.
    """
    robot = _robot(robot)
    rng = _rng(seed)
    targets = list(targets)
    if not targets:
        raise ConfigurationError("solve_trajectory needs at least one target")
    results: list[Result] = []
    previous = None if q0 is None else robot.check_q(q0)
    for i, target in enumerate(targets):
        problem, solver_options = make_problem(robot, target, q0=previous, **dict(options))
        if pro and i > 0:
            problem = problem.with_pro_box(previous, delta)
        results.append(_run(problem, method, rng, solver_options))
        previous = results[-1].q
    return results
