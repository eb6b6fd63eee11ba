"""The base of every goal kind: the frame it is on, its weight and tolerances, checked when the goal is made
(see :mod:`evoik_pin.goals`)."""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
import pinocchio as pin

from ..errors import FrameError, OptionError, TargetError
from .bands import AXES, band_aux, band_errors, parse_pose_axes

__all__ = ["DEFAULT_GOAL_TOLERANCE", "Goal", "number", "point3"]

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



def point3(value, what: str) -> np.ndarray:
    """``value`` as 3 finite numbers (m), or a TargetError naming ``what``."""
    try:
        p = np.array(value, dtype=float)
    except (TypeError, ValueError):
        raise TargetError(f"{what} must be 3 finite numbers (m) (a 3-vector), got {value!r}") from None
    if p.shape != (3,) or not np.isfinite(p).all():
        raise TargetError(f"{what} must be 3 finite numbers (m) (a 3-vector), got {value!r}")
    return p

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
    #: A goal set's members (:mod:`.goal_set`): one single-target goal each; None for one target.
    alternatives: tuple | None = field(default=None, init=False, repr=False)

    def _init_common(self, frame, weight, tolerance, rotation_tolerance, kind: int, oriented: bool) -> None:
        """Set and check the fields every goal has (a frozen dataclass's fields, hence object.__setattr__)."""
        for name, value in (("frame", frame), ("weight", weight), ("tolerance", tolerance),
                            ("rotation_tolerance", rotation_tolerance), ("kind", kind), ("has_orientation", oriented)):
            object.__setattr__(self, name, value)
        self._check_common()

    def _init_pose_axes(self, frame, weight, tolerance, rotation_tolerance, free, kinds: tuple[int, int],
                        where: str) -> None:
        """Set and check the fields of a pose-like goal (:class:`Pose`, :class:`RelativePose`): those of
        :meth:`_init_common`, its ``band`` and ``free`` (:func:`.bands.parse_pose_axes`; ``where`` names the goal in
        the messages) and its aux row; kind ``kinds[0]`` under a norm tolerance with no free axis, else
        ``kinds[1]``, whose errors under bands are their excess over them (tolerances 0)."""
        band, free = parse_pose_axes(tolerance, rotation_tolerance, free, where)
        plain = band is None and not free
        if band is None:
            self._init_common(frame, weight, tolerance, rotation_tolerance, kinds[0] if plain else kinds[1], True)
        else:  # the errors of a banded goal are its excess over the bands: met at 0
            self._init_common(frame, weight, 0.0, 0.0, kinds[1], True)
        object.__setattr__(self, "band", band)
        object.__setattr__(self, "free", free)
        self._set_aux(None if plain else band_aux(band, free, AXES, DEFAULT_GOAL_TOLERANCE))

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
    #: Whether the goal puts the frame's origin somewhere (False for orientation and pointing goals: their target
    #: position pt is no place for the frame, and seed ranking leaves it out). A class attribute, not a field.
    has_position = True

    def aux(self) -> np.ndarray | None:
        """The kernel's ``aux`` row of this goal (:mod:`evoik_pin.solvers.lm.layout`'s ``AUX_*``, read-only; None:
        its kind reads none), made once with the goal (:meth:`_set_aux`)."""
        return self.__dict__.get("_aux")

    def _set_aux(self, aux: np.ndarray | None) -> None:
        if aux is not None:
            aux.setflags(write=False)
        object.__setattr__(self, "_aux", aux)

    def population_errors(self, P: np.ndarray, R: np.ndarray, pt: np.ndarray, Rt: np.ndarray
                          ) -> tuple[np.ndarray, np.ndarray] | None:
        """(position errors (N,) m, orientation errors (N,) rad) of frame poses P (N, 3), R (N, 3, 3) for target
        (pt, Rt), as the kernel's success test sees them, for the kinds with an ``aux`` row (None for the others,
        whose errors are the distance and the rotation angle)."""
        aux = self.aux()
        if aux is None:
            return None
        return band_errors(self.kind, P, R, pt, Rt, aux)

    def encode(self) -> tuple[np.ndarray, np.ndarray]:  # pragma: no cover - abstract
        """The kernel's target ``(pt (3,), Rt (3, 3))`` of this goal."""
        raise NotImplementedError

    def errors(self, T: pin.SE3) -> tuple[float, float | None]:
        """(position error m or None, rotation angle rad or None) of the goal frame at pose ``T`` (base frame); for
        the kinds with bands, free axes or an axis to point, the errors their success test compares with the
        tolerances (:mod:`.bands`)."""
        pt, Rt = self.encode()
        aux = self.aux()
        if aux is not None:  # the kernel's own errors (its success test's), by its compiled code for one pose
            from ..solvers.lm.axes import axes_error

            # C-contiguous arrays, the one signature compiled_kernel() loads before any clock (a target's rotation
            # from Pinocchio is Fortran-ordered: another numba type, compiled or loaded mid-search)
            _, pos, rot = axes_error(self.kind, np.ascontiguousarray(T.rotation), np.ascontiguousarray(T.translation),
                                     np.ascontiguousarray(pt), np.ascontiguousarray(Rt), aux, np.empty((3, 3)),
                                     np.empty(3), np.empty(6))
            return self.reported(pos, rot)
        pos = float(np.linalg.norm(T.translation - pt))
        if not self.has_orientation:
            return pos, None
        return pos, float(np.linalg.norm(pin.log3(Rt.T @ T.rotation)))

    def reported(self, position_error: float, rotation_error: float | None) -> tuple[float | None, float | None]:
        """The errors :meth:`errors` reports from the LM kernel's errors of this goal (position m, rotation rad or
        None/NaN: the kernel's success test's numbers, :func:`~evoik_pin.solvers.lm.kernel.task_error`): the
        position error None for a goal without a position, the rotation None for one that reports no angle."""
        return ((float(position_error) if self.has_position else None),
                (float(rotation_error) if self.reports_angle else None))

    @property
    def reports_angle(self) -> bool:
        """Whether the goal's errors include an angle (rad): it constrains orientation, or it points an axis."""
        return self.has_orientation

    def met(self, position_error: float | None, orientation_error: float | None) -> bool:
        """Whether errors (m or None, rad or None) are within this goal's tolerances."""
        return (position_error is None or position_error <= self.tolerance) and (orientation_error is None
                                                     or orientation_error <= self.rotation_tolerance)
