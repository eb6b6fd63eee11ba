"""The public surface: :func:`solve`, :func:`solve_trajectory`, :func:`solve_all`, :func:`methods`.

Every call builds an :class:`~evoik_pin.problem.IKProblem` from the robot, the target and the shared
options, draws all randomness from one ``numpy.random.Generator`` seeded by ``seed``, and hands the
problem to the registered solver.
"""

from __future__ import annotations

import time

import numpy as np

from .errors import ConfigurationError, MethodError, OptionError, TargetError
from .problem import DEFAULT_PRO_DELTA, IKProblem, Target
from .result import Result
from .robot import Robot, load_robot
from .solvers import get_solver, methods

__all__ = ["DEFAULT_METHOD", "BatchResults", "make_problem", "methods", "solve", "solve_all", "solve_many",
           "solve_trajectory"]

#: Method used when none is named.
DEFAULT_METHOD = "memetic"

# Options consumed by the problem rather than by the solver.
_PROBLEM_OPTIONS = ("tolerance", "rotation_tolerance", "q0", "bounds", "objective", "orientation_weight",
                    "pose_metric")


class _DeferredGenerator:
    """A ``numpy.random.Generator`` for ``seed``, created on first use.

    Seeding a generator costs 10-50 us, a tenth of a typical memetic solve, whose deterministic stages (q0
    and the seed table) usually meet the tolerance without drawing a number. Solvers use the object like
    the Generator itself (every attribute is forwarded), and the draws are exactly those of
    ``np.random.default_rng(seed)``.
    """

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
            (lower, upper), ``objective``, ``orientation_weight``, ``pose_metric``, ``polish``) and the solver's own
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


class BatchResults(list):
    """The list of :class:`Result` that :func:`solve_many` returns, one per target in order, plus ``stats``.

    ``stats`` (a dict): ``n`` targets, ``solved``, ``success_rate``, ``time_s`` (wall clock of the whole
    call), ``throughput`` (targets per second, ``n / time_s``), ``batched`` (targets solved by the batched
    LM rounds) and ``fallback`` (targets handed to the per-target solver, and of those ``fallback_solved``).
    """

    stats: dict


def _coerce_targets(targets) -> list[Target]:
    """Targets as a list of :class:`Target`; a (N, 4, 4) array of poses is checked in one vectorized pass."""
    if isinstance(targets, np.ndarray) and targets.ndim == 3 and targets.shape[1:] == (4, 4):
        targets = targets.astype(float)
        if not np.isfinite(targets).all():
            bad = int(np.nonzero(~np.isfinite(targets).all(axis=(1, 2)))[0][0])
            raise TargetError(f"target {bad} contains NaN or inf")
        R = targets[:, :3, :3]
        ortho = np.abs(R.transpose(0, 2, 1) @ R - np.eye(3)).max(axis=(1, 2))
        bad = np.nonzero((ortho > 1e-6) | (np.linalg.det(R) < 0))[0]
        if bad.size:
            raise TargetError(f"target {int(bad[0])}: rotation is not a rotation matrix (R^T R must be I and "
                              "det R = +1 to 1e-6)")
        out = []
        for T in targets:  # already checked: skip Target's per-instance validation
            t = object.__new__(Target)
            object.__setattr__(t, "position", T[:3, 3].copy())
            object.__setattr__(t, "rotation", T[:3, :3].copy())
            object.__setattr__(t, "planar", False)
            object.__setattr__(t, "yaw", None)
            out.append(t)
        return out
    out = []
    for i, t in enumerate(targets):
        try:
            out.append(Target.coerce(t))
        except TargetError as exc:
            raise TargetError(f"target {i}: {exc}") from None
    return out


def _target_kind(t: Target) -> str:
    if t.planar:
        return "planar" if t.yaw is None else "planar_yaw"
    return "position" if t.rotation is None else "pose"


