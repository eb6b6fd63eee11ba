"""The public surface: :func:`solve`, :func:`solve_trajectory`, :func:`solve_all`, :func:`solve_many`,
:func:`methods`. This module routes; solver logic lives in :mod:`evoik_pin.solvers`.

Every call builds an :class:`~evoik_pin.problem.IKProblem` from the robot, the target and the shared
options, draws all randomness from one ``numpy.random.Generator`` seeded by ``seed``, and hands the
problem to the registered solver.
"""

from __future__ import annotations

import time

import numpy as np

from .call_setup import (  # noqa: F401  (api._run, api._PROBLEM_OPTIONS, ... are read by reach.py, cli.py, tests)
    _PROBLEM_OPTIONS,
    DEFAULT_ALL_METHOD,
    DEFAULT_METHOD,
    GOAL_METHODS,
    _check_goal_method,
    _DeferredGenerator,
    _goal_method_problem,
    _rng,
    _robot,
    _run,
    _with_goal_verdict,
    make_problem,
    split_options,
)
from .errors import ConfigurationError, MethodError, OptionError
from .goals.preferences import split_preferences
from .ik_solver import IKSolver, solver_for
from .problem import DEFAULT_PRO_DELTA, Target, check_pro_delta
from .result import Result
from .solvers import get_solver, methods
from .solvers.batch import solve_many_call
from .solvers.batch.batch_results import BatchResults
from .solvers.batch.goal_lists import GoalSource, is_goal_batch, is_problem_list
from .solvers.batch.threads import check_call
from .solvers.lm import ENGINES
from .solvers.options import check_int
from .solvers.search.all_solutions import SolutionList  # also registers "memetic-all"

__all__ = ["DEFAULT_ALL_METHOD", "DEFAULT_METHOD", "GOAL_METHODS", "BatchResults", "IKSolver", "SolutionList",
           "make_problem",
           "methods", "prepare", "solve", "solve_all", "solve_many", "solve_trajectory"]

def prepare(robot, bounds=None, table_size: int | None = None, engine: str = "compiled") -> float:
    """Do the one-time work of solving with ``robot`` now, so that no later solve pays for it.

    Loads the compiled LM kernel for pose, position and planar goals (numba: about 0.5 s per process from its
    on-disk cache; the first time after an install it is compiled, about 20 s, which one line on stderr announces:
    ``evoik_pin.solvers.lm.compiling``; goals with tolerance bands, free axes, pointing, centre of mass or relative
    poses load their own variant when first solved, before the clock) and builds the memetic solver's seed table
    for the search box (the robot's bounds, or ``bounds=(lower, upper)``; ``table_size`` entries, default
    memetic's). :func:`solve` does this by itself when needed, before its clock starts, and reports the time in
    ``Result.setup_s``; calling ``prepare`` first moves that cost out of the first solve altogether.

    Returns:
        The seconds spent (about 0 when everything was ready).
    """
    from .solvers.search.memetic import prepare as prepare_memetic
    from .solvers.search.seed_table import default_table_size

    t0 = time.perf_counter()
    robot = _robot(robot)
    problem, _ = make_problem(robot, np.zeros(3), bounds=bounds)
    size = default_table_size(robot.n) if table_size is None else check_int("table_size", table_size, 0)
    if engine not in ENGINES:
        raise OptionError(f"LM engine {engine!r} unknown; use one of {list(ENGINES)}")
    prepare_memetic(robot, problem.lower, problem.upper, size, engine)
    return time.perf_counter() - t0


