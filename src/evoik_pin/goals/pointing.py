"""The pointing kinds: Direction (a frame's axis along a direction) and LookAt (a frame's axis pointing at a point)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..errors import TargetError
from ..io.datafile import Flow, floats
from .bands import AUX_SIZE, angles
from .file_entries import FileKind, pointing, vector_target
from .goal import DEFAULT_GOAL_TOLERANCE, Goal, point3
from .registry import AXIS_ALONG, AXIS_AT, FAMILY_AXES, KindCode

__all__ = ["AUX_AXIS", "KIND_DIRECTION", "KIND_LOOK_AT", "Direction", "LookAt", "unit_vector"]

#: A direction's kernel code: the frame's axis minus the wanted unit direction (3 rows, base frame).
KIND_DIRECTION = AXIS_ALONG
#: The ``aux`` row of a pointing goal (``solvers/lm/axes.py``): AUX_AXIS (3,) the frame's unit axis.
AUX_AXIS = 0


def unit_vector(value, what: str) -> np.ndarray:
    """``value`` (3 finite numbers, not all zero) normalised to length 1, or a TargetError naming ``what``."""
    try:
        v = np.array(value, dtype=float)
    except (TypeError, ValueError):
        v = np.zeros(0)
    if v.shape != (3,):
        raise TargetError(f"{what} must be 3 numbers (a direction), got {value!r}")
    if not np.isfinite(v).all():
        raise TargetError(f"{what} must be 3 finite numbers, got {v.tolist()}")
    norm = float(np.linalg.norm(v))
    if norm < 1e-12:
        raise TargetError(f"{what} is zero, which points nowhere: give 3 numbers not all zero (e.g. [0, 0, 1])")
    return v / norm


@dataclass(frozen=True, eq=False, repr=False)
class _Pointing(Goal):
    """A frame's ``axis`` aimed along a direction (:class:`Direction`) or at a point (:class:`LookAt`), its target
    the field ``TARGET`` names: the error is the angle (rad) between the axis (turned with the frame) and the wanted
    direction; the kernel's residual ``R a - d`` (3 rows, base frame) is zero only when they are aligned."""

    axis: object = None
    #: The field holding the target, and the ``kind:`` in goals files.
    TARGET = FILE_KIND = ""

    def _init_pointing(self, frame: str, axis, target, weight, tolerance) -> None:
        name = type(self).__name__
        self._init_common(frame, weight, tolerance, tolerance, self.KIND_CODES[0].code, False)  # rad
        where = f"{name} on {frame!r}: {self.TARGET}"
        self._set(axis=unit_vector(axis, f"{name} on {frame!r}: axis"),
                  **{self.TARGET: point3(target, where) if self.has_point else unit_vector(target, where)})
        aux = np.zeros(AUX_SIZE)
        aux[AUX_AXIS:AUX_AXIS + 3] = self.axis
        self._set_aux(aux)

    def encode(self) -> tuple[np.ndarray, np.ndarray]:
        return getattr(self, self.TARGET).copy(), np.eye(3)

    def population_errors(self, P: np.ndarray, R: np.ndarray, pt: np.ndarray, Rt: np.ndarray
                          ) -> tuple[np.ndarray, np.ndarray]:
        """(zeros (N,), angles (N,) rad) between the axis of the frames R (N, 3, 3) and the wanted direction (for
        a point pt: the line from each origin P (N, 3) to it; pi on the point)."""
        A = R @ self.axis
        zeros = np.zeros(P.shape[0])
        if not self.has_point:
            return zeros, angles(A, np.broadcast_to(pt, A.shape))
        D = pt - P
        return zeros, np.where(np.linalg.norm(D, axis=1) < 1e-12, np.pi, angles(A, D))

    @classmethod
    def file_kind(cls) -> FileKind:
        """``kind: direction | look_at``: ``axis`` and ``target: {direction | point}``; weight, tolerance (rad)."""
        return FileKind(cls.FILE_KIND, cls, ("weight", "tolerance", "axis"), vector_target(cls.TARGET),
                        lambda g: Flow(**{cls.TARGET: floats(g.encode()[0])}), pointing(cls))

    def __repr__(self) -> str:
        return (f"{type(self).__name__}({self.frame!r}, axis={np.round(self.axis, 6).tolist()}, "
                f"{self.TARGET}={np.round(self.encode()[0], 6).tolist()}, weight={self.weight:g}, "
                f"tolerance={self.rotation_tolerance:g})")


@dataclass(frozen=True, eq=False, repr=False)
class Direction(_Pointing):
    """The frame's ``axis`` (3 numbers in the frame, normalised) parallel to ``direction`` (3 numbers in the base
    frame, normalised; the same way round, not opposite): a tool pointing down is ``Direction(tool, [0, 0, 1],
    [0, 0, -1])``. Position and the rotation about the axis free.

    Args: frame, axis, direction, then ``weight`` (> 0, default 1) and ``tolerance`` (rad, default 1e-6), the
    bound of the angle between the two.
    """

    direction: object = None
    has_point = False
    TARGET = FILE_KIND = "direction"
    MARKED = False
    KIND_CODES = (KindCode(KIND_DIRECTION, (3, 4, 5), FAMILY_AXES, has_position=False, angle=True),)

    def __init__(self, frame: str, axis, direction, weight: float = 1.0,
                 tolerance: float = DEFAULT_GOAL_TOLERANCE) -> None:
        self._init_pointing(frame, axis, direction, weight, tolerance)


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
