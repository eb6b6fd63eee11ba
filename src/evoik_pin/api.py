"""The public calls: :func:`solve`, :func:`solve_all`, :func:`solve_trajectory`, :func:`solve_many`, :func:`prepare`;
they route to :mod:`evoik_pin.solvers`. The reference with examples: docs/API.md."""

from __future__ import annotations

import time

import numpy as np

from .call_setup import (  # noqa: F401  (api._run, api._PROBLEM_OPTIONS, api._rng are read by cli.py, tests)
    _PROBLEM_OPTIONS,
    DEFAULT_ALL_METHOD,
    DEFAULT_METHOD,
    GOAL_METHODS,
    _check_goal_method,
    _rng,
    _robot,
    _run,
    make_problem,
)
from .errors import ConfigurationError, MethodError, OptionError
from .goals.preferences import split_preferences
from .ik_solver import IKSolver, check_no_preferences, solver_for
from .problem import DEFAULT_PRO_DELTA, Target, check_pro_delta, pro_box
from .result import Result
from .solvers import get_solver, methods
from .solvers.batch import solve_many_call
from .solvers.batch.batch_results import BatchResults
from .solvers.batch.goal_lists import GoalSource, is_goal_batch, is_problem_list
from .solvers.batch.threads import check_call
from .solvers.lm import ENGINES
from .solvers.options import check_choice, check_int
from .solvers.search.all_solutions import SolutionList  # also registers "memetic-all"

__all__ = ["DEFAULT_ALL_METHOD", "DEFAULT_METHOD", "GOAL_METHODS", "BatchResults", "IKSolver", "SolutionList",
           "make_problem",
           "methods", "prepare", "solve", "solve_all", "solve_many", "solve_trajectory"]


def prepare(robot, bounds=None, table_size: int | None = None, engine: str = "compiled") -> float:
    """Load the compiled LM kernel and build memetic's seed table for ``robot``'s box (``bounds=(lower, upper)``,
    ``table_size`` entries, default memetic's) now, so that no later solve pays for it (:attr:`Result.setup_s`).

    Returns:
        The seconds spent (about 0 when everything was ready). Raises OptionError: an unknown ``engine``.
    """
    from .solvers.search.memetic import prepare as prepare_memetic
    from .solvers.search.seed_table import default_table_size

    t0 = time.perf_counter()
    robot = _robot(robot)
    problem, _ = make_problem(robot, np.zeros(3), bounds=bounds)
    size = default_table_size(robot.n) if table_size is None else check_int("table_size", table_size, 0)
    prepare_memetic(robot, problem.lower, problem.upper, size, check_choice("engine", engine, ENGINES))
    return time.perf_counter() - t0


def solve(robot, target, method: str = DEFAULT_METHOD, seed=None, **options) -> Result:
    """Solve one IK problem: the cached :class:`~evoik_pin.IKSolver`'s solve for ``robot``, ``method`` and ``options``.

    Args:
        robot: a :class:`Robot` or anything :func:`load_robot` accepts.
        target: a 3-vector position (m), a ``pin.SE3``, a (4, 4) matrix or a :class:`Target` for the tip; or a goal
            list (:mod:`evoik_pin.goals`, a method of :data:`GOAL_METHODS`), its errors in ``Result.goal_errors``.
        method: a name from :func:`methods` (default ``"memetic"``).
        seed: int or ``numpy.random.Generator``; the same seed gives the same result.
        **options: the problem's (``tolerance`` m, ``rotation_tolerance`` rad, ``q0`` (n,), ``bounds``, ``objective``,
            ``orientation_weight``, ``pose_metric``, ``scene``, ``margin`` m), ``polish``, ``prefer``, ``locked``
            and the method's own (docs/API.md).

    Returns:
        A :class:`Result`; an unreachable target gives ``success=False`` and the best approximation, no exception.
    """
    return solver_for(robot, method, options, target).solve(target, options.get("q0"), seed)


def solve_all(robot, target, method: str = DEFAULT_ALL_METHOD, seed=None, **options) -> SolutionList:
    """Every distinct IK solution of one target (or goal list), nearest ``q0`` (or zero) first; docs/API.md.

    Args: as :func:`solve`; ``method`` a multi-solution method (default ``"memetic-all"``; also ``"hga"``, ``"ga"``,
    ``"algebraic"``), whose own options (``count``, ``class_radius`` rad, ``timeout`` s, ...) it takes.

    Returns:
        A :class:`SolutionList` (a list of :class:`Result`, ``[]`` when none was found; ``.result`` the search's
        own Result, ``.message`` why).

    Raises:
        MethodError: a method returning one solution. OptionError: a bad option.
    """
    info = get_solver(method)
    if not info.multi_solution:
        capable = [m for m in methods() if get_solver(m).multi_solution]
        raise MethodError(f"method {method!r} returns one solution; solve_all needs one of: "
                          f"{', '.join(capable) or '(none)'}")
    if "prefer" in options:  # which one answer to return is solve's choice; solve_all returns them all
        info.check_options({k: v for k, v in options.items() if k not in (*_PROBLEM_OPTIONS, "locked", "polish")})
    result = solver_for(robot, method, options, target).solve(target, options.get("q0"), seed)  # solve's pipeline
    return SolutionList(result.solutions or [], result)


