"""The base of every goal kind: the frame it is on, its weight and tolerances, checked when the goal is made
(see :mod:`evoik_pin.goals`); goal sets; and what the kinds on two frames share (their checks, ``aux`` row and
placements over a population: :func:`check_frame_pair`, :func:`pack_frame_pair`, :func:`pair_placements`).

Goal sets: one goal whose target is any one of several (``Pose(frame, [T1, ..., Tk])``,
``Position(frame, [p1, ..., pk])``), the grasps a planner offers of which any will do.

A goal set is a goal like the others (its frame, weight and tolerances), packed for the kernel with its first
member's target; its ``alternatives`` hold one single-target goal per member, in the order given. Solvers try the
members (:meth:`evoik_pin.problem.IKProblem.variants`); ``Result.chosen[i]`` is the index of the member goal ``i``
meets.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
import pinocchio as pin

from ..errors import FrameError, OptionError, TargetError
from .bands import AUX_SIZE, AXES, band_aux, band_errors, parse_pose_axes
from .registry import register

__all__ = ["A_REL_BAND", "A_REL_JOINT", "A_REL_P", "A_REL_R", "A_REL_SIGNS", "BOTH", "DEFAULT_GOAL_TOLERANCE", "Goal",
           "FramePair", "check_frame_pair", "init_set", "is_set", "number", "pack_frame_pair", "pair_placements",
           "point3"]

#: Default tolerance of a goal: 1e-6 m (and rad for a pose's rotation).
DEFAULT_GOAL_TOLERANCE = 1e-6


def number(value, what: str, accepted: str) -> float:
    """``value`` as a finite float, or an OptionError naming ``what`` and what is ``accepted``."""
    try:
        x = float(value)
    except (TypeError, ValueError):
        raise OptionError(f"{what} must be {accepted}, got {value!r}") from None
    if not math.isfinite(x):
        raise OptionError(f"{what} must be {accepted}, got {value!r}")
    return x



def point3(value, what: str) -> np.ndarray:
    """``value`` as 3 finite numbers (m), or a TargetError naming ``what``."""
    try:
        p = np.array(value, dtype=float)
    except (TypeError, ValueError):
        raise TargetError(f"{what} must be 3 finite numbers (m) (a 3-vector), got {value!r}") from None
    if p.shape != (3,) or not np.isfinite(p).all():
        raise TargetError(f"{what} must be 3 finite numbers (m) (a 3-vector), got {value!r}")
    return p

@dataclass(frozen=True, eq=False)
class Goal:
    """A goal on one frame (abstract: :class:`Pose`, :class:`Position`). See the module docstring.

    A kind (a subclass) declares what the solvers need of it: ``KIND_CODES``, its kernel codes
    (:class:`.registry.KindCode`: rows, compiled family, orientation, position, angle; registered when the class is
    made), :meth:`population_errors` (its violation over a population, NumPy), :meth:`file_kind` (its entry in
    goals files) and :meth:`marker` (its viewer marker)."""

    #: The kind's kernel codes (:class:`.registry.KindCode`); a class attribute, registered by __init_subclass__.
    KIND_CODES = ()

    def __init_subclass__(cls, **kwargs) -> None:
        super().__init_subclass__(**kwargs)
        if "KIND_CODES" in cls.__dict__:
            register(cls, *cls.KIND_CODES)

    frame: str
    weight: float = 1.0
    tolerance: float = DEFAULT_GOAL_TOLERANCE
    rotation_tolerance: float | None = None
    #: The LM kernel's goal kind (``KIND_*``), and whether the goal constrains orientation.
    kind: int = field(default=-1, init=False, repr=False)
    has_orientation: bool = field(default=False, init=False, repr=False)
    #: A goal set's members (:func:`init_set`): one single-target goal each; None for one target.
    alternatives: tuple | None = field(default=None, init=False, repr=False)

    def _init_common(self, frame, weight, tolerance, rotation_tolerance, kind: int, oriented: bool) -> None:
        """Set and check the fields every goal has (a frozen dataclass's fields, hence object.__setattr__)."""
        for name, value in (("frame", frame), ("weight", weight), ("tolerance", tolerance),
                            ("rotation_tolerance", rotation_tolerance), ("kind", kind), ("has_orientation", oriented)):
            object.__setattr__(self, name, value)
        self._check_common()

    def _init_pose_axes(self, frame, weight, tolerance, rotation_tolerance, free, kinds: tuple[int, int],
                        where: str) -> None:
        """Set and check the fields of a pose-like goal (:class:`Pose`, :class:`RelativePose`): those of
        :meth:`_init_common`, its ``band`` and ``free`` (:func:`.bands.parse_pose_axes`; ``where`` names the goal in
        the messages) and its aux row; kind ``kinds[0]`` under a norm tolerance with no free axis, else
        ``kinds[1]``, whose errors under bands are their excess over them (tolerances 0)."""
        band, free = parse_pose_axes(tolerance, rotation_tolerance, free, where)
        plain = band is None and not free
        if band is None:
            self._init_common(frame, weight, tolerance, rotation_tolerance, kinds[0] if plain else kinds[1], True)
        else:  # the errors of a banded goal are its excess over the bands: met at 0
            self._init_common(frame, weight, 0.0, 0.0, kinds[1], True)
        object.__setattr__(self, "band", band)
        object.__setattr__(self, "free", free)
        self._set_aux(None if plain else band_aux(band, free, AXES, DEFAULT_GOAL_TOLERANCE))

    def _check_common(self) -> None:
        if not isinstance(self.frame, str) or not self.frame:
            raise FrameError(f"a goal's frame is a frame name (a non-empty string), got {self.frame!r}")
        self._check_numbers(f"the goal on {self.frame!r}")

    def _check_numbers(self, what: str) -> None:
        """Check and set weight and tolerances; ``what`` names the goal in the messages."""
        weight = number(self.weight, f"weight of {what}", "a finite number > 0")
        if weight <= 0:
            raise OptionError(f"weight of {what} must be > 0, got {self.weight!r}")
        tol = DEFAULT_GOAL_TOLERANCE if self.tolerance is None else number(  # None: the default
            self.tolerance, f"tolerance (m) of {what}", "a finite number >= 0")
        rtol = tol if self.rotation_tolerance is None else number(
            self.rotation_tolerance, f"rotation_tolerance (rad) of {what}", "a finite number >= 0")
        if tol < 0 or rtol < 0:
            raise OptionError(f"tolerances of {what} must be >= 0, got {self.tolerance!r} m and "
                              f"{self.rotation_tolerance!r} rad")
        object.__setattr__(self, "weight", weight)
        object.__setattr__(self, "tolerance", tol)
        object.__setattr__(self, "rotation_tolerance", rtol)

    @property
    def label(self) -> str:
        """How messages name this goal: its frame (goals beyond one frame say more)."""
        return self.frame
    #: Whether the goal puts the frame's origin somewhere (False for orientation and pointing goals: their target
    #: position pt is no place for the frame, and seed ranking leaves it out). A class attribute, not a field.
    has_position = True

    def aux(self) -> np.ndarray | None:
        """The kernel's ``aux`` row of this goal (its kind's layout, e.g. :mod:`.bands`' ``AUX_*``, read-only; None:
        its kind reads none), made once with the goal (:meth:`_set_aux`)."""
        return self.__dict__.get("_aux")

    def _set_aux(self, aux: np.ndarray | None) -> None:
        if aux is not None:
            aux.setflags(write=False)
        object.__setattr__(self, "_aux", aux)

    def population_errors(self, P: np.ndarray, R: np.ndarray, pt: np.ndarray, Rt: np.ndarray
                          ) -> tuple[np.ndarray, np.ndarray] | None:
        """(position errors (N,) m, orientation errors (N,) rad) of frame poses P (N, 3), R (N, 3, 3) for target
        (pt, Rt), as the kernel's success test sees them, for the kinds with an ``aux`` row (None for the others,
        whose errors are the distance and the rotation angle)."""
        aux = self.aux()
        if aux is None:
            return None
        return band_errors(self.kind, P, R, pt, Rt, aux)

    @classmethod
    def file_kind(cls):
        """This kind's entry in goals files (a :class:`.file_entries.FileKind`: its ``kind:`` name, fields, how its
        target is read and written), or None for a kind goals files do not take."""
        return None

    def marker(self) -> tuple[str, np.ndarray, np.ndarray | None] | None:
        """This goal's viewer marker: (node name, position (3,) m in the base frame, rotation (3, 3) for a triad or
        None for a sphere), or None when its target is no place in the base frame. Default: its frame's target."""
        p, R = self.encode()
        return self.frame, p, (R if self.has_orientation else None)

    def encode(self) -> tuple[np.ndarray, np.ndarray]:  # pragma: no cover - abstract
        """The kernel's target ``(pt (3,), Rt (3, 3))`` of this goal."""
        raise NotImplementedError

    def errors(self, T: pin.SE3) -> tuple[float, float | None]:
        """(position error m or None, rotation angle rad or None) of the goal frame at pose ``T`` (base frame); for
        the kinds with bands, free axes or an axis to point, the errors their success test compares with the
        tolerances (:mod:`.bands`)."""
        pt, Rt = self.encode()
        aux = self.aux()
        if aux is not None:  # the kernel's own errors (its success test's), by their NumPy twin for one pose
            pos, rot = self.population_errors(np.asarray(T.translation)[None], np.asarray(T.rotation)[None], pt, Rt)
            return self.reported(pos[0], rot[0])
        pos = float(np.linalg.norm(T.translation - pt))
        if not self.has_orientation:
            return pos, None
        return pos, float(np.linalg.norm(pin.log3(Rt.T @ T.rotation)))

    def reported(self, position_error: float, rotation_error: float | None) -> tuple[float | None, float | None]:
        """The errors :meth:`errors` reports from the LM kernel's errors of this goal (position m, rotation rad or
        None/NaN: the kernel's success test's numbers, :func:`~evoik_pin.solvers.lm.kernel.task_error`): the
        position error None for a goal without a position, the rotation None for one that reports no angle."""
        return ((float(position_error) if self.has_position else None),
                (float(rotation_error) if self.reports_angle else None))

    @property
    def reports_angle(self) -> bool:
        """Whether the goal's errors include an angle (rad): it constrains orientation, or it points an axis."""
        return self.has_orientation

    def met(self, position_error: float | None, orientation_error: float | None) -> bool:
        """Whether errors (m or None, rad or None) are within this goal's tolerances."""
        return (position_error is None or position_error <= self.tolerance) and (orientation_error is None
                                                     or orientation_error <= self.rotation_tolerance)


# ------------------------------------------------------------------ goal sets
def is_set(target, single_shape: tuple[int, ...]) -> bool:
    """Whether ``target`` is a list of targets rather than one: an array of shape (k, *single_shape), or a list
    or tuple whose members are ``pin.SE3`` or arrays of ``single_shape`` (an empty one too, refused by
    :func:`init_set`). A (4, 4) nested list is one pose, a 3-list of numbers one position."""
    if isinstance(target, np.ndarray):
        return target.ndim == len(single_shape) + 1 and target.shape[1:] == single_shape
    if not isinstance(target, (list, tuple)):
        return False
    if not target:
        return True
    return all(isinstance(t, pin.SE3) or np.shape(t) == single_shape for t in target)


def init_set(goal, targets, single, what: str) -> None:
    """Make ``goal`` (being constructed) the set of ``single(t)`` for each member ``t`` of ``targets``: its target
    is the first member's, its ``alternatives`` the members' goals. ``what`` names the kind and its members in
    errors ("Pose" and "poses"). TargetError for an empty set, naming the member index of a bad one."""
    kind, members = what.split()
    if len(targets) == 0:
        raise TargetError(f"{kind} on {goal.frame!r}: a goal set with no {members}; give at least one "
                          f"(a list of {members}, or one)")
    made = []
    for i, t in enumerate(targets):
        try:
            made.append(single(t))
        except TargetError as exc:
            raise TargetError(f"{kind} on {goal.frame!r}, member {i} of the goal set: {exc}") from None
    object.__setattr__(goal, "target", made[0].target)
    object.__setattr__(goal, "alternatives", tuple(made))
    encoded = [m.encode() for m in made]  # the members' kernel targets, (k, 3) and (k, 3, 3), for vectorized use
    object.__setattr__(goal, "member_targets", (np.array([e[0] for e in encoded]), np.array([e[1] for e in encoded])))


# ------------------------------------------------------------------ goals on two frames
#: What the goals on two frames share (:class:`~.relative_pose.RelativePose`,
#: :class:`~.relative_position.RelativePosition`): frame b placed relative to frame a. Their ``aux`` row (read by the
#: compiled ``solvers/lm/balance.py``): frame a's physical joint (-1: the base) at A_REL_JOINT, its folded placement
#: R (9, row-major) at A_REL_R and p (3,) at A_REL_P; the AUX_SIZE band columns of a pose with axes from A_REL_BAND
#: (:mod:`.bands`; unused by the kinds without bands); then A_REL_SIGNS + k (k < m), per physical joint k: +1 when it
#: moves frame b only, -1 frame a only, :data:`BOTH` (or 0, as the kind asks) both, 0 neither.
A_REL_JOINT, A_REL_R, A_REL_P, A_REL_BAND = 0, 1, 10, 13
A_REL_SIGNS = A_REL_BAND + AUX_SIZE
#: The sign of a joint that moves both frames, for a kind whose error sees them (a vector in the world's axes turns
#: with them); kinds seen in frame a's axes mark those joints 0 (they move the two frames together).
BOTH = 2.0


class FramePair:
    """What the goals on two frames share (:class:`~.relative_pose.RelativePose`,
    :class:`~.relative_position.RelativePosition`): frame b is the goal's ``frame``, frame a its ``frame_a``."""

    @property
    def frame_b(self) -> str:
        """The frame placed relative to ``frame_a`` (the goal's ``frame``)."""
        return self.frame

    @property
    def frames(self) -> list[str]:
        """The frames this goal names: frame_a, frame_b."""
        return [self.frame_a, self.frame]

    @property
    def label(self) -> str:
        """How messages name this goal: ``frame_a -> frame_b``."""
        return f"{self.frame_a} -> {self.frame}"

    def pair_errors(self, Ta, Tb) -> tuple[float, float | None]:
        """The goal's errors (position m, rotation rad or None) for frame a's and frame b's poses ``Ta``, ``Tb``
        (``pin.SE3``, base frame): what ``robot_errors`` reports, from poses a caller already has."""
        raise NotImplementedError


def check_frame_pair(frame_a, frame_b, kind: str) -> None:
    """FrameError unless ``frame_a`` and ``frame_b`` are two different frame names (non-empty strings); ``kind``
    names the goal in the message."""
    for name, value in (("frame_a", frame_a), ("frame_b", frame_b)):
        if not isinstance(value, str) or not value:
            raise FrameError(f"{kind}'s {name} is a frame name (a non-empty string), got {value!r}")
    if frame_a == frame_b:
        raise FrameError(f"{kind} needs two frames, got {frame_a!r} twice")


def pack_frame_pair(robot, frame_a: str, frame_b: str, band: np.ndarray | None = None,
                    both: float = 0.0) -> tuple[np.ndarray, np.ndarray]:
    """(aux row, support row (m,) bool) of a goal on frames a and b of ``robot`` (the ``A_REL_*`` layout above):
    frame a's joint and folded placement, the band columns ``band`` (AUX_SIZE,) when given, and each joint's sign
    (``both`` for the joints moving both frames). Raises FrameError for an unknown frame, or two frames no joint
    moves apart (nor, with ``both``, turns together)."""
    ja, Ra, pa = robot.frame_constants(frame_a)
    jb = robot.frame_constants(frame_b)[0]
    tree = robot.tree
    on_a, on_b = np.zeros(tree.m, dtype=bool), np.zeros(tree.m, dtype=bool)
    on_a[tree.ancestors(ja)], on_b[tree.ancestors(jb)] = True, True
    signs = on_b.astype(float) - on_a.astype(float)  # joints moving both move the two frames together
    shared = on_a & on_b
    # with ``both`` set (a vector in the world's axes) a revolute joint moving both frames turns the vector: two
    # frames on one link still make a goal then (a head's direction from the neck)
    if not signs.any() and not (both and (shared & tree.revolute).any()):
        raise FrameError(f"no active joint of {robot.name} moves frame {frame_b!r} relative to "
                         f"{frame_a!r}: load the robot with both among its tips (tips=[...]) or tips='all'")
    signs[shared] = both
    aux = np.zeros(A_REL_SIGNS + tree.m)
    aux[A_REL_JOINT] = ja
    aux[A_REL_R:A_REL_R + 9] = Ra.ravel()
    aux[A_REL_P:A_REL_P + 3] = pa
    if band is not None:  # bands, free axes
        aux[A_REL_BAND:A_REL_BAND + AUX_SIZE] = band
    aux[A_REL_SIGNS:] = signs
    return aux, on_a | on_b


def pair_placements(robot, Q: np.ndarray, frame_a: str, frame_b: str
                    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Over a population Q (N, n): frame a's rotations R_a (N, 3, 3) (base frame), the vectors p_b - p_a (N, 3)
    (m, base frame) and frame b's rotations R_b (N, 3, 3), from the robot's batch kinematics."""
    P, R = robot.fk_batch(Q, validate=False, frames=[frame_a, frame_b])
    return R[:, 0], P[:, 1] - P[:, 0], R[:, 1]
