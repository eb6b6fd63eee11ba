"""Pose: a frame's position and orientation at a target pose (see :mod:`evoik_pin.goals`)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from ..errors import TargetError
from ..solvers.lm.layout import KIND_POSE
from ..target import Target
from . import goal_set
from .goal import DEFAULT_GOAL_TOLERANCE, Goal

__all__ = ["Pose"]


@dataclass(frozen=True, eq=False, repr=False)
class Pose(Goal):
    """The frame's position and orientation at ``target``: a (4, 4) homogeneous matrix, a ``pin.SE3`` or a
    :class:`~evoik_pin.problem.Target` with a rotation, in the robot's base frame (m).

    ``target`` may be a goal set: a list of poses or a (k, 4, 4) array, any one of which will do
    (:mod:`.goal_set`).

    Args: frame, target, then ``weight`` (> 0, default 1), ``tolerance`` (m, default 1e-6) and
    ``rotation_tolerance`` (rad, default ``tolerance``).
    """

    target: object = None
    weight: float = 1.0
    tolerance: float = DEFAULT_GOAL_TOLERANCE
    rotation_tolerance: float | None = None

    def __init__(self, frame: str, target, weight: float = 1.0, tolerance: float = DEFAULT_GOAL_TOLERANCE,
                 rotation_tolerance: float | None = None) -> None:
        self._init_common(frame, weight, tolerance, rotation_tolerance, KIND_POSE, True)
        if goal_set.is_set(target, (4, 4)):  # any one of several poses
            return goal_set.init_set(self, target, lambda T: Pose(frame, T, weight, tolerance, rotation_tolerance),
                                     "Pose poses")
        if isinstance(target, (list, tuple)) and len(target) == 3 or np.ndim(target) == 1:
            raise TargetError(f"Pose on {frame!r}: a 3-vector is a position; use Position({frame!r}, p) or give a "
                              "4 x 4 pose or a pin.SE3")
        try:
            t = Target.coerce(target)
        except TargetError as exc:
            raise TargetError(f"Pose on {frame!r}: {exc}") from None
        if t.rotation is None or t.planar:
            raise TargetError(f"Pose on {frame!r} needs a target with a rotation (4 x 4 pose or pin.SE3); use "
                              f"Position({frame!r}, p) for a position alone")
        object.__setattr__(self, "target", pin.SE3(np.array(t.rotation), np.array(t.position)))

    def encode(self) -> tuple[np.ndarray, np.ndarray]:
        return np.array(self.target.translation), np.array(self.target.rotation)

    def __repr__(self) -> str:
        p = np.round(self.target.translation, 6).tolist()
        rpy = np.round(pin.rpy.matrixToRpy(self.target.rotation), 6).tolist()
        return (f"Pose({self.frame!r}, position={p}, rpy={rpy}, weight={self.weight:g}, tolerance={self.tolerance:g}, "
                f"rotation_tolerance={self.rotation_tolerance:g})")
