"""LookAt: a frame's axis pointing at a point (see :mod:`evoik_pin.goals`)."""

from __future__ import annotations

from dataclasses import dataclass

from .direction import _Pointing
from .goal import DEFAULT_GOAL_TOLERANCE
from .registry import AXIS_AT, FAMILY_AXES, KindCode

__all__ = ["KIND_LOOK_AT", "LookAt"]

#: A look-at's kernel code: the frame's axis minus the unit direction to the point (3 rows, base frame).
KIND_LOOK_AT = AXIS_AT


@dataclass(frozen=True, eq=False, repr=False)
class LookAt(_Pointing):
    """The frame's ``axis`` (3 numbers in the frame, normalised) pointing at ``point`` (3 numbers, m, base frame):
    a head camera on an object is ``LookAt(camera, [0, 0, 1], p_object)`` (the optical axis of a ROS ``*_optical``
    frame is its z). The frame's position is free but enters the direction; a frame on the point is never met.

    Args: frame, axis, point, then ``weight`` (> 0, default 1) and ``tolerance`` (rad, default 1e-6), the bound of
    the angle between the axis and the line from the frame's origin to the point.
    """

    point: object = None
    has_point = True
    TARGET, FILE_KIND = "point", "look_at"
    KIND_CODES = (KindCode(KIND_LOOK_AT, (3, 4, 5), FAMILY_AXES, has_position=False, angle=True),)

    def __init__(self, frame: str, axis, point, weight: float = 1.0, tolerance: float = DEFAULT_GOAL_TOLERANCE) -> None:
        self._init_pointing(frame, axis, point, weight, tolerance)
