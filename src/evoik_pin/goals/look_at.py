"""LookAt: a frame's axis pointing at a point (see :mod:`evoik_pin.goals`)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..solvers.lm.layout import KIND_LOOK_AT
from .direction import _Pointing
from .goal import DEFAULT_GOAL_TOLERANCE, point3

__all__ = ["LookAt"]


@dataclass(frozen=True, eq=False, repr=False)
class LookAt(_Pointing):
    """The frame's ``axis`` (3 numbers in the frame, normalised) pointing at ``point`` (3 numbers, m, base frame):
    a head camera on an object is ``LookAt(camera, [0, 0, 1], p_object)`` (the optical axis of a ROS ``*_optical``
    frame is its z). The frame's position is free but enters the direction; a frame on the point is never met.

    Args: frame, axis, point, then ``weight`` (> 0, default 1) and ``tolerance`` (rad, default 1e-6), the bound of
    the angle between the axis and the line from the frame's origin to the point.
    """

    point: object = None
    weight: float = 1.0
    tolerance: float = DEFAULT_GOAL_TOLERANCE
    rotation_tolerance: float | None = None

    def __init__(self, frame: str, axis, point, weight: float = 1.0,
                 tolerance: float = DEFAULT_GOAL_TOLERANCE) -> None:
        self._init_pointing(frame, axis, weight, tolerance, KIND_LOOK_AT)
        object.__setattr__(self, "point", point3(point, f"LookAt on {frame!r}: point"))

    def encode(self) -> tuple[np.ndarray, np.ndarray]:
        return self.point.copy(), np.eye(3)

    def __repr__(self) -> str:
        return (f"LookAt({self.frame!r}, axis={np.round(self.axis, 6).tolist()}, "
                f"point={np.round(self.point, 6).tolist()}, weight={self.weight:g}, "
                f"tolerance={self.rotation_tolerance:g})")
