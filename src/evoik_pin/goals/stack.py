"""The goal stack: G goals on frames of one robot packed as the LM kernel reads them (:class:`GoalStack`, :func:`bind`),
and the targets' encoding as ``pt`` (3,), ``Rt`` (3, 3) (:func:`encode_target`, :class:`TargetArrays`). A goal's spec
holds its kind's declaration (:mod:`.registry`): numba's disk cache would not see the registry's tables change."""

from __future__ import annotations

import dataclasses
import weakref
from dataclasses import dataclass, field

import numpy as np
import pinocchio as pin

from ..errors import FrameError, LockedJointsError, TargetError
from ..robot.frames import listed
from .goal import Goal
from .planar import KIND_PLANAR, KIND_PLANAR_YAW, Planar
from .pose import KIND_POSE, Pose
from .position import KIND_POSITION, Position
from .registry import (
    FAMILY_BEYOND_FRAME,
    KINDS,
    ORIENTED_KINDS,
    TASK_ROWS,
)

__all__ = ["GOAL_SIZE", "G_ANGLE", "G_FAMILY", "G_JOINT", "G_KIND", "G_ROW", "G_ROWS", "G_RTOL", "G_TOL", "G_WEIGHT",
           "KIND_PLANAR", "KIND_PLANAR_YAW", "GoalArrays", "GoalStack", "TargetArrays", "bind", "encode_target",
           "encode_targets", "free_entries", "is_goal_list", "owned", "spec_row", "structure", "target_kind",
           "tip_goals"]

#: Columns of a goal's spec: kind, physical joint of its frame (-1: the base), sqrt(weight), tolerances (m, rad),
#: first row in the stacked error; then its kind's declaration: its row count, its compiled family (``FAMILY_*``)
#: and 1.0 when its errors include an angle.
G_KIND, G_JOINT, G_WEIGHT, G_TOL, G_RTOL, G_ROW, G_ROWS, G_FAMILY, G_ANGLE = range(9)
GOAL_SIZE = 9


def spec_row(kind: int, joint: int, weight: float, tolerance: float, rotation_tolerance: float,
             row: int) -> np.ndarray:
    """One goal's spec (GOAL_SIZE,): the given columns and those its kind declares."""
    code = KINDS[int(kind)]
    return np.array([kind, joint, np.sqrt(weight), tolerance, rotation_tolerance, row, len(code.rows), code.family,
                     1.0 if code.angle else 0.0])


def owned(a: np.ndarray, dtype=None) -> np.ndarray:
    """``a`` if it is a C-contiguous, writable array (of ``dtype`` when given), else such a copy: the type the
    kernel's entry points are compiled for (a read-only array is another numba type)."""
    if a.flags.writeable and a.flags.c_contiguous and (dtype is None or a.dtype == dtype):
        return a
    return np.array(a, dtype=dtype, order="C")


def target_kind(target) -> int:
    """The ``KIND_*`` of a :class:`~evoik_pin.problem.Target`."""
    if target.planar:
        return KIND_PLANAR if target.yaw is None else KIND_PLANAR_YAW
    return KIND_POSITION if target.rotation is None else KIND_POSE


def encode_target(target) -> tuple[np.ndarray, np.ndarray]:
    """The kernel's ``(pt (3,), Rt (3, 3))`` of one target: pose (position m, rotation), position (position,
    identity), planar (x, y, yaw rad or 0; identity)."""
    if target.planar:
        pt = np.array([target.position[0], target.position[1], target.yaw or 0.0])
        return pt, np.eye(3)
    Rt = np.eye(3) if target.rotation is None else owned(target.rotation, float)
    return owned(target.position, float), Rt


def encode_targets(targets) -> tuple[np.ndarray, np.ndarray]:
    """``(P (N, 3), Rts (N, 3, 3))`` of N targets of one kind (:func:`encode_target` each), for the kernel's batch
    entry points."""
    P, Rts = zip(*map(encode_target, targets), strict=True)
    return np.array(P, dtype=float), np.array(Rts, dtype=float)