def solve(robot, target, method: str = DEFAULT_METHOD, seed=None, **options) -> Result:
    """Solve one IK problem.

    Args:
        robot: a :class:`Robot` or anything :func:`load_robot` accepts.
        target: a 3-vector position (m), a ``pin.SE3``, a (4, 4) matrix or a :class:`Target` for the robot's tip;
            or a list of goals on its frames (:mod:`evoik_pin.goals`: ``[Pose(frame, T), Position(frame, p),
            ...]``, any method of :data:`GOAL_METHODS`), met together; ``Result.goal_errors`` then gives each goal's
            errors.
        method: a name from :func:`methods` (default ``"memetic"``).
        seed: int or ``numpy.random.Generator``; the same seed gives the same result.
        **options: shared ones (``tolerance`` m, ``rotation_tolerance`` rad, ``q0`` (n,), ``bounds``
            (lower, upper), ``objective``, ``orientation_weight``, ``pose_metric``, ``polish``, ``scene`` (a
            :class:`Scene` or a scene file's path, str or Path), ``margin`` m) and the solver's own
            (``population``, ``max_generations``, ...; see each solver's docstring).
            ``prefer``: ``"first"`` (default: the first answer found), ``"nearest"`` (the answer nearest ``q0``)
            or ``"manipulability"`` (the most dexterous) among the answers found within ``timeout`` (default
            0.7 ms for the last two; method ``"memetic"``; :mod:`evoik_pin.solvers.search.choose`).
            ``locked``: ``{joint: value}`` (rad or m), joints held fixed for this call (:meth:`Robot.locked`);
            ``q0``, ``bounds`` and the answer's ``q`` stay in ``robot``'s full layout, the locked joints at
            their values. The goal list may hold preferences (:mod:`evoik_pin.goals.preferences`: ``Posture``,
            ``JointLimitMargin``, ``Manipulability``, ``MinimalDisplacement``), met as well as the goals allow.

    Returns:
        A :class:`Result`; an unreachable target gives ``success=False``, the best approximation and a
        message, not an exception.

    Every call is an :class:`~evoik_pin.IKSolver`'s solve: the one kept for that robot, method and options (per
    thread) when they are plain values (numbers, strings, a Scene object, ``locked``), whose checks and set-up are
    made once; else one made for the call (a robot by name, a scene file's path, array bounds). A loop of many
    solves can also make its own (``IKSolver(robot, **options).solve(T, q0, seed)``).
    """
    return solver_for(robot, method, options, target).solve(target, options.get("q0"), seed)


def solve_all(robot, target, method: str = DEFAULT_ALL_METHOD, seed=None, **options) -> SolutionList:
    """Every distinct IK solution of one target, best first.

    The default method, ``"memetic-all"`` (:mod:`evoik_pin.solvers.search.all_solutions`), runs batched
    Levenberg-Marquardt from ``q0`` and the seed-table entries nearest to the target, and clusters the
    converged runs into distinct solutions:

    * as many joints as task rows (a 6-D pose on a 6-joint arm, a position on a 3-joint arm, planar (x, y) on
      a 2-joint arm): every solution, e.g. up to 8 on UR arms and spherical wrists, up to 16 on a general 6R;
    * redundant arms (more joints than task rows: Panda on poses, a 6-DOF arm on positions): ``count``
      solutions (default 8) spread over the self-motion manifold by farthest-point selection; the smallest
      pairwise joint distance between them is in ``.message`` and ``.result.history["min_pairwise_distance"]``.

    Distinct means more than ``class_radius`` (default 1e-3 rad) apart in joint space, compared modulo 2 pi on
    joints whose range spans a full turn (continuous joints, UR's +-2 pi joints): one answer per class, never
    two. Each answer is the representative of its class nearest to ``q0`` (to zero without ``q0``): on every
    full-turn joint the multiple of 2 pi inside the box nearest to ``q0``'s value. Every answer lies inside
    the bounds and meets the tolerances by the robot's forward kinematics, re-checked before it is returned.
    "Best first" means nearest ``q0`` (or zero) first: every answer meets the tolerances, so the error does
    not rank them. ``method="hga"`` (paper 001), ``"ga"`` and ``"algebraic"`` keep their own behaviour
    (best = lowest cost first).

    Args:
        robot: a :class:`Robot` or anything :func:`load_robot` accepts.
        target: a pose (``pin.SE3``, (4, 4)), a 3-vector position (m) or a :class:`Target` (planar too); or a goal
            list (:mod:`evoik_pin.goals`): every solution meets every goal within its own tolerances (each with its
            ``goal_errors``); ``memetic-all`` measures distinctness on the joints that move some goal frame and puts
            the others at ``q0`` (zero without it), and a whole robot, redundant, gets ``count`` spread solutions.
        method: a multi-solution method (default ``"memetic-all"``; also ``"hga"``, ``"ga"``, ``"algebraic"``).
        seed: int or ``numpy.random.Generator``; the same seed gives the same solutions (``memetic-all`` draws
            random numbers only when its deterministic starts run out).
        **options: shared ones (``tolerance``, ``rotation_tolerance``, ``q0``, ``bounds``, ...) and the method's
            own; for ``memetic-all``: ``count`` (>= 1), ``timeout`` (s, default 0.02), ``max_starts``,
            ``class_radius`` (rad), ``batch``, ``patience``, ``min_hits``, ``pool``, ``table_size``, ``iterations``,
            ``engine`` (see :func:`evoik_pin.solvers.search.all_solutions.memetic_all`). ``locked``: ``{joint:
            value}`` (rad or m), as for :func:`solve`: the solutions of the robot with those joints held, each ``q``
            in ``robot``'s layout.

    Returns:
        A :class:`SolutionList`: a ``list`` of :class:`Result` (one per solution; plain list behaviour, ``[]``
        when none was found) whose ``.result`` is the search's own :class:`Result` and ``.message`` its
        message. An empty list is not an error: ``.message`` says why (an unreachable pose: "no solution after
        ... LM start(s) ...; best position error ... m ... exceeds the tolerance ...: the target is out of
        reach").

    Raises:
        MethodError: ``method`` returns one solution only (or is ``"algebraic"`` on a goal list other than one goal
        on the tip). OptionError: a bad option (e.g. ``count`` < 1).
    """
    info = get_solver(method)
    if not info.multi_solution:
        capable = [m for m in methods() if get_solver(m).multi_solution]
        raise MethodError(
            f"method {method!r} returns one solution; solve_all needs one of: {', '.join(capable) or '(none)'}"
        )
    if "prefer" in options:  # which one answer to return is solve's choice; solve_all returns them all
        info.check_options({k: v for k, v in options.items() if k not in (*_PROBLEM_OPTIONS, "locked", "polish")})
    result = solver_for(robot, method, options, target).solve(target, options.get("q0"), seed)  # solve's pipeline
    return SolutionList(result.solutions or [], result)


