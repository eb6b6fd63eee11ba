"""Batch solving: many independent IK targets in one call (:func:`solve_many`), on every core or a Ray cluster.

The top of the batch package: it checks the call's arguments (backend, workers, ``q0``), reads the targets
(:class:`~.targets.TargetSource`), hands them to an engine below it, and wraps the engine's arrays
(:class:`~.batch_results.BatchOutcome`) as what :func:`evoik_pin.solve_many` returns
(:class:`~.batch_results.BatchResults`):

* ``backend="local"``: :class:`~.threads.BatchSolver` on ``workers`` threads of this process (:mod:`.threads`
  explains the batched rounds, the chunks and the per-target generators);
* ``backend="ray"``: :class:`~.ray_actors.RayBatch`, chunks handed to Ray actors that each run a
  :class:`~.threads.BatchSolver` (:mod:`.ray_actors`).
"""

from __future__ import annotations

import time
from collections.abc import Callable

import numpy as np

from ...errors import ConfigurationError, OptionError
from ...robot.locking import expand_result, expand_rows, kept_columns, locked_note, locked_robot, shrink_q
from ..options import check_choice
from .batch_results import SOURCE_SINGLE, BatchOutcome, BatchResults
from .targets import source_of
from .threads import BatchSolver, check_workers, progress_bar, root_entropy

__all__ = ["BACKENDS", "solve_many"]

#: Where :func:`solve_many` runs: threads of this process, or actors of a Ray cluster.
BACKENDS = ("local", "ray")



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


def _check_backend(backend) -> str:
    return check_choice("backend", backend, BACKENDS)


def solve_many(robot, targets, make_problem: Callable, run: Callable, method: str, seed=None, q0=None,
               workers=None, backend: str = "local", address: str | None = None, progress: bool = False,
               choose: Callable | None = None, prefer: str | None = None, locked: dict | None = None,
               **options) -> BatchResults:
    """Solve many independent IK targets (see the module docstring); called by :func:`evoik_pin.solve_many`.

    Args:
        robot: a loaded :class:`~evoik_pin.robot.Robot`.
        targets: anything :meth:`Target.coerce_many` accepts (a sequence of targets, or (N, 4, 4) poses), or a
            sequence of goal lists (:mod:`.goal_lists`).
        make_problem, run: the API's problem builder and solver runner (``api.make_problem``, ``api._run``).
        method: solver name. seed: int, None or Generator (:func:`root_entropy`).
        q0: None, one (n,) start for every target, or (N, n) starts.
        workers: threads (local) or actors (ray); None: every core (local) or every CPU of the cluster (ray).
        backend: "local" or "ray". address: a Ray cluster's address (ray only; default ``RAY_ADDRESS``).
        progress: a tqdm bar over chunks.
        choose, prefer: see :class:`~.threads.BatchSolver` (``prefer`` checked by the caller; None: the first
            answer).
        locked: ``{joint: value}`` (rad or m): the call solved on ``robot.locked(locked)``
            (:func:`~evoik_pin.robot.locking.locked_robot`), ``q0`` and ``bounds`` given and the answers' ``q``
            returned in ``robot``'s layout, the locked joints at their values.
        **options: as for :func:`evoik_pin.solve`.
    """
    t_start = time.perf_counter()
    backend = _check_backend(backend)
    if backend == "local" and address is not None:
        raise OptionError("address names a Ray cluster: give it with backend='ray'")
    workers = None if workers is None and backend == "ray" else check_workers(workers)
    full = robot
    if locked:  # checked here (an unknown joint, a value beyond its limits); the batch solved on the locked robot
        robot = locked_robot(full, locked)
        values = {k: float(v) for k, v in locked.items()}
        if options.get("bounds") is not None:
            lower, upper = options["bounds"]
            options["bounds"] = (shrink_q(full, robot, lower), shrink_q(full, robot, upper))
    source = source_of(robot, targets)  # goal lists: every one checked here, before any work
    N = len(source)
    if N == 0:
        raise ConfigurationError("solve_many needs at least one target")
    Q0 = _start_configurations(full, q0, N)
    if Q0 is None and source.goals:
        source.require_q0(range(N))  # MinimalDisplacement is measured from q0
    if locked and Q0 is not None:
        Q0 = np.ascontiguousarray(Q0[:, kept_columns(full, robot)])
    entropy = root_entropy(seed)
    if backend == "ray":
        from .ray_actors import RayBatch

        job = RayBatch(robot, make_problem, run, method, entropy, options, workers=workers, address=address,
                       choose=choose, prefer=prefer)
        outcome = job.solve(source, Q0, progress=progress)
        template = job.template()
        workers = job.workers
    else:
        solver = BatchSolver(robot, make_problem, run, method, entropy, options, choose=choose, prefer=prefer)
        bar = progress_bar(progress, "solve_many")
        try:
            outcome = solver.solve(source, Q0, workers=workers, progress=bar)
        finally:
            if bar is not None:
                bar.close()
        template = solver.template
    if locked:
        outcome.q = expand_rows(full, robot, values, outcome.q)
        outcome.note = locked_note(values)
        for r in outcome.singles.values():
            expand_result(full, robot, values, r)
    return BatchResults(outcome, template, _stats(outcome, t_start, workers, backend))


def _stats(outcome: BatchOutcome, t_start: float, workers: int | None, backend: str) -> dict:
    """:class:`BatchResults`' ``stats`` of a call that started at ``t_start`` (``time.perf_counter()``)."""
    elapsed = time.perf_counter() - t_start
    n = len(outcome)
    solved = int(np.count_nonzero(outcome.success))
    batched = int(np.count_nonzero(outcome.source != SOURCE_SINGLE))
    return {
        "n": n, "solved": solved, "success_rate": solved / n, "time_s": elapsed,
        "throughput": n / elapsed if elapsed > 0 else float("inf"), "batched": batched, "fallback": n - batched,
        "fallback_solved": solved - batched, "workers": workers, "backend": backend,
    }