class _Rows:
    """N problems' targets ``P``, ``Rts``, by row (:class:`TargetArrays`, :class:`GoalArrays`)."""

    def __len__(self) -> int:
        return int(self.P.shape[0])

    def take(self, rows: np.ndarray):
        """The problems at ``rows`` (an index array), as new arrays."""
        return dataclasses.replace(self, P=self.P[rows], Rts=self.Rts[rows])


@dataclass(frozen=True)
class TargetArrays(_Rows):
    """N targets of one kind as the kernel reads them (:func:`encode_targets`), without Target objects.

    Attributes:
        kind: their ``KIND_*``. P: (N, 3) positions (m; planar: x, y, yaw rad). Rts: (N, 3, 3) rotations
            (identity for targets without one).
    """

    kind: int
    P: np.ndarray
    Rts: np.ndarray

    @classmethod
    def of(cls, targets) -> TargetArrays:
        """The arrays of a list of Target of one kind."""
        return cls(target_kind(targets[0]), *encode_targets(targets))

    @classmethod
    def from_poses(cls, H: np.ndarray) -> TargetArrays:
        """Pose targets from (N, 4, 4) homogeneous matrices already checked (``Target.check_poses``)."""
        return cls(KIND_POSE, np.ascontiguousarray(H[:, :3, 3], dtype=float),
                   np.ascontiguousarray(H[:, :3, :3], dtype=float))

    @property
    def oriented(self) -> bool:
        """True when the targets constrain orientation."""
        return self.kind in ORIENTED_KINDS


@dataclass(frozen=True)
class GoalStack:
    """G goals on frames of one robot as the kernel reads them, without their targets (one stack serves any
    number of problems).

    Attributes:
        spec: (G, GOAL_SIZE) the ``G_*`` columns. R: (G, 3, 3), p: (G, 3) (m) each frame's folded placement on
            its joint (``Robot.frame_constants``). support: (G, m) bool, the physical joints that move each frame.
        rows: total rows of the stacked error. kinds: (G,) the ``KIND_*``. frames: the frame names.
        aux: (G, A) float, A >= 1: each goal's further numbers, read by its kind's code (zeros where none).
        any_oriented: some goal constrains orientation.
    """

    spec: np.ndarray
    R: np.ndarray
    p: np.ndarray
    support: np.ndarray
    rows: int
    kinds: tuple
    frames: tuple
    aux: np.ndarray = None
    any_oriented: bool = field(init=False)
    #: :func:`free_entries`' answer once asked, as its one member.
    _free: list = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        object.__setattr__(self, "any_oriented", any(k in ORIENTED_KINDS for k in self.kinds))
        object.__setattr__(self, "aux", np.zeros((self.spec.shape[0], 1)) if self.aux is None else self.aux)
        object.__setattr__(self, "_free", [])

    @property
    def arrays(self) -> tuple:
        """The stack's arguments of the kernel's entry points, in their order: spec, R, p, support, aux."""
        return self.spec, self.R, self.p, self.support, self.aux

    @classmethod
    def of(cls, robot, frames, kinds, weights, tolerances, rotation_tolerances, aux=None) -> GoalStack:
        """The stack of goals on ``frames`` (names; None: the robot's tip) of ``kinds`` (``KIND_*``) with
        ``weights`` (> 0), ``tolerances`` (m) and ``rotation_tolerances`` (rad), one each per goal; ``aux``: per
        goal its further numbers (a 1-d array or None), zero-padded into the (G, A) ``aux`` array.

        Cached per robot and these values (the last 64): a goal list solved again with new targets gets the same
        stack, so an LM engine kept from solve to solve is retargeted, not rebuilt."""
        given = aux is not None and any(a is not None for a in aux)
        key = (tuple(frames), tuple(int(k) for k in kinds), tuple(float(w) for w in weights),
               tuple(float(t) for t in tolerances), tuple(float(t) for t in rotation_tolerances),
               tuple(None if a is None else np.asarray(a, dtype=float).tobytes() for a in aux) if given else None)
        hit = _recall(_STACK_CACHE, robot, key)
        if hit is not None:
            return hit
        joints, R, p = zip(*map(robot.frame_constants, frames), strict=True)
        rows = np.cumsum([0] + [len(TASK_ROWS[k]) for k in kinds])
        spec = np.array([spec_row(*args) for args in zip(kinds, joints, weights, tolerances, rotation_tolerances,
                                                          rows[:-1], strict=True)])
        packed = None
        if given:
            packed = np.zeros((len(frames), max(len(a) for a in aux if a is not None)))
            for g, a in enumerate(aux):
                if a is not None:
                    packed[g, :len(a)] = a
        return _remember(_STACK_CACHE, robot, key, cls(
            spec, np.array(R), np.array(p), robot.tree.support_mask(joints), int(rows[-1]),
            tuple(int(k) for k in kinds), tuple(robot.tip if f is None else f for f in frames), packed))

    @classmethod
    def single(cls, robot, kind: int, tolerance: float, rotation_tolerance: float) -> GoalStack:
        """The tip's one goal of weight 1."""
        return cls.of(robot, [robot.tip], [kind], [1.0], [tolerance], [rotation_tolerance])

    def __len__(self) -> int:
        return int(self.spec.shape[0])

    @property
    def oriented(self) -> np.ndarray:
        """(G,) bool: the goals that constrain orientation."""
        return np.array([k in ORIENTED_KINDS for k in self.kinds], dtype=bool)


