"""Paper 003's repair: damped-least-squares steps towards the target, all individuals at once (:func:`dls_repair`)."""

from __future__ import annotations

import numpy as np

from ... import lie
from ...problem import IKProblem
from .common import halton

__all__ = ["dls_repair"]


def _task_rows(problem: IKProblem) -> list[int]:
    """Jacobian rows of the task: planar (vx, vy[, wz]); 3-D (vx, vy, vz[, wx, wy, wz])."""
    t = problem.target
    if t.planar:
        return [0, 1, 5] if t.yaw is not None else [0, 1]
    return [0, 1, 2, 3, 4, 5] if t.rotation is not None else [0, 1, 2]


def _movable_rows(problem: IKProblem, rows: list[int], frame: str | None = None) -> tuple[list[int], list[int]]:
    """Split Jacobian ``rows`` of ``frame`` (default the tip) into those the chain moves it along and those it never
    does (zero at 64 configurations spread over the box, e.g. vz of a planar chain: manipulability 0 everywhere)."""
    Q = problem.lower + halton(problem.n, 64, skip=1) * (problem.upper - problem.lower)
    moving = np.abs(problem.robot.jacobian_batch(Q, validate=False, frame=frame)[:, rows]).max(axis=(0, 2)) > 1e-12
    return [r for r, m in zip(rows, moving, strict=True) if m], [r for r, m in zip(rows, moving, strict=True) if not m]


def _task_errors(problem: IKProblem, Q: np.ndarray) -> np.ndarray:
    """Task-space error vectors (N, m) target - current, in the rows of :func:`_task_rows` (m, rad)."""
    t = problem.target
    p, R = problem.robot.fk_batch(Q)
    if t.planar:
        e = [t.position[0] - p[:, 0], t.position[1] - p[:, 1]]
        if t.yaw is not None:
            e.append(lie.wrap_angle(t.yaw - lie.yaw(R)))
        return np.stack(e, axis=1)
    e = t.position - p
    if t.rotation is None:
        return e
    # Rotation error: the world-frame rotation vector of R_target R^T.
    return np.concatenate([e, lie.log3(np.einsum("ij,nkj->nik", t.rotation, R))], axis=1)


def dls_repair(problem: IKProblem, Q: np.ndarray, steps: int, damping: float = 1e-4,
               weights: np.ndarray | None = None, task=None) -> np.ndarray:
    """``Q`` (N, n) after ``steps`` damped-least-squares steps ``dq = W J^T (J W J^T + damping^2 I)^-1 e``, each
    clipped into the box (N evaluations a step). ``weights`` W (n,): default ones. ``task(Q) -> (e (N, m),
    J (N, m, n))``: the errors and Jacobian rows to zero (default the target's :func:`_task_rows`)."""
    if task is None:
        rows = _task_rows(problem)

        def task(Q):
            return _task_errors(problem, Q), problem.robot.jacobian_batch(Q)[:, rows]

    W = np.ones(problem.n) if weights is None else np.asarray(weights, float)
    lam2 = None
    for _ in range(steps):
        e, J = task(Q)
        problem.evaluations += Q.shape[0]
        if lam2 is None:
            lam2 = damping ** 2 * np.eye(J.shape[1])
        JW = J * W
        y = np.linalg.solve(JW @ J.transpose(0, 2, 1) + lam2, e[:, :, None])[..., 0]
        Q = np.clip(Q + np.einsum("nji,nj->ni", JW, y), problem.lower, problem.upper)
    return Q
