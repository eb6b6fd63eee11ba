"""Position: a frame's origin at a target point, orientation free."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from ..errors import TargetError
from .bands import AXES
from .file_entries import position_target, position_text
from .goal import DEFAULT_GOAL_TOLERANCE, Goal, init_set, is_set
from .registry import BANDED_POINT, FAMILY_AXES, FAMILY_FRAME, POINT, KindCode

__all__ = ["KIND_POSITION", "KIND_POSITION_BAND", "Position"]

#: A position's kernel codes: under a norm tolerance, and with bands (base frame).
KIND_POSITION, KIND_POSITION_BAND = POINT, BANDED_POINT


@dataclass(frozen=True, eq=False, repr=False)
class Position(Goal):
    """The frame's origin at ``target``, a 3-vector (m) in the robot's base frame; orientation free.

    Args: frame, target, then ``weight`` (> 0, default 1) and ``tolerance`` (m, default (or None) 1e-6): one number, the
    bound of the position error's norm, or 3 numbers, half-widths of the error ``p - p_t`` along the BASE frame's
    x, y, z (a position target has no frame of its own; ``inf``: free), met when every component is within its
    band. See :mod:`evoik_pin.goals.bands`.

    ``target`` may be a goal set: a list of 3-vectors or a (k, 3) array, any one of which will do
    (:func:`.goal.init_set`).
    """

    target: object = None
    #: The per-axis half-widths (3,) (m, base frame; inf: free) of a banded position, else None.
    band: object = None
    KIND_CODES = (KindCode(KIND_POSITION, (0, 1, 2), FAMILY_FRAME),
                  KindCode(KIND_POSITION_BAND, (0, 1, 2), FAMILY_AXES))
    #: ``kind: position``: ``target: {position}`` (m).
    FILE_ENTRY = ("position", ("weight", "tolerance"), position_target, position_text)

    def __init__(self, frame: str, target, weight: float = 1.0,
                 tolerance: float | object = DEFAULT_GOAL_TOLERANCE) -> None:
        self._init_axes(frame, weight, tolerance, None, None, AXES[:3], (KIND_POSITION, KIND_POSITION_BAND),
                        f"Position on {frame!r}")
        if is_set(target, (3,)):  # any one of several points
            return init_set(self, target, lambda p: Position(frame, p, weight, tolerance), "Position points")
        try:
            p = np.array(target.homogeneous if isinstance(target, pin.SE3) else target, dtype=float)
        except (TypeError, ValueError):
            p = np.array(None)
        if p.shape != (3,) or not np.isfinite(p).all():
            raise TargetError(f"Position on {frame!r} takes a 3-vector (m) of finite numbers (not NaN or inf; "
                              f"Pose({frame!r}, T) for a pose), got {target!r} (shape {p.shape})")
        self._set(target=p.copy())

    def __repr__(self) -> str:
        tol = f"{self.tolerance:g}" if self.band is None else f"{self.band.tolist()}"
        return f"Position({self.frame!r}, {np.round(self.target, 6).tolist()}, weight={self.weight:g}, tolerance={tol})"
