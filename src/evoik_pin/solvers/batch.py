"""Batch solving: many independent IK targets in one call (:func:`solve_many`).

With the memetic method (the default) the targets are solved in batched rounds first: every unsolved target
starts from its nearest seed-table entry (from ``q0`` in the first round when given), and one call of the LM
engine (:func:`~evoik_pin.solvers.lm.solve_pairs`, one compiled kernel call over all (start, target) pairs)
runs memetic's LM iteration on all of them; each further round tries the next-nearest table entry for the
targets still unsolved. The targets left after ``table_seeds`` rounds go to the per-target ``memetic`` solver
(with the same options, e.g. ``timeout``), told which table entries were already tried. Other methods, a
custom ``objective`` or ``polish=True`` solve the targets one by one through the same route as
:func:`evoik_pin.solve`.

This is the module that grows with the batch work (workers, clusters, scenes): ``api.solve_many`` only routes
here.
"""

from __future__ import annotations

import time
from collections.abc import Callable

import numpy as np

from ..errors import ConfigurationError
from ..objectives import default_cost
from ..problem import Target
from ..result import Result
from .collision_verdict import with_collision_verdict
from .lm import solve_pairs
from .lm.layout import target_kind
from .memetic import DEFAULT_TABLE_SEEDS, default_table_size, seed_table

__all__ = ["BatchResults", "solve_many"]


class BatchResults(list):
    """The list of :class:`Result` that :func:`solve_many` returns, one per target in order, plus ``stats``.

    ``stats`` (a dict): ``n`` targets, ``solved``, ``success_rate``, ``time_s`` (wall clock of the whole
    call), ``throughput`` (targets per second, ``n / time_s``), ``batched`` (targets solved by the batched
    LM rounds) and ``fallback`` (targets handed to the per-target solver, and of those ``fallback_solved``).
    """

    stats: dict


def _start_configurations(robot, q0, N: int) -> np.ndarray | None:
    """q0 as (N, n) starts: None, one (n,) joint vector for every target, or one per target (N, n)."""
    if q0 is None:
        return None
    Q0 = np.asarray(q0, dtype=float)
    if Q0.ndim == 1:
        return np.broadcast_to(robot.check_q(Q0), (N, robot.n))
    if Q0.shape != (N, robot.n) or not np.isfinite(Q0).all():
        raise ConfigurationError(f"q0 must be one joint vector ({robot.n},) or one per target ({N}, {robot.n}) of "
                                 f"finite numbers, got shape {Q0.shape}")
    return Q0


def solve_many(robot, targets, make_problem: Callable, run: Callable, method: str, rng, q0=None,
               **options) -> BatchResults:
    """Solve many independent IK targets (see the module docstring); called by :func:`evoik_pin.solve_many`.

    Args:
        robot: a loaded :class:`~evoik_pin.robot.Robot`.
        targets: anything :meth:`Target.coerce_many` accepts (a sequence of targets, or (N, 4, 4) poses).
        make_problem, run: the API's problem builder and solver runner (``api.make_problem``, ``api._run``),
            so a target solved one by one is solved exactly as :func:`evoik_pin.solve` would.
        method: solver name. rng: the call's random generator (one serves all targets).
        q0: None, one (n,) start for every target, or (N, n) starts.
        **options: as for :func:`evoik_pin.solve`.
    """
    t_start = time.perf_counter()
    targets = Target.coerce_many(targets)
    N = len(targets)
    if N == 0:
        raise ConfigurationError("solve_many needs at least one target")
    Q0 = _start_configurations(robot, q0, N)

    def one_by_one(i: int, **extra) -> Result:
        problem, solver_options = make_problem(robot, targets[i], q0=None if Q0 is None else Q0[i], **dict(options))
        solver_options.update(extra)
        return run(problem, method, rng, solver_options)

    if method != "memetic" or options.get("objective") is not None or options.get("polish"):
        return _with_stats(BatchResults(one_by_one(i) for i in range(N)), t_start, batched=0, fallback=N)

    # One template problem checks the shared options once (tolerances, bounds, weights, solver options).
    template, solver_options = make_problem(robot, targets[0], **dict(options))
    from . import get_solver

    get_solver("memetic").check_options(solver_options)
    table_size = solver_options.get("table_size")
    table_size = default_table_size(robot.n) if table_size is None else int(table_size)
    rounds = int(solver_options.get("table_seeds", DEFAULT_TABLE_SEEDS)) if table_size > 0 else 0
    engine = solver_options.get("engine", "compiled")
    lower, upper = template.lower, template.upper
    results: list[Result | None] = [None] * N
    n_batched = 0
    by_kind: dict[int, list[int]] = {}
    for i, t in enumerate(targets):
        by_kind.setdefault(target_kind(t), []).append(i)
    scene = template.scene
    table = seed_table(robot, lower, upper, table_size) if rounds else None
    free = table.free_mask(scene, template.margin) if table is not None and scene is not None else None
    if free is not None:
        rounds = min(rounds, int(np.count_nonzero(free)))
    for members in by_kind.values():
        pending = np.array(members)
        plan = ([("q0", None)] if Q0 is not None else []) + [("seed table", r) for r in range(rounds)]
        for label, rank in plan:
            if pending.size == 0:
                break
            t0 = time.perf_counter()
            group = [targets[i] for i in pending]
            Qs = Q0[pending] if rank is None else table.Q[table.nearest(group, rank + 1, free)[:, rank]]
            out = solve_pairs(robot, Qs, group, lower, upper, template.tolerance, template.rotation_tolerance,
                              engine=engine)
            if scene is not None:  # the exact check: an answer in collision stays pending for the next round
                for j in np.nonzero(out.converged)[0]:
                    out.converged[j] = not scene.in_collision(out.q[j], template.margin)
            share = (time.perf_counter() - t0) / pending.size
            solved = np.nonzero(out.converged)[0]
            rot = out.orientation_error
            cost = default_cost(out.position_error, rot, template.orientation_weight, template.pose_metric)
            for j in solved:
                c = float(cost[j])
                results[pending[j]] = with_collision_verdict(template, Result(
                    q=out.q[j].copy(), position_error=float(out.position_error[j]),
                    orientation_error=None if rot is None else float(rot[j]), cost=c, success=True,
                    generations=0, evaluations=int(out.evaluations[j]), time_s=share,
                    history={"best_cost": np.array([c]), "mean_cost": np.array([c]), "diversity": np.array([0.0])},
                    message=f"tolerance reached by batched LM from {label} (solve_many)", method="memetic",
                    collision_free=None if scene is None else True))  # passed the exact check above
            n_batched += solved.size
            pending = pending[~out.converged]
    fallback = [i for i in range(N) if results[i] is None]
    for i in fallback:  # the per-target memetic solver, with every option (and q0) of the call
        # the batched rounds tried the nearest entries already
        results[i] = one_by_one(i, table_offset=options.get("table_offset", rounds))
    return _with_stats(BatchResults(results), t_start, batched=n_batched, fallback=len(fallback))


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
