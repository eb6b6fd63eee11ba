"""IK targets: a position (3,) m, a pose, or a planar (x, y[, yaw]) target in the robot's base frame, checked once
(:class:`Target`): finite numbers of the right shape, a rotation matrix, within :data:`MAX_TARGET_NORM` of the base.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from .errors import TargetError
from .lie import is_rotation
from .lie.so3 import is_rotation_entries

__all__ = ["MAX_TARGET_NORM", "Target", "pose_arrays"]

#: Farthest target position accepted (m from the base origin): beyond any arm's reach by orders of magnitude, and
#: low enough that squared distances (1e12 m^2) stay far from float overflow in every solver and feature space.
MAX_TARGET_NORM = 1e6


def _beyond_text(position: np.ndarray) -> str:
    """'target position (x, y, z) m is ... m from the base, beyond ...' for a position beyond MAX_TARGET_NORM."""
    norm = math.hypot(*position.tolist())
    return (f"target position ({', '.join(f'{x:.3g}' for x in position)}) m is {norm:.3g} m from the base, beyond "
            f"any arm's reach (accepted: at most MAX_TARGET_NORM = {MAX_TARGET_NORM:g} m)")


def _vector(value, name: str, sizes: tuple[int, ...], bound: float | None = None) -> np.ndarray:
    """``value`` as a finite float vector with one of ``sizes`` entries; with ``bound``, a Euclidean norm at most
    ``bound`` (a position, m)."""
    try:
        arr = np.asarray(value, dtype=float)
    except (TypeError, ValueError) as exc:
        raise TargetError(f"{name} must be numbers, got {value!r}") from exc
    if arr.ndim != 1 or arr.shape[0] not in sizes:
        raise TargetError(f"{name} must have {' or '.join(map(str, sizes))} entries, got shape {arr.shape}")
    # math.hypot: huge finite entries give their norm without an overflow warning; NaN and inf propagate
    norm = math.hypot(*arr.tolist())
    if not norm <= (math.inf if bound is None else bound):
        if not np.isfinite(arr).all():
            raise TargetError(f"{name} contains NaN or inf: {arr}")
        raise TargetError(_beyond_text(arr))
    return arr


_TARGET_FORMS = "target must be a 3-vector position (m), a pin.SE3, a 4 x 4 homogeneous matrix or a Target"
_NOT_ROTATION = ("target rotation is not a rotation matrix (R^T R must be I and det R = +1 to 1e-6); "
                 "orthonormalize it or pass roll-pitch-yaw angles")


def _rotation(value) -> np.ndarray:
    try:
        R = np.asarray(value, dtype=float)
    except (TypeError, ValueError) as exc:
        raise TargetError(f"target rotation must be a 3 x 3 matrix of numbers, got {value!r}") from exc
    if R.shape != (3, 3):
        raise TargetError(f"target rotation must be a 3 x 3 matrix, got shape {R.shape}")
    if not is_rotation_entries(*R.reshape(9).tolist()):
        # a NaN or inf fails the test's first line; which of the two it was is looked up only here
        if not np.isfinite(R).all():
            raise TargetError("target rotation contains NaN or inf")
        raise TargetError(_NOT_ROTATION)
    return R


def _pose_ok(position: np.ndarray, rotation: np.ndarray) -> bool:
    """Whether float arrays ``position`` (3,) m and ``rotation`` (3, 3) pass :class:`Target`'s checks (finite, within
    :data:`MAX_TARGET_NORM` of the base, a rotation matrix), on Python floats (about 1 us)."""
    return math.hypot(*position.tolist()) <= MAX_TARGET_NORM and is_rotation_entries(*rotation.reshape(9).tolist())


def _unchecked_pose(cls, position: np.ndarray, rotation: np.ndarray):
    """A ``cls`` (Target) of ``position`` (3,) m and ``rotation`` (3, 3) checked already: no ``__post_init__``."""
    t = object.__new__(cls)
    t.__dict__.update(position=position, rotation=rotation, planar=False, yaw=None)  # frozen: no __setattr__
    return t


def pose_arrays(target, check_rotation: bool = True) -> tuple[np.ndarray, np.ndarray | None] | None:
    """(position (3,) m, rotation (3, 3) or None) of a ``pin.SE3``, a float64 (4, 4) pose (bottom row exactly
    [0 0 0 1]), a float64 3-vector or a 3-D :class:`Target` that passes :class:`Target`'s checks, without making a
    Target; None otherwise (:meth:`Target.coerce` then gives the verdict). The arrays may be views of ``target``.
    ``check_rotation=False`` leaves a pose's rotation unchecked: the caller checks it (:func:`is_rotation_entries`)
    before using it, as an IKSolver's repeat call does inside its compiled guaranteed runs."""
    kind = type(target)
    if kind is pin.SE3:
        position, rotation = target.translation, target.rotation
    elif kind is np.ndarray and target.dtype == np.float64:
        if target.shape == (3,):
            return (target, None) if math.hypot(*target.tolist()) <= MAX_TARGET_NORM else None
        if target.shape != (4, 4) or target[3].tolist() != [0.0, 0.0, 0.0, 1.0]:
            return None
        position, rotation = target[:3, 3], target[:3, :3]
    elif kind is Target and not target.planar:
        return target.position, target.rotation  # checked when it was made
    else:
        return None
    ok = _pose_ok(position, rotation) if check_rotation else math.hypot(*position.tolist()) <= MAX_TARGET_NORM
    return (position, rotation) if ok else None


