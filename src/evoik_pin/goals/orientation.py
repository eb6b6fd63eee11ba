"""Orientation: a frame's orientation at a target rotation, position free."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from ..errors import TargetError
from ..target import _rotation
from .bands import AXES
from .file_entries import matrix_text, orientation_target
from .goal import DEFAULT_GOAL_TOLERANCE, Goal
from .registry import BANDED_ROTATION, FAMILY_AXES, KindCode

__all__ = ["KIND_ORIENTATION", "Orientation"]

#: An orientation's kernel code: the rotation vector's components with bands (a norm tolerance: bands of 0).
KIND_ORIENTATION = BANDED_ROTATION


@dataclass(frozen=True, eq=False, repr=False)
class Orientation(Goal):
    """The frame's orientation at ``target``: a (3, 3) rotation matrix, a ``pin.SE3`` or a (4, 4) pose (its
    rotation; the position is ignored), in the robot's base frame; position free.

    Args: frame, target, then ``weight`` (> 0, default 1), ``tolerance`` (rad, default 1e-6): one number, the
    bound of the rotation angle, or 3 numbers, half-widths of the components rx, ry, rz of ``log3(R_t^T R)``
    (``inf``: free), and ``free``: rotation axes left free, any of ``"rx ry rz"`` (``free="rz"``: any rotation
    about the target's z axis; with one number as tolerance its error is then the angle between the frame's and
    the target's z axes). See :mod:`evoik_pin.goals.bands`.
    """

    target: object = None
    band: object = None
    free: tuple = ()
    KIND_CODES = (KindCode(KIND_ORIENTATION, (3, 4, 5), FAMILY_AXES, oriented=True, has_position=False, angle=True),)
    MARKED = False
    #: ``kind: orientation``: ``target: {rpy | rpy_rad}`` or ``{matrix}`` (3 x 3).
    FILE_ENTRY = ("orientation", ("weight", "tolerance", "free"), orientation_target, matrix_text)

    def __init__(self, frame: str, target, weight: float = 1.0, tolerance: float | object = DEFAULT_GOAL_TOLERANCE,
                 free=None) -> None:
        where = f"Orientation on {frame!r}"
        self._init_axes(frame, weight, tolerance, None, free, AXES[3:], (None, KIND_ORIENTATION), where)
        if isinstance(target, pin.SE3):
            target = target.rotation
        elif np.shape(target) == (4, 4):
            target = np.asarray(target, dtype=float)[:3, :3]
        try:
            R = _rotation(target)
        except TargetError as exc:
            raise TargetError(f"{where} takes a 3 x 3 rotation, a pin.SE3 or a 4 x 4 pose: {exc}") from None
        self._set(target=np.array(R))

    def __repr__(self) -> str:
        rpy = np.round(pin.rpy.matrixToRpy(self.target), 6).tolist()
        tol = f"{self.rotation_tolerance:g}" if self.band is None else f"{self.band.tolist()}"
        free = f", free={' '.join(self.free)!r}" if self.free else ""
        return f"Orientation({self.frame!r}, rpy={rpy}, weight={self.weight:g}, tolerance={tol}{free})"
