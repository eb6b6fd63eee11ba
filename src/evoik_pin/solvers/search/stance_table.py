"""Standing starts for a goal list that holds a stance (issue 32): a :class:`~evoik_pin.goals.CenterOfMass` support
goal whose every support frame is fixed by a :class:`~evoik_pin.goals.Pose` goal (soles on the ground), on a floating
base. A :class:`StanceTable` holds configurations that already meet the stance goals (made once per stance by LM on
those goals alone, before any clock), ranked by the other goals' nearness: LM from the nearest has little more than
the hands to move, where from the seed table's random bases and legs it must stand the whole body up too."""

from __future__ import annotations

import threading
import weakref

import numpy as np

from ...goals.center_of_mass import KIND_COM_SUPPORT
from ...goals.pose import KIND_POSE
from ...goals.registry import KIND_BEYOND_FRAME
from .seed_table import base_onto, kept_per_robot, seed_targets

__all__ = ["STANCE_TABLE_SIZE", "StanceTable", "stance_indices", "stance_key", "stance_starts", "stance_table"]

#: Standing configurations a stance table holds.
STANCE_TABLE_SIZE = 256
#: LM runs a stance table's making may take, per configuration it holds (an unreachable stance stops there).
RUNS_PER_ENTRY = 4
#: Seed of the starts a stance table is made from (its own generator: a solve's ``rng`` draws nothing for it). Not a
#: small number: benchmarks draw their problems' configurations from seeds 0, 1, 2, ... the same way, and a table made
#: from the same draws would hold their answers.
TABLE_SEED = 0x57A9CE
#: Stance tables kept per robot (the last ones made).
TABLES_PER_ROBOT = 4
#: The rotation's features are this share of the ranked frames' largest distance (m) from the first support frame
#: times the rotation matrix's entries.
ROTATION_SHARE = 0.1


def stance_indices(goals) -> tuple[int, ...] | None:
    """The indices in ``goals`` of a stance: each support frame's :class:`Pose` goal (a full pose, no bands), then the
    first CenterOfMass support goal all of whose support frames have one; None when the goals hold no stance, or
    nothing but one (no other goal to rank the table by)."""
    poses = {g.frame: i for i, g in enumerate(goals) if g.kind == KIND_POSE and g.alternatives is None}
    for i, g in enumerate(goals):
        if g.kind == KIND_COM_SUPPORT and g.alternatives is None and all(f in poses for f in g.support):
            chosen = (*(poses[f] for f in g.support), i)
            return chosen if len(chosen) < len(goals) else None
    return None


class StanceTable:
    """Configurations (Q (size, n)) meeting a stance's goals in a search box, and their nearness to other goals.

    Args:
        problem: an IK problem (a goal list on a floating-base robot) whose goals hold a stance.
        stance: :func:`stance_indices` of its goals.

    Made by LM (the compiled engine) on the stance goals alone from :data:`STANCE_TABLE_SIZE` x
    :data:`RUNS_PER_ENTRY` starts at most, each every joint uniform in the box (a generator of its own, seeded
    :data:`TABLE_SEED`) and the base upright: the first support frame on its target when every other joint is 0
    (clipped into the box). Q holds the converged runs' answers (none for an unreachable stance)."""

    def __init__(self, problem, stance: tuple[int, ...]) -> None:
        from ...problem import IKProblem  # the problem module imports the solvers' package
        from ..lm import DEFAULT_ITERATIONS, LevenbergMarquardt

        robot = self._robot = problem.robot
        lower, upper = problem.lower, problem.upper
        goals = [problem.goals[i] for i in stance]
        sub = IKProblem(robot, goals, lower=lower, upper=upper)
        lm = LevenbergMarquardt(sub)
        base = _upright_base(robot, goals[0], lower, upper)
        rng = np.random.default_rng(TABLE_SEED)
        out = []
        for _ in range(RUNS_PER_ENTRY * STANCE_TABLE_SIZE):
            q = rng.uniform(lower, upper)
            q[:6] = base
            run = lm.run(q, DEFAULT_ITERATIONS)
            if run.converged:
                out.append(run.q)
                if len(out) == STANCE_TABLE_SIZE:
                    break
        self.Q = np.array(out).reshape(-1, robot.n)
        self._anchor = goals[0].frame
        #: (heading rad, x, y m) of the first support frame's target: the ground frame the entries stand in
        self.ground = _ground_frame(goals[0].target)
        self._features: dict = {}  # frames -> (P (size, G, 3), R (size, G, 3, 3), rotation scale m)

    def ranked(self, goals, pt: np.ndarray, Rt: np.ndarray, rest: list[int], k: int) -> np.ndarray:
        """Indices of the (up to) ``k`` entries nearest the goals ``rest`` (indices into ``goals``, targets pt (G, 3)
        m, Rt (G, 3, 3) in the table's frame) of one frame, nearest first: the sum over them of weight x
        (|p - p_t|^2 + s^2 |R - R_t|_F^2), over the goals' own position and orientation (s: :data:`ROTATION_SHARE` x
        the frames' reach)."""
        rest = [g for g in rest if goals[g].kind < KIND_BEYOND_FRAME]
        if not rest or not self.Q.shape[0]:
            return np.arange(min(k, self.Q.shape[0]))
        P, R, s = self._poses(tuple(goals[g].frame for g in rest))
        d = np.zeros(self.Q.shape[0])
        for j, g in enumerate(rest):
            goal = goals[g]
            if goal.has_position:
                d += goal.weight * ((P[:, j] - pt[g]) ** 2).sum(axis=1)
            if goal.has_orientation:
                d += goal.weight * s * s * ((R[:, j] - Rt[g]) ** 2).sum(axis=(1, 2))
        return np.argsort(d, kind="stable")[:k]

    def _poses(self, frames: tuple[str, ...]) -> tuple[np.ndarray, np.ndarray, float]:
        """The entries' poses of ``frames`` and the rotation's scale (m), cached per frames."""
        hit = self._features.get(frames)
        if hit is None:
            P, R = self._robot.fk_batch(self.Q, validate=False, frames=list(frames))
            anchor = self._robot.fk_batch(self.Q, validate=False, frames=[self._anchor])[0]
            reach = float(np.sqrt(((P - anchor) ** 2).sum(axis=2)).max()) if P.size else 1.0
            if len(self._features) > 8:
                self._features.clear()
            hit = self._features[frames] = (P, R, ROTATION_SHARE * max(reach, 1e-3))
        return hit


