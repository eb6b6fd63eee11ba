"""IK problems: what a solver sees (:class:`IKProblem`: robot, target or goal list, objective, search box,
tolerances, scene) and the cost and errors of a population from one forward-kinematics pass."""

from __future__ import annotations

import math
import os
from dataclasses import dataclass, field, replace
from typing import TYPE_CHECKING

import numpy as np

from .errors import ConfigurationError, OptionError
from .goals import bind, is_goal_list
from .goals.goal import FramePair
from .goals.registry import KIND_BEYOND_FRAME
from .goals.stack import owned, tip_goals
from .io.datafile import naming
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
from .robot.robot import NEAR_UNBOUNDED
from .solvers.options import check_nonnegative, check_positive
from .target import MAX_TARGET_NORM, Target

if TYPE_CHECKING:
    from .scene import Scene

__all__ = ["COLLISION_PENALTY", "DEFAULT_PRO_DELTA", "MAX_TARGET_NORM", "NEAR_UNBOUNDED", "Evaluation", "IKProblem",
           "Target", "check_pro_delta", "check_q0", "coerce_scene", "errors_text", "pro_box", "shortfall_text",
           "target_box"]

#: Added to the cost (m + rad) of a configuration in collision when a scene is given: more than any pose error
#: of a reachable arm's configuration, so a search prefers every collision-free configuration.
COLLISION_PENALTY = 10.0
#: Half-width (rad) of paper 002's "Pro" search box around the previous trajectory solution.
DEFAULT_PRO_DELTA = np.pi / 100
#: Most combinations of goal-set members a solve searches (:meth:`IKProblem.variants`).
MAX_VARIANTS = 256


def check_pro_delta(delta) -> float:
    """The half-width (rad) of paper 002's "Pro" search box as a float > 0; OptionError otherwise."""
    return check_positive("delta (the Pro box half-width)", delta, unit="rad")


def check_q0(robot: Robot, q0) -> np.ndarray:
    """``q0`` as ``robot``'s (n,) joint vector (rad or m); ConfigurationError naming q0 otherwise."""
    with naming("q0", ConfigurationError):
        return robot.check_q(q0)


def coerce_scene(robot: Robot, scene) -> Scene | None:
    """The :class:`~evoik_pin.scene.Scene` a ``scene`` argument names: a Scene, a scene file's path (str or
    ``os.PathLike``, :meth:`Scene.from_file`) or None.

    Raises:
        OptionError: another type. SceneError: a file that is missing or does not parse.
    """
    from .scene import Scene

    if scene is None or isinstance(scene, Scene):
        return scene
    if isinstance(scene, (str, os.PathLike)):
        return Scene.from_file(robot, scene)
    raise OptionError(f"scene must be an evoik_pin.Scene or the path of a scene file (str or pathlib.Path; "
                      f".yaml, .yml or .json), got {type(scene).__name__}")


def goal_summary(goals, errors, orientation_weight: float) -> tuple[float, float | None, float]:
    """(largest position error m, largest rotation angle rad or None, cost) of ``goals``' errors ``errors`` (per goal:
    position m or None, angle rad or None; :meth:`IKProblem.goal_errors`): the cost is the sum over the goals of
    ``weight x (position error + orientation_weight x angle)``."""
    # _goal_cost's sum for one row, in plain floats: faster than NumPy for a few goals
    pos = cost = 0.0
    for g, (p, r) in zip(goals, errors, strict=True):
        p, r = p or 0.0, r or 0.0  # None: a goal without a position (Orientation, ...) or an angle
        pos = pos if pos != pos else (p if p != p else max(pos, p))  # NumPy's max: a NaN error stays NaN
        cost += (p + orientation_weight * r) * g.weight
    return float(pos), max((r for _, r in errors if r is not None), default=None), float(cost)


@dataclass(frozen=True)
class Evaluation:
    """Cost and errors of a population (each (N,)); ``orientation_error`` is None for position targets."""

    cost: np.ndarray
    position_error: np.ndarray
    orientation_error: np.ndarray | None


