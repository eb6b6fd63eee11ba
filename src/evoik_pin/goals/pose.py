"""Pose: a frame's position and orientation at a target pose."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from ..errors import TargetError
from ..target import Target, pose_arrays
from .bands import AXES, pose_text
from .file_entries import matrix_text, pose_target
from .goal import DEFAULT_GOAL_TOLERANCE, Goal, init_set, is_set
from .registry import BANDED_LOG6, FAMILY_AXES, FAMILY_FRAME, LOG6, KindCode

__all__ = ["KIND_POSE", "KIND_POSE_AXES", "Pose", "se3_target"]

#: A pose's kernel codes: under a norm tolerance (the SE(3) logarithm), and with bands or free axes.
KIND_POSE, KIND_POSE_AXES = LOG6, BANDED_LOG6


def se3_target(target, where: str) -> pin.SE3:
    """``target`` (a (4, 4) homogeneous matrix, a ``pin.SE3`` or a Target with a rotation; m) as a ``pin.SE3``, or
    a TargetError naming ``where``."""
    arrays = pose_arrays(target)  # a checked pin.SE3 or float (4, 4) pose: no Target made
    if arrays is not None and arrays[1] is not None:
        return target.copy() if type(target) is pin.SE3 else pin.SE3(np.array(arrays[1]), np.array(arrays[0]))
    if isinstance(target, (list, tuple)) and len(target) == 3 or np.ndim(target) == 1:
        raise TargetError(f"{where}: a 3-vector is a position (Position goals take one); give a 4 x 4 pose or a "
                          "pin.SE3")
    try:
        t = Target.coerce(target)
    except TargetError as exc:
        raise TargetError(f"{where}: {exc}") from None
    if t.rotation is None or t.planar:
        raise TargetError(f"{where} needs a target with a rotation (4 x 4 pose or pin.SE3)")
    return pin.SE3(np.array(t.rotation), np.array(t.position))


@dataclass(frozen=True, eq=False, repr=False)
class Pose(Goal):
    """The frame's position and orientation at ``target``: a (4, 4) homogeneous matrix, a ``pin.SE3`` or a
    :class:`~evoik_pin.problem.Target` with a rotation, in the robot's base frame (m).

    Args: frame, target, then ``weight`` (> 0, default 1), ``tolerance`` (m, default (or None) 1e-6),
    ``rotation_tolerance`` (rad, default ``tolerance``) and ``free``.

    ``tolerance`` is either one number, the bound of the position error's norm (and ``rotation_tolerance`` of the
    rotation angle), or 6 numbers, per-axis half-widths of the error seen in the target frame: the position error
    ``R_t^T (p - p_t)`` along x, y, z (m), then the components of the rotation vector ``log3(R_t^T R)`` (rad)
    (``inf``: free). ``free`` names axes left free, any of ``"x y z rx ry rz"`` (a string or a list):
    ``free="rz"``, any rotation about the target's z axis (a drill). See :mod:`evoik_pin.goals.bands`.

    ``target`` may be a goal set: a list of poses or a (k, 4, 4) array, any one of which will do
    (:func:`.goal.init_set`).
    """

    target: object = None
    #: The per-axis half-widths (6,) (m, rad; inf on free axes) of a banded pose, else None; the free axes' names.
    band: object = None
    free: tuple = ()
    KIND_CODES = (KindCode(KIND_POSE, (0, 1, 2, 3, 4, 5), FAMILY_FRAME, oriented=True, angle=True),
                  KindCode(KIND_POSE_AXES, (0, 1, 2, 3, 4, 5), FAMILY_AXES, oriented=True, angle=True))
    #: ``kind: pose``: ``target: {position, rpy | rpy_rad}`` or ``{matrix}``; a goal set's members as poses.
    FILE_ENTRY = ("pose", ("weight", "tolerance", "rotation_tolerance", "free"), pose_target, matrix_text,
                  {"set_member": lambda t: t.se3()})

    def __init__(self, frame: str, target, weight: float = 1.0, tolerance: float | object = DEFAULT_GOAL_TOLERANCE,
                 rotation_tolerance: float | None = None, free=None) -> None:
        self._init_axes(frame, weight, tolerance, rotation_tolerance, free, AXES, (KIND_POSE, KIND_POSE_AXES),
                        f"Pose on {frame!r}")
        if is_set(target, (4, 4)):  # any one of several poses
            free = self.free or None
            return init_set(self, target, lambda T: Pose(frame, T, weight, tolerance, rotation_tolerance, free),
                            "Pose poses")
        self._set(target=se3_target(target, f"Pose on {frame!r}"))

    def __repr__(self) -> str:
        return f"Pose({self.frame!r}, {pose_text(self)})"
