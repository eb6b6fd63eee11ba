"""A goal list checked against a robot and packed for the LM kernel (see :mod:`evoik_pin.goals`)."""

from __future__ import annotations

import dataclasses
import weakref

import numpy as np

from ..errors import FrameError, LockedJointsError, TargetError
from ..solvers.lm.layout import KIND_BEYOND_FRAME, GoalStack
from .goal import Goal

__all__ = ["bind", "is_goal_list"]

#: Two goals on one frame clash when their target positions (m) or rotations (Frobenius norm) differ by more.
_CLASH = 1e-9


def is_goal_list(value) -> bool:
    """True for a list or tuple of goals (an empty one too: :func:`bind` refuses it by name)."""
    return isinstance(value, (list, tuple)) and all(isinstance(g, Goal) for g in value)


def bind(robot, goals) -> tuple[list[Goal], GoalStack, np.ndarray, np.ndarray]:
    """Check ``goals`` against ``robot`` and pack them for the LM kernel: (the goals as a list, their
    :class:`~evoik_pin.solvers.lm.layout.GoalStack`, targets pt (G, 3), Rt (G, 3, 3)).

    A list of goals on frames (no goal beyond one frame) with the frames, kinds, weights, tolerances and ``aux``
    rows of a list bound before on this robot (an :class:`~evoik_pin.IKSolver`'s calls: new targets, the same
    goals) takes its checked stack from :data:`_BOUND`: only the targets are packed (and, for a frame given two
    goals, their clash checked: it reads the targets).

    Raises: TargetError for an empty list, a member that is no goal, or one frame given clashing targets;
    FrameError for an unknown frame (with the closest names) or a frame no active joint moves; LockedJointsError
    (a FrameError) for a frame only a floating base moves while joints between the root and it are locked.
    """
    goals = list(goals)
    if not goals:
        raise TargetError("the goal list is empty: give at least one goal (Pose(frame, T), Position(frame, p))")
    for i, g in enumerate(goals):
        if not isinstance(g, Goal):
            raise TargetError(f"goal {i} is a {type(g).__name__}, not a goal: use Pose(frame, T) or "
                              "Position(frame, p) from evoik_pin.goals")
    key = _signature(robot, goals)
    hit = _BOUND.get(key) if key is not None else None
    if hit is not None and hit[0]() is robot:
        stack = hit[1]
        if len(stack.frames) > len(set(stack.frames)):
            _check_frames(robot, goals)  # the clash test reads the targets
    else:
        _check_frames(robot, goals)
        stack = GoalStack.of(robot, [g.frame for g in goals], [g.kind for g in goals], [g.weight for g in goals],
                             [g.tolerance for g in goals], [g.rotation_tolerance for g in goals],
                             [g.aux() for g in goals])
        stack = _beyond_frame(robot, goals, stack)
        if key is not None:
            if len(_BOUND) >= 64:
                _BOUND.pop(next(iter(_BOUND)))
            _BOUND[key] = (weakref.ref(robot), stack)
    G = len(goals)
    pt, Rt = np.empty((G, 3)), np.empty((G, 3, 3))
    for g, goal in enumerate(goals):
        pt[g], Rt[g] = goal.encode()
    return goals, stack, pt, Rt


#: Stacks of goal lists bound before, by robot and the goals' :func:`_signature` (the last 64): a hit skips the
#: frames' checks (their verdict depends on the robot and the frame names alone) and GoalStack.of's key.
_BOUND: dict = {}


def _signature(robot, goals) -> tuple | None:
    """What :func:`bind`'s checks and stack read of ``goals`` besides their targets, with the robot's id: per goal
    its class, frame, kind, weight, tolerances and ``aux`` row; None when a goal packs itself against the robot
    (a goal beyond one frame: :func:`_beyond_frame`)."""
    parts = [id(robot)]
    for g in goals:
        if g.kind >= KIND_BEYOND_FRAME:
            return None
        aux = g.aux()
        parts.append((type(g), g.frame, g.kind, g.weight, g.tolerance, g.rotation_tolerance,
                      None if aux is None else aux.tobytes()))
    return tuple(parts)


def _check_frames(robot, goals) -> None:
    """FrameError for a goal's unknown frame (with the closest names) or one no active joint moves;
    :func:`_check_not_base_only` for one only a floating base moves; TargetError for one frame given two goals
    with clashing targets."""
    seen: dict[int, Goal] = {}
    for g in goals:
        if g.kind >= KIND_BEYOND_FRAME:  # centre of mass, relative pose: checked as they pack (_beyond_frame)
            continue
        fid = robot.frame_id(g.frame)  # FrameError with the closest names
        if not robot.moving_joints(g.frame):
            raise FrameError(f"no active joint of {robot.name} moves frame {g.frame!r}: load the robot with that frame "
                             f"among its tips (tips=[...]) or with tips='all', or aim at another frame")
        _check_not_base_only(robot, g.frame)
        other = seen.get(fid)
        if other is not None and other.aux() is None and g.aux() is None:  # bands, free axes, pointing: no clash
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
    """LockedJointsError for a goal frame that only the floating base's six entries move while joints between the
    root and it are locked (another branch than the robot's tips, or left out by ``joints=[...]``): the base moves
    every frame, so the frame passes the "some active joint moves it" test, yet no joint below the base can reach
    for it and the goal binds."""
    if not robot.floating_base:
        return
    base = set(robot.joint_names[:6])  # a floating base's entries come first in q
    if not set(robot.moving_joints(frame)) <= base:
        return
    # joints fixed at values the caller chose (Robot.locked, solve's locked=) are placed on purpose: a leg held in a
    # posture may be carried by the base. Only fixed joints between the root and the frame: the base's job too.
    locked = [j for j in robot.locked_joints(frame) if j not in robot.locked_values]
    if not locked:
        return
    tips = ", ".join(map(repr, robot.tips))
    shown = ", ".join(locked[:12]) + (f", ... ({len(locked) - 12} more)" if len(locked) > 12 else "")
    raise LockedJointsError(
        f"only the floating base moves frame {frame!r} of {robot.name}: the joints between the root and it are "
        f"locked ({shown}), so the base alone would have to reach it. Free them when loading the robot: "
        f"tips=[{tips}, {frame!r}] (the chains to each), joints=[...] naming them with the others to keep free, "
        f"or tips='all' (the whole tree; what a branching URDF gets without tip=/tips=)")


def _beyond_frame(robot, goals, stack: GoalStack) -> GoalStack:
    """``stack`` with the ``aux`` and ``support`` rows of the goals beyond one frame (:class:`CenterOfMass`,
    :class:`RelativePose`: their ``pack(robot)``, which checks their frames and the robot's masses)."""
    packed = {g: goal.pack(robot) for g, goal in enumerate(goals) if goal.kind >= KIND_BEYOND_FRAME}
    if not packed:
        return stack
    width = max(max(a.size for a, _ in packed.values()), stack.aux.shape[1])
    aux = np.zeros((len(goals), width))
    aux[:, :stack.aux.shape[1]] = stack.aux
    support = stack.support.copy()
    for g, (row, moved) in packed.items():
        aux[g, :row.size] = row
        support[g] = moved
    return dataclasses.replace(stack, aux=aux, support=support)
