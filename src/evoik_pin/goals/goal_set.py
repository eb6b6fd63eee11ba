"""Goal sets: one goal whose target is any one of several (``Pose(frame, [T1, ..., Tk])``,
``Position(frame, [p1, ..., pk])``), the grasps a planner offers of which any will do.

A goal set is a goal like the others (its frame, weight and tolerances), packed for the kernel with its first
member's target; its ``alternatives`` hold one single-target goal per member, in the order given. Solvers try the
members (:meth:`evoik_pin.problem.IKProblem.variants`); ``Result.chosen[i]`` is the index of the member goal ``i``
meets.
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin

from ..errors import TargetError

__all__ = ["init_set", "is_set"]


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
