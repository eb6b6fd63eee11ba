"""RelativePose: one frame's pose seen from another (two hands holding a box) (see :mod:`evoik_pin.goals`)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from ..errors import FrameError, TargetError
from ..solvers.lm.layout import (
    A_REL_BAND,
    A_REL_JOINT,
    A_REL_P,
    A_REL_R,
    A_REL_SIGNS,
    AUX_SIZE,
    KIND_POSE_AXES,
    KIND_RELATIVE_POSE,
    KIND_RELATIVE_POSE_AXES,
)
from .bands import band_errors, tolerance_text
from .goal import DEFAULT_GOAL_TOLERANCE, Goal
from .pose import Pose

__all__ = ["RelativePose"]


@dataclass(frozen=True, eq=False, repr=False)
class RelativePose(Goal):
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

    def __init__(self, frame_a: str, frame_b: str, target, weight: float = 1.0,
                 tolerance: float | object = DEFAULT_GOAL_TOLERANCE, rotation_tolerance: float | None = None,
                 free=None) -> None:
        self._init_pose_axes(frame_b, weight, tolerance, rotation_tolerance, free,
                             (KIND_RELATIVE_POSE, KIND_RELATIVE_POSE_AXES),
                             f"RelativePose of {frame_b!r} seen from {frame_a!r}")
        if not isinstance(frame_a, str) or not frame_a:
            raise FrameError(f"RelativePose's frame_a is a frame name (a non-empty string), got {frame_a!r}")
        if frame_a == frame_b:
            raise FrameError(f"RelativePose needs two frames, got {frame_a!r} twice")
        try:
            pose = Pose(frame_b, target)
        except TargetError as exc:
            raise TargetError(f"RelativePose of {frame_b!r} seen from {frame_a!r}: {exc}") from None
        object.__setattr__(self, "frame_a", frame_a)
        object.__setattr__(self, "target", pose.target)

    @property
    def frame_b(self) -> str:
        """The frame whose pose is seen from ``frame_a`` (the goal's ``frame``)."""
        return self.frame

    @property
    def frames(self) -> list[str]:
        """The frames this goal names: frame_a, frame_b."""
        return [self.frame_a, self.frame]

    @property
    def label(self) -> str:
        """How messages name this goal: ``frame_a -> frame_b``."""
        return f"{self.frame_a} -> {self.frame}"

    def encode(self) -> tuple[np.ndarray, np.ndarray]:
        return np.array(self.target.translation), np.array(self.target.rotation)

    def pack(self, robot) -> tuple[np.ndarray, np.ndarray]:
        """(aux row, support row (m,) bool) on ``robot`` (the ``A_REL_*`` layout of
        :mod:`~evoik_pin.solvers.lm.layout`): frame a's joint and folded placement, and the sign of each joint in
        the relative motion. Raises FrameError for an unknown frame or two frames no joint moves apart."""
        ja, Ra, pa = robot.frame_constants(self.frame_a)
        jb = robot.frame_constants(self.frame)[0]
        tree = robot.tree
        on_a, on_b = np.zeros(tree.m, dtype=bool), np.zeros(tree.m, dtype=bool)
        on_a[tree.ancestors(ja)], on_b[tree.ancestors(jb)] = True, True
        signs = on_b.astype(float) - on_a.astype(float)  # joints moving both move the two frames together
        if not signs.any():
            raise FrameError(f"no active joint of {robot.name} moves frame {self.frame!r} relative to "
                             f"{self.frame_a!r}: load the robot with both among its tips (tips=[...]) or tips='all'")
        aux = np.zeros(A_REL_SIGNS + tree.m)
        aux[A_REL_JOINT] = ja
        aux[A_REL_R:A_REL_R + 9] = Ra.ravel()
        aux[A_REL_P:A_REL_P + 3] = pa
        if self.aux() is not None:  # bands, free axes
            aux[A_REL_BAND:A_REL_BAND + AUX_SIZE] = self.aux()
        aux[A_REL_SIGNS:] = signs
        return aux, on_a | on_b

    def batch_key(self) -> tuple:
        """What this goal's kernel numbers depend on besides its target (solve_many batches lists alike)."""
        return (self.frame_a,)

    def robot_errors(self, robot, q) -> tuple[float, float]:
        """(position error m, rotation error rad) at ``q`` (n,), from Pinocchio's kinematics: the distance and the
        rotation angle, or with bands or free axes the errors its success test compares with the tolerances
        (:func:`.bands.band_errors`)."""
        rel = robot.fk(q, self.frame_a).actInv(robot.fk(q, self.frame))
        if self.aux() is not None:  # bands, free axes: Pose's errors for b's pose seen from a
            pt, Rt = self.encode()
            pos, rot = band_errors(KIND_POSE_AXES, rel.translation[None], rel.rotation[None], pt, Rt, self.aux())
            return float(pos[0]), float(rot[0])
        return (float(np.linalg.norm(rel.translation - self.target.translation)),
                float(np.linalg.norm(pin.log3(self.target.rotation.T @ rel.rotation))))

    def robot_population_errors(self, robot, Q) -> tuple[np.ndarray, np.ndarray]:
        """(position errors (N,) m, rotation errors (N,) rad) of a population Q (N, n), as :meth:`robot_errors`."""
        from ..lie import relative_angle

        P, R = robot.fk_batch(Q, validate=False, frames=[self.frame_a, self.frame])
        Ra = R[:, 0]
        p_rel = np.einsum("nji,nj->ni", Ra, P[:, 1] - P[:, 0])
        R_rel = np.einsum("nji,njk->nik", Ra, R[:, 1])
        pt, Rt = self.encode()
        if self.aux() is not None:  # bands, free axes: Pose's errors for b's pose seen from a
            return band_errors(KIND_POSE_AXES, p_rel, R_rel, pt, Rt, self.aux())
        return np.linalg.norm(p_rel - pt, axis=1), relative_angle(Rt, R_rel)

    def __repr__(self) -> str:
        p = np.round(self.target.translation, 6).tolist()
        rpy = np.round(pin.rpy.matrixToRpy(self.target.rotation), 6).tolist()
        return (f"RelativePose({self.frame_a!r}, {self.frame!r}, position={p}, rpy={rpy}, weight={self.weight:g}, "
                f"{tolerance_text(self)})")