@dataclass(frozen=True)
class Target:
    """An IK target for the tip frame, in the robot's base frame.

    Attributes:
        position: (3,) tip position in m; for a planar target (2,) = (x, y).
        rotation: (3, 3) tip orientation, or None for a position-only target.
        planar: True for a planar target (x, y[, yaw]) of an arm moving in the base xy-plane.
        yaw: planar heading in rad (rotation about base z), or None.
    """

    position: np.ndarray
    rotation: np.ndarray | None = None
    planar: bool = False
    yaw: float | None = None

    def __post_init__(self) -> None:
        pos = _vector(self.position, "target position", (2,) if self.planar else (3,), MAX_TARGET_NORM)
        object.__setattr__(self, "position", pos)
        if self.rotation is not None:
            if self.planar:
                raise TargetError("a planar target takes a yaw angle, not a rotation matrix")
            object.__setattr__(self, "rotation", _rotation(self.rotation))
        if self.yaw is not None:
            if not self.planar:
                raise TargetError("yaw applies to planar targets only; give a rotation for 3-D targets")
            if not np.isfinite(self.yaw):
                raise TargetError(f"target yaw must be finite, got {self.yaw}")

    @classmethod
    def planar_target(cls, x: float, y: float, yaw: float | None = None) -> Target:
        """Planar target (x, y in m, optional yaw in rad) for arms moving in the base xy-plane."""
        return cls(position=np.array([x, y], dtype=float), planar=True, yaw=None if yaw is None else float(yaw))

    @classmethod
    def from_rpy(cls, position, rpy) -> Target:
        """Pose target from a position (m) and roll-pitch-yaw angles (rad), R = Rz(yaw) Ry(pitch) Rx(roll)."""
        rpy = _vector(rpy, "target roll-pitch-yaw", (3,))
        return cls(position=position, rotation=pin.rpy.rpyToMatrix(*rpy))

    @classmethod
    def coerce(cls, target) -> Target:
        """A Target from a Target, a ``pin.SE3``, a (4, 4) homogeneous matrix or a 3-vector position."""
        if isinstance(target, Target):
            return target
        if isinstance(target, pin.SE3):
            position, rotation = np.array(target.translation), np.array(target.rotation)
        else:
            try:
                arr = np.asarray(target, dtype=float)
            except (TypeError, ValueError) as exc:
                raise TargetError(f"{_TARGET_FORMS}; got {target!r}") from exc
            if arr.ndim == 1 and arr.shape[0] == 3:
                return cls(position=arr)
            if arr.shape != (4, 4):
                raise TargetError(f"{_TARGET_FORMS} (Target.planar_target(x, y, yaw) for planar arms); got an array "
                                  f"of shape {arr.shape}")
            a, b, c, d = arr[3].tolist()
            # the bottom row on Python floats first (a NaN fails every comparison: numpy's test then decides)
            if not (abs(a) <= 1e-9 and abs(b) <= 1e-9 and abs(c) <= 1e-9 and abs(d - 1.0) <= 1e-9):
                if np.isfinite(arr[3]).all() and np.abs(arr[3] - [0.0, 0.0, 0.0, 1.0]).max() > 1e-9:
                    raise TargetError(f"the bottom row of a 4 x 4 homogeneous pose must be [0 0 0 1], got "
                                      f"{arr[3].tolist()}")
            position, rotation = arr[:3, 3], arr[:3, :3]
        # checked on Python floats (about 1 us); a bad pose is built the checked way, which raises its error
        if _pose_ok(position, rotation):
            return _unchecked_pose(cls, position, rotation)
        return cls(position=position, rotation=rotation)

    @classmethod
    def from_poses(cls, poses) -> list[Target]:
        """Pose targets from an array of N homogeneous matrices (N, 4, 4) (m), checked in one vectorized pass
        (:meth:`check_poses`)."""
        return [_unchecked_pose(cls, T[:3, 3].copy(), T[:3, :3].copy()) for T in cls.check_poses(poses)]

    @staticmethod
    def check_poses(poses) -> np.ndarray:
        """``poses`` as a float (N, 4, 4) array of homogeneous matrices (m), checked in one vectorized pass: finite
        numbers, translations at most ``MAX_TARGET_NORM`` m from the base, rotation blocks orthonormal with det +1
        (to 1e-6), bottom rows [0 0 0 1]. A TargetError names the first bad target's index."""
        H = np.asarray(poses, dtype=float)
        if H.ndim != 3 or H.shape[1:] != (4, 4):
            raise TargetError(f"poses must be an array of shape (N, 4, 4), got shape {H.shape}")
        finite = np.isfinite(H).all(axis=(1, 2))
        if not finite.all():
            raise TargetError(f"target {int(np.nonzero(~finite)[0][0])} contains NaN or inf")
        # entries clipped where they cannot change a verdict, so that no product overflows (and warns): a
        # coordinate beyond 2 MAX_TARGET_NORM is beyond the bound either way, a rotation entry beyond 2 is no
        # rotation's either way
        P = np.minimum(np.abs(H[:, :3, 3]), 2.0 * MAX_TARGET_NORM)
        far = np.nonzero((P * P).sum(axis=1) > MAX_TARGET_NORM**2)[0]
        if far.size:
            k = int(far[0])
            raise TargetError(f"target {k}: {_beyond_text(H[k, :3, 3])}")
        bad = np.nonzero(~is_rotation(H[:, :3, :3]))[0]
        if bad.size:
            raise TargetError(f"target {int(bad[0])}: rotation is not a rotation matrix (R^T R must be I and "
                              "det R = +1 to 1e-6)")
        bottom = np.abs(H[:, 3] - [0.0, 0.0, 0.0, 1.0]).max(axis=1)
        bad = np.nonzero(bottom > 1e-9)[0]
        if bad.size:
            raise TargetError(f"target {int(bad[0])}: the bottom row of a homogeneous pose must be [0 0 0 1], "
                              f"got {H[int(bad[0]), 3].tolist()}")
        return H

    @classmethod
    def coerce_many(cls, targets) -> list[Target]:
        """Targets from a sequence of anything :meth:`coerce` accepts, or from an (N, 4, 4) array of poses
        (:meth:`from_poses`); a TargetError names the index of the first bad target."""
        if isinstance(targets, np.ndarray) and targets.ndim == 3 and targets.shape[1:] == (4, 4):
            return cls.from_poses(targets)
        out = []
        for i, t in enumerate(targets):
            try:
                out.append(cls.coerce(t))
            except TargetError as exc:
                raise TargetError(f"target {i}: {exc}") from None
        return out

    @property
    def has_orientation(self) -> bool:
        """True when the target constrains orientation (a rotation, or a planar yaw)."""
        return self.rotation is not None or self.yaw is not None

    def se3(self) -> pin.SE3:
        """The target as a ``pin.SE3`` (identity rotation for position-only targets; planar: z = 0)."""
        if self.planar:
            R = pin.rpy.rpyToMatrix(0.0, 0.0, self.yaw or 0.0)
            return pin.SE3(R, np.array([self.position[0], self.position[1], 0.0]))
        return pin.SE3(np.eye(3) if self.rotation is None else self.rotation, self.position.copy())
