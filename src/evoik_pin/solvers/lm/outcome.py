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
        position_error: m; orientation_error: rad (None when the target has no orientation).
        converged: the errors meet the problem's tolerances.
        iterations: steps tried; evaluations: forward-kinematics calls (one per step tried, plus one).
    """

    q: np.ndarray
    position_error: float
    orientation_error: float | None
    converged: bool
    iterations: int
    evaluations: int

    @property
    def error(self) -> float:
        """Position error + orientation error (m + rad): the score used to rank failed attempts."""
        return self.position_error + (self.orientation_error or 0.0)


@dataclass
class PairsOutcome:
    """End state of LM runs on N (start, target) pairs: configurations (N, n), position errors (N,) m,
    orientation errors (N,) rad or None (targets without orientation), converged (N,) bool and
    forward-kinematics evaluations (N,) per pair."""

    q: np.ndarray
    position_error: np.ndarray
    orientation_error: np.ndarray | None
    converged: np.ndarray
    evaluations: np.ndarray