def solve_trajectory(robot, targets, method: str = DEFAULT_METHOD, q0=None, pro: bool = False,
                     delta: float = DEFAULT_PRO_DELTA, seed=None, dt: float | None = None, velocity_limits=None,
                     **options) -> list[Result]:
    """Solve a sequence of targets, each warm-started from the previous solution (its ``q`` the next point's ``q0``).

    ``targets``: targets of the tip (anything :func:`solve` accepts), or goal lists (:mod:`evoik_pin.goals`), one
    per point: a whole robot's motion (e.g. retargeting), each list checked before the first point is solved (a bad
    one named by its index), solved by a method of ``GOAL_METHODS``.

    With ``pro=True`` (paper 002's "Pro-" variants) the search box of every point after the first is the previous
    solution +- ``delta`` rad, intersected with the bounds. One random generator serves the whole trajectory, so a
    seed fixes every point. Every target and option is checked before the first point is solved (a bad target named
    by its index).

    ``prefer``, ``locked`` and goal lists holding preferences (:mod:`evoik_pin.goals.preferences`) are :func:`solve`'s:
    each point is ``solve(robot, target, method, rng, prefer=..., locked=..., q0=previous q)`` (the rng shared, the
    Pro box as ``bounds``). ``prefer="nearest"``: each answer nearest the previous point's (the first point's nearest
    ``q0``, then required), a continuous joint path from a redundant arm; ``"manipulability"``: the most dexterous.
    ``locked``: ``{joint: value}`` (rad or m) held at every point; ``q0`` and the answers' ``q`` in ``robot``'s
    layout.

    A trajectory a robot can follow: ``dt`` (s, > 0, between two points) with ``velocity_limits`` (``True``: the
    URDF's; a factor > 0 of them; or an array (n,) in rad/s and m/s; :mod:`evoik_pin.robot.velocity_limits`, with
    a floating base's linear (x, y, z) and Euler-rate (yaw, pitch, roll) limits) puts every answer after the first
    inside ``|q_t - q_{t-1}| <= v_max dt`` of the one before (:meth:`IKSolver.solve_within`): no flip, no jump. A
    point that cannot be reached within that box gets the answer inside it closest to meeting its goals, its goal
    errors and ``success=False``; the next points go on from there. Full-turn joints move in unwrapped values (a
    continuous joint crossing pi keeps going). The first point is solved freely (``method``, ``prefer``) when
    ``q0`` is not given; with ``q0`` (the robot's current configuration) it too lies inside the box around ``q0``.
    Scenes hold at every point (an answer that would collide stops short of the contact, ``success=False``). The
    points after the first are Levenberg-Marquardt in the box whatever ``method`` (the box holds one branch);
    ``pro`` is not accepted with it (the velocity box is the box).

    Raises:
        OptionError: one of ``dt`` and ``velocity_limits`` without the other, a bad ``dt`` or ``velocity_limits``,
        ``pro=True`` with them; the errors of :func:`solve` for bad targets and options.
    """
    robot = _robot(robot)
    rng = _rng(seed)
    # every target and option checked before the first point is solved
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
    if step is not None:
        return _velocity_trajectory(robot, targets, method, previous, step, rng, options)
    for i, target in enumerate(targets):
        point = {**options, "q0": previous}
        if pro and i > 0:  # the previous answer's box: that point's problem's search box +- delta, q0 clipped into it
            box, _ = make_problem(robot, split_preferences(target)[0], q0=previous, **options)
            box = box.with_pro_box(previous, delta)
            point.update(q0=box.q0, bounds=(box.lower, box.upper))
        results.append(solve(robot, target, method, rng, **point))  # one generator for the whole trajectory
        previous = results[-1].q
    return results