def solve_trajectory(robot, targets, method: str = DEFAULT_METHOD, q0=None, pro: bool = False,
                     delta: float = DEFAULT_PRO_DELTA, seed=None, dt: float | None = None, velocity_limits=None,
                     **options) -> list[Result]:
    """Solve a sequence of targets (or goal lists), each from the previous answer (its ``q`` the next ``q0``), with
    one random generator for the whole path; every target and option checked before the first point.

    Args: as :func:`solve`, plus ``pro`` (paper 002's box: the previous answer +- ``delta`` rad after the first
    point), ``dt`` (s) with ``velocity_limits`` (True, a factor of the URDF's or an array (n,) rad/s and m/s): every
    answer within ``v_max dt`` of the one before (:meth:`IKSolver.solve_within`); docs/API.md.

    Returns:
        A list of :class:`Result`, one per target.

    Raises:
        OptionError: one of ``dt`` and ``velocity_limits`` without the other, bad values, ``pro=True`` with them;
        :func:`solve`'s errors for bad targets and options (named by index).
    """
    robot = _robot(robot)
    rng = _rng(seed)
    prefer = _checked_prefer(options.pop("prefer", None), method, q0 is not None)
    locked = options.pop("locked", None)
    solved_on = robot.locked(locked) if locked else robot  # an unknown joint, a value beyond its limits
    if is_goal_batch(targets):
        source = GoalSource(solved_on, targets)  # every goal list (and its preferences) checked against the robot
        if q0 is None:
            source.require_q0([0])  # the later points start from the one before
        targets = source.raw
        _check_goal_method(method)
    else:
        targets = Target.coerce_many(targets if isinstance(targets, np.ndarray) else list(targets))
    if not targets:
        raise ConfigurationError("solve_trajectory needs at least one target")
    if pro:
        delta = check_pro_delta(delta)
    step = _velocity_step(robot, dt, velocity_limits, pro)
    options = check_call(robot, make_problem, method, options)
    results: list[Result] = []
    previous = None if q0 is None else robot.check_q(q0)
    if locked:
        options["locked"] = locked
    if prefer is not None:
        options["prefer"] = prefer
    box_solver = None
    if step is not None:  # one solver (and its box stage) for every point within the velocity box
        for target in targets:
            check_no_preferences(target)
        box_solver = IKSolver(robot, method, **{k: v for k, v in options.items() if k != "prefer"})
    for i, target in enumerate(targets):
        if box_solver is not None and previous is not None:
            results.append(box_solver.solve_within(target, previous, step, rng))
        else:
            point = {**options, "q0": previous}
            if pro and i > 0:  # the previous answer's box: that point's search box +- delta, q0 clipped into it
                box = make_problem(robot, split_preferences(target)[0], q0=previous, **options)[0]
                lower, upper = pro_box(box.lower, box.upper, previous, delta)
                point.update(q0=np.clip(previous, lower, upper), bounds=(lower, upper))
            results.append(solve(robot, target, method, rng, **point))  # one generator for the whole trajectory
        previous = results[-1].q
    return results


def solve_many(robot, targets, method: str = DEFAULT_METHOD, seed=None, q0=None, workers: int | None = None,
               backend: str = "local", address: str | None = None, progress: bool = False,
               **options) -> BatchResults:
    """Solve many independent targets (or goal lists) on every core or Ray actors (:mod:`evoik_pin.solvers.batch`);
    memetic runs batched LM rounds first. Every target and option checked before any work; docs/API.md, SCALE.md.

    Args: as :func:`solve`, plus ``targets`` (a sequence, or an (N, 4, 4) array of poses), ``q0`` (None, (n,) or
    (N, n)), ``workers`` (threads or actors), ``backend`` (``"local"`` or ``"ray"``), ``address`` (a Ray cluster),
    ``progress`` (a tqdm bar). Target i draws from ``SeedSequence(seed).spawn(N)[i]`` whatever the workers.

    Returns:
        A :class:`BatchResults`: a :class:`Result` per target, the answers as arrays (``q`` (N, n), ``success``,
        ...) and ``stats``.

    Raises:
        OptionError, MethodError, FrameError, BoundsError, TargetError (named by index), BackendError.
    """
    get_solver(method)  # an unknown method fails before any work
    _rng(seed)  # the seed's checks
    if is_goal_batch(targets) or is_problem_list(targets):
        _check_goal_method(method)
    prefer = _checked_prefer(options.pop("prefer", None), method, q0 is not None)
    return solve_many_call.solve_many(_robot(robot), targets, make_problem, _run, method, seed=seed, q0=q0,
                                      workers=workers, backend=backend, address=address, progress=progress,
                                      choose=solve, prefer=prefer, locked=options.pop("locked", None), **options)


def _velocity_step(robot, dt, velocity_limits, pro: bool) -> np.ndarray | None:
    """``v_max dt`` (n,) (rad or m), or None without ``dt`` and ``velocity_limits``; OptionError as solve_trajectory."""
    from .robot.velocity_limits import check_dt
    from .robot.velocity_limits import velocity_limits as limits_of

    if dt is None and velocity_limits is None:
        return None
    if dt is None or velocity_limits is None:
        given, missing = ("dt", "velocity_limits") if velocity_limits is None else ("velocity_limits", "dt")
        raise OptionError(f"solve_trajectory: {given} needs {missing} too (dt in s between points and velocity_limits "
                          "True, a factor or an array (n,) of rad/s and m/s), or neither")
    if pro:
        raise OptionError("solve_trajectory: pro=True and velocity limits are two search boxes; give one of them")
    return limits_of(robot, velocity_limits) * check_dt(dt)


def _checked_prefer(prefer, method: str, q0_given: bool) -> str | None:
    """``prefer`` checked as :func:`solve` checks it: None for ``"first"``, else ``"nearest"`` or ``"manipulability"``.
    OptionError: an unknown value, "nearest" without q0; MethodError: a method other than memetic."""
    from .solvers.search.prefer import check_prefer, check_prefer_method

    prefer = check_prefer("first" if prefer is None else prefer)
    if prefer == "first":
        return None
    check_prefer_method(prefer, method)
    return check_prefer(prefer, q0_given)