_STACK_CACHE: dict = {}  # GoalStack.of's


def _recall(cache: dict, robot, key):
    """What ``cache`` holds for ``robot`` and ``key``, or None."""
    hit = cache.get((id(robot), key))
    return hit[1] if hit is not None and hit[0]() is robot else None  # a dead robot's id may be reused


def _remember(cache: dict, robot, key, value):
    """Keep ``value`` in ``cache`` for ``robot`` (weakly) and ``key``, the last 64 kept; return it."""
    if len(cache) >= 64:
        cache.pop(next(iter(cache)))
    cache[(id(robot), key)] = (weakref.ref(robot), value)
    return value

#: The goal class of each tip-target kind (:func:`tip_goals`).
_TIP_CLASSES = {KIND_POSE: Pose, KIND_POSITION: Position, KIND_PLANAR: Planar, KIND_PLANAR_YAW: Planar}


@dataclass(frozen=True)
class GoalArrays(_Rows):
    """N problems over one goal stack (other targets) as the kernel's pair entry point reads them.

    Attributes:
        stack: the :class:`GoalStack` every problem shares. P: (N, G, 3) target positions (m). Rts: (N, G, 3, 3)
            target rotations (identity for goals without one).
    """

    stack: GoalStack
    P: np.ndarray
    Rts: np.ndarray

    @property
    def oriented(self) -> bool:
        return self.stack.any_oriented


# ------------------------------------------------------------------ binding a goal list
_PLANAR = {KIND_PLANAR, KIND_PLANAR_YAW}
#: Two goals on one frame clash when their target positions (m) or rotations (Frobenius norm) differ by more.
_CLASH = 1e-9


def is_goal_list(value) -> bool:
    """True for a list or tuple of goals (an empty one too: :func:`bind` refuses it by name)."""
    return isinstance(value, (list, tuple)) and all(isinstance(g, Goal) for g in value)


