"""RelativePose: one frame's pose seen from another (two hands holding a box) (see :mod:`evoik_pin.goals`)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..lie import relative_angle
from .bands import AXES, band_errors, pose_text
from .file_entries import FileKind, matrix_text, pair_kind, pose_target
from .goal import DEFAULT_GOAL_TOLERANCE, FramePair, Goal
from .pose import se3_target
from .registry import BANDED_LOG6, FAMILY_BEYOND_FRAME, RELATIVE_BANDED_LOG6, RELATIVE_LOG6, KindCode

__all__ = ["KIND_RELATIVE_POSE", "KIND_RELATIVE_POSE_AXES", "RelativePose"]

#: The kernel codes of one frame's pose seen from another (6 rows): under a norm tolerance (the SE(3) logarithm), and
#: with bands or free axes. Their ``aux`` row: ``goal.A_REL_*``.
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
    #: The per-axis half-widths (6,) (m, rad; inf on free axes) of a banded goal, else None; the free axes' names.
    band: object = None
    free: tuple = ()
    KIND_CODES = (KindCode(KIND_RELATIVE_POSE, (0, 1, 2, 3, 4, 5), FAMILY_BEYOND_FRAME, oriented=True, angle=True),
                  KindCode(KIND_RELATIVE_POSE_AXES, (0, 1, 2, 3, 4, 5), FAMILY_BEYOND_FRAME, oriented=True,
                           angle=True))
    #: The optional fields of its goals-file entry: Pose's.
    FILE_FIELDS = ("weight", "tolerance", "rotation_tolerance", "free")

    def __init__(self, frame_a: str, frame_b: str, target, weight: float = 1.0,
                 tolerance: float | object = DEFAULT_GOAL_TOLERANCE, rotation_tolerance: float | None = None,
                 free=None) -> None:
        where = f"RelativePose of {frame_b!r} seen from {frame_a!r}"
        self._init_axes(frame_b, weight, tolerance, rotation_tolerance, free, AXES,
                        (KIND_RELATIVE_POSE, KIND_RELATIVE_POSE_AXES), where)
        self._init_pair(frame_a, frame_b, "RelativePose")
        self._set(target=se3_target(target, where))

    def encode(self) -> tuple[np.ndarray, np.ndarray]:
        return np.array(self.target.translation), np.array(self.target.rotation)

    @classmethod
    def file_kind(cls) -> FileKind:
        """``kind: relative_pose``: ``frame_a``, ``frame`` (frame b) and a pose ``target`` (b seen from a), with
        Pose's optional fields."""
        return pair_kind(cls, "relative_pose", pose_target, matrix_text)

    def placement_errors(self, Ra, d, Rb) -> tuple[np.ndarray, np.ndarray]:
        """The distance and rotation angle of b's pose seen from a to the target, or with bands or free axes
        Pose's errors (:func:`.bands.band_errors`)."""
        p_rel = np.einsum("nji,nj->ni", Ra, d)
        R_rel = np.einsum("nji,njk->nik", Ra, Rb)
        pt, Rt = self.encode()
        if self.aux() is not None:
            return band_errors(BANDED_LOG6, p_rel, R_rel, pt, Rt, self.aux())
        return np.linalg.norm(p_rel - pt, axis=1), relative_angle(Rt, R_rel)

    def __repr__(self) -> str:
        return f"RelativePose({self.frame_a!r}, {self.frame!r}, {pose_text(self)})"
