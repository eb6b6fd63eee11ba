"""IK targets and problems: what a solver is asked to reach, within which bounds, to which tolerance.

A solver sees only an :class:`IKProblem`: the robot, the :class:`Target`, the objective (a vectorized
cost over a population), the search box and the tolerances. ``IKProblem.evaluate`` computes the cost and
the position / orientation errors of a whole population from one forward-kinematics pass.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace
from typing import TYPE_CHECKING

import numpy as np
import pinocchio as pin

from .errors import BoundsError, ConfigurationError, OptionError, TargetError
from .objectives import (
    POSE_METRICS,
    Objective,
    PopulationKinematics,
    PositionError,
    default_objective,
    orientation_errors,
    position_errors,
)
from .robot import Robot

if TYPE_CHECKING:
    from .scene import Scene

__all__ = ["COLLISION_PENALTY", "DEFAULT_PRO_DELTA", "Evaluation", "IKProblem", "Target"]

#: Added to the cost (m + rad) of a configuration in collision when a scene is given: more than any pose error
#: of a reachable arm's configuration, so a search prefers every collision-free configuration.
COLLISION_PENALTY = 10.0
#: Half-width (rad) of paper 002's "Pro" search box around the previous trajectory solution.
DEFAULT_PRO_DELTA = np.pi / 100


def _vector(value, name: str, sizes: tuple[int, ...]) -> np.ndarray:
    try:
        arr = np.asarray(value, dtype=float)
    except (TypeError, ValueError) as exc:
        raise TargetError(f"{name} must be numbers, got {value!r}") from exc
    if arr.ndim != 1 or arr.shape[0] not in sizes:
        raise TargetError(f"{name} must have {' or '.join(map(str, sizes))} entries, got shape {arr.shape}")
    if not math.isfinite(arr.dot(arr)):  # NaN or inf anywhere; one C call, as this runs once per solve
        raise TargetError(f"{name} contains NaN or inf: {arr}")
    return arr


_EYE3 = np.eye(3)


def _rotation(value) -> np.ndarray:
    try:
        R = np.asarray(value, dtype=float)
    except (TypeError, ValueError) as exc:
        raise TargetError(f"target rotation must be a 3 x 3 matrix of numbers, got {value!r}") from exc
    if R.shape != (3, 3):
        raise TargetError(f"target rotation must be a 3 x 3 matrix, got shape {R.shape}")
    v = R.reshape(9)
    if not math.isfinite(v.dot(v)):
        raise TargetError("target rotation contains NaN or inf")
    # det R = R[0] . (R[1] x R[2]); written out, as np.linalg.det costs more than the rest of the check
    det = (R[0, 0] * (R[1, 1] * R[2, 2] - R[1, 2] * R[2, 1]) - R[0, 1] * (R[1, 0] * R[2, 2] - R[1, 2] * R[2, 0])
           + R[0, 2] * (R[1, 0] * R[2, 1] - R[1, 1] * R[2, 0]))
    D = (R.T.dot(R) - _EYE3).reshape(9)
    if D.dot(D) > 1e-12 or det < 0:  # |R^T R - I|_F <= 1e-6
        raise TargetError(
            "target rotation is not a rotation matrix (R^T R must be I and det R = +1 to 1e-6); "
            "orthonormalize it or pass roll-pitch-yaw angles"
        )
    return R


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
        pos = _vector(self.position, "target position", (2,) if self.planar else (3,))
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
            return cls(position=np.array(target.translation), rotation=np.array(target.rotation))
        try:
            arr = np.asarray(target, dtype=float)
        except (TypeError, ValueError) as exc:
            raise TargetError(
                f"target must be a 3-vector position (m), a pin.SE3, a 4 x 4 homogeneous matrix or a Target; "
                f"got {target!r}"
            ) from exc
        if arr.shape == (4, 4):
            if np.isfinite(arr[3]).all() and np.abs(arr[3] - [0.0, 0.0, 0.0, 1.0]).max() > 1e-9:
                raise TargetError(f"the bottom row of a 4 x 4 homogeneous pose must be [0 0 0 1], got "
                                  f"{arr[3].tolist()}")
            return cls(position=arr[:3, 3], rotation=arr[:3, :3])
        if arr.ndim == 1 and arr.shape[0] == 3:
            return cls(position=arr)
        raise TargetError(
            f"target must be a 3-vector position (m), a pin.SE3, a 4 x 4 homogeneous matrix or a Target "
            f"(Target.planar_target(x, y, yaw) for planar arms); got an array of shape {arr.shape}"
        )

    @classmethod
    def from_poses(cls, poses) -> list[Target]:
        """Pose targets from an array of N homogeneous matrices (N, 4, 4) (m), checked in one vectorized pass
        (:meth:`check_poses`)."""
        H = cls.check_poses(poses)
        out = []
        for T in H:  # already checked: skip the per-instance validation of __post_init__
            t = object.__new__(cls)
            object.__setattr__(t, "position", T[:3, 3].copy())
            object.__setattr__(t, "rotation", T[:3, :3].copy())
            object.__setattr__(t, "planar", False)
            object.__setattr__(t, "yaw", None)
            out.append(t)
        return out

    @staticmethod
    def check_poses(poses) -> np.ndarray:
        """``poses`` as a float (N, 4, 4) array of homogeneous matrices (m), checked in one vectorized pass: finite
        numbers, rotation blocks orthonormal with det +1 (to 1e-6), bottom rows [0 0 0 1]. A TargetError names the
        first bad target's index."""
        H = np.asarray(poses, dtype=float)
        if H.ndim != 3 or H.shape[1:] != (4, 4):
            raise TargetError(f"poses must be an array of shape (N, 4, 4), got shape {H.shape}")
        finite = np.isfinite(H).all(axis=(1, 2))
        if not finite.all():
            raise TargetError(f"target {int(np.nonzero(~finite)[0][0])} contains NaN or inf")
        R = H[:, :3, :3]
        ortho = np.abs(R.transpose(0, 2, 1) @ R - np.eye(3)).max(axis=(1, 2))
        bad = np.nonzero((ortho > 1e-6) | (np.linalg.det(R) < 0))[0]
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


