""":func:`solve_many`, the top of the batch package: the call's checks, its engine (:func:`batch_engine`) and its
answers as :class:`~.batch_results.BatchResults`."""

from __future__ import annotations

import time
from collections.abc import Callable

import numpy as np

from ...errors import ConfigurationError, OptionError
from ...robot.locking import expand_result, expand_rows, kept_columns, locked_note, locked_robot, shrink_q
from ..options import check_choice
from .batch_results import SOURCE_SINGLE, BatchOutcome, BatchResults
from .goal_lists import source_of
from .threads import BatchSolver, check_workers, root_entropy

__all__ = ["BACKENDS", "batch_engine", "check_backend", "solve_many"]

#: Where :func:`solve_many` runs: threads of this process, or actors of a Ray cluster.
BACKENDS = ("local", "ray")


def check_backend(backend: str, workers, address: str | None) -> int | None:
    """``workers`` checked for ``backend`` (one of :data:`BACKENDS`): an int >= 1, or None for Ray's default (every
    CPU of the cluster). OptionError: an unknown backend, a bad ``workers``, an ``address`` without Ray."""
    backend = check_choice("backend", backend, BACKENDS)
    if backend == "local" and address is not None:
        raise OptionError("address names a Ray cluster: give it with backend='ray'")
    return None if workers is None and backend == "ray" else check_workers(workers)


def batch_engine(robot, make_problem: Callable, run: Callable, method: str, entropy: int, options: dict,
                 backend: str = "local", workers: int | None = None, address: str | None = None, **kwargs):
    """The engine of one call on ``backend`` (``workers`` checked by :func:`check_backend`): a
    :class:`~.threads.BatchSolver` on ``workers`` threads, or a :class:`~.ray_actors.RayBatch` on Ray actors. Either
    has ``solve(targets, Q0=None, progress=False) -> BatchOutcome``, ``template`` and ``workers``; the other
    arguments are :class:`~.threads.BatchSolver`'s."""
    if backend == "ray":
        from .ray_actors import RayBatch

        return RayBatch(robot, make_problem, run, method, entropy, options, workers=workers, address=address, **kwargs)
    return BatchSolver(robot, make_problem, run, method, entropy, options, workers=workers, **kwargs)


def solve_many(robot, targets, make_problem: Callable, run: Callable, method: str, seed=None, q0=None,
               workers=None, backend: str = "local", address: str | None = None, progress: bool = False,
               choose: Callable | None = None, prefer: str | None = None, locked: dict | None = None,
               **options) -> BatchResults:
    """Solve many independent IK problems; the engine of :func:`evoik_pin.solve_many`, whose docstring gives the
    arguments. ``make_problem``, ``run``, ``choose``: see :class:`~.threads.BatchSolver`. ``locked``: solved on
    :func:`~evoik_pin.robot.locking.locked_robot`, ``q0``, ``bounds`` and answers in ``robot``'s layout."""
    t_start = time.perf_counter()
    workers = check_backend(backend, workers, address)
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
    engine = batch_engine(robot, make_problem, run, method, root_entropy(seed), options, backend, workers, address,
                          choose=choose, prefer=prefer)
    outcome = engine.solve(source, Q0, progress=progress)
    if locked:
        outcome.q = expand_rows(full, robot, values, outcome.q)
        outcome.note = locked_note(values)
        for r in outcome.singles.values():
            expand_result(full, robot, values, r)
    return BatchResults(outcome, engine.template, _stats(outcome, t_start, engine.workers, backend))


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
