"""Joint-space clustering of IK candidates, respecting angle wrap-around.

Two configurations whose revolute joints differ by 2 pi put every link in the same place, so distances
between configurations use the wrapped difference ``(a - b + pi) mod 2 pi - pi`` on revolute joints (rad)
and the plain difference on prismatic joints (m). The Euclidean norm of that difference vector is the
distance used throughout (it mixes rad and m on mixed chains; both are O(1) on the arms we ship).

:func:`leader_clusters` is the greedy "leader" clustering used by the all-solutions methods (``ga``,
``hga``, ``algebraic``): candidates are visited best first; each one either lies within ``radius`` of an
already chosen leader (and joins it) or becomes a new leader. The loop runs once per cluster, not once
per candidate, so it stays cheap for populations of thousands.
"""

from __future__ import annotations

import numpy as np

from ... import lie
from ..options import check_positive

__all__ = ["joint_differences", "joint_distances", "leader_clusters"]


def joint_differences(A: np.ndarray, b: np.ndarray, revolute: np.ndarray) -> np.ndarray:
    """``A - b`` (N, n) with revolute columns wrapped into [-pi, pi) (rad); prismatic columns in m."""
    d = np.asarray(A, float) - np.asarray(b, float)
    return np.where(revolute, lie.wrap_angle(d), d)


def joint_distances(A: np.ndarray, b: np.ndarray, revolute: np.ndarray) -> np.ndarray:
    """Wrapped joint-space distances (N,) from every row of ``A`` (N, n) to ``b`` (n,)."""
    return np.linalg.norm(joint_differences(A, b, revolute), axis=1)


def leader_clusters(Q: np.ndarray, cost: np.ndarray, radius: float, revolute: np.ndarray,
                    max_clusters: int | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Greedy leader clustering of configurations, best (lowest cost) first.

    Args:
        Q: (N, n) configurations (rad or m).
        cost: (N,) costs; lower is better. NaN costs are treated as worst.
        radius: cluster radius in the wrapped joint-space distance (rad / m), > 0.
        revolute: (n,) bool mask of revolute joints (wrapped differences).
        max_clusters: stop after this many clusters (the remaining candidates get label -1).

    Returns:
        ``(leaders, labels)``: indices into ``Q`` of the cluster leaders, best first (M,), and the
        cluster label of every candidate (N,) in 0..M-1 (or -1 when ``max_clusters`` cut it off).
    """
    radius = check_positive("cluster radius", radius, unit="rad")
    Q = np.asarray(Q, float)
    N = Q.shape[0]
    order = np.argsort(np.where(np.isnan(cost), np.inf, cost), kind="stable")
    labels = np.full(N, -1)
    leaders: list[int] = []
    remaining = order
    while remaining.size and (max_clusters is None or len(leaders) < max_clusters):
        lead = int(remaining[0])
        near = joint_distances(Q[remaining], Q[lead], revolute) <= radius
        labels[remaining[near]] = len(leaders)
        leaders.append(lead)
        remaining = remaining[~near]
    return np.array(leaders, dtype=int), labels