def _upright_base(robot, pose_goal, lower: np.ndarray, upper: np.ndarray) -> np.ndarray:
    """The floating base's six entries (:func:`~.seed_table.base_onto`) that put ``pose_goal``'s frame on its target
    when every other joint is 0 clipped into the box."""
    q = np.minimum(np.maximum(0.0, lower), upper)
    q[:6] = 0.0
    T = robot.fk(q, pose_goal.frame)  # relative to the base: the base is at the origin
    return base_onto(pose_goal.target.translation, pose_goal.target.rotation, T.translation, T.rotation, lower, upper)


def _ground_frame(T) -> tuple[float, float, float]:
    """(heading rad, x m, y m) of a pose ``T`` (pin.SE3) on the ground: its x axis's direction about the world's z,
    its origin's x and y."""
    R, p = T.rotation, T.translation
    return float(np.arctan2(R[1, 0], R[0, 0])), float(p[0]), float(p[1])


def _turn(heading: float) -> np.ndarray:
    """The rotation (3, 3) by ``heading`` (rad) about the world's z."""
    c, s = np.cos(heading), np.sin(heading)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def stance_key(problem, stance: tuple[int, ...]) -> tuple:
    """What a stance table depends on: the box, each support frame's target seen from the first one's ground frame
    (:func:`_ground_frame`; rounded to 1e-9: a stance moved on the ground, or turned about the vertical, has the same
    key, its CoM support goal the same answers), the goals' weights and tolerances, the support goal's numbers."""
    goals = problem.goals
    heading, x, y = _ground_frame(goals[stance[0]].target)
    turn = _turn(-heading)
    seen = []
    for g in (goals[i] for i in stance[:-1]):
        M = np.eye(4)
        M[:3, :3] = turn @ g.target.rotation
        M[:3, 3] = turn @ (g.target.translation - [x, y, 0.0])
        seen.append((g.frame, (np.round(M, 9) + 0.0).tobytes(), g.weight, g.tolerance, g.rotation_tolerance))
    support = goals[stance[-1]]
    return (problem.lower.tobytes(), problem.upper.tobytes(), *seen, support.batch_key(), support.weight,
            support.tolerance)


def stance_table(problem, make: bool = True) -> tuple[StanceTable, tuple[int, ...]] | None:
    """(the cached :class:`StanceTable` of ``problem``'s stance, :func:`stance_indices`) for a goal list on a
    floating-base robot that holds a stance and other goals; None otherwise. Made on first use when ``make`` (one-time
    set-up: 256-400 LM runs, 25-80 ms on a humanoid; without ``make``, None until then), then kept per robot and
    :func:`stance_key`: the same stance elsewhere on the ground takes the same table (:func:`stance_starts` moves its
    entries)."""
    robot = problem.robot
    if problem.target is not None or not robot.floating_base:
        return None
    stance = stance_indices(problem.goals)
    if stance is None:
        return None
    with _MAKING:  # solve_many's threads: one table made per stance, the cache changed by one at a time
        table = kept_per_robot(_TABLES, robot, stance_key(problem, stance),
                               (lambda: StanceTable(problem, stance)) if make else None, TABLES_PER_ROBOT)
    return None if table is None else (table, stance)


_TABLES: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()
_MAKING = threading.Lock()


def stance_starts(problem, found: tuple[StanceTable, tuple[int, ...]], starts, k: int):
    """The starts of a goal list holding a stance (``found``: :func:`stance_table`'s), lazily: the stance table's
    ``k`` entries nearest the other goals, then the seed table's ``starts`` (an iterable of (n,) configurations).
    A table made for the same stance elsewhere on the ground: the goals' targets are seen from its ground frame, its
    entries' bases moved onto this stance's (clipped into the box)."""
    table, stance = found
    goals = problem.goals
    rest = [g for g in range(len(goals)) if g not in stance]
    pt, Rt = seed_targets(problem)
    here = _ground_frame(goals[stance[0]].target)
    moved = here != table.ground
    if moved:  # targets into the table's ground frame: T -> G_table G_here^-1 T
        turn = _turn(table.ground[0] - here[0])
        pt = (pt - [here[1], here[2], 0.0]) @ turn.T + [table.ground[1], table.ground[2], 0.0]
        Rt = turn @ Rt
        back = turn.T  # an entry's base back onto this stance: the inverse move
    for i in table.ranked(goals, pt, Rt, rest, k):
        q = table.Q[i].copy()
        if moved:
            q[:3] = (q[:3] - [table.ground[1], table.ground[2], 0.0]) @ back.T + [here[1], here[2], 0.0]
            q[3] = (q[3] + here[0] - table.ground[0] + np.pi) % (2.0 * np.pi) - np.pi  # the yaw, one turn
            q[:6] = np.minimum(np.maximum(q[:6], problem.lower[:6]), problem.upper[:6])
        yield q
    yield from starts