def free_entries(robot, stack: GoalStack) -> np.ndarray | None:
    """(n,) bool: the entries of ``robot``'s q that move no goal of ``stack`` (no physical joint they drive is in a
    goal's support: another arm, the head, a hand's fingers when only the other hand is posed); None when every entry
    moves some goal. Such entries change no goal's error. Kept on the stack (equal goal lists share one)."""
    if stack._free:
        return stack._free[0]
    driven = robot.tree_constants()[4][stack.support.any(axis=0)]  # the entries of q driving a goal's joints
    used = np.zeros(robot.n, dtype=bool)
    used[driven[(driven >= 0) & (driven < robot.n)]] = True
    stack._free[:] = [None if used.all() else ~used]  # one assignment: solve_many's threads may race to it
    return stack._free[0]


def tip_goals(robot, target, tolerance: float, rotation_tolerance: float
              ) -> tuple[list[Goal], GoalStack, np.ndarray, np.ndarray]:
    """:func:`bind`'s answer for a tip Target (checked already): its one goal on the robot's tip (a Pose, Position or
    Planar of weight 1, ``tolerance`` m, ``rotation_tolerance`` rad), the tip's stack, pt (1, 3) and Rt (1, 3, 3).
    Nothing is checked again (a control loop makes one per step)."""
    kind = target_kind(target)
    key = (kind, tolerance, rotation_tolerance)
    hit = _recall(_TIP_GOALS, robot, key)
    if hit is None:
        fields = {"frame": robot.tip, "weight": 1.0, "tolerance": tolerance, "rotation_tolerance": rotation_tolerance,
                  "kind": kind, "has_orientation": target.has_orientation, "alternatives": None, "band": None,
                  "_aux": None, **({"free": ()} if kind == KIND_POSE else {})}
        hit = _remember(_TIP_GOALS, robot, key, (GoalStack.single(robot, kind, tolerance, rotation_tolerance),
                                                 _TIP_CLASSES[kind], fields))
    pt, Rt = encode_target(target)
    goal = object.__new__(hit[1])  # frozen dataclasses: their fields set as their __init__ sets them
    goal.__dict__.update(hit[2], target=pin.SE3(Rt, pt) if kind == KIND_POSE else pt)
    if hit[1] is Planar:
        goal.__dict__["yaw"] = target.yaw
    return [goal], hit[0], pt[None], Rt[None]


#: :func:`tip_goals`' per robot, kind and tolerances: the tip's stack, the goal class, its fields but the target.
_TIP_GOALS: dict = {}


def bind(robot, goals) -> tuple[list[Goal], GoalStack, np.ndarray, np.ndarray]:
    """Check ``goals`` against ``robot`` and pack them for the LM kernel: (the goals as a list, their
    :class:`GoalStack`, targets pt (G, 3), Rt (G, 3, 3)). A list like one bound before on this robot (new targets)
    takes its checked stack from the cache.

    Raises: TargetError for an empty list, a member that is no goal, or one frame given clashing targets;
    FrameError for an unknown frame (with the closest names) or a frame no active joint moves; LockedJointsError
    for a frame only a floating base moves while joints between the root and it are locked.
    """
    goals = list(goals)
    if not goals:
        raise TargetError("the goal list is empty: give at least one goal (Pose(frame, T), Position(frame, p))")
    for i, g in enumerate(goals):
        if not isinstance(g, Goal):
            raise TargetError(f"goal {i} is a {type(g).__name__}, not a goal: use Pose(frame, T) or "
                              "Position(frame, p) from evoik_pin.goals")
    # goals beyond one frame pack their rows against the robot on every bind: only lists without them are kept
    key = None if any(_packs_itself(g) for g in goals) else structure(goals)
    stack = None if key is None else _recall(_BOUND, robot, key)
    if stack is None or len(stack.frames) > len(set(stack.frames)):  # a hit: the clash test reads the targets
        _check_frames(robot, goals)
    if stack is None:
        # the goals beyond one frame pack their aux and support rows against the robot (checking their frames)
        packed = {g: goal.pack(robot) for g, goal in enumerate(goals) if _packs_itself(goal)}
        stack = GoalStack.of(robot, [g.frame for g in goals], [g.kind for g in goals], [g.weight for g in goals],
                             [g.tolerance for g in goals], [g.rotation_tolerance for g in goals],
                             [packed[g][0] if g in packed else goal.aux() for g, goal in enumerate(goals)])
        if packed:
            support = stack.support.copy()
            for g, (_, moved) in packed.items():
                support[g] = moved
            stack = dataclasses.replace(stack, support=support)
        if key is not None:
            _remember(_BOUND, robot, key, stack)
    pt, Rt = zip(*(goal.encode() for goal in goals), strict=True)
    return goals, stack, np.array(pt, dtype=float), np.array(Rt, dtype=float)


