"""A goal list checked against a robot and packed for the LM kernel (see :mod:`evoik_pin.goals`)."""

from __future__ import annotations

import dataclasses

import numpy as np

from ..errors import FrameError, TargetError
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
        if g.kind >= KIND_BEYOND_FRAME:  # centre of mass, relative pose: checked as they pack (_beyond_frame)
            continue
        fid = robot.frame_id(g.frame)  # FrameError with the closest names
        if not robot.moving_joints(g.frame):
            raise FrameError(f"no active joint of {robot.name} moves frame {g.frame!r}: load the robot with that frame "
                             f"among its tips (tips=[...]) or with tips='all', or aim at another frame")
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
    stack = GoalStack.of(robot, [g.frame for g in goals], [g.kind for g in goals], [g.weight for g in goals],
                         [g.tolerance for g in goals], [g.rotation_tolerance for g in goals], [g.aux() for g in goals])
    stack = _beyond_frame(robot, goals, stack)
    encoded = [g.encode() for g in goals]
    pt = np.ascontiguousarray([e[0] for e in encoded], dtype=float)
    Rt = np.ascontiguousarray([e[1] for e in encoded], dtype=float)
    return goals, stack, pt, Rt


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
