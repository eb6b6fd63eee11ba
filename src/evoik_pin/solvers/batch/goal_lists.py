"""The problems of a :func:`~evoik_pin.solve_many` call in the one form the batch engine reads (:class:`GoalBlock`,
chunk by chunk): goal lists (:class:`GoalSource`) and tip targets as one-goal problems on the tip
(:class:`TargetSource`); and :class:`GoalTree`, the seed table searched by nearness to them."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from ...errors import ConfigurationError, FrameError, OptionError, TargetError
from ...goals import Goal, bind, is_goal_list
from ...goals.preferences import check_preferences, holds_preferences, split_preferences
from ...goals.registry import KIND_BEYOND_FRAME, POSITIONLESS_KINDS
from ...goals.stack import G_WEIGHT, GoalArrays, GoalStack, TargetArrays, structure, target_kind
from ...problem import Target

__all__ = ["GoalBlock", "GoalSource", "GoalTree", "TargetSource", "is_goal_batch", "source_of", "structure"]


def is_problem_list(value) -> bool:
    """True for one whole-robot problem: a list or tuple of goals, preferences among them or not."""
    return is_goal_list(value) or holds_preferences(value)


def is_goal_batch(targets) -> bool:
    """True when ``targets`` is a sequence of goal lists (some member a non-empty :func:`is_problem_list`), not of
    single targets nor one goal list alone."""
    if not isinstance(targets, (list, tuple)) or not targets or is_problem_list(targets):
        return False
    return any(isinstance(t, (list, tuple)) and t and is_problem_list(t) for t in targets)


@dataclass
class GoalBlock:
    """Consecutive problems of a call, grouped by goal stack: the one form the batch engine solves.

    Attributes:
        groups: ``[(rows, arrays)]``: the block's row indices (k,) of one stack and their
            :class:`~evoik_pin.goals.stack.GoalArrays`, in the order the stacks first appear.
        size: the block's rows. target: row ``i``'s problem for the one-by-one solver (its
            :class:`~evoik_pin.problem.Target` or goal list).
        tip: True for tip targets (answers reported as single-target results), False for goal lists.
    """

    groups: list[tuple[np.ndarray, GoalArrays]]
    size: int
    target: Callable[[int], object]
    tip: bool = False

    def __len__(self) -> int:
        return self.size


class GoalSource:
    """The goal lists of a call, every one checked against ``robot`` when made (:func:`evoik_pin.goals.bind`,
    :func:`check_preferences`; the error names the list's index), then handed out chunk by chunk (:meth:`block`).
    Lists holding preferences or goal sets are left to the one-by-one solver.

    Attributes:
        preferences: ``{index: [preference, ...]}`` of the lists holding preferences.
    """

    goals = True
    poses = None  # no (N, 4, 4) array: Ray sends the lists themselves

    def __init__(self, robot, lists) -> None:
        self.raw = [list(goals) if isinstance(goals, (list, tuple)) else goals for goals in lists]
        self._stacks: dict[tuple, object] = {}  # structure -> its GoalStack
        self._keys: list[tuple] = []
        self._targets: list[tuple[np.ndarray, np.ndarray]] = []  # per list: pt (G, 3), Rt (G, 3, 3)
        self.preferences: dict[int, list] = {}
        self._frames: dict[int, str] = {}  # the first goal's frame of each list holding preferences
        self._robot = robot
        checked: set[tuple] = set()
        for i, goals in enumerate(self.raw):
            if not isinstance(goals, list) or not is_problem_list(goals):
                raise TargetError(f"goal list {i} is a {type(goals).__name__}, not a list of goals: give each problem "
                                  "as a list of Pose(frame, T) / Position(frame, p) (evoik_pin.goals)")
            try:
                if holds_preferences(goals):
                    goals, prefs = split_preferences(goals)
                    seen = (goals[0].frame, *map(id, prefs))  # lists sharing their preference objects: checked once
                    if seen not in checked:
                        check_preferences(robot, prefs, goals[0].frame, with_q0=True)
                        checked.add(seen)
                    self.preferences[i], self._frames[i] = prefs, goals[0].frame
                key = structure(goals)
                # a list repeating a frame is checked whole (its targets may clash); others' frames once per structure
                if key not in self._stacks or len({g.frame for g in goals}) < len(goals):
                    _, stack, pt, Rt = bind(robot, goals)
                    self._stacks.setdefault(key, stack)
                else:
                    encoded = [g.encode() for g in goals]
                    pt, Rt = np.array([e[0] for e in encoded]), np.array([e[1] for e in encoded])
            except (TargetError, FrameError, ConfigurationError, OptionError) as exc:
                raise type(exc)(f"goal list {i}: {exc}") from None
            self._keys.append(key)
            self._targets.append((pt, Rt))

    def __len__(self) -> int:
        return len(self.raw)

    @property
    def structures(self) -> int:
        """Number of distinct structures among the lists."""
        return len(self._stacks)

    def chunk(self, a: int, b: int) -> list[list[Goal]]:
        """Lists a to b - 1 (already checked)."""
        return self.raw[a:b]

    def block(self, a: int, b: int, tolerances: tuple[float, float] | None = None) -> GoalBlock:
        """Lists a to b - 1 as a :class:`GoalBlock` (``tolerances`` unused: each goal has its own)."""
        by_key: dict[tuple, list[int]] = {}
        for i in range(a, b):
            if i in self.preferences or any(g.alternatives is not None for g in self.raw[i]):
                continue  # goal sets and preferences go to the one-by-one solver (search.answer_choice)
            by_key.setdefault(self._keys[i], []).append(i)
        groups = []
        for key, rows in by_key.items():
            P = np.ascontiguousarray([self._targets[i][0] for i in rows], dtype=float)
            Rts = np.ascontiguousarray([self._targets[i][1] for i in rows], dtype=float)
            groups.append((np.array(rows) - a, GoalArrays(self._stacks[key], P, Rts)))
        lists = self.raw[a:b]
        return GoalBlock(groups, len(lists), lists.__getitem__)

    def check(self) -> None:
        """Nothing to do: every list was checked when the source was made."""

    def require_q0(self, rows) -> None:
        """The OptionError of the first list among ``rows`` whose preferences need a q0 (MinimalDisplacement)."""
        for i in rows:
            prefs = self.preferences.get(i)
            if prefs:
                try:
                    check_preferences(self._robot, prefs, self._frames[i], with_q0=False)
                except OptionError as exc:
                    raise OptionError(f"goal list {i}: {exc}") from None


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
        return self._named(Target.coerce_many, self.raw[a:b])

    def _named(self, check, part):
        """``check(part)``; its TargetError re-raised naming the bad target by its index in the call (:meth:`check`)."""
        try:
            return check(part)
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
        H = self._named(Target.check_poses, poses[a:b])
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


class GoalTree:
    """The seed table's entries searchable by nearness to problems of one goal stack in memetic's goal metric: a
    k-d tree over the table's goal features (:meth:`SeedTable.goal_table_features`), or for a tip target's stack
    (``tip``) the table's own tree of its kind (:meth:`SeedTable.nearest`). ``allowed``: (size,) bool, the entries to
    search (a scene's collision-free ones), or None for all."""

    def __init__(self, robot, table, stack, allowed: np.ndarray | None = None, tip: bool = False) -> None:
        self.table, self.allowed = table, allowed
        self.tip_kind = stack.kinds[0] if tip else None
        if tip:  # the table's tree of the kind built now (BatchSolver makes its trees under a lock)
            table.nearest(self.tip_kind, np.zeros((0, 3)), np.zeros((0, 3, 3)), 1, allowed)
            return
        from scipy.spatial import cKDTree

        # per goal (sqrt(weight), oriented); a goal beyond one frame has no frame target to rank by: weight 0
        weights = np.where(np.array(stack.kinds) >= KIND_BEYOND_FRAME, 0.0, stack.spec[:, G_WEIGHT]).tolist()
        self.spec = tuple((w, bool(o)) + ((False,) if k in POSITIONLESS_KINDS else ())  # SeedTable.goal_spec's
                          for w, o, k in zip(weights, stack.oriented, stack.kinds, strict=True))
        F, _ = table.goal_table_features(tuple(stack.frames), self.spec)
        self.index = np.arange(table.Q.shape[0]) if allowed is None else np.nonzero(allowed)[0]
        self.tree = cKDTree(F[self.index])

    def nearest(self, arrays: GoalArrays, k: int, eps: float = 0.0) -> np.ndarray:
        """Indices (N, k) of the entries nearest to each problem, nearest first (k capped at the entries searched);
        ``eps``: ``cKDTree.query``'s approximation factor."""
        if self.tip_kind is not None:
            return self.table.nearest(self.tip_kind, arrays.P[:, 0], arrays.Rts[:, 0], k, self.allowed, eps)
        k = min(k, self.tree.n)
        N = len(arrays)
        if k == 0 or N == 0:
            return np.zeros((N, 0), dtype=np.intp)
        _, idx = self.tree.query(self.table.goal_features(self.spec, arrays.P, arrays.Rts), k=k, eps=eps)
        return self.index[np.asarray(idx, dtype=np.intp).reshape(N, k)]
