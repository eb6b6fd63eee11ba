"""Vectorized IK objectives: every cost maps a population ``Q`` (N, n) to costs (N,) in one call, its terms sharing
one forward-kinematics pass (:class:`PopulationKinematics`) and composing as weighted sums:
``PositionError(t) + 0.5 * OrientationError(t)``. Each term's docstring gives its formula and unit.
"""

from __future__ import annotations

from functools import cached_property

import numpy as np

from . import lie
from .errors import OptionError

__all__ = ["JointLimitMargin", "ManipulabilityCost", "MaxJointDisplacement", "Objective", "OrientationError",
           "PopulationKinematics", "POSE_METRICS", "PoseDistance", "PoseError", "PositionError", "RPYPoseError",
           "WeightedJointDisplacement", "default_cost", "default_objective", "orientation_errors", "position_errors"]


class PopulationKinematics:
    """Kinematics of one population, computed on first use and shared by every term of an objective: ``positions``
    (N, 3) m, ``rotations`` (N, 3, 3), ``jacobians`` (N, 6, n) in the base frame."""

    def __init__(self, robot, Q: np.ndarray) -> None:
        self.robot = robot
        self.Q = Q
        self._full = None

    @classmethod
    def from_poses(cls, robot, Q: np.ndarray, positions: np.ndarray, rotations: np.ndarray) -> PopulationKinematics:
        """Kinematics of ``Q`` (N, n) whose tip poses are already known: positions (N, 3) m, rotations
        (N, 3, 3), e.g. from a local solver's own forward kinematics, so no batch pass is repeated."""
        kin = cls(robot, Q)
        kin._full = (positions, rotations)
        return kin

    @cached_property
    def positions(self) -> np.ndarray:
        return self.robot.positions_batch(self.Q) if self._full is None else self._full[0]

    @cached_property
    def rotations(self) -> np.ndarray:
        if self._full is None:
            self._full = self.robot.fk_batch(self.Q, validate=False)
        return self._full[1]

    @cached_property
    def jacobians(self) -> np.ndarray:
        return self.robot.jacobian_batch(self.Q, validate=False)


def position_errors(target, kin: PopulationKinematics) -> np.ndarray:
    """Position error (N,) in m: Euclidean distance to the target (planar: in the xy-plane), cached on ``kin`` per
    target (``IKProblem.evaluate`` asks twice)."""
    cached = kin.__dict__.get("_position_errors")
    if cached is not None and cached[0] is target:
        return cached[1]
    d = (kin.positions[:, :2] if target.planar else kin.positions) - target.position
    err = np.sqrt((d * d).sum(axis=1))
    kin._position_errors = (target, err)
    return err


def orientation_errors(target, kin: PopulationKinematics) -> np.ndarray:
    """Orientation error (N,) in rad: rotation angle to the target (planar: |wrapped yaw difference|)."""
    if target.planar:
        return np.abs(lie.wrap_angle(lie.yaw(kin.rotations) - target.yaw))
    return lie.relative_angle(target.rotation, kin.rotations)


class Objective:
    """A vectorized cost. Subclasses implement :meth:`value`; ``+`` and scalar ``*`` build weighted sums."""

    def value(self, Q: np.ndarray, kin: PopulationKinematics) -> np.ndarray:  # pragma: no cover - abstract
        raise NotImplementedError

    def from_errors(self, target, position_error: float, orientation_error: float | None) -> float | None:
        """The cost from known errors towards ``target`` (position m, orientation rad or None) when the objective is a
        function of them alone (a local solver has them from its own kinematics); None otherwise."""
        return None

    def __call__(self, Q: np.ndarray, kin: PopulationKinematics | None = None, robot=None) -> np.ndarray:
        """Costs (N,) of ``Q`` (N, n). Pass ``kin`` to share kinematics, or ``robot`` to compute them."""
        if kin is None:
            if robot is None:
                raise OptionError("evaluate an objective with kin=PopulationKinematics(...) or robot=...")
            kin = PopulationKinematics(robot, Q)
        return self.value(Q, kin)

    def __add__(self, other: Objective) -> WeightedSum:
        if not isinstance(other, Objective):
            return NotImplemented
        return WeightedSum(self._terms() + other._terms())

    def __mul__(self, weight: float) -> WeightedSum:
        w = float(weight)
        return WeightedSum([(w * c, t) for c, t in self._terms()])

    __rmul__ = __mul__

    def _terms(self) -> list[tuple[float, Objective]]:
        return [(1.0, self)]

    def __repr__(self) -> str:
        return f"{type(self).__name__}()"


