"""Standing starts for a goal list that holds a stance (issue 32): a :class:`~evoik_pin.goals.CenterOfMass` support
goal whose every support frame is fixed by a :class:`~evoik_pin.goals.Pose` goal (soles on the ground), on a floating
base. The seed table's entries have random bases and legs: from them LM must stand the whole body up and place the
hands at once, which on G1 took up to 40 LM runs. A :class:`StanceTable` holds configurations that already meet the
stance goals (made once per stance by LM on those goals alone, before any clock), ranked by the other goals'
nearness: LM from the nearest has little more than the hands to move (on G1's 300 benchmark problems, p95 3 and at
most 14 LM runs instead of 10 and 39; scripts/bench_balance_humanoids.py)."""

from __future__ import annotations

import weakref

import numpy as np

from ...goals.center_of_mass import KIND_COM_SUPPORT
from ...goals.pose import KIND_POSE
from ...goals.registry import KIND_BEYOND_FRAME
from ...lie import rpy

__all__ = ["STANCE_TABLE_SIZE", "StanceTable", "stance_indices", "stance_starts", "stance_table"]

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
#: times the rotation matrix's entries (on G1, 0.1 started 84 % of the problems at an entry one LM run solves, the
#: seed table's quarter reach 74 %; 0.05 83 %).
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
        self._features: dict = {}  # frames -> (P (size, G, 3), R (size, G, 3, 3), rotation scale m)

    def ranked(self, problem, rest: list[int], k: int) -> np.ndarray:
        """Indices of the (up to) ``k`` entries nearest the goals ``rest`` (indices into ``problem.goals``) of one
        frame, nearest first: the sum over them of weight x (|p - p_t|^2 + s^2 |R - R_t|_F^2), over the goals' own
        position and orientation (s: :data:`ROTATION_SHARE` x the frames' reach)."""
        from .seed_table import seed_targets

        goals = problem.goals
        rest = [g for g in rest if goals[g].kind < KIND_BEYOND_FRAME]
        if not rest or not self.Q.shape[0]:
            return np.arange(min(k, self.Q.shape[0]))
        P, R, s = self._poses(tuple(goals[g].frame for g in rest))
        pt, Rt = seed_targets(problem)
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
    """The floating base's six entries (x, y, z, yaw, pitch, roll; clipped into the box) that put ``pose_goal``'s frame
    on its target when every other joint is 0 clipped into the box."""
    q = np.minimum(np.maximum(0.0, lower), upper)
    q[:6] = 0.0
    T = robot.fk(q, pose_goal.frame)  # relative to the base: the base is at the origin
    R = pose_goal.target.rotation @ T.rotation.T
    base = np.concatenate([pose_goal.target.translation - R @ T.translation, rpy(R)[0, ::-1]])
    return np.minimum(np.maximum(base, lower[:6]), upper[:6])


def stance_table(problem) -> tuple[StanceTable, tuple[int, ...]] | None:
    """(the cached :class:`StanceTable` of ``problem``'s stance, :func:`stance_indices`) for a goal list on a
    floating-base robot that holds a stance and other goals; None otherwise. Made on first use (one-time set-up:
    ~256-400 LM runs, 30-70 ms on a humanoid), then kept per robot, box and stance targets."""
    robot = problem.robot
    if problem.target is not None or not robot.floating_base:
        return None
    stance = stance_indices(problem.goals)
    if stance is None:
        return None
    goals = problem.goals
    key = (problem.lower.tobytes(), problem.upper.tobytes(), *(
        (g.frame, g.target.homogeneous.tobytes(), g.weight, g.tolerance, g.rotation_tolerance)
        for g in (goals[i] for i in stance[:-1])), goals[stance[-1]].batch_key(), goals[stance[-1]].tolerance)
    per_robot = _TABLES.setdefault(robot, {})
    table = per_robot.get(key)
    if table is None:
        table = StanceTable(problem, stance)
        if len(per_robot) >= TABLES_PER_ROBOT:
            per_robot.pop(next(iter(per_robot)))
        per_robot[key] = table
    return table, stance


_TABLES: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()


def stance_starts(problem, found: tuple[StanceTable, tuple[int, ...]], starts, k: int):
    """The starts of a goal list holding a stance (``found``: :func:`stance_table`'s), lazily: the stance table's
    ``k`` entries nearest the other goals, then the seed table's ``starts`` (an iterable of (n,) configurations)."""
    table, stance = found
    rest = [g for g in range(len(problem.goals)) if g not in stance]
    for i in table.ranked(problem, rest, k):
        yield table.Q[i].copy()
    yield from starts