def solve_many(robot, targets, method: str = DEFAULT_METHOD, seed=None, q0=None, workers: int | None = None,
               backend: str = "local", address: str | None = None, progress: bool = False,
               **options) -> BatchResults:
    """Solve many independent IK targets, on every core or on a Ray cluster (:mod:`evoik_pin.solvers.batch`).

    ``targets`` may be goal lists (:mod:`evoik_pin.goals`), one whole-robot problem each: lists of one structure
    (the same frames, kinds, weights and tolerances; different targets) are batched together, lists of different
    structures in groups of their own (:mod:`evoik_pin.solvers.batch.goal_lists`); every list is checked before any
    work (a bad frame, an empty list, an entry that is no goal list: an error naming the list's index).
    ``position_error`` and ``orientation_error`` are then the largest over each list's goals, and each
    :class:`Result` has its ``goal_errors``.

    With ``method="memetic"`` (the default) the targets are solved in batched rounds first: every unsolved
    target starts from its nearest seed-table entry (from ``q0`` in the first round when given), and one
    call of the compiled LM engine runs memetic's LM iteration on all of them, each round trying the
    next-nearest table entry for the targets still unsolved (``table_seeds`` rounds, as many as memetic
    tries). The targets left go to the per-target ``memetic`` solver (with the same options, e.g.
    ``timeout``). Other methods, a custom ``objective`` or ``polish=True`` solve the targets one by one.

    Args:
        robot: a :class:`Robot` or anything :func:`load_robot` accepts.
        targets: a sequence of targets (anything :func:`solve` accepts: poses, positions, planar
            targets, all of one kind or mixed), or an array of N homogeneous poses (N, 4, 4), checked in one
            vectorized pass (:meth:`Target.check_poses`) and solved without a Target object per pose. One target
            alone (a ``pin.SE3``, one (4, 4) pose, one 3-vector, a :class:`Target`) is one target.
        method: solver name.
        seed: int, None or Generator. A target solved one by one draws from its own generator,
            ``SeedSequence(seed).spawn(N)[i]`` (a Generator ``seed`` gives one draw as the entropy), so a seed fixes
            every result whatever ``workers`` and ``backend`` (up to a wall-clock ``timeout``, as for
            :func:`solve`: ``timeout=None, max_restarts=k`` makes the budget machine-independent).
        q0: None, one (n,) start for every target, or (N, n) starts.
        workers: local: threads running the batched rounds, default every core of the process's CPU affinity
            (``1``: the calling thread only); ray: actors (one CPU each), default every CPU of the cluster.
        backend: ``"local"`` (this process) or ``"ray"``: chunks of targets go to Ray actors that load the
            robot once (``pip install 'evoik_pin[ray]'``); an existing cluster at ``address`` (or
            ``RAY_ADDRESS``), else an already initialized Ray, else a new local instance of ``workers`` CPUs.
            An actor that dies has its chunk re-run on a new one.
        address: a Ray cluster's address (``"ray://head:10001"``, ``"head:6379"`` or ``"auto"``); ray only.
        progress: show a tqdm progress bar over the chunks.
        **options: as for :func:`solve` (``tolerance``, ``rotation_tolerance``, ``bounds``, ``scene``, ``margin``,
            ``orientation_weight``, ``timeout``, ``max_restarts``, ``table_seeds``, ...), every one checked before
            any work, as :func:`solve` checks it (:func:`evoik_pin.solvers.batch.threads.check_call`).
            ``prefer``: ``"nearest"`` (``q0`` required) or ``"manipulability"`` (method memetic): every target solved
            one by one as :func:`solve` solves it, with its own generator, so ``results[i]`` is ``solve(robot,
            targets[i], seed=default_rng(SeedSequence(seed).spawn(N)[i]), prefer=..., q0=...)`` (in the calling
            thread with ``backend="local"``; on the actors with ``"ray"``). Goal lists holding preferences
            (``Posture``, ``JointLimitMargin``, ``Manipulability``, ``MinimalDisplacement``) are solved the same
            way, the other lists in batched rounds. ``locked``: ``{joint: value}`` (rad or m): the call is solved on
            ``robot.locked(locked)`` (the batched rounds too); ``q0``, ``bounds`` and ``results.q`` (N, n) are in
            ``robot``'s layout, the locked joints at their values.

    Returns:
        A :class:`BatchResults`: a sequence of :class:`Result` in target order (each made when first read:
        ``results[i]``, iteration, ``list(results)``), the same answers as read-only arrays (``results.q`` (N, n),
        ``results.success``, ``results.position_error``, ``results.orientation_error``, ``results.cost``,
        ``results.evaluations``), and ``stats`` with the throughput (``results.stats["throughput"]`` targets per
        second). A batch-solved target's ``time_s`` is its share of the batched rounds (their wall time divided
        by the targets they processed).

    Raises:
        OptionError: ``workers`` < 1, an unknown ``backend``, any option :func:`solve` refuses (an unknown
        ``prefer``, ``prefer="nearest"`` without ``q0``). MethodError: ``prefer`` with a method other than memetic.
        FrameError / BoundsError: a ``locked`` joint that does not exist / a value beyond its limits. TargetError: a
        bad target or one beyond ``MAX_TARGET_NORM`` (1e6 m), a goal list of preferences alone, named by its index.
        BackendError: Ray not installed, a cluster address that cannot be reached, a chunk that keeps failing.
    """
    get_solver(method)  # an unknown method fails before any work
    _rng(seed)  # the seed's checks
    if is_goal_batch(targets) or is_problem_list(targets):
        _check_goal_method(method)
    prefer = _checked_prefer(options.pop("prefer", None), method, q0 is not None)
    return solve_many_call.solve_many(_robot(robot), targets, make_problem, _run, method, seed=seed, q0=q0,
                                      workers=workers, backend=backend, address=address, progress=progress,
                                      choose=solve, prefer=prefer, locked=options.pop("locked", None), **options)




