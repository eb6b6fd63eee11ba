"""``polish=True``: any solver's answer taken to machine precision by the LM engine.

:func:`polish_result` runs one Levenberg-Marquardt run (:class:`~evoik_pin.solvers.lm.LevenbergMarquardt`) from
a result's configuration and keeps it when it lowers the error. :func:`evoik_pin.solve` calls it for every
method given ``polish=True`` (the paper solvers' DE, ISADE, PSO, GA ... answers, typically 1e-3 to 1e-5 m,
become 1e-12).
"""

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
    """``result`` with its configuration polished by Levenberg-Marquardt (the ``polish=True`` of every method).

    LM runs from ``result.q`` for at most ``iterations`` steps on the problem's task error; the polished
    configuration replaces ``result.q`` only when its error (position + orientation, m + rad) is lower.
    The history is kept; ``evaluations`` and ``time_s`` grow by the polish's; the message says what the
    polish did. ``engine``: ``"compiled"`` or ``"python"`` (:mod:`evoik_pin.solvers.lm`). ``rng`` is accepted for
    the uniform hook signature; the polish draws no random numbers.
    """
    t0 = time.perf_counter()
    iterations = check_int("iterations", iterations, 1)
    lm = LevenbergMarquardt(problem, engine=engine)
    out = lm.run(np.asarray(result.q, dtype=float), iterations)
    before = result.position_error + (result.orientation_error or 0.0)
    improved = out.error < before
    if improved:
        q = out.q
        pos, rot, cost = problem.assess(q, out.position_error, out.orientation_error)
    else:
        q = np.asarray(result.q, dtype=float)
        pos, rot, cost = result.position_error, result.orientation_error, result.cost
    success = bool(problem.succeeded(pos, rot))
    if improved:
        note = f"polished by Levenberg-Marquardt ({out.iterations} steps): {errors_text(pos, rot)}"
    else:
        note = f"polished by Levenberg-Marquardt ({out.iterations} steps): no improvement"
    message = (result.message + "; " if result.message else "") + note
    if success and not result.success:
        message += "; tolerance reached"
    return Result(
        q=q.copy(), position_error=pos, orientation_error=rot, cost=cost, success=success,
        generations=result.generations, evaluations=result.evaluations + out.evaluations,
        time_s=result.time_s + (time.perf_counter() - t0), history=result.history, message=message,
        method=result.method, solutions=result.solutions, front=result.front,
    )
