"""IK targets and problems: what a solver is asked to reach, within which bounds, to which tolerance.

A solver sees only an :class:`IKProblem`: the robot, the :class:`Target`, the objective (a vectorized
cost over a population), the search box and the tolerances. ``IKProblem.evaluate`` computes the cost and
the position / orientation errors of a whole population from one forward-kinematics pass.
"""

from __future__ import annotations

import math
import os
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
from .solvers.options import check_positive

if TYPE_CHECKING:
    from .scene import Scene

__all__ = ["COLLISION_PENALTY", "DEFAULT_PRO_DELTA", "MAX_TARGET_NORM", "NEAR_UNBOUNDED", "Evaluation", "IKProblem",
           "Target", "check_pro_delta", "coerce_scene", "errors_text", "shortfall_text", "target_box"]

#: Farthest target position accepted (m from the base origin): beyond any arm's reach by orders of magnitude, and
#: low enough that squared distances (1e12 m^2) stay far from float overflow in every solver and feature space.
MAX_TARGET_NORM = 1e6

#: Added to the cost (m + rad) of a configuration in collision when a scene is given: more than any pose error
#: of a reachable arm's configuration, so a search prefers every collision-free configuration.
COLLISION_PENALTY = 10.0
#: Half-width (rad) of paper 002's "Pro" search box around the previous trajectory solution.
DEFAULT_PRO_DELTA = np.pi / 100
#: A joint whose bound reaches this far (``|lower|`` or ``|upper|`` >= 1000 m or rad) is near-unbounded: URDFs give
#: the virtual joints of mobile bases limits like +-999999 to mean "none" (limits beyond 1e10, and absent ones,
#: are already read as none by :class:`~evoik_pin.robot.Robot`). No real arm joint travels 1 km or 160 turns.
NEAR_UNBOUNDED = 1e3


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
    # math.hypot scales, so huge finite entries give their norm rather than an overflow warning (a dot product
    # would); NaN anywhere gives NaN, inf gives inf. One C call, as this runs once per solve.
    norm = math.hypot(*arr.tolist())
    if not norm <= (math.inf if bound is None else bound):
        if not np.isfinite(arr).all():
            raise TargetError(f"{name} contains NaN or inf: {arr}")
        raise TargetError(_beyond_text(arr))
    return arr


_EYE3 = np.eye(3)
_NOT_ROTATION = ("target rotation is not a rotation matrix (R^T R must be I and det R = +1 to 1e-6); "
                 "orthonormalize it or pass roll-pitch-yaw angles")


def _rotation(value) -> np.ndarray:
    try:
        R = np.asarray(value, dtype=float)
    except (TypeError, ValueError) as exc:
        raise TargetError(f"target rotation must be a 3 x 3 matrix of numbers, got {value!r}") from exc
    if R.shape != (3, 3):
        raise TargetError(f"target rotation must be a 3 x 3 matrix, got shape {R.shape}")
    v = R.reshape(9)
    # Frobenius norm sqrt(3) for a rotation; math.hypot gives it without an overflow warning for huge entries (a
    # dot product would warn), so the products below only ever see entries of a near-rotation
    if not math.hypot(*v.tolist()) <= 2.0:
        if not np.isfinite(v).all():
            raise TargetError("target rotation contains NaN or inf")
        raise TargetError(_NOT_ROTATION)
    # det R = R[0] . (R[1] x R[2]); written out, as np.linalg.det costs more than the rest of the check
    det = (R[0, 0] * (R[1, 1] * R[2, 2] - R[1, 2] * R[2, 1]) - R[0, 1] * (R[1, 0] * R[2, 2] - R[1, 2] * R[2, 0])
           + R[0, 2] * (R[1, 0] * R[2, 1] - R[1, 1] * R[2, 0]))
    D = (R.T.dot(R) - _EYE3).reshape(9)
    if D.dot(D) > 1e-12 or det < 0:  # |R^T R - I|_F <= 1e-6
        raise TargetError(_NOT_ROTATION)
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
        R = np.clip(H[:, :3, :3], -2.0, 2.0)
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


def check_pro_delta(delta) -> float:
    """The half-width (rad) of paper 002's "Pro" search box as a float > 0; OptionError otherwise."""
    return check_positive("delta (the Pro box half-width)", delta, unit="rad")


