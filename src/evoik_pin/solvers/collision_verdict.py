"""The exact collision verdict on a solver's answer (:func:`with_collision_verdict`): the one place where a scene's
judgement enters a Result."""

from __future__ import annotations

from dataclasses import replace

from ..problem import IKProblem
from ..result import Result

__all__ = ["pairs_text", "with_collision_verdict"]


def pairs_text(pairs: list[tuple[str, str]], most: int = 3) -> str:
    """'a - b, c - d (+2 more)' for messages."""
    text = ", ".join(f"{a} - {b}" for a, b in pairs[:most])
    return text + (f" (+{len(pairs) - most} more)" if len(pairs) > most else "")


def with_collision_verdict(problem: IKProblem, result: Result) -> Result:
    """``result`` judged against ``problem.scene`` (unchanged without one): ``collision_free`` and ``min_distance`` from
    the exact mesh check (unless the solver decided it already), ``success`` requiring it, the pairs in contact
    named in the message, multi-solution results keeping their collision-free solutions only."""
    scene = problem.scene
    if scene is None:
        return result
    q = result.q.copy()
    free = result.collision_free
    if free is None:
        free = not scene.in_collision(q, problem.margin)
    message = result.message
    if not free:
        where = f" (margin {problem.margin:g} m)" if problem.margin > 0 else ""
        pairs = pairs_text(scene.colliding_pairs(q, problem.margin))
        message = f"{message}; the answer is in collision{where}: {pairs}"
    solutions = result.solutions
    if solutions:
        judged = [with_collision_verdict(problem, s) for s in solutions]
        solutions = [s for s in judged if s.collision_free]
        if len(solutions) < len(judged):
            message += f"; {len(judged) - len(solutions)} of {len(judged)} solutions dropped: in collision"
    return replace(result, success=bool(result.success and free), collision_free=free, message=message,
                   solutions=solutions, distance_source=lambda: scene.distance(q))