def solve_many(robot, targets, method: str = DEFAULT_METHOD, seed=None, q0=None, **options) -> BatchResults:
    """Solve many independent IK targets, amortizing the per-call overhead.

    With ``method="memetic"`` (the default) the targets are solved in batched rounds first: every
    unsolved target starts from its nearest seed-table entry (from ``q0`` in the first round when given),
    and one call runs Levenberg-Marquardt on all of them per round, each round trying the next-nearest
    table entry for the targets still unsolved: for pose and position targets one compiled loop over the
    pairs (:func:`~evoik_pin.solvers.polish.compiled_pairs`, memetic's LM iteration), for planar targets or
    ``engine="python"`` a NumPy batch LM (:func:`~evoik_pin.solvers.polish.batch_levenberg_marquardt`: one
    kinematics pass and one batched solve per iteration for all unsolved targets at once). The
    targets left after ``table_seeds`` rounds go to the per-target ``memetic`` solver (with the same
    options, e.g. ``timeout``). Other methods, or a custom ``objective``, solve the targets one by one.

    Args:
        robot: a :class:`Robot` or anything :func:`load_robot` accepts.
        targets: a sequence of targets (anything :func:`solve` accepts: poses, positions, planar
            targets, all of one kind or mixed), or an array of N homogeneous poses (N, 4, 4), checked in one
            vectorized pass.
        method: solver name. seed: int or Generator; one generator serves all targets, so a seed fixes
            every result (up to the per-target time budget, as for :func:`solve`).
        q0: None, one (n,) start for every target, or (N, n) starts.
        **options: as for :func:`solve` (``tolerance``, ``rotation_tolerance``, ``bounds``,
            ``orientation_weight``, ``timeout``, ``max_restarts``, ``table_seeds``, ...).

    Returns:
        A :class:`BatchResults`: ``list[Result]`` in target order, plus ``stats`` with the throughput
        (``results.stats["throughput"]`` targets per second). A batch-solved target's ``time_s`` is its
        share of the batched rounds (their wall time divided by the targets they processed).
    """
    t_start = time.perf_counter()
    robot = _robot(robot)
    rng = _rng(seed)
    targets = _coerce_targets(targets)
    N = len(targets)
    if N == 0:
        raise ConfigurationError("solve_many needs at least one target")
    Q0 = None
    if q0 is not None:
        Q0 = np.asarray(q0, dtype=float)
        if Q0.ndim == 1:
            Q0 = np.broadcast_to(robot.check_q(Q0), (N, robot.n))
        elif Q0.shape != (N, robot.n) or not np.isfinite(Q0).all():
            raise ConfigurationError(f"q0 must be one joint vector ({robot.n},) or one per target ({N}, {robot.n}) "
                                     f"of finite numbers, got shape {Q0.shape}")
    info = get_solver(method)
    if method != "memetic" or options.get("objective") is not None or options.get("polish"):
        results = BatchResults()
        for i, t in enumerate(targets):
            problem, solver_options = make_problem(robot, t, q0=None if Q0 is None else Q0[i], **dict(options))
            results.append(_run(problem, method, rng, solver_options))
        return _with_stats(results, t_start, batched=0, fallback=N)

    # One template problem checks the shared options once (tolerances, bounds, weights).
    template, solver_options = make_problem(robot, targets[0], **dict(options))
    info.check_options(solver_options)
    from .solvers.memetic import default_table_size, seed_table
    from .solvers.polish import batch_levenberg_marquardt, compiled_pairs

    table_size = solver_options.get("table_size")
    table_size = default_table_size(robot.n) if table_size is None else int(table_size)
    rounds = int(solver_options.get("table_seeds", 8))
    lower, upper = template.lower, template.upper
    tol, rtol, w = template.tolerance, template.rotation_tolerance, template.orientation_weight
    results: list[Result | None] = [None] * N
    n_batched = 0
    by_kind: dict[str, list[int]] = {}
    for i, t in enumerate(targets):
        by_kind.setdefault(_target_kind(t), []).append(i)
    table = seed_table(robot, lower, upper, table_size) if table_size > 0 else None
    for kind, members in by_kind.items():
        # pose and position targets: one compiled LM run per pair (the engine of memetic's LM); planar ones, or
        # engine="python": NumPy batch LM over all pairs at once
        compiled = kind in ("pose", "position") and solver_options.get("engine", "compiled") == "compiled"
        members = np.array(members)
        pending = members
        plan = [("q0", None)] if Q0 is not None else []
        plan += [("seed table", r) for r in range(rounds if table is not None else 0)]
        for label, rank in plan:
            if pending.size == 0:
                break
            t0 = time.perf_counter()
            group = [targets[i] for i in pending]
            if rank is None:
                Qs = Q0[pending]
            else:
                Qs = table.Q[table.nearest(group, rank + 1)[:, rank]]
            if compiled:
                out = compiled_pairs(robot, Qs, group, lower, upper, tol, rtol)
            else:
                # 15 steps: converging pairs need about 5-10; the rest are left to the next seed or the fallback
                out = batch_levenberg_marquardt(robot, Qs, group, lower, upper, tol, rtol, max_iterations=15)
            share = (time.perf_counter() - t0) / pending.size
            for j in np.nonzero(out.converged)[0]:
                pos = float(out.position_error[j])
                rot = None if out.orientation_error is None else float(out.orientation_error[j])
                if rot is None:
                    cost = pos
                else:
                    cost = pos + w * rot if template.pose_metric == "sum" else float(np.hypot(pos, w * rot))
                results[pending[j]] = Result(
                    q=out.q[j].copy(), position_error=pos, orientation_error=rot, cost=cost, success=True,
                    generations=0, evaluations=int(out.evaluations[j]), time_s=share,
                    history={"best_cost": np.array([cost]), "mean_cost": np.array([cost]),
                             "diversity": np.array([0.0])},
                    message=f"tolerance reached by batched LM from {label} (solve_many)", method="memetic")
            n_batched += int(out.converged.sum())
            pending = pending[~out.converged]
    fallback = [i for i in range(N) if results[i] is None]
    tried = rounds if table is not None else 0
    for i in fallback:  # the per-target memetic solver, with every option (and q0) of the call
        problem, opts = make_problem(robot, targets[i], q0=None if Q0 is None else Q0[i], **dict(options))
        opts.setdefault("table_offset", tried)  # the batched rounds tried the nearest entries already
        results[i] = _run(problem, "memetic", rng, opts)
    out_list = BatchResults(results)
    return _with_stats(out_list, t_start, batched=n_batched, fallback=len(fallback))


def _with_stats(results: BatchResults, t_start: float, batched: int, fallback: int) -> BatchResults:
    elapsed = time.perf_counter() - t_start
    solved = sum(r.success for r in results)
    n = len(results)
    results.stats = {
        "n": n, "solved": solved, "success_rate": solved / n, "time_s": elapsed,
        "throughput": n / elapsed if elapsed > 0 else float("inf"), "batched": batched, "fallback": fallback,
        "fallback_solved": solved - batched,
    }
    return results