class WeightedSum(Objective):
    """``sum_i w_i f_i(Q)``; build it with ``+`` and ``*`` on objectives."""

    def __init__(self, terms: list[tuple[float, Objective]]) -> None:
        self.terms = terms

    def _terms(self) -> list[tuple[float, Objective]]:
        return list(self.terms)

    def from_errors(self, target, position_error, orientation_error):
        total = 0.0
        for w, term in self.terms:
            v = term.from_errors(target, position_error, orientation_error)
            if v is None:
                return None
            total += w * v
        return total

    def value(self, Q, kin):
        total = np.zeros(Q.shape[0])
        for w, term in self.terms:
            if w != 0.0:
                total += w * term.value(Q, kin)
        return total

    def __repr__(self) -> str:
        return " + ".join(f"{w:g}*{t!r}" for w, t in self.terms)


class PositionError(Objective):
    """Distance (m) from the tip to the target position."""

    def __init__(self, target) -> None:
        self.target = target

    def value(self, Q, kin):
        return position_errors(self.target, kin)

    def from_errors(self, target, position_error, orientation_error):
        return position_error if target is self.target else None


class OrientationError(Objective):
    """Rotation angle (rad) between the tip and the target orientation."""

    def __init__(self, target) -> None:
        if not target.has_orientation:
            raise OptionError("OrientationError needs a target with a rotation (or a planar yaw)")
        self.target = target

    def value(self, Q, kin):
        return orientation_errors(self.target, kin)

    def from_errors(self, target, position_error, orientation_error):
        return orientation_error if target is self.target and orientation_error is not None else None


def PoseError(target, position_weight: float = 1.0, orientation_weight: float = 1.0) -> Objective:  # noqa: N802
    """``position_weight`` x position error (m) + ``orientation_weight`` x rotation angle (rad)."""
    # the WeightedSum that ``position_weight * PositionError(target) + ...`` builds, made directly: the default pose
    # objective is made on every solve
    return WeightedSum([(float(position_weight), PositionError(target)),
                        (float(orientation_weight), OrientationError(target))])


class PoseDistance(Objective):
    """``sqrt(position_error^2 + (orientation_weight x rotation_angle)^2)`` (m): the Euclidean norm of the weighted
    6-D error; the zero set of :func:`PoseError` without its crease where one error is zero."""

    def __init__(self, target, orientation_weight: float = 1.0) -> None:
        if not target.has_orientation:
            raise OptionError("PoseDistance needs a target with a rotation (or a planar yaw)")
        self.target = target
        self.orientation_weight = float(orientation_weight)

    def value(self, Q, kin):
        rotation = orientation_errors(self.target, kin)
        return np.hypot(position_errors(self.target, kin), self.orientation_weight * rotation)

    def from_errors(self, target, position_error, orientation_error):
        if target is not self.target or orientation_error is None:
            return None
        return float(np.hypot(position_error, self.orientation_weight * orientation_error))

    def __repr__(self) -> str:
        return f"PoseDistance(orientation_weight={self.orientation_weight:g})"


class RPYPoseError(Objective):
    """Paper 004: ``sigma ||P_G - P_E|| + epsilon ||O_G - O_E||`` (position m, O roll-pitch-yaw rad, wrapped);
    the paper's sigma = 0.3, epsilon = 0.7 by default."""

    def __init__(self, target, sigma: float = 0.3, epsilon: float = 0.7) -> None:
        if target.rotation is None:
            raise OptionError("RPYPoseError needs a pose target (position and rotation)")
        self.target, self.sigma, self.epsilon = target, float(sigma), float(epsilon)
        self._rpy_target = lie.rpy(target.rotation)[0]

    def value(self, Q, kin):
        d_rpy = lie.wrap_angle(lie.rpy(kin.rotations) - self._rpy_target)
        pos = np.linalg.norm(kin.positions - self.target.position, axis=1)
        return self.sigma * pos + self.epsilon * np.linalg.norm(d_rpy, axis=1)

    def __repr__(self) -> str:
        return f"RPYPoseError(sigma={self.sigma:g}, epsilon={self.epsilon:g})"


