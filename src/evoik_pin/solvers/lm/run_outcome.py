"""What an LM run returns: :class:`LMOutcome` for one run, :class:`PairsOutcome` for a batch of pairs."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["LMOutcome", "PairsOutcome"]


@dataclass
class LMOutcome:
    """End state of one LM run.

    Attributes:
        q: (n,) final configuration, inside the search box.
        position_error: m; orientation_error: rad (None when no goal has an orientation): the largest over the
            goals.
        converged: every goal's errors meet its tolerances.
        iterations: steps tried; evaluations: forward-kinematics calls (one per step tried, plus one).
        goal_errors: (G, 2) each goal's (position error m, orientation error rad or nan) when the problem has
            several goals; None for one (its errors are the two above).
        cost: the weighted squared task error |e|^2 at q (m^2, rad^2), None when not computed.
    """

    q: np.ndarray
    position_error: float
    orientation_error: float | None
    converged: bool
    iterations: int
    evaluations: int
    goal_errors: np.ndarray | None = None
    cost: float | None = None

    @property
    def error(self) -> float:
        """Position error + orientation error (m + rad), the largest over the goals."""
        return self.position_error + (self.orientation_error or 0.0)

    @property
    def rank(self) -> float:
        """The score failed attempts are ranked by: :attr:`error` for one goal, the weighted |e|^2 for several (a
        compromise between goals that cannot all be met is what their weights make it)."""
        return self.error if self.goal_errors is None or self.cost is None else self.cost


@dataclass
class PairsOutcome:
    """End state of LM runs on N (start, target) pairs: configurations (N, n), position errors (N,) m, orientation
    errors (N,) rad or None, converged (N,) bool and kinematics evaluations (N,); for goal stacks the errors are the
    largest over the goals and ``goal_errors`` (N, G, 2) gives each goal's (position m, orientation rad or NaN)."""

    q: np.ndarray
    position_error: np.ndarray
    orientation_error: np.ndarray | None
    converged: np.ndarray
    evaluations: np.ndarray
    goal_errors: np.ndarray | None = None
