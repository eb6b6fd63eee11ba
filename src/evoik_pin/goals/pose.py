"""Pose: a frame's position and orientation at a target pose (see :mod:`evoik_pin.goals`)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from ..errors import TargetError
from ..solvers.lm.layout import KIND_POSE, KIND_POSE_AXES
from ..target import Target
from . import goal_set
from .bands import tolerance_text
from .goal import DEFAULT_GOAL_TOLERANCE, Goal

__all__ = ["Pose"]


@dataclass(frozen=True, eq=False, repr=False)
class Pose(Goal):
    """The frame's position and orientation at ``target``: a (4, 4) homogeneous matrix, a ``pin.SE3`` or a
    :class:`~evoik_pin.problem.Target` with a rotation, in the robot's base frame (m).

    Args: frame, target, then ``weight`` (> 0, default 1), ``tolerance`` (m, default (or None) 1e-6),
    ``rotation_tolerance`` (rad, default ``tolerance``) and ``free``.

    ``tolerance`` is either one number, the bound of the position error's norm (and ``rotation_tolerance`` of the
    rotation angle), or 6 numbers, per-axis half-widths of the error seen in the target frame: the position error
    ``R_t^T (p - p_t)`` along x, y, z (m), then the components of the rotation vector ``log3(R_t^T R)`` (rad)
    (``inf``: free; ``rotation_tolerance`` then has no use). ``free`` names axes left free, any of
    ``"x y z rx ry rz"`` (a string with spaces or a list): ``free="rz"``, any rotation about the target's z axis
    (a drill, a suction cup). With one number and one free rotation axis, the rotation error is the angle between
    the frame's and the target's axis of that name. See :mod:`evoik_pin.goals.bands`.

    ``target`` may be a goal set: a list of poses or a (k, 4, 4) array, any one of which will do
    (:mod:`.goal_set`).
    """

    target: object = None
    weight: float = 1.0
    tolerance: float = DEFAULT_GOAL_TOLERANCE
    rotation_tolerance: float | None = None
    #: The per-axis half-widths (6,) (m, rad; inf on free axes) of a banded pose, else None; the free axes' names.
    band: object = None
    free: tuple = ()

    def __init__(self, frame: str, target, weight: float = 1.0, tolerance: float | object = DEFAULT_GOAL_TOLERANCE,
                 rotation_tolerance: float | None = None, free=None) -> None:
        self._init_pose_axes(frame, weight, tolerance, rotation_tolerance, free, (KIND_POSE, KIND_POSE_AXES),
                             f"Pose on {frame!r}")
        free = self.free
        if goal_set.is_set(target, (4, 4)):  # any one of several poses
            return goal_set.init_set(self, target, lambda T: Pose(frame, T, weight, tolerance, rotation_tolerance,
                                                                  free or None), "Pose poses")
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
        return f"Pose({self.frame!r}, position={p}, rpy={rpy}, weight={self.weight:g}, {tolerance_text(self)})"
