"""Position: a frame's origin at a target point, orientation free (see :mod:`evoik_pin.goals`)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from ..errors import TargetError
from ..solvers.lm.layout import KIND_POSITION
from . import goal_set
from .goal import DEFAULT_GOAL_TOLERANCE, Goal

__all__ = ["Position"]


@dataclass(frozen=True, eq=False, repr=False)
class Position(Goal):
    """The frame's origin at ``target``, a 3-vector (m) in the robot's base frame; orientation free.

    ``target`` may be a goal set: a list of 3-vectors or a (k, 3) array, any one of which will do
    (:mod:`.goal_set`).

    Args: frame, target, then ``weight`` (> 0, default 1) and ``tolerance`` (m, default 1e-6).
    """

    target: object = None
    weight: float = 1.0
    tolerance: float = DEFAULT_GOAL_TOLERANCE
    rotation_tolerance: float | None = None

    def __init__(self, frame: str, target, weight: float = 1.0, tolerance: float = DEFAULT_GOAL_TOLERANCE) -> None:
        self._init_common(frame, weight, tolerance, None, KIND_POSITION, False)
        if goal_set.is_set(target, (3,)):  # any one of several points
            return goal_set.init_set(self, target, lambda p: Position(frame, p, weight, tolerance), "Position points")
        if isinstance(target, pin.SE3) or np.shape(target) == (4, 4):
            raise TargetError(f"Position on {frame!r} takes a 3-vector (m); use Pose({frame!r}, T) for a pose")
        try:
            p = np.asarray(target, dtype=float)
        except (TypeError, ValueError):
            raise TargetError(f"Position on {frame!r} takes a 3-vector (m), got {target!r}") from None
        if p.shape != (3,):
            raise TargetError(f"Position on {frame!r} takes a 3-vector (m), got shape {p.shape}")
        if not np.isfinite(p).all():
            raise TargetError(f"Position on {frame!r}: target contains NaN or inf: {p}")
        object.__setattr__(self, "target", p.copy())

    def encode(self) -> tuple[np.ndarray, np.ndarray]:
        return self.target.copy(), np.eye(3)

    def __repr__(self) -> str:
        return (f"Position({self.frame!r}, {np.round(self.target, 6).tolist()}, weight={self.weight:g}, "
                f"tolerance={self.tolerance:g})")