@dataclass
class IKProblem:
    """Robot + target (or goal list) + objective + search box + tolerances: everything a solver sees.

    Attributes:
        robot: the robot to solve for.
        target: the tip's :class:`Target` (coerced from any accepted form) when the problem came as one; None for a
            goal list.
        goals: the goal list every solver reads (:mod:`evoik_pin.goals`, given as ``target`` or ``goals``), bound to
            the robot; a tip target's is its one goal on the tip (:func:`~evoik_pin.goals.stack.tip_goals`). A goal
            list's cost is the weighted sum over the goals of position error + ``orientation_weight`` x angle.
        objective: a tip target's vectorized cost; default :func:`~evoik_pin.objectives.default_objective`. None
            for a goal list.
        lower, upper: (n,) search box (rad or m); default the robot's bounds, near-unbounded joints narrowed around
            the target (:func:`target_box`).
        tolerance: success threshold on the position error (m); rotation_tolerance: on the angle (rad), default
            ``tolerance``.
        q0: optional (n,) initial / previous configuration.
        orientation_weight: m per rad in the pose cost; pose_metric: ``"sum"`` or ``"euclidean"``
            (:data:`~evoik_pin.objectives.POSE_METRICS`).
        scene: a :class:`~evoik_pin.scene.Scene` or a scene file's path (:func:`coerce_scene`): answers must be
            collision-free; the cost of a configuration whose convex-hull proxies collide gets ``COLLISION_PENALTY``.
        margin: clearance (m) an answer must keep from collisions.
        evaluations: configurations evaluated so far (every :meth:`evaluate` adds N).
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
    goals: list | None = None
    evaluations: int = field(default=0, compare=False)

    def __post_init__(self) -> None:
        if is_goal_list(self.target):
            self.target, self.goals = None, self.target
        if self.target is None:
            if self.objective is not None:
                raise OptionError("a goal list has its own cost (the goals' weighted errors); give no objective")
            self.goals, *self._goal_stack = bind(self.robot, self.goals)
        else:
            self.target = Target.coerce(self.target)
        if self.rotation_tolerance is None:
            self.rotation_tolerance = self.tolerance
        for name in ("tolerance", "orientation_weight", "rotation_tolerance"):
            setattr(self, name, check_nonnegative(name, getattr(self, name)))
        if self.target is not None:  # the tip target's one goal: what every solver below reads
            self.goals, *self._goal_stack = tip_goals(self.robot, self.target, self.tolerance, self.rotation_tolerance)
        if self.lower is None and self.upper is None:  # the robot's own bounds, checked when they were set
            if self.target is None:  # a goal list: the robot's bounds (near-unbounded joints: give bounds=)
                self.lower, self.upper = self.robot.lower.copy(), self.robot.upper.copy()
            else:
                self.lower, self.upper = target_box(self.robot, self.target, self.robot.lower, self.robot.upper)
        else:
            lower = self.robot.lower if self.lower is None else np.asarray(self.lower, dtype=float)
            upper = self.robot.upper if self.upper is None else np.asarray(self.upper, dtype=float)
            self.lower, self.upper = self.robot.checked_bounds(lower, upper)
        if self.q0 is not None:
            self.q0 = check_q0(self.robot, self.q0)
        self.margin = check_nonnegative("margin (m)", self.margin)
        if self.scene is not None:
            self.scene = coerce_scene(self.robot, self.scene)
            self.scene.check_robot(self.robot)
        if self.pose_metric not in POSE_METRICS:
            raise OptionError(f"pose_metric {self.pose_metric!r} is not one of {POSE_METRICS}")
        if self.target is not None and self.objective is None:
            self.objective = default_objective(self.target, self.orientation_weight, self.pose_metric)

    @property
    def n(self) -> int:
        """Number of joints."""
        return self.robot.n

    def copy_with(self, **fields) -> IKProblem:
        """This problem with ``fields`` replaced and no evaluation counted, the values taken as checked (no
        ``__post_init__``): a new target's, goals' or box's problem sharing the rest."""
        p = object.__new__(IKProblem)
        p.__dict__ = {**self.__dict__, "evaluations": 0, **fields}
        return p

    # ------------------------------------------------------------------ goal lists
    def goal_stack(self):
        """(the LM kernel's :class:`~evoik_pin.solvers.lm.layout.GoalStack`, targets pt (G, 3), Rt (G, 3, 3)) of a goal
        list."""
        return tuple(self._goal_stack)

    def nearest_members(self, Q: np.ndarray) -> np.ndarray:
        """(N, G) int: per row of ``Q`` (N, n) and goal, the index of the goal set's member whose errors the
        violation (:meth:`goal_violation`) reads, the one nearest by position + orientation_weight x angle (0 for a
        goal with one target). Bookkeeping: no evaluation is counted."""
        return self._goal_population_members(Q)[2]

    def goal_rows(self, Q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The LM kernel's task rows of a goal list at each row of ``Q`` (N, n): the stacked error e (N, rows) and its
        Jacobian E (N, rows, n), each goal's rows scaled by the square root of its weight, a goal set's those of the
        member nearest (:meth:`nearest_members`). One compiled call; no evaluation is counted."""
        from .solvers.lm.population_rows import task_rows_batch

        stack, pt, Rt = self._goal_stack
        Q = owned(np.asarray(Q), float)  # writable C arrays throughout: the entry's one compiled signature
        N = Q.shape[0]
        P, Rts = np.repeat(pt[None], N, axis=0), np.repeat(Rt[None], N, axis=0)
        if self.goal_sets:
            members = self.nearest_members(Q)
            for g in self.goal_sets:
                P[:, g], Rts[:, g] = (t[members[:, g]] for t in self.goals[g].member_targets)
        e, E = np.empty((N, stack.rows)), np.empty((N, stack.rows, self.n))
        task_rows_batch(Q, *(owned(a) for a in self.robot.tree_constants()), *(owned(a) for a in stack.arrays), P, Rts,
                        e, E, np.empty((N, len(self.goals), 2)))
        return e, E

    def _goal_population_members(self, Q: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(position errors (N, G) m, rotation angles (N, G) rad, 0 for goals without orientation) of ``Q`` (N, n), and
        the goal-set members they are of (:meth:`nearest_members`)."""
        from .lie import relative_angle

        P, R = self.robot.fk_batch(Q, validate=False, frames=[g.frame for g in self.goals])
        _, pt, Rt = self._goal_stack
        d = P - pt
        pos = np.sqrt((d * d).sum(axis=2))
        rot = np.zeros_like(pos)
        for g, goal in enumerate(self.goals):
            if goal.kind >= KIND_BEYOND_FRAME:  # centre of mass, relative pose: their own violation
                pos[:, g], rot[:, g] = goal.robot_population_errors(self.robot, Q)
                continue
            kinded = goal.population_errors(P[:, g], R[:, g], pt[g], Rt[g])  # bands, free axes, pointing
            if kinded is not None:
                pos[:, g], rot[:, g] = kinded
            elif goal.has_orientation:
                rot[:, g] = relative_angle(Rt[g], R[:, g])
        members = np.zeros(pos.shape, dtype=np.intp)
        for g in self.goal_sets:  # a goal set's violation: that of its member nearest by the goals' cost
            for m, member in enumerate(self.goals[g].alternatives[1:], start=1):
                pm, Rm = member.encode()
                pos_m = np.linalg.norm(P[:, g] - pm, axis=1)
                rot_m = relative_angle(Rm, R[:, g]) if member.has_orientation else np.zeros_like(pos_m)
                better = pos_m + self.orientation_weight * rot_m < pos[:, g] + self.orientation_weight * rot[:, g]
                pos[:, g] = np.where(better, pos_m, pos[:, g])
                rot[:, g] = np.where(better, rot_m, rot[:, g])
                members[:, g] = np.where(better, m, members[:, g])
        return pos, rot, members

    def _goal_cost(self, pos: np.ndarray, rot: np.ndarray) -> np.ndarray:
        """The goals' cost (N,) from their errors (N, G): the weighted sum of position + orientation_weight x angle."""
        w = np.array([g.weight for g in self.goals])
        return (pos + self.orientation_weight * rot) @ w

    def goal_errors(self, q: np.ndarray) -> list[tuple[float, float | None]]:
        """Each goal's (position error m, rotation angle rad or None) at ``q`` (n,), in the goals' order (a goal
        set's: those of its member :meth:`chosen` picks)."""
        return self.goal_errors_and_chosen(q)[0]

    def goal_errors_and_chosen(self, q: np.ndarray) -> tuple[list[tuple[float, float | None]], list[int | None]]:
        """(:meth:`goal_errors`, :meth:`chosen`) at ``q`` (n,) from one kinematics pass: a goal set's member is
        picked once for both."""
        q = np.asarray(q, dtype=float)
        robot, goals = self.robot, self.goals
        # a two-frame goal's frame a joins the same Pinocchio pass: its errors from the two poses (pair_errors), not
        # from a kinematics pass of its own per goal (a retargeting frame has ~10 of them)
        paired = [g for g in goals if isinstance(g, FramePair)]
        fids = [robot.frame_id(g.frame) for g in goals] + [robot.frame_id(g.frame_a) for g in paired]
        poses = robot.frame_poses_unchecked(q, fids)
        frame_a_pose = dict(zip(map(id, paired), poses[len(goals):], strict=True))

        def beyond(g, T) -> tuple[float, float | None]:
            Ta = frame_a_pose.get(id(g))
            return g.robot_errors(robot, q) if Ta is None else g.pair_errors(Ta, T)

        picked = [(None, beyond(g, T)) if g.kind >= KIND_BEYOND_FRAME else self._member(g, T)
                  for g, T in zip(goals, poses[:len(goals)], strict=True)]
        return [p[1] for p in picked], [p[0] for p in picked]

    # ------------------------------------------------------------------ goal sets (evoik_pin.goals.goal)
    @property
    def goal_sets(self) -> list[int]:
        """Indices of the goals that are goal sets (any one of several targets)."""
        found = self.__dict__.get("_goal_set_indices")
        if found is None or found[0] is not self.goals:
            found = self.__dict__["_goal_set_indices"] = (self.goals, [i for i, g in enumerate(self.goals)
                                                                       if g.alternatives is not None])
        return found[1]

    def _member(self, goal, T) -> tuple[int | None, tuple[float, float | None]]:
        """(index of the member of ``goal`` its frame at pose ``T`` meets, or failing that is nearest to by
        position + orientation_weight x angle; None for a single target), with that member's errors)."""
        if goal.alternatives is None:
            return None, goal.errors(T)
        from .lie import relative_angle

        P, R = goal.member_targets  # a vectorized screen, then the exact errors of the member picked
        pos = np.linalg.norm(P - T.translation, axis=1)
        rot = relative_angle(T.rotation, R) if goal.has_orientation else np.zeros_like(pos)
        met = np.nonzero((pos <= goal.tolerance) & (rot <= goal.rotation_tolerance))[0]
        i = int(met[0]) if met.size else int(np.argmin(pos + self.orientation_weight * rot))
        return i, goal.alternatives[i].errors(T)

    def chosen(self, q: np.ndarray) -> list[int | None] | None:
        """Per goal, the index of the member of a goal set the configuration ``q`` (n,) meets (or comes nearest
        to), None for a goal with one target; None for a tip target (:meth:`reported`)."""
        return self.reported(self.goal_errors_and_chosen(q)[1])

    def variant_targets(self, most: int = MAX_VARIANTS) -> tuple[list[tuple], np.ndarray, np.ndarray]:
        """The combinations of goal-set members (:meth:`variants`) without making their problems: (members chosen
        per goal, None for a single target; targets pt (V, G, 3), Rt (V, G, 3, 3)). OptionError beyond ``most``."""
        import itertools

        _, pt, Rt = self.goal_stack()
        sets = self.goal_sets
        sizes = [len(self.goals[g].alternatives) for g in sets]
        if math.prod(sizes) > most:
            raise OptionError(f"goal sets of {' x '.join(map(str, sizes))} members make {math.prod(sizes)} "
                              f"combinations; at most {most} are searched: give fewer members")
        combos = list(itertools.product(*[range(k) for k in sizes]))
        P = np.repeat(pt[None], len(combos), axis=0)
        R = np.repeat(Rt[None], len(combos), axis=0)
        for g, members in zip(sets, np.array(combos, dtype=np.intp).reshape(len(combos), -1).T, strict=True):
            P[:, g], R[:, g] = self.goals[g].member_targets[0][members], self.goals[g].member_targets[1][members]
        G = len(self.goals)  # a choice per goal: its member, None for a goal with one target
        choices = [tuple(dict(zip(sets, combo, strict=True)).get(g) for g in range(G)) for combo in combos]
        return choices, P, R

    def variant(self, choice: tuple, pt: np.ndarray, Rt: np.ndarray) -> IKProblem:
        """The problem of one combination of goal-set members (:meth:`variant_targets`): those members as its goals,
        sharing this problem's box, q0 and scene."""
        if not self.goal_sets:
            return self
        goals = [g if m is None else g.alternatives[m] for g, m in zip(self.goals, choice, strict=True)]
        return self.copy_with(goals=goals, _goal_stack=[self._goal_stack[0], pt, Rt])

    def variants(self, most: int = MAX_VARIANTS) -> list[tuple[tuple, IKProblem]]:
        """The single-target problems of a goal list with goal sets, one per combination of their members (in
        ``itertools.product`` order over the sets): (members chosen per goal, None for a single target; the problem
        with those members as goals, sharing this one's box, q0 and scene). A list of one (None choices, self)
        without goal sets. OptionError beyond ``most`` combinations."""
        if not self.goal_sets:
            return [(tuple([None] * len(self.goals)), self)]
        choices, P, R = self.variant_targets(most)
        return [(c, self.variant(c, P[v], R[v])) for v, c in enumerate(choices)]

    def goal_summary(self, errors) -> tuple[float, float | None, float]:
        """(largest position error m, largest rotation angle rad or None, cost) of a goal list's errors
        (:meth:`goal_errors`): what :meth:`assess` returns for a goal list (:func:`goal_summary`)."""
        return goal_summary(self.goals, errors, self.orientation_weight)

    def summary(self, q: np.ndarray, errors) -> tuple[float, float | None, float]:
        """(largest position error m, largest angle rad or None, cost) of ``q`` (n,) whose goals' errors are
        ``errors`` (:meth:`goal_errors`, or the kernel's): a goal list's :meth:`goal_summary`; a tip target's
        errors with its objective's cost (:meth:`assess`)."""
        if self.target is None:
            return goal_summary(self.goals, errors, self.orientation_weight)
        return self.assess(q, *errors[0])

    def reported(self, errors):
        """What a Result reports as ``goal_errors``: ``errors`` for a goal list, None for a tip target."""
        return errors if self.target is None else None

    def goals_met(self, errors) -> bool:
        """Whether every goal's errors (:meth:`goal_errors`) are within its tolerances."""
        return all(g.met(p, r) for g, (p, r) in zip(self.goals, errors, strict=True))

    def goal_violation(self, Q: np.ndarray, count: bool = True) -> np.ndarray:
        """(N,) how far each row of ``Q`` (N, n) is from meeting every goal: the sum over the goals of the position
        error beyond the goal's ``tolerance`` (m) plus the rotation angle beyond its ``rotation_tolerance`` (rad);
        0 exactly where every goal is met. Counts N evaluations unless ``count`` is False (bookkeeping)."""
        pos, rot, _ = self._goal_population_members(Q)
        self.evaluations += Q.shape[0] if count else 0
        tol = np.array([g.tolerance for g in self.goals])
        rtol = np.array([g.rotation_tolerance if g.reports_angle else np.inf for g in self.goals])
        return (np.maximum(pos - tol, 0.0) + np.maximum(rot - rtol, 0.0)).sum(axis=1)

    def rows_met(self, Q: np.ndarray) -> np.ndarray:
        """(N,) bool: whether each row of ``Q`` (N, n) solves the problem, by the criterion of :func:`evoik_pin.solve`'s
        verdict: every goal within its own tolerances. Bookkeeping: no evaluation is counted."""
        return self.goal_violation(Q, count=False) <= 0.0

    def tightened(self, tolerance: float) -> IKProblem:
        """This problem (robot, box, target or goals) with every tolerance at most ``tolerance`` (m and rad): for
        refinement runs of the LM engine, which stop once the tolerances are met. It keeps its goals (their
        own tolerances still judge answers); only the kernel's goal stack gets the smaller tolerances."""
        from .goals.stack import G_RTOL, G_TOL

        stack, pt, Rt = self._goal_stack
        spec = stack.spec.copy()
        spec[:, [G_TOL, G_RTOL]] = np.minimum(spec[:, [G_TOL, G_RTOL]], tolerance)
        return self.copy_with(goals=list(self.goals), _goal_stack=[replace(stack, spec=spec), pt, Rt])

    def evaluate(self, Q: np.ndarray, count: bool = True) -> Evaluation:
        """Cost and errors of a population ``Q`` (N, n), from one kinematics pass (a goal list: the largest errors
        over the goals); N evaluations counted unless ``count`` is False (bookkeeping, not search)."""
        counted = Q.shape[0] if count else 0
        if self.target is None:
            pos, rot, _ = self._goal_population_members(Q)
            self.evaluations += counted
            oriented = any(g.reports_angle for g in self.goals)
            return Evaluation(self._penalized(Q, self._goal_cost(pos, rot)), pos.max(axis=1),
                              rot.max(axis=1) if oriented else None)
        target = self.target
        if type(self.objective) is PositionError and self.objective.target is target and not target.planar:
            # the default position-only objective, in the solvers' inner loop: skip the generic machinery
            d = self.robot.positions_batch(Q) - target.position
            err = np.sqrt((d * d).sum(axis=1))
            self.evaluations += counted
            return Evaluation(self._penalized(Q, err), err, None)
        kin = PopulationKinematics(self.robot, Q)
        self.evaluations += counted
        cost = self._penalized(Q, self.objective(Q, kin))
        pos = position_errors(self.target, kin)
        rot = orientation_errors(self.target, kin) if self.target.has_orientation else None
        return Evaluation(cost, pos, rot)

    def cost(self, Q: np.ndarray) -> np.ndarray:
        """Objective values (N,) of a population ``Q`` (N, n)."""
        if self.target is None:
            return self.evaluate(Q).cost
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
        """(position error m, orientation error rad or None, objective cost) of one configuration ``q`` (n,); errors a
        local solver already has at this ``q`` are reused, and the cost too when the objective is a function of them
        (:meth:`Objective.from_errors`)."""
        if self.target is None:
            return self.goal_summary(self.goal_errors(q))
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
        lower, upper = pro_box(self.lower, self.upper, q_prev, check_pro_delta(delta))
        return replace(self, lower=lower, upper=upper, q0=np.clip(q_prev, lower, upper), evaluations=0)


def pro_box(lower: np.ndarray, upper: np.ndarray, q_prev: np.ndarray, delta: float) -> tuple[np.ndarray, np.ndarray]:
    """Paper 002's "Pro" search box: ``q_prev +- delta`` (rad or m) intersected with [lower, upper], each (n,)."""
    return (np.clip(np.maximum(lower, q_prev - delta), lower, upper),
            np.clip(np.minimum(upper, q_prev + delta), lower, upper))


def target_box(robot: Robot, target: Target, lower: np.ndarray, upper: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The search box (lower, upper), each (n,) in rad or m, of ``robot`` for ``target``: copies of [lower, upper]
    with each near-unbounded joint (a bound beyond :data:`NEAR_UNBOUNDED`) narrowed to where answers lie, inside
    [lower, upper] (joints driving mimic joints keep it):

    * a revolute joint: one turn, [c - pi, c + pi] (c = 0 clipped into [lower + pi, upper - pi]);
    * a prismatic joint no revolute joint before it turns (a mobile base's x, y, z): ``pinv(A) (t - p_ref)`` (A its
      axes (3, k), p_ref the tip with them at 0) +- the rest of the chain's reach R over A's smallest singular value,
      plus a margin of max(0.1 m, 0.1 R);
    * a prismatic joint a revolute joint turns: +- (|t| + R + margin); after a near-unbounded revolute joint (a base
      moving forward after its yaw) [|t| - R - margin, |t| + R + margin] (give ``bounds=`` to search beyond).
    """
    lower, upper = np.array(lower, dtype=float), np.array(upper, dtype=float)
    far = (np.abs(lower) >= NEAR_UNBOUNDED) | (np.abs(upper) >= NEAR_UNBOUNDED)
    if not far.any():
        return lower, upper
    F_R, F_p, revolute = robot.chain_constants()
    index, scale, offset = robot.chain_coupling()
    # the chain's physical joints' ranges (robot.chain_joints() holds every physical joint of the tree: a mimic finger
    # off the base->tip chain is one more)
    a, b = scale * lower[index] + offset, scale * upper[index] + offset
    plo, phi = np.minimum(a, b), np.maximum(a, b)
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


def shortfall_text(problem: IKProblem, pos: float, rot: float | None, goal_errors=None) -> str:
    """What a failed solve missed, for its message: the best errors against the tolerances, or for a goal list
    (``goal_errors``: each goal's; ``pos`` and ``rot`` the largest) the goals not met."""
    if problem.target is None:
        unmet = [g.label for g, e in zip(problem.goals, goal_errors, strict=True) if not g.met(*e)]
        return f"best {errors_text(pos, rot)} (largest over the goals); goals not met: {', '.join(unmet)}"
    accepted = f"position error <= {problem.tolerance:g} m" + (
        "" if rot is None else f", orientation error <= {problem.rotation_tolerance:g} rad")
    return f"best {errors_text(pos, rot)} exceeds the tolerance ({accepted})"

