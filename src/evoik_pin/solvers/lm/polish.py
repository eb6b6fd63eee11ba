"""``polish=True`` of every method (:func:`evoik_pin.solve`): any solver's answer taken to machine precision by one
LM run, kept when it lowers the error."""

from __future__ import annotations

import time

import numpy as np

from ...problem import IKProblem, errors_text
from ...result import Result
from ..options import check_int
from .engine import LevenbergMarquardt

__all__ = ["POLISH_ITERATIONS", "polish_result"]

#: Steps allowed when polishing another solver's answer (already close: it converges or stalls quickly).
POLISH_ITERATIONS = 100


def polish_result(problem: IKProblem, result: Result, rng: np.random.Generator | None = None,
                  iterations: int = POLISH_ITERATIONS, engine: str = "compiled") -> Result:
    """``result`` with its configuration replaced by one LM run's from ``result.q`` (at most ``iterations`` steps)
    when that lowers its error (m + rad); ``evaluations``, ``time_s`` and the message grow by the polish's.
    ``engine``: ``"compiled"`` or ``"python"``. ``rng``: the hooks' uniform signature (no random numbers drawn).
    """
    t0 = time.perf_counter()
    iterations = check_int("iterations", iterations, 1)
    lm = LevenbergMarquardt(problem, engine=engine)
    out = lm.run(np.asarray(result.q, dtype=float), iterations)
    if out.error < result.position_error + (result.orientation_error or 0.0):
        q = out.q
        pos, rot, cost = problem.assess(q, out.position_error, out.orientation_error)
        note = errors_text(pos, rot)
    else:
        q = np.asarray(result.q, dtype=float)
        pos, rot, cost = result.position_error, result.orientation_error, result.cost
        note = "no improvement"
    success = bool(problem.succeeded(pos, rot))
    note = f"polished by Levenberg-Marquardt ({out.iterations} steps): {note}"
    message = (result.message + "; " if result.message else "") + note
    if success and not result.success:
        message += "; tolerance reached"
    return Result(
        q=q.copy(), position_error=pos, orientation_error=rot, cost=cost, success=success,
        generations=result.generations, evaluations=result.evaluations + out.evaluations,
        time_s=result.time_s + (time.perf_counter() - t0), history=result.history, message=message,
        method=result.method, solutions=result.solutions, front=result.front,
    )
