"""RelativePose: one frame's pose seen from another (two hands holding a box) (see :mod:`evoik_pin.goals`)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from .bands import band_errors, tolerance_text
from .file_entries import FileKind, field_entries, matrix_text, pair_goal, pose_target
from .goal import DEFAULT_GOAL_TOLERANCE, FramePair, Goal, check_frame_pair, pack_frame_pair, pair_placements
from .pose import se3_target
from .registry import BANDED_LOG6, FAMILY_BEYOND_FRAME, RELATIVE_BANDED_LOG6, RELATIVE_LOG6, KindCode

__all__ = ["KIND_RELATIVE_POSE", "KIND_RELATIVE_POSE_AXES", "RelativePose"]

#: The kernel codes of one frame's pose seen from another (6 rows): under a norm tolerance (the SE(3) logarithm), and
#: with bands or free axes (those of a pose with axes for frame b's pose in frame a's coordinates). Their ``aux`` row:
#: ``goal.A_REL_*``.
KIND_RELATIVE_POSE, KIND_RELATIVE_POSE_AXES = RELATIVE_LOG6, RELATIVE_BANDED_LOG6



@dataclass(frozen=True, eq=False, repr=False)
class RelativePose(FramePair, Goal):
    """Frame ``frame_b``'s pose seen from frame ``frame_a`` equals ``target`` (a (4, 4) homogeneous matrix or a
    ``pin.SE3``, m): ``T_a^-1 T_b = T``, wherever the two frames are (a box of known size held by two hands: the
    second gripper's pose in the first's). Its error is ``log6(T^-1 T_a^-1 T_b)`` (m, rad): met when the position
    of b seen from a is within ``tolerance`` (m) of T's and the rotation angle within ``rotation_tolerance``
    (rad; default ``tolerance``).

    ``tolerance`` and ``free`` are :class:`Pose`'s, in the target frame T (the error of ``T^-1 T_a^-1 T_b``): 6
    numbers are per-axis half-widths of the position error ``R_t^T (p - p_t)`` (m) and of the components of
    ``log3(R_t^T R)`` (rad), for (R, p) frame b's pose seen from frame a; ``free`` names axes left free among
    ``"x y z rx ry rz"`` (``free="rz"``: the box may turn about its axis, T's z). See :mod:`evoik_pin.goals.bands`.

    Args: frame_a, frame_b, target, then ``weight`` (> 0, default 1), ``tolerance``, ``rotation_tolerance`` and
    ``free``.
    """

    frame_a: str = ""
    target: object = None
    weight: float = 1.0
    tolerance: float = DEFAULT_GOAL_TOLERANCE
    rotation_tolerance: float | None = None
    #: The per-axis half-widths (6,) (m, rad; inf on free axes) of a banded goal, else None; the free axes' names.
    band: object = None
    free: tuple = ()
    KIND_CODES = (KindCode(KIND_RELATIVE_POSE, (0, 1, 2, 3, 4, 5), FAMILY_BEYOND_FRAME, oriented=True, angle=True),
                  KindCode(KIND_RELATIVE_POSE_AXES, (0, 1, 2, 3, 4, 5), FAMILY_BEYOND_FRAME, oriented=True,
                           angle=True))

    def __init__(self, frame_a: str, frame_b: str, target, weight: float = 1.0,
                 tolerance: float | object = DEFAULT_GOAL_TOLERANCE, rotation_tolerance: float | None = None,
                 free=None) -> None:
        self._init_pose_axes(frame_b, weight, tolerance, rotation_tolerance, free,
                             (KIND_RELATIVE_POSE, KIND_RELATIVE_POSE_AXES),
                             f"RelativePose of {frame_b!r} seen from {frame_a!r}")
        check_frame_pair(frame_a, frame_b, "RelativePose")
        object.__setattr__(self, "frame_a", frame_a)
        object.__setattr__(self, "target", se3_target(target, f"RelativePose of {frame_b!r} seen from {frame_a!r}"))

    def encode(self) -> tuple[np.ndarray, np.ndarray]:
        return np.array(self.target.translation), np.array(self.target.rotation)

    def pack(self, robot) -> tuple[np.ndarray, np.ndarray]:
        """(aux row, support row (m,) bool) on ``robot`` (:func:`.goal.pack_frame_pair`: frame a's joint and
        folded placement, the bands, the sign of each joint in the relative motion). Raises FrameError for an
        unknown frame or two frames no joint moves apart."""
        return pack_frame_pair(robot, self.frame_a, self.frame, self.aux())

    def marker(self) -> None:
        """None: the target is a pose in frame a, no place in the base frame."""
        return None

    #: The optional fields of its goals-file entry: Pose's.
    FILE_FIELDS = ("weight", "tolerance", "rotation_tolerance", "free")

    @classmethod
    def file_kind(cls) -> FileKind:
        """``kind: relative_pose``: ``frame_a``, ``frame`` (frame b) and a pose ``target`` (b seen from a), with
        Pose's optional fields."""
        return FileKind("relative_pose", cls, (), pose_target, matrix_text,
                        read=lambda entry, what: pair_goal(cls, entry, what, "relative_pose", cls.FILE_FIELDS,
                                                           pose_target),
                        write=lambda g: ({"frame_a": g.frame_a, "frame": g.frame, "kind": "relative_pose",
                                          "target": matrix_text(g)} | field_entries(g, cls.FILE_FIELDS)))

    def batch_key(self) -> tuple:
        """What this goal's kernel numbers depend on besides its target (solve_many batches lists alike)."""
        return (self.frame_a,)

    def robot_errors(self, robot, q) -> tuple[float, float]:
        """(position error m, rotation error rad) at ``q`` (n,), from Pinocchio's kinematics: the distance and the
        rotation angle, or with bands or free axes the errors its success test compares with the tolerances
        (:func:`.bands.band_errors`)."""
        return self.pair_errors(robot.fk(q, self.frame_a), robot.fk(q, self.frame))

    def pair_errors(self, Ta: pin.SE3, Tb: pin.SE3) -> tuple[float, float]:
        """(position error m, rotation error rad) for frame a's and frame b's poses ``Ta``, ``Tb`` (base frame), as
        :meth:`robot_errors` reports them."""
        rel = Ta.actInv(Tb)
        if self.aux() is not None:  # bands, free axes: Pose's errors for b's pose seen from a
            pt, Rt = self.encode()
            pos, rot = band_errors(BANDED_LOG6, rel.translation[None], rel.rotation[None], pt, Rt, self.aux())
            return float(pos[0]), float(rot[0])
        return (float(np.linalg.norm(rel.translation - self.target.translation)),
                float(np.linalg.norm(pin.log3(self.target.rotation.T @ rel.rotation))))

    def robot_population_errors(self, robot, Q) -> tuple[np.ndarray, np.ndarray]:
        """(position errors (N,) m, rotation errors (N,) rad) of a population Q (N, n), as :meth:`robot_errors`."""
        from ..lie import relative_angle

        Ra, d, Rb = pair_placements(robot, Q, self.frame_a, self.frame)
        p_rel = np.einsum("nji,nj->ni", Ra, d)
        R_rel = np.einsum("nji,njk->nik", Ra, Rb)
        pt, Rt = self.encode()
        if self.aux() is not None:  # bands, free axes: Pose's errors for b's pose seen from a
            return band_errors(BANDED_LOG6, p_rel, R_rel, pt, Rt, self.aux())
        return np.linalg.norm(p_rel - pt, axis=1), relative_angle(Rt, R_rel)

    def __repr__(self) -> str:
        p = np.round(self.target.translation, 6).tolist()
        rpy = np.round(pin.rpy.matrixToRpy(self.target.rotation), 6).tolist()
        return (f"RelativePose({self.frame_a!r}, {self.frame!r}, position={p}, rpy={rpy}, weight={self.weight:g}, "
                f"{tolerance_text(self)})")
