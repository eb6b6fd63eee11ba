"""Goals of an IK problem on a whole robot: which frame goes where, with which weight and tolerances.

A problem is a list of goals, each on one frame of the robot (any Pinocchio frame: a link, a joint frame, a fixed
frame), with its target expressed in the robot's base frame (for a floating base: the world frame)::

    from evoik_pin.goals import Pose, Position
    goals = [Pose("left_sole_link", T_lf), Pose("right_sole_link", T_rf), Position("arm_right_7_link", p_rh)]
    result = evoik_pin.solve(talos, goals)

* :class:`Pose`: position and orientation (6 residual rows: the SE(3) logarithm of the frame seen from the
  target, m and rad); its target a (4, 4) homogeneous matrix, a ``pin.SE3`` or a :class:`~evoik_pin.problem.Target`
  with a rotation;
* :class:`Position`: position only (3 rows, m); its target a 3-vector (m).

Each goal checks its inputs when made (an :mod:`evoik_pin.errors` class naming what is wrong) and packs itself into
the LM kernel's goal stack (:class:`~evoik_pin.solvers.lm.layout.GoalStack`: kind, frame, weight, tolerances);
:func:`bind` checks a goal list against a robot (frames that exist and that some active joint moves, the same frame
twice with clashing targets). A goal's ``weight`` (> 0) scales its rows by ``sqrt(weight)``, so goals that cannot
all be met settle on the compromise the weights make; it is met when its position error is within ``tolerance``
(m) and, for a pose, its rotation angle within ``rotation_tolerance`` (rad; default: ``tolerance``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
import pinocchio as pin

from .errors import FrameError, OptionError, TargetError
from .solvers.lm.layout import KIND_POSE, KIND_POSITION, GoalStack
from .target import Target

__all__ = ["DEFAULT_GOAL_TOLERANCE", "Goal", "Pose", "Position", "bind", "is_goal_list"]

#: Default tolerance of a goal: 1e-6 m (and rad for a pose's rotation).
DEFAULT_GOAL_TOLERANCE = 1e-6
#: Two goals on one frame clash when their target positions (m) or rotations (Frobenius norm) differ by more.
_CLASH = 1e-9


def _number(value, what: str, accepted: str) -> float:
    """``value`` as a finite float, or an OptionError naming ``what`` and what is ``accepted``."""
    try:
        x = float(value)
    except (TypeError, ValueError):
        raise OptionError(f"{what} must be {accepted}, got {value!r}") from None
    if not math.isfinite(x):
        raise OptionError(f"{what} must be {accepted}, got {value!r}")
    return x


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

    def _init_common(self, frame, weight, tolerance, rotation_tolerance, kind: int, oriented: bool) -> None:
        """Set and check the fields every goal has (a frozen dataclass's fields, hence object.__setattr__)."""
        for name, value in (("frame", frame), ("weight", weight), ("tolerance", tolerance),
                            ("rotation_tolerance", rotation_tolerance), ("kind", kind), ("has_orientation", oriented)):
            object.__setattr__(self, name, value)
        self._check_common()

    def _check_common(self) -> None:
        if not isinstance(self.frame, str) or not self.frame:
            raise FrameError(f"a goal's frame is a frame name (a non-empty string), got {self.frame!r}")
        weight = _number(self.weight, f"weight of the goal on {self.frame!r}", "a finite number > 0")
        if weight <= 0:
            raise OptionError(f"weight of the goal on {self.frame!r} must be > 0, got {self.weight!r}")
        tol = _number(self.tolerance, f"tolerance (m) of the goal on {self.frame!r}", "a finite number >= 0")
        rtol = tol if self.rotation_tolerance is None else _number(
            self.rotation_tolerance, f"rotation_tolerance (rad) of the goal on {self.frame!r}", "a finite number >= 0")
        if tol < 0 or rtol < 0:
            raise OptionError(f"tolerances of the goal on {self.frame!r} must be >= 0, got {self.tolerance!r} m and "
                              f"{self.rotation_tolerance!r} rad")
        object.__setattr__(self, "weight", weight)
        object.__setattr__(self, "tolerance", tol)
        object.__setattr__(self, "rotation_tolerance", rtol)

    def encode(self) -> tuple[np.ndarray, np.ndarray]:  # pragma: no cover - abstract
        """The kernel's target ``(pt (3,), Rt (3, 3))`` of this goal."""
        raise NotImplementedError

    def errors(self, T: pin.SE3) -> tuple[float, float | None]:
        """(position error m, rotation angle rad or None) of the goal frame at pose ``T`` (base frame)."""
        pt, Rt = self.encode()
        pos = float(np.linalg.norm(T.translation - pt))
        if not self.has_orientation:
            return pos, None
        return pos, float(np.linalg.norm(pin.log3(Rt.T @ T.rotation)))

    def met(self, position_error: float, orientation_error: float | None) -> bool:
        """Whether errors (m, rad or None) are within this goal's tolerances."""
        return position_error <= self.tolerance and (orientation_error is None
                                                     or orientation_error <= self.rotation_tolerance)


@dataclass(frozen=True, eq=False, repr=False)
class Pose(Goal):
    """The frame's position and orientation at ``target``: a (4, 4) homogeneous matrix, a ``pin.SE3`` or a
    :class:`~evoik_pin.problem.Target` with a rotation, in the robot's base frame (m).

    Args: frame, target, then ``weight`` (> 0, default 1), ``tolerance`` (m, default 1e-6) and
    ``rotation_tolerance`` (rad, default ``tolerance``).
    """

    target: object = None
    weight: float = 1.0
    tolerance: float = DEFAULT_GOAL_TOLERANCE
    rotation_tolerance: float | None = None

    def __init__(self, frame: str, target, weight: float = 1.0, tolerance: float = DEFAULT_GOAL_TOLERANCE,
                 rotation_tolerance: float | None = None) -> None:
        self._init_common(frame, weight, tolerance, rotation_tolerance, KIND_POSE, True)
        if isinstance(target, (list, tuple)) and len(target) == 3 or np.ndim(target) == 1:
            raise TargetError(f"Pose on {frame!r}: a 3-vector is a position; use Position({frame!r}, p) or give a "
                              "4 x 4 pose or a pin.SE3")
        try:
            t = Target.coerce(target)
        except TargetError as exc:
            raise TargetError(f"Pose on {frame!r}: {exc}") from None
        if t.rotation is None or t.planar:
            raise TargetError(f"Pose on {frame!r} needs a target with a rotation (4 x 4 pose or pin.SE3); use "
                              f"Position({frame!r}, p) for a position alone")
        object.__setattr__(self, "target", pin.SE3(np.array(t.rotation), np.array(t.position)))

    def encode(self) -> tuple[np.ndarray, np.ndarray]:
        return np.array(self.target.translation), np.array(self.target.rotation)

    def __repr__(self) -> str:
        p = np.round(self.target.translation, 6).tolist()
        rpy = np.round(pin.rpy.matrixToRpy(self.target.rotation), 6).tolist()
        return (f"Pose({self.frame!r}, position={p}, rpy={rpy}, weight={self.weight:g}, tolerance={self.tolerance:g}, "
                f"rotation_tolerance={self.rotation_tolerance:g})")


@dataclass(frozen=True, eq=False, repr=False)
class Position(Goal):
    """The frame's origin at ``target``, a 3-vector (m) in the robot's base frame; orientation free.

    Args: frame, target, then ``weight`` (> 0, default 1) and ``tolerance`` (m, default 1e-6).
    """

    target: object = None
    weight: float = 1.0
    tolerance: float = DEFAULT_GOAL_TOLERANCE
    rotation_tolerance: float | None = None

    def __init__(self, frame: str, target, weight: float = 1.0, tolerance: float = DEFAULT_GOAL_TOLERANCE) -> None:
        self._init_common(frame, weight, tolerance, None, KIND_POSITION, False)
        if isinstance(target, pin.SE3) or np.shape(target) == (4, 4):
            raise TargetError(f"Position on {frame!r} takes a 3-vector (m); use Pose({frame!r}, T) for a pose")
        try:
            p = np.asarray(target, dtype=float)
        except (TypeError, ValueError):
            raise TargetError(f"Position on {frame!r} takes a 3-vector (m), got {target!r}") from None
        if p.shape != (3,):
            raise TargetError(f"Position on {frame!r} takes a 3-vector (m), got shape {p.shape}")
        if not np.isfinite(p).all():
            raise TargetError(f"Position on {frame!r}: target contains NaN or inf: {p}")
        object.__setattr__(self, "target", p.copy())

    def encode(self) -> tuple[np.ndarray, np.ndarray]:
        return self.target.copy(), np.eye(3)

    def __repr__(self) -> str:
        return (f"Position({self.frame!r}, {np.round(self.target, 6).tolist()}, weight={self.weight:g}, "
                f"tolerance={self.tolerance:g})")


def is_goal_list(value) -> bool:
    """True for a list or tuple of goals (an empty one too: :func:`bind` refuses it by name)."""
    return isinstance(value, (list, tuple)) and all(isinstance(g, Goal) for g in value)


def bind(robot, goals) -> tuple[list[Goal], GoalStack, np.ndarray, np.ndarray]:
    """Check ``goals`` against ``robot`` and pack them for the LM kernel: (the goals as a list, their
    :class:`~evoik_pin.solvers.lm.layout.GoalStack`, targets pt (G, 3), Rt (G, 3, 3)).

    Raises: TargetError for an empty list, a member that is no goal, or one frame given clashing targets;
    FrameError for an unknown frame (with the closest names) or a frame no active joint moves.
    """
    goals = list(goals)
    if not goals:
        raise TargetError("the goal list is empty: give at least one goal (Pose(frame, T), Position(frame, p))")
    for i, g in enumerate(goals):
        if not isinstance(g, Goal):
            raise TargetError(f"goal {i} is a {type(g).__name__}, not a goal: use Pose(frame, T) or "
                              "Position(frame, p) from evoik_pin.goals")
    seen: dict[int, Goal] = {}
    for g in goals:
        fid = robot.frame_id(g.frame)  # FrameError with the closest names
        if not robot.moving_joints(g.frame):
            raise FrameError(f"no active joint of {robot.name} moves frame {g.frame!r}: load the robot with that frame "
                             f"among its tips (tips=[...]) or with tips='all', or aim at another frame")
        other = seen.get(fid)
        if other is not None:
            pa, Ra = other.encode()
            pb, Rb = g.encode()
            clash = np.linalg.norm(pa - pb) > _CLASH
            if other.has_orientation and g.has_orientation:
                clash = clash or np.linalg.norm(Ra - Rb) > _CLASH
            if clash:
                raise TargetError(f"frame {g.frame!r} has two goals with different targets ({pa.round(6).tolist()} and "
                                  f"{pb.round(6).tolist()}): give each frame one target")
        seen[fid] = g
    stack = GoalStack.of(robot, [g.frame for g in goals], [g.kind for g in goals], [g.weight for g in goals],
                         [g.tolerance for g in goals], [g.rotation_tolerance for g in goals])
    encoded = [g.encode() for g in goals]
    pt = np.ascontiguousarray([e[0] for e in encoded], dtype=float)
    Rt = np.ascontiguousarray([e[1] for e in encoded], dtype=float)
    return goals, stack, pt, Rt