# ------------------------------------------------ solve_trajectory within velocity limits
def _velocity_step(robot, dt, velocity_limits, pro: bool) -> np.ndarray | None:
    """The largest step per entry, ``v_max dt`` (n,) (rad or m), of solve_trajectory's ``dt`` and
    ``velocity_limits``; None when neither is given. OptionError: one without the other, bad values, with ``pro``."""
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


def _velocity_trajectory(robot, targets, method: str, q0, step: np.ndarray, rng, options: dict) -> list[Result]:
    """solve_trajectory's points within the velocity box of the one before (:meth:`IKSolver.solve_within`): the first
    one solved freely without ``q0``, inside the box of ``q0`` with it. One solver (and its box stage) for every
    point; one generator."""
    from .goals.preferences import Preference

    if any(type(t) in (list, tuple) and any(isinstance(x, Preference) for x in t) for t in targets):
        raise OptionError("velocity limits meet goals only: a goal list with preferences (Posture, "
                          "JointLimitMargin, ...) is not accepted with velocity_limits; drop the preferences")
    box_options = {k: v for k, v in options.items() if k != "prefer"}  # the box holds one answer: nothing to prefer
    solver = IKSolver(robot, method, **box_options)
    results: list[Result] = []
    previous = q0
    for i, target in enumerate(targets):
        if i == 0 and previous is None:
            results.append(solve(robot, target, method, rng, **options))
        else:
            results.append(solver.solve_within(target, previous, step, rng))
        previous = results[-1].q
    return results


# ------------------------------------------------ solve's choices beyond one answer: prefer=, preferences, locked=
def _checked_prefer(prefer, method: str, q0_given: bool) -> str | None:
    """``prefer`` checked as :func:`solve` checks it, before any work: None for the first answer (None or
    ``"first"``), else ``"nearest"`` or ``"manipulability"``. OptionError: an unknown value, or "nearest" without
    q0; MethodError: a method other than memetic (it gives one answer, nothing to choose among)."""
    from .solvers.search.prefer import check_prefer, check_prefer_method

    prefer = check_prefer("first" if prefer is None else prefer)
    if prefer == "first":
        return None
    check_prefer_method(prefer, method)
    return check_prefer(prefer, q0_given)
