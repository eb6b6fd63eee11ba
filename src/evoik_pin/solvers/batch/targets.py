"""The tip targets of a :func:`~evoik_pin.solve_many` call as the batch solver reads them: chunks of one-goal
problems on the tip (:class:`~.goal_lists.GoalBlock`, the form goal lists take), one group per target kind over
:meth:`GoalStack.single`'s stack. An (N, 4, 4) array of poses is encoded with no Target object made (a Target costs
a tenth of a batched solve): only the targets left to the per-target solver get one.
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin

from ...errors import TargetError
from ...goals.stack import GoalArrays, GoalStack, TargetArrays, target_kind
from ...problem import Target
from .goal_lists import GoalBlock, GoalSource, is_goal_batch, is_problem_list

__all__ = ["TargetSource", "source_of"]


def tip_group(robot, rows: np.ndarray, arrays: TargetArrays, tolerances: tuple[float, float]
              ) -> tuple[np.ndarray, GoalArrays]:
    """Rows (k,) of tip targets of one kind as one-goal problems over the tip's stack with ``tolerances`` (m, rad)."""
    stack = GoalStack.single(robot, arrays.kind, *tolerances)
    return rows, GoalArrays(stack, arrays.P[:, None], arrays.Rts[:, None])


def _one_target(targets) -> bool:
    """True when ``targets`` is one target rather than a sequence of them: a ``pin.SE3``, a Target, or an array (or
    nested lists) of shape (4, 4) or (3,)."""
    if isinstance(targets, (pin.SE3, Target)):
        return True
    if isinstance(targets, np.ndarray):
        return targets.shape in ((4, 4), (3,))
    if isinstance(targets, (list, tuple)) and len(targets) in (3, 4):  # short: the array costs nothing
        try:
            return np.asarray(targets, dtype=float).shape in ((4, 4), (3,))
        except (TypeError, ValueError):  # targets of other kinds (SE3, Target) in a list
            return False
    return False


class TargetSource:
    """The user's tip targets (an (N, 4, 4) array of poses, any sequence :meth:`Target.coerce_many` accepts, an
    iterable, or one target alone), made into :class:`~.goal_lists.GoalBlock` objects chunk by chunk."""

    goals = False  # tip targets (goal lists: :class:`~.goal_lists.GoalSource`)

    def __init__(self, robot, targets) -> None:
        self.robot = robot
        if _one_target(targets):
            targets = targets[None] if isinstance(targets, np.ndarray) and targets.ndim == 2 else [targets]
        self.raw = targets if isinstance(targets, (np.ndarray, list, tuple)) else list(targets)

    def __len__(self) -> int:
        return len(self.raw)

    @property
    def poses(self) -> np.ndarray | None:
        """The (N, 4, 4) array when the targets are one (Ray sends its slices as they are), else None."""
        raw = self.raw
        return raw if isinstance(raw, np.ndarray) and raw.ndim == 3 and raw.shape[1:] == (4, 4) else None

    def chunk(self, a: int, b: int) -> list[Target]:
        """Targets a to b - 1 as :class:`Target` objects (a TargetError names a bad one by its index in the call)."""
        try:
            return Target.coerce_many(self.raw[a:b])
        except TargetError:
            self.check()
            raise

    def block(self, a: int, b: int, tolerances: tuple[float, float]) -> GoalBlock:
        """Targets a to b - 1 as one-goal problems with the call's ``tolerances`` (m, rad), grouped by kind."""
        poses = self.poses
        if poses is None:
            targets = self.chunk(a, b)
            by_kind: dict[int, list[int]] = {}
            for i, t in enumerate(targets):
                by_kind.setdefault(target_kind(t), []).append(i)
            groups = [tip_group(self.robot, np.array(rows), TargetArrays.of([targets[i] for i in rows]), tolerances)
                      for rows in by_kind.values()]
            return GoalBlock(groups, len(targets), targets.__getitem__, tip=True)
        try:
            H = Target.check_poses(poses[a:b])
        except TargetError:
            self.check()
            raise
        return GoalBlock([tip_group(self.robot, np.arange(H.shape[0]), TargetArrays.from_poses(H), tolerances)],
                         H.shape[0], lambda i: Target.from_poses(H[i:i + 1])[0], tip=True)

    def check(self) -> None:
        """Coerce every target: the TargetError (naming the first bad target's index) if there is one."""
        Target.coerce_many(self.raw)


def source_of(robot, targets) -> TargetSource | GoalSource:
    """The source of a call's problems: a :class:`~.goal_lists.GoalSource` for goal lists (one alone: one problem),
    else a :class:`TargetSource`; an existing source as it is."""
    if isinstance(targets, (TargetSource, GoalSource)):
        return targets
    if is_problem_list(targets) and len(targets) > 0:
        return GoalSource(robot, [targets])
    return GoalSource(robot, targets) if is_goal_batch(targets) else TargetSource(robot, targets)
