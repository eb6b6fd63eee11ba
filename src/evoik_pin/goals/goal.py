"""The base of every goal kind: the frame it is on, its weight and tolerances, checked when the goal is made
(see :mod:`evoik_pin.goals`)."""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
import pinocchio as pin

from ..errors import FrameError, OptionError

__all__ = ["DEFAULT_GOAL_TOLERANCE", "Goal", "number"]

#: Default tolerance of a goal: 1e-6 m (and rad for a pose's rotation).
DEFAULT_GOAL_TOLERANCE = 1e-6


def number(value, what: str, accepted: str) -> float:
    """``value`` as a finite float, or an OptionError naming ``what`` and what is ``accepted``."""
    try:
        x = float(value)
    except (TypeError, ValueError):
        raise OptionError(f"{what} must be {accepted}, got {value!r}") from None
    if not math.isfinite(x):
        raise OptionError(f"{what} must be {accepted}, got {value!r}")
    return x


@dataclass(frozen=True, eq=False)
class Goal:
    """A goal on one frame (abstract: :class:`Pose`, :class:`Position`). See the module docstring."""

    frame: str
    weight: float = 1.0
    tolerance: float = DEFAULT_GOAL_TOLERANCE
    rotation_tolerance: float | None = None
    #: The LM kernel's goal kind (``KIND_*``), and whether the goal constrains orientation.
    kind: int = field(default=-1, init=False, repr=False)
    has_orientation: bool = field(default=False, init=False, repr=False)

    def _init_common(self, frame, weight, tolerance, rotation_tolerance, kind: int, oriented: bool) -> None:
        """Set and check the fields every goal has (a frozen dataclass's fields, hence object.__setattr__)."""
        for name, value in (("frame", frame), ("weight", weight), ("tolerance", tolerance),
                            ("rotation_tolerance", rotation_tolerance), ("kind", kind), ("has_orientation", oriented)):
            object.__setattr__(self, name, value)
        self._check_common()

    def _check_common(self) -> None:
        if not isinstance(self.frame, str) or not self.frame:
            raise FrameError(f"a goal's frame is a frame name (a non-empty string), got {self.frame!r}")
        self._check_numbers(f"the goal on {self.frame!r}")

    def _check_numbers(self, what: str) -> None:
        """Check and set weight and tolerances; ``what`` names the goal in the messages."""
        weight = number(self.weight, f"weight of {what}", "a finite number > 0")
        if weight <= 0:
            raise OptionError(f"weight of {what} must be > 0, got {self.weight!r}")
        tol = DEFAULT_GOAL_TOLERANCE if self.tolerance is None else number(  # None: the default
            self.tolerance, f"tolerance (m) of {what}", "a finite number >= 0")
        rtol = tol if self.rotation_tolerance is None else number(
            self.rotation_tolerance, f"rotation_tolerance (rad) of {what}", "a finite number >= 0")
        if tol < 0 or rtol < 0:
            raise OptionError(f"tolerances of {what} must be >= 0, got {self.tolerance!r} m and "
                              f"{self.rotation_tolerance!r} rad")
        object.__setattr__(self, "weight", weight)
        object.__setattr__(self, "tolerance", tol)
        object.__setattr__(self, "rotation_tolerance", rtol)

    @property
    def label(self) -> str:
        """How messages name this goal: its frame (goals beyond one frame say more)."""
        return self.frame

    def encode(self) -> tuple[np.ndarray, np.ndarray]:  # pragma: no cover - abstract
        """The kernel's target ``(pt (3,), Rt (3, 3))`` of this goal."""
        raise NotImplementedError

    def errors(self, T: pin.SE3) -> tuple[float, float | None]:
        """(position error m, rotation angle rad or None) of the goal frame at pose ``T`` (base frame)."""
        pt, Rt = self.encode()
        pos = float(np.linalg.norm(T.translation - pt))
        if not self.has_orientation:
            return pos, None
        return pos, float(np.linalg.norm(pin.log3(Rt.T @ T.rotation)))

    def met(self, position_error: float, orientation_error: float | None) -> bool:
        """Whether errors (m, rad or None) are within this goal's tolerances."""
        return position_error <= self.tolerance and (orientation_error is None
                                                     or orientation_error <= self.rotation_tolerance)