def coerce_scene(robot: Robot, scene) -> Scene | None:
    """The :class:`~evoik_pin.scene.Scene` a ``scene`` argument names: a Scene as it is, a scene file's path
    (``str`` or ``os.PathLike``; ``.yaml``, ``.yml`` or ``.json``) read by :meth:`Scene.from_file` for ``robot``,
    None as None. Every entry point's scene goes through here (the ones solving many targets once, up front).

    Raises:
        OptionError: another type. SceneError: a file that is missing or does not parse (naming the file).
    """
    from .scene import Scene

    if scene is None or isinstance(scene, Scene):
        return scene
    if isinstance(scene, (str, os.PathLike)):
        return Scene.from_file(robot, scene)
    raise OptionError(f"scene must be an evoik_pin.Scene or the path of a scene file (str or pathlib.Path; "
                      f".yaml, .yml or .json), got {type(scene).__name__}")


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
        robot: the chain to solve for.
        target: the :class:`Target` (coerced from the accepted target forms).
        objective: vectorized cost; default: position error (m) plus, for pose targets,
            ``orientation_weight`` x rotation angle (rad).
        lower, upper: (n,) search box (rad or m); default the robot's bounds, except that near-unbounded joints
            (:data:`NEAR_UNBOUNDED`) are searched within a box around the target (:func:`target_box`). Bounds
            given are used as given.
        tolerance: success threshold on the position error (m).
        rotation_tolerance: success threshold on the orientation error (rad); defaults to ``tolerance``.
        q0: optional (n,) initial / previous configuration (seeds the population; used by displacement
            objectives).
        orientation_weight: m per rad in the default pose objective.
        pose_metric: how the default pose objective combines the two errors: ``"sum"`` (position +
            weight x angle, the default) or ``"euclidean"`` (sqrt(position^2 + (weight x angle)^2),
            :class:`~evoik_pin.objectives.PoseDistance`). Ignored for position targets and custom objectives.
        scene: an optional :class:`~evoik_pin.scene.Scene` (the robot's body and obstacles), or a scene file's path
            (:func:`coerce_scene`): answers must be
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
    scene: Scene | str | os.PathLike | None = None
    margin: float = 0.0
    evaluations: int = field(default=0, compare=False)

    def __post_init__(self) -> None:
        self.target = Target.coerce(self.target)
        if self.rotation_tolerance is None:
            self.rotation_tolerance = self.tolerance
        for name in ("tolerance", "orientation_weight", "rotation_tolerance"):
            _check_nonnegative(name, getattr(self, name))
        if self.lower is None and self.upper is None:  # the robot's own bounds, checked when they were set
            self.lower, self.upper = target_box(self.robot, self.target, self.robot.lower, self.robot.upper)
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
            self.scene = coerce_scene(self.robot, self.scene)
            self.scene.check_robot(self.robot)
        if self.objective is None:
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

    def evaluate(self, Q: np.ndarray) -> Evaluation:
        """Cost and errors of a population ``Q`` (N, n), from one kinematics pass."""
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
        delta = check_pro_delta(delta)
        lower = np.clip(np.maximum(self.lower, q_prev - delta), self.lower, self.upper)
        upper = np.clip(np.minimum(self.upper, q_prev + delta), self.lower, self.upper)
        return replace(self, lower=lower, upper=upper, q0=np.clip(q_prev, lower, upper), evaluations=0)


def target_box(robot: Robot, target: Target, lower: np.ndarray, upper: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The search box (lower, upper), each (n,) in rad or m, of ``robot`` for ``target``: [lower, upper] (copies),
    with each near-unbounded joint (a bound beyond :data:`NEAR_UNBOUNDED`) narrowed to where answers lie.

    * a revolute joint: one turn, [c - pi, c + pi] (c = 0 clipped into [lower + pi, upper - pi]): every angle
      modulo 2 pi, so nothing is lost;
    * a prismatic joint whose axis no revolute joint before it turns (a mobile base's virtual x, y, z): the
      values that bring the tip to the target, ``pinv(A) (t - p_ref)`` (A: the axes of these joints (3, k) in the
      base frame, p_ref: the tip position with them at 0 and the other joints at 0 clipped into their bounds),
      +- the reach of the rest of the chain (twice the sum of its link offsets and prismatic travel, R, over A's
      smallest singular value), plus a margin of max(0.1 m, 0.1 R);
    * a prismatic joint a revolute joint turns: +- (|t| + R + margin), t the target position; when a
      near-unbounded revolute joint turns it (a base's forward motion after its yaw), only the values pointing
      it at the target, [|t| - R - margin, |t| + R + margin] (a far target is then not searched with the base
      facing away from it; give ``bounds=`` to search there).

    The result lies inside [lower, upper], so an answer inside it keeps the robot's nominal limits. Joints
    driving mimic joints keep [lower, upper].
    """
    lower, upper = np.array(lower, dtype=float), np.array(upper, dtype=float)
    far = (np.abs(lower) >= NEAR_UNBOUNDED) | (np.abs(upper) >= NEAR_UNBOUNDED)
    if not far.any():
        return lower, upper
    F_R, F_p, revolute = robot.chain_constants()
    index, scale, offset = robot.chain_coupling()
    _, _, plo, phi = robot.chain_joints()
    single = np.bincount(index, minlength=robot.n) == 1  # the entry moves one physical joint of the chain
    phys_far = far[index] & single[index]
    travel = np.where(~revolute & ~phys_far, np.maximum(np.abs(plo), np.abs(phi)), 0.0)
    reach = float(np.linalg.norm(F_p, axis=1).sum() + travel.sum())
    margin = max(0.1, 0.1 * reach)
    t = target.se3().translation
    box_lo, box_hi = lower.copy(), upper.copy()
    fixed, axes, turned, full_turn = [], [], [], {}
    R = F_R[0].copy()
    turning = spun = False
    for k in range(len(revolute)):
        if phys_far[k] and not revolute[k]:
            (turned if turning else fixed).append(k)
            full_turn[k] = spun
            if not turning:
                axes.append(R[:, 2].copy())
        turning = turning or bool(revolute[k])
        spun = spun or bool(revolute[k] and phys_far[k])
        R = R @ F_R[k + 1]  # a prismatic joint's Z(x) does not turn; after a revolute one R is no longer used
    phys_lo, phys_hi = {}, {}
    for k in np.nonzero(phys_far & revolute)[0]:
        j = index[k]
        c = float(np.clip(0.0, lower[j] + np.pi, upper[j] - np.pi))
        phys_lo[k], phys_hi[k] = scale[k] * (c - np.pi) + offset[k], scale[k] * (c + np.pi) + offset[k]
    h_turned = float(np.linalg.norm(t)) + reach + margin
    for k in turned:
        # The LM's steps are at most 1 m, so a symmetric +-|t| box leaves seeds far out of reach of a far target:
        # after a full-turn joint, search the values that put the joint's far end within reach of the target with
        # that turn pointing it there (both signs once the target is within reach of the base itself).
        near = h_turned - 2.0 * (reach + margin) if full_turn[k] else -h_turned
        phys_lo[k], phys_hi[k] = max(-h_turned, near), h_turned
    if fixed:
        A = np.array(axes).T  # (3, k)
        q_ref = np.where(far, 0.0, np.clip(0.0, lower, upper))
        p_ref = robot.fk(q_ref).translation
        sigma = max(float(np.linalg.svd(A, compute_uv=False).min()), 1e-3)
        centre = np.linalg.pinv(A) @ (t - p_ref)
        h = (2.0 * reach + len(turned) * h_turned) / sigma + margin
        for k, c in zip(fixed, centre, strict=True):
            phys_lo[k], phys_hi[k] = c - h, c + h
    for k, a in phys_lo.items():  # back from the physical joint's value to q's entry
        j = index[k]
        b = sorted(((a - offset[k]) / scale[k], (phys_hi[k] - offset[k]) / scale[k]))
        box_lo[j] = min(max(b[0], lower[j]), upper[j])
        box_hi[j] = max(min(b[1], upper[j]), box_lo[j])
    return box_lo, box_hi


# ---------------------------------------------------------------------- result messages
def errors_text(pos: float, rot: float | None) -> str:
    """'position error ... m[, orientation error ... rad]' for result messages."""
    return f"position error {pos:.3g} m" + ("" if rot is None else f", orientation error {rot:.3g} rad")


def shortfall_text(problem: IKProblem, pos: float, rot: float | None) -> str:
    """'best position error ... m[, orientation error ... rad] exceeds the tolerance (position error <= ... m[,
    orientation error <= ... rad])' for the messages of failed solves: each error and tolerance with its unit,
    the orientation's only for a target that constrains it (``rot`` not None)."""
    accepted = f"position error <= {problem.tolerance:g} m" + (
        "" if rot is None else f", orientation error <= {problem.rotation_tolerance:g} rad")
    return f"best {errors_text(pos, rot)} exceeds the tolerance ({accepted})"