class MaxJointDisplacement(Objective):
    """Paper 000's f2: ``max_k |q_k - q_init,k|`` (rad or m) from an initial configuration."""

    def __init__(self, q_init) -> None:
        self.q_init = np.asarray(q_init, dtype=float)

    def value(self, Q, kin):
        return np.abs(Q - self.q_init).max(axis=1)


class WeightedJointDisplacement(Objective):
    """``sqrt(sum_k K_k (q_k - q_prev,k)^2)`` (gains K (n,), default ones): paper 003's smoothness S, paper 002's
    ``||q - q0||``."""

    def __init__(self, q_prev, gains=None) -> None:
        self.q_prev = np.asarray(q_prev, dtype=float)
        self.gains = np.ones_like(self.q_prev) if gains is None else np.asarray(gains, dtype=float)
        if self.gains.shape != self.q_prev.shape or np.any(self.gains < 0) or not np.all(np.isfinite(self.gains)):
            raise OptionError(f"gains must be {self.q_prev.size} finite values >= 0, got {gains!r}")

    def value(self, Q, kin):
        return np.sqrt(((Q - self.q_prev) ** 2 * self.gains).sum(axis=1))

    def __repr__(self) -> str:
        return f"WeightedJointDisplacement(gains={self.gains.tolist()})"


class ManipulabilityCost(Objective):
    """Paper 003's manipulability cost of Y = sqrt(det(J J^T)), J the ``rows`` of the base-frame Jacobian (as in
    ``Robot.manipulability``): ``form="inverse"``: ``1 / (Y + 1)``; ``"negative"``: ``-Y``; ``"value"``: Y."""

    _FORMS = ("inverse", "negative", "value")

    def __init__(self, rows="translation", form: str = "inverse") -> None:
        if form not in self._FORMS:
            raise OptionError(f"manipulability form {form!r} is not one of {self._FORMS}")
        self.rows, self.form = rows, form

    def value(self, Q, kin):
        J = kin.jacobians[:, kin.robot.task_rows(self.rows)]
        Y = np.sqrt(np.maximum(np.linalg.det(J @ J.transpose(0, 2, 1)), 0.0))
        if self.form == "inverse":
            return 1.0 / (Y + 1.0)
        return -Y if self.form == "negative" else Y

    def __repr__(self) -> str:
        return f"ManipulabilityCost(rows={self.rows!r}, form={self.form!r})"


class JointLimitMargin(Objective):
    """``1 - min_k(distance of q_k to its nearer limit / half-range_k)``: 0 at mid-range, 1 at a limit."""

    def __init__(self, lower, upper) -> None:
        self.lower, self.upper = np.asarray(lower, float), np.asarray(upper, float)
        self.half = np.maximum((self.upper - self.lower) / 2, 1e-12)

    def value(self, Q, kin):
        margin = np.minimum(Q - self.lower, self.upper - Q) / self.half
        return 1.0 - margin.min(axis=1)


#: How the default objective combines position and orientation errors of a pose target: ``sum`` (m + weight x
#: rad, :func:`PoseError`) or ``euclidean`` (:class:`PoseDistance`).
POSE_METRICS = ("sum", "euclidean")


def default_cost(position_error, orientation_error, orientation_weight: float = 1.0, pose_metric: str = "sum"):
    """:func:`default_objective`'s value from the errors (scalars or arrays; ``orientation_error`` None for position
    targets), for batch solvers, which have no per-target objective object."""
    if orientation_error is None:
        return position_error
    if pose_metric == "euclidean":
        return np.hypot(position_error, orientation_weight * orientation_error)
    return position_error + orientation_weight * orientation_error


def default_objective(target, orientation_weight: float = 1.0, pose_metric: str = "sum") -> Objective:
    """Position error for position targets; for pose targets position + weight x orientation error
    (``pose_metric="sum"``) or the Euclidean norm of the two (``"euclidean"``)."""
    if pose_metric not in POSE_METRICS:
        raise OptionError(f"pose_metric {pose_metric!r} is not one of {POSE_METRICS}")
    if not target.has_orientation:
        return PositionError(target)
    if pose_metric == "euclidean":
        return PoseDistance(target, orientation_weight)
    return PoseError(target, 1.0, orientation_weight)
