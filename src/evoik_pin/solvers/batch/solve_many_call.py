""":func:`solve_many`, the top of the batch package: the call's checks, the engine (``backend="local"``:
:class:`~.threads.BatchSolver` on threads; ``"ray"``: :class:`~.ray_actors.RayBatch`) and its answers as
:class:`~.batch_results.BatchResults`."""

from __future__ import annotations

import time
from collections.abc import Callable

import numpy as np

from ...errors import ConfigurationError, OptionError
from ...robot.locking import expand_result, expand_rows, kept_columns, locked_note, locked_robot, shrink_q
from ..options import check_choice
from .batch_results import SOURCE_SINGLE, BatchOutcome, BatchResults
from .targets import source_of
from .threads import BatchSolver, ProgressBar, check_workers, root_entropy

__all__ = ["BACKENDS", "solve_many"]

#: Where :func:`solve_many` runs: threads of this process, or actors of a Ray cluster.
BACKENDS = ("local", "ray")


def solve_many(robot, targets, make_problem: Callable, run: Callable, method: str, seed=None, q0=None,
               workers=None, backend: str = "local", address: str | None = None, progress: bool = False,
               choose: Callable | None = None, prefer: str | None = None, locked: dict | None = None,
               **options) -> BatchResults:
    """Solve many independent IK problems; the engine of :func:`evoik_pin.solve_many`, whose docstring gives the
    arguments. ``make_problem``, ``run``, ``choose``: see :class:`~.threads.BatchSolver`. ``locked``: solved on
    :func:`~evoik_pin.robot.locking.locked_robot`, ``q0``, ``bounds`` and answers in ``robot``'s layout."""
    t_start = time.perf_counter()
    backend = check_choice("backend", backend, BACKENDS)
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
    Q0 = None if q0 is None else np.asarray(q0, dtype=float)  # one (n,) start for every target, or one per target
    if Q0 is not None and Q0.ndim == 1:
        Q0 = np.broadcast_to(full.check_q(Q0), (N, full.n))
    elif Q0 is not None and (Q0.shape != (N, full.n) or not np.isfinite(Q0).all()):
        raise ConfigurationError(f"q0 must be one joint vector ({full.n},) or one per target ({N}, {full.n}) of "
                                 f"finite numbers, got shape {Q0.shape}")
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
        with ProgressBar("solve_many", enabled=progress) as bar:
            outcome = solver.solve(source, Q0, workers=workers, progress=bar)
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
