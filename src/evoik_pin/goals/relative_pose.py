"""The goals placing one frame relative to another (two hands holding a box; a limb vector when retargeting a motion):
RelativePose (frame b's pose seen from frame a) and RelativePosition (its origin) (see :mod:`evoik_pin.goals`)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..errors import OptionError
from ..lie import relative_angle
from .bands import AXES, band_errors, pose_text
from .file_entries import matrix_text, pose_target, position_target, position_text
from .goal import BOTH, DEFAULT_GOAL_TOLERANCE, FramePair, Goal, point3
from .pose import se3_target
from .registry import (
    BANDED_LOG6,
    FAMILY_BEYOND_FRAME,
    RELATIVE_BANDED_LOG6,
    RELATIVE_LOG6,
    RELATIVE_POINT_IN_A,
    RELATIVE_POINT_WORLD,
    KindCode,
)

__all__ = ["EXPRESSED_IN", "KIND_RELATIVE_POSE", "KIND_RELATIVE_POSE_AXES", "KIND_RELATIVE_POSITION",
           "KIND_RELATIVE_POSITION_IN_A", "RelativePose", "RelativePosition"]

#: The kernel codes of one frame's pose seen from another (6 rows): under a norm tolerance, and with bands or free
#: axes. Their ``aux`` row: ``goal.A_REL_*``.
KIND_RELATIVE_POSE, KIND_RELATIVE_POSE_AXES = RELATIVE_LOG6, RELATIVE_BANDED_LOG6


@dataclass(frozen=True, eq=False, repr=False)
class RelativePose(FramePair, Goal):
    """Frame ``frame_b``'s pose seen from frame ``frame_a`` equals ``target`` (a (4, 4) homogeneous matrix or a
    ``pin.SE3``, m): ``T_a^-1 T_b = T``, wherever the two frames are (a box of known size held by two hands: the
    second gripper's pose in the first's). Its error is ``log6(T^-1 T_a^-1 T_b)`` (m, rad): met when the position
    of b seen from a is within ``tolerance`` (m) of T's and the rotation angle within ``rotation_tolerance``
    (rad; default ``tolerance``).

    ``tolerance`` and ``free`` are :class:`Pose`'s, for frame b's pose seen from frame a in the target frame T
    (``free="rz"``: the box may turn about T's z). See :mod:`evoik_pin.goals.bands`.

    Args: frame_a, frame_b, target, then ``weight`` (> 0, default 1), ``tolerance``, ``rotation_tolerance`` and
    ``free``.
    """

    frame_a: str = ""
    target: object = None
    #: As Pose's.
    band: object = None
    free: tuple = ()
    KIND_CODES = (KindCode(KIND_RELATIVE_POSE, (0, 1, 2, 3, 4, 5), FAMILY_BEYOND_FRAME, oriented=True, angle=True),
                  KindCode(KIND_RELATIVE_POSE_AXES, (0, 1, 2, 3, 4, 5), FAMILY_BEYOND_FRAME, oriented=True,
                           angle=True))
    #: ``kind: relative_pose``: ``frame_a``, ``frame`` (frame b), a pose ``target`` (b seen from a) and Pose's fields.
    FILE_ENTRY = ("relative_pose", ("weight", "tolerance", "rotation_tolerance", "free"), pose_target, matrix_text)

    def __init__(self, frame_a: str, frame_b: str, target, weight: float = 1.0,
                 tolerance: float | object = DEFAULT_GOAL_TOLERANCE, rotation_tolerance: float | None = None,
                 free=None) -> None:
        where = f"RelativePose of {frame_b!r} seen from {frame_a!r}"
        self._init_axes(frame_b, weight, tolerance, rotation_tolerance, free, AXES,
                        (KIND_RELATIVE_POSE, KIND_RELATIVE_POSE_AXES), where)
        self._init_pair(frame_a, "RelativePose")
        self._set(target=se3_target(target, where))

    def placement_errors(self, Ra, d, Rb) -> tuple[np.ndarray, np.ndarray]:
        """The distance and rotation angle of b's pose seen from a to the target; with bands or free axes Pose's."""
        p_rel = np.einsum("nji,nj->ni", Ra, d)
        R_rel = np.einsum("nji,njk->nik", Ra, Rb)
        pt, Rt = self.encode()
        if self.aux() is not None:
            return band_errors(BANDED_LOG6, p_rel, R_rel, pt, Rt, self.aux())
        return np.linalg.norm(p_rel - pt, axis=1), relative_angle(Rt, R_rel)

    def __repr__(self) -> str:
        return f"RelativePose({self.frame_a!r}, {self.frame!r}, {pose_text(self)})"


#: Its kernel codes (3 rows each, the compiled ``solvers/lm/balance.py``): ``p_b - p_a - p`` in the world's axes,
#: and ``R_a^T (p_b - p_a) - p`` in frame a's. Their ``aux`` row: ``goal.A_REL_*``.
KIND_RELATIVE_POSITION, KIND_RELATIVE_POSITION_IN_A = RELATIVE_POINT_WORLD, RELATIVE_POINT_IN_A
#: The axes ``p`` may be given in: frame a's, or the world's (the robot's base frame).
EXPRESSED_IN = ("a", "world")


@dataclass(frozen=True, eq=False, repr=False)
class RelativePosition(FramePair, Goal):
    """Frame ``frame_b``'s origin at ``p`` (3 numbers, m) from frame ``frame_a``'s origin, wherever the two frames
    are: ``p_b - p_a = p`` in the world's axes (``expressed_in="world"``: the robot's base frame; the vector keeps its
    direction in space), or ``R_a^T (p_b - p_a) = p`` in frame a's axes (``expressed_in="a"``, the default: the
    vector turns with frame a). Two hands holding a box 0.3 m wide: ``RelativePosition("left_hand", "right_hand",
    [0, -0.3, 0])``; a limb vector when retargeting a motion: ``expressed_in="world"``. Orientation free.

    Its error is ``|e|`` (m) of that equation's residual e; met when within ``tolerance`` (m, > 0, default 1e-6).

    Args: frame_a, frame_b, p, then ``expressed_in`` ("a" or "world"), ``weight`` (> 0, default 1) and ``tolerance``.
    """

    frame_a: str = ""
    target: object = None
    expressed_in: str = "a"
    KIND_CODES = (KindCode(KIND_RELATIVE_POSITION, (0, 1, 2), FAMILY_BEYOND_FRAME),
                  KindCode(KIND_RELATIVE_POSITION_IN_A, (0, 1, 2), FAMILY_BEYOND_FRAME))
    #: ``kind: relative_position``: ``frame_a``, ``frame`` (frame b), ``target: {position: [x, y, z]}`` (m).
    FILE_ENTRY = ("relative_position", ("expressed_in", "weight", "tolerance"), position_target, position_text)

    def __init__(self, frame_a: str, frame_b: str, p, expressed_in: str = "a", weight: float = 1.0,
                 tolerance: float = DEFAULT_GOAL_TOLERANCE) -> None:
        if expressed_in not in EXPRESSED_IN:
            raise OptionError(f"RelativePosition's expressed_in must be one of {', '.join(map(repr, EXPRESSED_IN))} "
                              f"(frame a's axes or the world's), got {expressed_in!r}")
        kind = KIND_RELATIVE_POSITION_IN_A if expressed_in == "a" else KIND_RELATIVE_POSITION
        self._init_common(frame_b, weight, tolerance, None, kind, False)
        self._init_pair(frame_a, "RelativePosition")
        if not self.tolerance > 0:
            raise OptionError(f"tolerance (m) of the RelativePosition of {frame_b!r} from {frame_a!r} must be > 0, "
                              f"got {tolerance!r}")
        self._set(expressed_in=expressed_in, target=point3(p, f"RelativePosition of {frame_b!r} from {frame_a!r}: p"))

    @property
    def p(self) -> np.ndarray:
        """The target (3,) (m)."""
        return self.target

    @property
    def both(self) -> float:
        """:data:`.goal.BOTH` in the world's axes (a joint moving both frames turns the vector), else 0."""
        return BOTH if self.expressed_in == "world" else 0.0

    def placement_errors(self, Ra, d, Rb) -> tuple[np.ndarray, np.ndarray]:
        """(|e| (N,) m, zeros (N,)): e the vector p_b - p_a, in the axes ``expressed_in`` names, minus ``p``."""
        v = np.einsum("nji,nj->ni", Ra, d) if self.expressed_in == "a" else d
        return np.linalg.norm(v - self.target, axis=1), np.zeros(len(d))

    def __repr__(self) -> str:
        return (f"RelativePosition({self.frame_a!r}, {self.frame!r}, {np.round(self.target, 6).tolist()}, "
                f"expressed_in={self.expressed_in!r}, weight={self.weight:g}, tolerance={self.tolerance:g})")