@dataclass(frozen=True)
class Evaluation:
    """Cost and errors of a population (each (N,)); ``orientation_error`` is None for position targets."""

    cost: np.ndarray
    position_error: np.ndarray
    orientation_error: np.ndarray | None


def _check_nonnegative(name: str, value) -> None:
    """OptionError unless ``value`` is a finite number >= 0 (math.isfinite: this runs on every solve)."""
    try:
        ok = math.isfinite(value) and value >= 0
    except TypeError:
        ok = False
    if not ok:
        raise OptionError(f"{name} must be a finite number >= 0, got {value!r}")


@dataclass
class IKProblem:
    """Robot + target + objective + search box + tolerances: everything a solver sees.

    Attributes:
        robot: the robot to solve for.
        target: the :class:`Target` (coerced from the accepted target forms) of the robot's tip; None for a goal
            list.
        goals: a list of goals on frames of the robot (:mod:`evoik_pin.goals`: ``Pose``, ``Position``), each with
            its weight and tolerances, instead of one target (pass the list as ``target`` or as ``goals``); checked
            against the robot (:func:`evoik_pin.goals.bind`). Its cost is the weighted sum over the goals of
            position error + ``orientation_weight`` x rotation angle; its errors the largest over the goals.
        objective: vectorized cost; default: position error (m) plus, for pose targets,
            ``orientation_weight`` x rotation angle (rad).
        lower, upper: (n,) search box (rad or m); default the robot's bounds.
        tolerance: success threshold on the position error (m).
        rotation_tolerance: success threshold on the orientation error (rad); defaults to ``tolerance``.
        q0: optional (n,) initial / previous configuration (seeds the population; used by displacement
            objectives).
        orientation_weight: m per rad in the default pose objective.
        pose_metric: how the default pose objective combines the two errors: ``"sum"`` (position +
            weight x angle, the default) or ``"euclidean"`` (sqrt(position^2 + (weight x angle)^2),
            :class:`~evoik_pin.objectives.PoseDistance`). Ignored for position targets and custom objectives.
        scene: an optional :class:`~evoik_pin.scene.Scene` (the robot's body and obstacles): answers must be
            collision-free; :meth:`evaluate` and :meth:`cost` add ``COLLISION_PENALTY`` to the cost of
            configurations whose convex-hull proxies collide (steering every evolutionary method); the exact
            mesh check judges every answer (:mod:`evoik_pin.solvers.collision_verdict`).
        margin: clearance (m) an answer must keep from collisions (pairs closer than it count as colliding).
        evaluations: number of configurations evaluated so far (every call of :meth:`evaluate` adds N).
    """

    robot: Robot
    target: Target
    objective: Objective | None = None
    lower: np.ndarray | None = None
    upper: np.ndarray | None = None
    tolerance: float = 1e-6
    rotation_tolerance: float | None = None
    q0: np.ndarray | None = None
    orientation_weight: float = 1.0
    pose_metric: str = "sum"
    scene: Scene | None = None
    margin: float = 0.0
    goals: list | None = None
    evaluations: int = field(default=0, compare=False)

    def __post_init__(self) -> None:
        if self.goals is None and is_goal_list(self.target):
            self.goals = self.target
        if self.goals is not None:
            if self.objective is not None:
                raise OptionError("a goal list has its own cost (the goals' weighted errors); give no objective")
            self.target = None
            self.goals, *self._goal_stack = bind(self.robot, self.goals)
        else:
            self.target = Target.coerce(self.target)
        if self.rotation_tolerance is None:
            self.rotation_tolerance = self.tolerance
        for name in ("tolerance", "orientation_weight", "rotation_tolerance"):
            _check_nonnegative(name, getattr(self, name))
        if self.lower is None and self.upper is None:  # the robot's own bounds, checked when they were set
            self.lower, self.upper = self.robot.lower.copy(), self.robot.upper.copy()
        else:
            lower = self.robot.lower if self.lower is None else np.asarray(self.lower, dtype=float)
            upper = self.robot.upper if self.upper is None else np.asarray(self.upper, dtype=float)
            self.lower, self.upper = self._checked_bounds(lower, upper)
        if self.q0 is not None:
            try:
                self.q0 = self.robot.check_q(self.q0)
            except ConfigurationError as exc:
                raise ConfigurationError(f"q0: {exc}") from None
        _check_nonnegative("margin (m)", self.margin)
        if self.scene is not None:
            from .scene import Scene

            if not isinstance(self.scene, Scene):
                raise OptionError(f"scene must be an evoik_pin.Scene, got {type(self.scene).__name__}")
            self.scene.check_robot(self.robot)
        if self.goals is not None:
            if self.pose_metric not in POSE_METRICS:
                raise OptionError(f"pose_metric {self.pose_metric!r} is not one of {POSE_METRICS}")
        elif self.objective is None:
            self.objective = default_objective(self.target, self.orientation_weight, self.pose_metric)
        elif self.pose_metric not in POSE_METRICS:
            raise OptionError(f"pose_metric {self.pose_metric!r} is not one of {POSE_METRICS}")

    def _checked_bounds(self, lower: np.ndarray, upper: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        n = self.robot.n
        lower, upper = lower.reshape(-1), upper.reshape(-1)
        if lower.shape != (n,) or upper.shape != (n,):
            raise BoundsError(f"bounds need {n} values each (one per joint), got {lower.size} and {upper.size}")
        if not (np.isfinite(lower).all() and np.isfinite(upper).all()):
            raise BoundsError("bounds must be finite numbers (rad or m); got NaN or inf")
        if (lower > upper).any():
            k = int(np.nonzero(lower > upper)[0][0])
            raise BoundsError(f"inverted bounds for joint {self.robot.joint_names[k]!r}: {lower[k]} > {upper[k]}")
        return lower.copy(), upper.copy()

    @property
    def n(self) -> int:
        """Number of joints."""
        return self.robot.n

    # ------------------------------------------------------------------ goal lists
    def goal_stack(self):
        """(the LM kernel's :class:`~evoik_pin.solvers.lm.layout.GoalStack`, targets pt (G, 3), Rt (G, 3, 3)) of a goal
        list."""
        return tuple(self._goal_stack)

    def _goal_population_errors(self, Q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(position errors (N, G) m, rotation angles (N, G) rad, 0 for goals without orientation) of ``Q``."""
        from .lie import relative_angle

        P, R = self.robot.fk_batch(Q, validate=False, frames=[g.frame for g in self.goals])
        _, pt, Rt = self._goal_stack
        d = P - pt
        pos = np.sqrt((d * d).sum(axis=2))
        rot = np.zeros_like(pos)
        for g, goal in enumerate(self.goals):
            if goal.has_orientation:
                rot[:, g] = relative_angle(Rt[g], R[:, g])
        return pos, rot

    def _goal_cost(self, pos: np.ndarray, rot: np.ndarray) -> np.ndarray:
        """The goals' cost (N,) from their errors (N, G): the weighted sum of position + orientation_weight x angle."""
        w = np.array([g.weight for g in self.goals])
        return (pos + self.orientation_weight * rot) @ w

    def goal_errors(self, q: np.ndarray) -> list[tuple[float, float | None]]:
        """Each goal's (position error m, rotation angle rad or None) at ``q`` (n,), in the goals' order."""
        fids = [self.robot.frame_id(g.frame) for g in self.goals]
        poses = self.robot.frame_poses_unchecked(np.asarray(q, dtype=float), fids)
        return [g.errors(T) for g, T in zip(self.goals, poses, strict=True)]

    def goals_met(self, errors) -> bool:
        """Whether every goal's errors (:meth:`goal_errors`) are within its tolerances."""
        return all(g.met(p, r) for g, (p, r) in zip(self.goals, errors, strict=True))

    def evaluate(self, Q: np.ndarray) -> Evaluation:
        """Cost and errors of a population ``Q`` (N, n), from one kinematics pass (a goal list: the largest errors
        over the goals)."""
        if self.goals is not None:
            pos, rot = self._goal_population_errors(Q)
            self.evaluations += Q.shape[0]
            oriented = any(g.has_orientation for g in self.goals)
            return Evaluation(self._penalized(Q, self._goal_cost(pos, rot)), pos.max(axis=1),
                              rot.max(axis=1) if oriented else None)
        target = self.target
        if type(self.objective) is PositionError and self.objective.target is target and not target.planar:
            # the default position-only objective, in the solvers' inner loop: skip the generic machinery
            d = self.robot.positions_batch(Q) - target.position
            err = np.sqrt((d * d).sum(axis=1))
            self.evaluations += Q.shape[0]
            return Evaluation(self._penalized(Q, err), err, None)
        kin = PopulationKinematics(self.robot, Q)
        self.evaluations += Q.shape[0]
        cost = self._penalized(Q, self.objective(Q, kin))
        pos = position_errors(self.target, kin)
        rot = orientation_errors(self.target, kin) if self.target.has_orientation else None
        return Evaluation(cost, pos, rot)

    def cost(self, Q: np.ndarray) -> np.ndarray:
        """Objective values (N,) of a population ``Q`` (N, n)."""
        if self.goals is not None:
            return self.evaluate(Q).cost
        kin = PopulationKinematics(self.robot, Q)
        self.evaluations += Q.shape[0]
        return self._penalized(Q, self.objective(Q, kin))

    def _penalized(self, Q: np.ndarray, cost: np.ndarray) -> np.ndarray:
        """``cost`` plus COLLISION_PENALTY where the scene's convex-hull proxies collide (no scene: ``cost``)."""
        if self.scene is None:
            return cost
        return cost + COLLISION_PENALTY * self.scene.collides(Q, self.margin, proxy=True)

    def assess(self, q: np.ndarray, position_error: float | None = None, orientation_error: float | None = None
               ) -> tuple[float, float | None, float]:
        """(position error m, orientation error rad or None, objective cost) of one configuration ``q`` (n,).

        Pass the errors when a local solver already has them at this very ``q`` (from its own kinematics):
        they are reused, and so is the cost when the objective is a function of the errors alone
        (:meth:`Objective.from_errors`); otherwise one forward-kinematics call fills the kinematics the
        objective reads (no batch pass).
        """
        if self.goals is not None:
            errors = self.goal_errors(q)
            pos = np.array([[p for p, _ in errors]])
            rot = np.array([[r or 0.0 for _, r in errors]])
            rots = [r for _, r in errors if r is not None]
            return float(pos.max()), (max(rots) if rots else None), float(self._goal_cost(pos, rot)[0])
        target = self.target
        if position_error is not None:
            cost = self.objective.from_errors(target, position_error, orientation_error)
            if cost is not None:
                return position_error, orientation_error, float(cost)
        T = self.robot.fk_unchecked(q)
        Q = q[None]
        kin = PopulationKinematics.from_poses(self.robot, Q, np.array(T.translation)[None], np.array(T.rotation)[None])
        if position_error is None:
            position_error = float(position_errors(target, kin)[0])
            orientation_error = float(orientation_errors(target, kin)[0]) if target.has_orientation else None
        return position_error, orientation_error, float(self.objective(Q, kin)[0])

    def succeeded(self, position_error, orientation_error=None) -> np.ndarray:
        """Elementwise success: position error <= tolerance and orientation error <= rotation_tolerance."""
        ok = np.asarray(position_error) <= self.tolerance
        if orientation_error is not None:
            ok = ok & (np.asarray(orientation_error) <= self.rotation_tolerance)
        return ok

    def with_pro_box(self, q_prev, delta: float = DEFAULT_PRO_DELTA) -> IKProblem:
        """Paper 002's "Pro" problem: the search box is ``q_prev +- delta`` intersected with the bounds."""
        q_prev = self.robot.check_q(q_prev)
        if not (np.isfinite(delta) and delta > 0):
            raise OptionError(f"Pro box half-width delta must be > 0 rad, got {delta!r}")
        lower = np.clip(np.maximum(self.lower, q_prev - delta), self.lower, self.upper)
        upper = np.clip(np.minimum(self.upper, q_prev + delta), self.lower, self.upper)
        return replace(self, lower=lower, upper=upper, q0=np.clip(q_prev, lower, upper), evaluations=0)


# Imported last: goals reads the LM engine's layout, whose package imports this module (for IKProblem, Target).
from .goals import bind, is_goal_list  # noqa: E402
