"""The seed table: configurations spread over a search box with their tip poses, searchable by nearness to a target.

One table per robot and box (:func:`seed_table`, cached), built from a deterministic Halton sequence (no random
numbers drawn) with its forward kinematics computed once. Read by the memetic solver (:mod:`.memetic`, its stage 2),
by ``memetic-all`` (:mod:`.all_solutions`, its starts) and by :func:`~evoik_pin.solve_many`'s batched rounds
(:mod:`evoik_pin.solvers.batch.threads`). Nearness is ``|p - p_t|^2 + w^2 |R - R_t|_F^2`` with ``w`` a quarter of
the arm's reach (m per unit of the Frobenius distance, which is ``2 sqrt(2) sin(angle / 2)``); position and planar
targets use their own features.
"""

from __future__ import annotations

import weakref

import numpy as np
import pinocchio as pin

from ...goals.pose import KIND_POSE
from ...goals.position import KIND_POSITION
from ...goals.registry import KIND_BEYOND_FRAME
from ...goals.relative_pose import KIND_RELATIVE_POSE, KIND_RELATIVE_POSE_AXES
from ...goals.stack import KIND_PLANAR, KIND_PLANAR_YAW, encode_targets, target_kind
from ...lie import rpy
from ...problem import Target
from ..paper.common import halton

__all__ = ["DEFAULT_GOAL_TABLE_SEEDS", "DEFAULT_TABLE_SEEDS", "SeedTable", "default_table_size", "load_goal_helpers",
           "seed_table"]


#: Seed-table entries tried per target, nearest first (memetic's stage 2 and solve_many's batched rounds).
DEFAULT_TABLE_SEEDS = 17
#: Starts tried for a goal list before memetic's DE restarts (:meth:`SeedTable.goal_starts`: composed starts and
#: table entries alternately). On whole robots a start costs an LM run (~0.1 ms on Talos) and a DE generation a
#: population's tree kinematics in numpy (~1 ms on Talos): with 48 starts every one of 200 Talos, Go2 and Baxter
#: problems (scripts/bench_goals.py) was solved without a restart, against 199, 197 and 198 with 17.
DEFAULT_GOAL_TABLE_SEEDS = 48
#: Target kinds a seed table serves, each with its own nearness features.
_KIND_KEYS = {KIND_POSE: "pose", KIND_POSITION: "position", KIND_PLANAR: "planar", KIND_PLANAR_YAW: "planar_yaw"}
_KINDS = tuple(_KIND_KEYS.values())