#: Stacks of goal lists bound before, by robot and :func:`structure` (the last 64): a hit skips the frames' checks.
_BOUND: dict = {}


def structure(goals) -> tuple:
    """What a goal list's stack depends on besides its targets: each goal's frame, kind, weight, tolerances and aux
    row, and for a goal beyond one frame its ``batch_key()``. Lists of one structure share a stack."""
    return tuple((g.frame, g.kind, g.weight, g.tolerance, g.rotation_tolerance,
                  None if g.aux() is None else g.aux().tobytes())
                 + (g.batch_key() if _packs_itself(g) else ()) for g in goals)


def _packs_itself(goal: Goal) -> bool:
    """Whether ``goal`` packs its own ``aux`` and ``support`` rows against the robot (``goal.pack(robot)``)."""
    return KINDS[goal.kind].family == FAMILY_BEYOND_FRAME


def _check_frames(robot, goals) -> None:
    """:func:`bind`'s checks of the goals on one frame."""
    seen: dict[int, Goal] = {}
    for g in goals:
        if _packs_itself(g):  # centre of mass, two frames: checked as they pack
            continue
        fid = robot.frame_id(g.frame)  # FrameError with the closest names
        if not robot.moving_joints(g.frame):
            raise FrameError(f"no active joint of {robot.name} moves frame {g.frame!r}: load the robot with that frame "
                             f"among its tips (tips=[...]) or with tips='all', or aim at another frame")
        _check_not_base_only(robot, g.frame)
        other = seen.get(fid)
        # bands, free axes, pointing and planar targets (x, y, yaw: no point) are no clash
        if other is not None and other.aux() is None and g.aux() is None and not {other.kind, g.kind} & _PLANAR:
            pa, Ra = other.encode()
            pb, Rb = g.encode()
            clash = np.linalg.norm(pa - pb) > _CLASH
            if other.has_orientation and g.has_orientation:
                clash = clash or np.linalg.norm(Ra - Rb) > _CLASH
            if clash:
                raise TargetError(f"frame {g.frame!r} has two goals with different targets ({pa.round(6).tolist()} and "
                                  f"{pb.round(6).tolist()}): give each frame one target")
        seen[fid] = g


def _check_not_base_only(robot, frame: str) -> None:
    """LockedJointsError for a goal frame that only the floating base moves while joints between the root and it
    are locked (another branch than the robot's tips): no joint below the base can reach for it."""
    if not robot.floating_base:
        return
    base = set(robot.joint_names[:6])  # a floating base's entries come first in q
    if not set(robot.moving_joints(frame)) <= base:
        return
    # joints locked at values the caller chose are placed on purpose (a leg held in a posture, carried by the base)
    locked = [j for j in robot.locked_joints(frame) if j not in robot.locked_values]
    if not locked:
        return
    tips = ", ".join(map(repr, robot.tips))
    raise LockedJointsError(
        f"only the floating base moves frame {frame!r} of {robot.name}: the joints between the root and it are "
        f"locked ({listed(locked, 12)}), so the base alone would have to reach it. Free them when loading the robot: "
        f"tips=[{tips}, {frame!r}] (the chains to each), joints=[...] naming them with the others to keep free, "
        f"or tips='all' (the whole tree; what a branching URDF gets without tip=/tips=)")
