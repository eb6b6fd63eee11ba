"""Joint-space clustering of IK candidates: distances are norms of differences wrapped into [-pi, pi) on revolute
joints (rad), plain on prismatic ones (m); :func:`leader_clusters` groups the all-solutions methods' candidates.
"""

from __future__ import annotations

import numpy as np

from ... import lie
from ..options import check_positive

__all__ = ["joint_differences", "joint_distances", "leader_clusters", "leader_rows"]


def joint_differences(A: np.ndarray, b: np.ndarray, revolute: np.ndarray) -> np.ndarray:
    """``A - b`` (N, n) with revolute columns wrapped into [-pi, pi) (rad); prismatic columns in m."""
    d = np.asarray(A, float) - np.asarray(b, float)
    return np.where(revolute, lie.wrap_angle(d), d)


def joint_distances(A: np.ndarray, b: np.ndarray, revolute: np.ndarray) -> np.ndarray:
    """Wrapped joint-space distances (N,) from every row of ``A`` (N, n) to ``b`` (n,)."""
    return np.linalg.norm(joint_differences(A, b, revolute), axis=1)


def leader_clusters(Q: np.ndarray, cost: np.ndarray, radius: float, revolute: np.ndarray,
                    max_clusters: int | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Greedy leader clustering of configurations ``Q`` (N, n), best (lowest ``cost`` (N,), NaN worst) first: each
    joins the first leader within ``radius`` (wrapped distance on the ``revolute`` (n,) mask) or leads a new
    cluster, at most ``max_clusters``. Returns the leaders' indices (M,), best first, and every candidate's
    label (N,) in 0..M-1 (-1 when cut off)."""
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


def leader_rows(Q: np.ndarray, cost: np.ndarray, radius: float, revolute: np.ndarray, max_clusters: int | None = None,
                min_members: int = 1) -> np.ndarray:
    """The leaders (M, n) of :func:`leader_clusters`, best first, of the clusters with at least ``min_members``."""
    leaders, labels = leader_clusters(Q, cost, radius, revolute, max_clusters)
    return np.asarray(Q)[leaders[np.bincount(labels[labels >= 0], minlength=len(leaders)) >= min_members]]