class SeedTable:
    """Configurations spread over a search box and their tip poses, searchable by nearness to a target.

    Attributes:
        Q: (size, n) configurations (a Halton sequence mapped onto the box; deterministic).
        positions: (size, 3) tip positions (m); rotations: (size, 3, 3).
        weight: m per unit of rotation-matrix (Frobenius) distance in the pose metric.
    """

    def __init__(self, robot, lower: np.ndarray, upper: np.ndarray, size: int) -> None:
        # Halton point 0 is the box's lower corner (often a singular, limit-bound pose): skip it.
        self.Q = lower + halton(robot.n, size, skip=1) * (upper - lower)
        self.positions, self.rotations = robot.fk_batch(self.Q, validate=False)
        self._robot = weakref.proxy(robot)  # for the goal frames' poses (a table never outlives its robot's cache)
        self._goal_features: dict = {}  # (frame, oriented, weight) per goal -> (features (size, d), squared norms)
        reach = float(np.sqrt((self.positions**2).sum(axis=1)).max()) if size else 1.0
        self.weight = 0.25 * max(reach, 1e-3)
        self._features: dict[str, tuple[np.ndarray, np.ndarray]] = {}
        self._trees: dict = {}  # feature key -> scipy.spatial.cKDTree
        self._gaps: dict[str, float] = {}  # feature key -> typical_gap_sq
        self._free: dict = {}  # (scene id, version, margin) -> (weakref to the scene, free mask)
        self._last: tuple = (None, None)  # (the last target, its one_target_features): Targets are immutable
        self._transposed: dict = {}  # feature key -> compiled_features
        self._one_goal: dict = {}  # (frame, weight, has_orientation, has_position) -> one_goal_features
        self._joint_features: dict = {}  # wrap mask bytes -> (joint features (size, d), squared norms)
        self._one_goal32: dict = {}  # id(one_goal_features' FT) -> (that FT, its float32 copy, sq's)
        self._stacked: dict = {}  # id(a _goal_parts list) -> (that list, its features stacked: _stacked_parts)
        if size:
            for key in _KINDS:  # one-time work here, not inside a solve's time budget
                self._table_features(key)
                self._gap(key)
            for key in ("pose", "position"):
                self.compiled_features(key)

    def _pose_features(self, key: str, P: np.ndarray, R: np.ndarray) -> np.ndarray:
        """Features (N, d) of tip poses (positions P (N, 3) m, rotations R (N, 3, 3)) for one target kind."""
        if key == "pose":
            return np.concatenate([P, self.weight * R.reshape(-1, 9)], axis=1)
        if key == "position":
            return P
        if key == "planar":
            return P[:, :2]
        return np.concatenate([P[:, :2], self.weight * R[:, :2, 0]], axis=1)  # heading, scaled like rotations

    def _table_features(self, key: str) -> tuple[np.ndarray, np.ndarray]:
        """(features (size, d), squared norms (size,)) of the table for one target kind, built once."""
        if key not in self._features:
            F = np.array(self._pose_features(key, self.positions, self.rotations), order="C")  # a copy
            self._features[key] = (F, (F * F).sum(axis=1))
        return self._features[key]

    def encoded_features(self, kind: int, P: np.ndarray, Rts: np.ndarray) -> tuple[str, np.ndarray]:
        """(kind key, features (N, d)) of N tip targets of one ``KIND_*`` in the kernel's encoding
        (:func:`~evoik_pin.goals.stack.encode_targets`: P (N, 3), Rts (N, 3, 3))."""
        key = _KIND_KEYS[kind]
        if kind == KIND_PLANAR_YAW:  # P[:, 2] is the yaw (rad): the heading, scaled like rotations
            yaw = P[:, 2]
            return key, np.concatenate([P[:, :2], self.weight * np.stack([np.cos(yaw), np.sin(yaw)], 1)], 1)
        return key, self._pose_features(key, P, Rts)

    def one_target_features(self, target: Target) -> tuple[str, np.ndarray]:
        """(kind key, features (d,)) of one target: :meth:`encoded_features`' row, the same numbers, without the
        batch encoding (this runs on every single-target solve)."""
        last = self._last
        if last[0] is target:  # a solve asks up to four times (ranking, q0's nearness, the gap)
            return last[1]
        if target.planar:
            key, f = self.encoded_features(target_kind(target), *encode_targets([target]))
            out = key, f[0]
        elif target.rotation is None:
            out = "position", np.array(target.position, dtype=float)  # our own (compiled callers fix its type)
        else:
            out = "pose", np.concatenate((target.position, self.weight * target.rotation.reshape(9)))
        self._last = (target, out)
        return out

    def ranked(self, target: Target, k: int, allowed: np.ndarray | None = None):
        """Indices of the (up to) k table entries nearest to one target, nearest first, lazily: the nearest
        costs one matrix-vector product and an argmin; the others are ranked only if asked for. ``allowed``
        (size,) bool: only those entries (e.g. :meth:`free_mask`)."""
        if k <= 0:
            return
        d = self.distances(*self.one_target_features(target))
        if allowed is not None:
            d = np.where(allowed, d, np.inf)
            k = min(k, int(np.count_nonzero(allowed)))
            if k <= 0:
                return
        first = int(d.argmin())
        yield first
        k = min(k, d.shape[0])
        if k > 1:
            part = np.argpartition(d, k - 1)[:k]
            for i in part[d[part].argsort()]:
                if i != first:
                    yield int(i)

    def compiled_features(self, key: str) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(features (size, d), the same transposed (d, size), squared norms (size,)) of one target kind, for the
        compiled ranking (:mod:`.nearest`); built once."""
        hit = self._transposed.get(key)
        if hit is None:
            F, sq = self._table_features(key)
            hit = self._transposed[key] = (F, np.ascontiguousarray(F.T), sq)
        return hit

    def joint_distances(self, q0: np.ndarray, wrap: np.ndarray) -> np.ndarray:
        """Each entry's squared joint-space distance (size,) to ``q0`` (n,) (rad^2 or m^2), a ``wrap`` joint (bool
        (n,): its range spans a full turn) by its chord on the unit circle, ``2 - 2 cos d`` (d^2 near 0, at most 4
        at half a turn: the difference taken to its nearest turn, without a modulo). One matrix-vector product over
        features kept per ``wrap`` (the joints, the wrapping ones as cos and sin; their squared norms): the modulo
        over the table took 100 us on UR10, the product 5."""
        key = wrap.tobytes()
        kept = self._joint_features.get(key)
        if kept is None:
            F = np.concatenate([self.Q[:, ~wrap], np.cos(self.Q[:, wrap]), np.sin(self.Q[:, wrap])], axis=1)
            kept = self._joint_features[key] = (F, np.einsum("ij,ij->i", F, F))
        F, sq = kept
        f = np.concatenate([q0[~wrap], np.cos(q0[wrap]), np.sin(q0[wrap])])
        d = F @ f
        d *= -2.0
        d += sq
        d += f @ f
        return d

    def distances(self, key: str, f: np.ndarray) -> np.ndarray:
        """The table's squared distances (size,) to features ``f`` (d,) of kind ``key`` (:meth:`one_target_features`)
        less ``|f|^2`` (the same for every entry): what :meth:`ranked` sorts (memetic's first runs too)."""
        F, sq = self._table_features(key)
        d = F @ f  # sq - 2 F f, in place: the same numbers (negation is exact), two fewer (size,) arrays
        d *= -2.0
        d += sq
        return d

    def ranked_goals(self, problem, k: int, allowed: np.ndarray | None = None):
        """:meth:`ranked` for a goal list (``problem.goals``): the entries nearest in the sum over the goals of their
        weight times ``|p - p_t|^2 (+ w^2 |R - R_t|_F^2 for a pose)``, each goal's frame posed by the entry, nearest
        first (ties: the lower index first). The goals' features over the table (the frames' poses, scaled by the
        square roots of the weights) are computed once per frame list, kinds and weights and cached, so a ranking
        is one compiled pass over them (:func:`~.nearest.rank_goal_entries`, which memetic's compiled first runs of
        a goal list make too: the same order)."""
        if k <= 0:
            return
        from .nearest import rank_goal_entries  # numba, loaded on first use (as the kernel is)

        layout = self.goal_layout(problem.goals)
        k = min(k, self.Q.shape[0] if allowed is None else int(np.count_nonzero(allowed)))
        if k <= 0:
            return
        pt, Rt = seed_targets(problem)
        out = np.empty(k, dtype=np.int64)
        m = rank_goal_entries(layout[0], layout[1], layout[5], layout[6], layout[7], self.weight,
                              np.ascontiguousarray(pt, dtype=float), np.ascontiguousarray(Rt, dtype=float),
                              _EVERY if allowed is None else allowed, k, out)
        yield from out[:m].tolist()

    def prepare_goals(self, goals) -> None:
        """Compute (once per frame list, kinds and weights; then cached) the goal features that
        :meth:`ranked_goals` and :meth:`goal_starts` read: forward kinematics of every entry, one-time set-up; and
        load (once per process; once per install: compile) the compiled rankings a search of these goals calls
        (:func:`load_goal_helpers` for several goals; a goal set's members' ranking,
        :func:`~.nearest.table_distances_many`, for choose), so that no solve's clock pays for that."""
        self._goal_table_features(goals)
        self._goal_parts(goals)
        if len(goals) > 1:
            load_goal_helpers()
        if "sets" not in _RANKING_LOADED and any(g.alternatives is not None for g in goals):
            from ..lm.compiling import load
            from .nearest import table_distances_many

            one = np.zeros((1, 1), dtype=np.float32)
            load("the seed table's rankings for goal sets", [(table_distances_many, (
                one, np.zeros(1, dtype=np.float32), one.copy(), np.empty((1, 1), dtype=np.float32)))],
                 RANKING_COMPILE_SECONDS)
            _RANKING_LOADED.append("sets")

    def goal_starts(self, problem, k: int, allowed: np.ndarray | None = None):
        """Up to ``k`` starting configurations (n,) for a goal list, lazily: composed ones and table entries
        alternately, a composed one first.

        The j-th table entry is the j-th of :meth:`ranked_goals`. The j-th composed start is assembled goal by goal:
        for each goal, the joints that move its frame (the floating base excepted) are taken from the table entry
        whose pose of that frame *relative to the root link* is the nearest to the goal's target (its j-th nearest
        on a fixed base; with a floating base, the nearest to the target seen from the j-th ranked entry's base,
        which the composed start keeps); the other joints are that entry's. A pose goal on a frame only the floating
        base moves (a quadruped's trunk) sets the base of every start, composed or not, and the composed starts
        then rank each goal's entries once, as on a fixed base. Each goal's chain thus gets its own
        good table entry where one entry rarely suits every goal of a whole robot (on Talos's four poses the LM
        run from the first composed start converges about 1.3 times as often as from the nearest entry). A joint
        shared by several goals' chains (a torso) takes the value of the last of them.
        """
        if k <= 0:
            return
        ranked = self.ranked_goals(problem, k, allowed)
        parts = self._goal_parts(problem.goals)
        robot = self._robot
        pt, Rt = seed_targets(problem)
        base = self._base_from_goals(problem, parts) if robot.floating_base else None
        if base is not None:  # the goals seen from the base that goal sets
            pt, Rt = _seen_from(base, pt, Rt)
        fixed = None
        made = 0
        for j, row in enumerate(ranked):
            q = self.Q[row].copy()
            if base is not None:
                q[:6] = base
            if robot.floating_base and base is None:  # the goals seen from this entry's base pose
                P_rel, R_rel = _seen_from(q[:6], pt, Rt)
                picks = self._nearest_per_goal(problem.goals, parts, P_rel, R_rel, 1, allowed)[:, 0]
            else:  # the first composed start needs each goal's nearest entry; the next ones, one ranking per goal
                if fixed is None or (j > 0 and fixed.shape[1] == 1):
                    fixed = self._nearest_per_goal(problem.goals, parts, pt, Rt, 1 if j == 0 else k, allowed)
                picks = fixed[:, j] if j < fixed.shape[1] else None
            if picks is not None:
                for (_, _, idx), e in zip(parts, picks, strict=True):
                    q[idx] = self.Q[e, idx]
                yield q
                made += 1
                if made >= k:
                    return
            entry = self.Q[row]
            if base is not None:
                entry = entry.copy()
                entry[:6] = base
            yield entry
            made += 1
            if made >= k:
                return

    def _base_from_goals(self, problem, parts) -> np.ndarray | None:
        """The floating base's six entries (clipped into the search box) that put the first pose goal on a frame
        only the floating base moves (the root link or a frame fixed to it: a quadruped's trunk) exactly on its
        target; None when no goal is such."""
        pt, Rt = seed_targets(problem)
        for g, (goal, (F, _, idx)) in enumerate(zip(problem.goals, parts, strict=True)):
            if goal.has_orientation and goal.has_position and idx.size == 0 and goal.kind < KIND_BEYOND_FRAME:
                s = np.sqrt(goal.weight)  # the features hold sqrt(weight) x the frame's pose relative to the root
                p_f, R_f = F[0, :3] / s, F[0, 3:].reshape(3, 3) / (s * self.weight)
                R = Rt[g] @ R_f.T
                base = np.concatenate([pt[g] - R @ p_f, rpy(R)[0, ::-1]])  # x, y, z, yaw, pitch, roll
                return np.minimum(np.maximum(base, problem.lower[:6]), problem.upper[:6])
        return None

    def _goal_parts(self, goals) -> list[tuple[np.ndarray, np.ndarray, np.ndarray]]:
        """Per goal (cached per frame list, kinds and weights): the table's features of its frame's pose relative to
        the root link (a floating base's six entries set to zero), their squared norms, and the indices of the
        entries of q (the floating base's excepted) that move the frame."""
        key = ("parts",) + tuple((g.frame, g.has_orientation, g.has_position, g.weight) for g in goals)
        hit = self._goal_features.get(key)
        if hit is None:
            robot = self._robot
            Q = self.Q
            if robot.floating_base:
                Q = Q.copy()
                Q[:, :6] = 0.0
            P, R = robot.fk_batch(Q, validate=False, frames=[g.frame for g in goals])
            names = list(robot.joint_names)
            first = 6 if robot.floating_base else 0
            hit = []
            for g, goal in enumerate(goals):
                spec = self.goal_spec(goals)[g:g + 1]
                F = np.concatenate(self._goal_feature_blocks(spec, P[:, g][None], R[:, g][None]), axis=1)
                seeded = goal.kind < KIND_BEYOND_FRAME or _anchor(goal, goals) is not None
                idx = np.array([i for i in map(names.index, robot.moving_joints(goal.frame)) if i >= first
                                and seeded], dtype=np.intp)  # the other goals beyond one frame compose nothing
                hit.append((np.ascontiguousarray(F), (F * F).sum(axis=1), idx))
            if len(self._goal_features) > 8:
                self._goal_features.clear()
            self._goal_features[key] = hit
        return hit

    def _nearest_per_goal(self, goals, parts, pt: np.ndarray, Rt: np.ndarray, k: int,
                          allowed: np.ndarray | None) -> np.ndarray:
        """(G, <= k) indices of the table entries nearest, goal by goal, to targets pt (G, 3), Rt (G, 3, 3) of the
        frames' poses relative to the root link, nearest first (ties: the lower index first): one compiled call
        for every goal (:func:`~.nearest.nearest_per_goal`; NumPy's products and rankings goal by goal took 15 us a
        goal, the composed starts a third of a Talos solve)."""
        from .nearest import nearest_per_goal  # numba, loaded on first use (as the kernel is)

        k = min(k, self.Q.shape[0] if allowed is None else int(np.count_nonzero(allowed)))
        FT, sq, start, scale, positioned, oriented = self._stacked_parts(goals, parts)
        out = np.empty((len(parts), k), dtype=np.int64)
        if k > 0:
            nearest_per_goal(FT, sq, start, scale, positioned, oriented, self.weight, np.ascontiguousarray(pt),
                             np.ascontiguousarray(Rt), _EVERY if allowed is None else allowed, k, out)
        return out.astype(np.intp, copy=False)

    def _stacked_parts(self, goals, parts) -> tuple:
        """:meth:`_goal_parts`' features of every goal stacked for :func:`~.nearest.nearest_per_goal`: (FT (D, size)
        the goals' features transposed, goal g's rows from start[g]; sq (G, size); start (G + 1,); scale (G,)
        sqrt(weight); positioned, oriented (G,) bool), as :meth:`goal_spec` gives them (:meth:`goal_layout`'s)."""
        return self.goal_layout(goals, parts)[2:8]

    def goal_layout(self, goals, parts=None) -> tuple:
        """Everything the compiled ranking and composition of a goal list's starts read (:func:`~.nearest.
        rank_goal_entries`, :func:`~.nearest.nearest_per_goal`, :func:`~.first_runs.goal_first_runs`), cached with
        :meth:`_goal_parts` (per frame list, kinds and weights): (FT (D, size), sq (size,) float32: the goal list's
        table features transposed (:meth:`goal_table_features`) and their squared norms; PT (E, size), psq (G, size)
        float32, pstart (G + 1,): each goal's features relative to the root link, stacked, goal g's rows from
        pstart[g] (single precision: a start's order is all they decide, :func:`~.nearest.table_distances32`);
        scale (G,) sqrt(weight); positioned, oriented (G,) bool (:meth:`goal_spec`); idx (I,) int64, idx_start
        (G + 1,): the entries of q each goal's chain sets in a composed start, goal g's
        ``idx[idx_start[g]:idx_start[g + 1]]``)."""
        if parts is None:
            parts = self._goal_parts(goals)
        key = id(parts)
        hit = self._stacked.get(key)
        if hit is None or hit[0] is not parts:
            spec = self.goal_spec(goals)
            F, sq_rank = self.goal_table_features(tuple(g.frame for g in goals), spec)
            FT = np.ascontiguousarray(F.T)
            PT = np.ascontiguousarray(np.concatenate([F for F, _, _ in parts], axis=1).T)
            sq = np.ascontiguousarray(np.stack([q for _, q, _ in parts]))
            start = np.cumsum([0] + [F.shape[1] for F, _, _ in parts]).astype(np.int64)
            scale = np.array([e[0] for e in spec], dtype=float)
            positioned = np.array([len(e) < 3 or bool(e[2]) for e in spec])
            oriented = np.array([bool(e[1]) for e in spec])
            idx = np.concatenate([np.zeros(0, dtype=np.int64)] + [i.astype(np.int64) for _, _, i in parts])
            idx_start = np.cumsum([0] + [i.size for _, _, i in parts]).astype(np.int64)
            if len(self._stacked) > 8:
                self._stacked.clear()
            # single precision for the rankings (nearest.table_distances32): a start's order only
            hit = self._stacked[key] = (parts, (FT.astype(np.float32), sq_rank.astype(np.float32),
                                                PT.astype(np.float32), sq.astype(np.float32), start, scale, positioned,
                                                oriented, idx, idx_start))
        return hit[1]

    def _goal_table_features(self, goals) -> tuple[np.ndarray, np.ndarray]:
        """:meth:`goal_table_features` of a goal list."""
        return self.goal_table_features(tuple(g.frame for g in goals), self.goal_spec(goals))

    def goal_table_features(self, frames, spec) -> tuple[np.ndarray, np.ndarray]:
        """(features (size, d), squared norms (size,)) of the goal frames ``frames`` over the table
        (:meth:`ranked_goals`, the batch engine's k-d tree), cached per frames and ``spec`` (:meth:`goal_spec`)."""
        key = (tuple(frames), tuple(spec))
        hit = self._goal_features.get(key)
        if hit is None:
            P, R = self._robot.fk_batch(self.Q, validate=False, frames=list(frames))
            F = self.goal_features(spec, P, R)
            if len(self._goal_features) > 8:
                self._goal_features.clear()
            hit = self._goal_features[key] = (np.ascontiguousarray(F), (F * F).sum(axis=1))
        return hit

    @staticmethod
    def goal_spec(goals) -> tuple[tuple, ...]:
        """Per goal, (sqrt(weight), has orientation), and False third for a goal without a position (orientation,
        pointing: its target's pt is no place for the frame): what the goal features depend on besides the
        frames. A goal beyond one frame without a target pose of its frame (a centre of mass, a relative pose whose
        first frame has no pose goal: :func:`seed_targets`) weighs 0: it ranks nothing."""
        return tuple((float(np.sqrt(g.weight)) if g.kind < KIND_BEYOND_FRAME or _anchor(g, goals) is not None
                      else 0.0, bool(g.has_orientation)) + (() if g.has_position else (False,)) for g in goals)

    def _goal_feature_blocks(self, spec, P: np.ndarray, R: np.ndarray) -> list[np.ndarray]:
        """Per goal g, the features (N, 3 or 12) of frame poses P[g] (N, 3) m, R[g] (N, 3, 3): ``sqrt(weight_g)``
        times the position and, for a goal with orientation, ``self.weight`` times the rotation's entries
        (``spec``: :meth:`goal_spec`). Their Euclidean distance is memetic's goal metric."""
        out = []
        for g, entry in enumerate(spec):
            s, oriented = entry[0], entry[1]
            if len(entry) < 3 or entry[2]:  # a goal with a position
                out.append(s * P[g])
            if oriented:
                out.append((s * self.weight) * R[g].reshape(-1, 9))
        if not out:  # pointing goals alone: no feature ranks the entries (all equally near)
            out.append(np.zeros((len(P[0]), 1)))
        return out

    def goal_features(self, spec, P: np.ndarray, R: np.ndarray) -> np.ndarray:
        """Features (N, d) of N poses of G goal frames, positions P (N, G, 3) m and rotations R (N, G, 3, 3)
        (``spec``: :meth:`goal_spec`): what :meth:`goal_table_features` holds for the table's entries."""
        return np.concatenate(self._goal_feature_blocks(spec, P.transpose(1, 0, 2), R.transpose(1, 0, 2, 3)), axis=1)

    def free_mask(self, scene, margin: float) -> np.ndarray:
        """(size,) bool: the entries whose convex-hull proxies are collision-free in ``scene`` at ``margin`` m
        (conservative: every such entry is mesh-free), computed once per scene version and margin (about
        20-60 us an entry: one-time set-up)."""
        key = (id(scene), scene.version, float(margin))
        hit = self._free.get(key)
        if hit is None or hit[0]() is not scene:
            if len(self._free) > 8:
                self._free.clear()
            hit = self._free[key] = (weakref.ref(scene), ~scene.collides(self.Q, margin, proxy=True))
        return hit[1]

    def distance_sq(self, target: Target, T: pin.SE3) -> float:
        """Squared nearness metric between a target and a tip pose ``T`` (the one :meth:`ranked` sorts by)."""
        key, f = self.one_target_features(target)
        if key == "pose":  # _pose_features's row, without its batch reshapes (once per solve with a q0)
            d = f - np.concatenate((T.translation, self.weight * T.rotation.reshape(9)))
        elif key == "position":
            d = f - T.translation
        else:
            d = f - self._pose_features(key, T.translation[None], T.rotation[None])[0]
        return float(d.dot(d))

    def entry_distance_sq(self, target: Target, i: int) -> float:
        """:meth:`distance_sq` between a target and table entry ``i``'s tip pose, from the table's own features
        (the same numbers: the features of ``i``'s pose are row ``i`` of the table's)."""
        key, f = self.one_target_features(target)
        d = f - self._table_features(key)[0][i]
        return float(d.dot(d))

    def typical_gap_sq(self, target: Target) -> float:
        """Median squared distance (in the metric of ``target``'s kind) from a table entry to its nearest
        other entry, over 64 sampled entries, cached: a start nearer the target than this is as good a guess
        as the table's nearest entry usually is."""
        return self._gap(self.one_target_features(target)[0])

    def _gap(self, key: str) -> float:
        gap = self._gaps.get(key)
        if gap is None:
            gap = self._gaps[key] = _typical_gap(*self._table_features(key))
        return gap

    def one_goal_features(self, goal) -> tuple:
        """For a goal list of one goal on one frame (memetic searches it as a single target: :mod:`.memetic`,
        :mod:`.first_runs`), the table's features of the goal's frame (:meth:`goal_table_features`: ``sp`` x the
        frame's position when the goal has one, then ``sr`` x its rotation's entries when it has an orientation):
        (F (size, D), FT (D, size), sq (size,), the typical squared gap between entries (:meth:`typical_gap_sq`'s,
        in these features), sp, sr), cached per frame, weight and kind. ``sp = sqrt(weight)``,
        ``sr = sqrt(weight) x self.weight``: :meth:`ranked_goals`'s metric."""
        # keyed by what goal_spec reads of a goal on one frame (its spec made on a miss only: 0.7 us a call)
        key = (goal.frame, goal.weight, goal.has_orientation, goal.has_position)
        hit = self._one_goal.get(key)
        if hit is None:
            spec = self.goal_spec([goal])
            F, sq = self.goal_table_features((goal.frame,), spec)
            s = spec[0][0]
            if len(self._one_goal) > 8:
                self._one_goal.clear()
            hit = self._one_goal[key] = (F, np.ascontiguousarray(F.T), sq, _typical_gap(F, sq), s, s * self.weight)
        return hit

    def one_goal_features32(self, goal) -> tuple[np.ndarray, np.ndarray]:
        """:meth:`one_goal_features`'s FT (D, size) and sq (size,) in single precision (cached): a goal set's members
        ranked against the table (:func:`~.nearest.table_distances_many`)."""
        F, FT, sq = self.one_goal_features(goal)[:3]
        hit = self._one_goal32.get(id(FT))
        if hit is None or hit[0] is not FT:
            if len(self._one_goal32) > 8:
                self._one_goal32.clear()
            hit = self._one_goal32[id(FT)] = (FT, FT.astype(np.float32), sq.astype(np.float32))
        return hit[1], hit[2]

    def one_goal_point(self, goal, p: np.ndarray, R: np.ndarray) -> np.ndarray:
        """The features (D,) of the pose (p (3,) m, R (3, 3)) of ``goal``'s frame (or of its target) in
        :meth:`one_goal_features`'s metric: the products :meth:`_goal_feature_blocks` makes, so the same numbers."""
        spec = self.goal_spec([goal])[0]
        s, oriented = spec[0], spec[1]
        parts = [s * p] if len(spec) < 3 or spec[2] else []
        if oriented:
            parts.append((s * self.weight) * R.reshape(9))
        return np.concatenate(parts)

    def nearest(self, kind: int, P: np.ndarray, Rts: np.ndarray, k: int, allowed: np.ndarray | None = None,
                eps: float = 0.0) -> np.ndarray:
        """Indices (N, k) of the k table entries nearest to each of N tip targets of one ``KIND_*`` in the kernel's
        encoding (P (N, 3), Rts (N, 3, 3): :class:`~evoik_pin.goals.stack.TargetArrays`), nearest first (only
        ``allowed`` entries when a (size,) bool mask is given; k is capped at their number).

        Many targets at once go through a k-d tree of the table's features (built once per target kind and
        mask): O(N log size), against O(N size) for the distance matrix that :meth:`ranked` uses for one target.
        ``eps`` > 0: approximate neighbours (``scipy.spatial.cKDTree.query``'s ``eps``: the i-th entry returned
        is within (1 + eps) times the distance of the true i-th nearest), several times cheaper in these 12-D
        features.
        """
        key, f = self.encoded_features(kind, P, Rts)
        tree_key = (key, None if allowed is None else allowed.tobytes())
        hit = self._trees.get(tree_key)
        if hit is None:
            from scipy.spatial import cKDTree

            index = np.arange(self.Q.shape[0]) if allowed is None else np.nonzero(allowed)[0]
            if len(self._trees) > 16:
                self._trees.clear()
            hit = self._trees[tree_key] = (cKDTree(self._table_features(key)[0][index]), index)
        tree, index = hit
        k = min(k, tree.n)
        N = f.shape[0]
        if k == 0 or N == 0:
            return np.zeros((N, 0), dtype=np.intp)
        _, idx = tree.query(f, k=k, eps=eps)
        return index[np.asarray(idx, dtype=np.intp).reshape(N, k)]


_GOAL_HELPERS_LOADED: list = []  # [True] once load_goal_helpers has run in this process


def load_goal_helpers() -> None:
    """Load (once per process; once after an install: compile) the compiled helpers a goal list's starts call from
    Python (:meth:`SeedTable.ranked_goals`, :meth:`SeedTable.goal_starts`: :func:`~.nearest.rank_goal_entries`,
    :func:`~.nearest.nearest_per_goal`, :func:`~.nearest.seen_from`), each on tiny arrays of the types those calls
    pass: one-time set-up that memetic makes before its clock starts, where the first ranking of a process's first
    goal list otherwise loaded them from its budget (a few ms each)."""
    if _GOAL_HELPERS_LOADED:
        return
    from ..lm.compiling import load
    from .nearest import nearest_per_goal, rank_goal_entries, seen_from

    FT, sq = np.zeros((3, 2), dtype=np.float32), np.zeros((1, 2), dtype=np.float32)
    scale, yes, no = np.ones(1), np.ones(1, dtype=bool), np.zeros(1, dtype=bool)
    pt, Rt = np.zeros((1, 3)), np.tile(np.eye(3), (1, 1, 1))
    load("the seed table's rankings for goal lists", [
        (rank_goal_entries, (FT, sq[0], scale, yes, no, 1.0, pt, Rt, _EVERY, 1, np.empty(1, dtype=np.int64))),
        (nearest_per_goal, (FT, sq, np.array([0, 3], dtype=np.int64), scale, yes, no, 1.0, pt, Rt, _EVERY, 1,
                            np.empty((1, 1), dtype=np.int64))),
        (seen_from, (np.zeros(6), pt, Rt, np.empty((1, 3)), np.empty((1, 3, 3))))], RANKING_COMPILE_SECONDS)
    _GOAL_HELPERS_LOADED.append(True)


def _typical_gap(F: np.ndarray, sq: np.ndarray) -> float:
    """Median squared distance from an entry to its nearest other entry, over 64 entries sampled evenly, in
    features F (size, d) with squared norms sq (size,)."""
    sample = np.linspace(0, F.shape[0] - 1, min(64, F.shape[0])).astype(int)
    D = sq[sample, None] + sq[None, :] - 2.0 * F[sample] @ F.T
    D[np.arange(sample.size), sample] = np.inf
    return float(np.median(D.min(axis=1)))


def _seen_from(base: np.ndarray, pt: np.ndarray, Rt: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Targets pt (G, 3), Rt (G, 3, 3) in the world seen from a floating base's pose (its six entries: x, y, z m,
    yaw, pitch, roll rad; rotation ``Rz(yaw) Ry(pitch) Rx(roll)``): ``B^-1 T`` per target, by the compiled
    :func:`~.nearest.seen_from` that memetic's compiled first runs use (the same numbers)."""
    from .nearest import seen_from  # numba, loaded on first use (as the kernel is)

    P_out, R_out = np.empty((pt.shape[0], 3)), np.empty((pt.shape[0], 3, 3))
    seen_from(np.ascontiguousarray(base, dtype=float), np.ascontiguousarray(pt, dtype=float),
              np.ascontiguousarray(Rt, dtype=float), P_out, R_out)
    return P_out, R_out


_EVERY = np.zeros(0, dtype=bool)  # nearest_per_goal's mask for every entry
_RANKING_LOADED: list = []  # the compiled rankings prepare_goals has loaded in this process ("sets")
#: About how long (s, one core) compiling the goal lists' rankings (nearest.py) takes from an empty cache.
RANKING_COMPILE_SECONDS = 1.0
_TABLES: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()
_TABLES_PER_ROBOT = 4


def default_table_size(n: int) -> int:
    """Seed-table size for an n-joint chain: 2^(n+5), clamped to [256, 4096] (about 1-5 ms to build)."""
    return int(min(4096, max(256, 2 ** (n + 5))))


def seed_table(robot, lower: np.ndarray, upper: np.ndarray, size: int) -> SeedTable:
    """The cached :class:`SeedTable` of ``robot`` over the box [lower, upper] (built on first use).

    A few boxes are kept per robot (the most recent ones), so a trajectory solved in narrow moving boxes
    does not grow the cache.
    """
    per_robot = _TABLES.setdefault(robot, {})
    key = (lower.tobytes(), upper.tobytes(), int(size))
    table = per_robot.get(key)
    if table is None:
        table = SeedTable(robot, lower, upper, size)
        if len(per_robot) >= _TABLES_PER_ROBOT:
            per_robot.pop(next(iter(per_robot)))
        per_robot[key] = table
    return table


def _anchor(goal, goals):
    """For a relative pose goal, the index of a pose goal on its first frame (None when there is none, or for any
    other goal)."""
    if goal.kind not in (KIND_RELATIVE_POSE, KIND_RELATIVE_POSE_AXES):  # with bands or free axes: T_1 T seeds too
        return None
    return next((i for i, g in enumerate(goals) if g.kind == KIND_POSE and g.frame == goal.frame_a), None)


def seed_targets(problem) -> tuple[np.ndarray, np.ndarray]:
    """The goals' targets pt (G, 3), Rt (G, 3, 3) as the seed table ranks them: a relative pose ``T_a^-1 T_b = T``
    whose frame a has a pose goal ``T_a = T_1`` (two hands holding a box, one of them placed) is frame b's pose
    ``T_1 T``, which the table can match like any pose goal."""
    _, pt, Rt = problem.goal_stack()
    goals = problem.goals
    out = None
    for g, goal in enumerate(goals):
        a = _anchor(goal, goals)
        if a is not None:
            if out is None:
                out = pt.copy(), Rt.copy()
            out[0][g] = pt[a] + Rt[a] @ pt[g]
            out[1][g] = Rt[a] @ Rt[g]
    return (pt, Rt) if out is None else out
