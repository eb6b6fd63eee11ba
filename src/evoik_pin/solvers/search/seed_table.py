"""The seed table (:func:`seed_table`, cached per robot and box): Halton configurations over a search box with their
frames' poses, ranked by nearness ``|p - p_t|^2 + w^2 |R - R_t|_F^2`` (``w``: a quarter of the arm's reach, m) to a
target, or summed with the goals' weights over a goal list; position and planar targets use their own features."""

from __future__ import annotations

import weakref
from typing import NamedTuple

import numpy as np

from ...goals.pose import KIND_POSE
from ...goals.position import KIND_POSITION
from ...goals.registry import KIND_BEYOND_FRAME
from ...goals.relative_pose import KIND_RELATIVE_POSE, KIND_RELATIVE_POSE_AXES
from ...goals.stack import KIND_PLANAR, KIND_PLANAR_YAW
from ...lie import rpy
from ..lm import compiling
from ..paper.common import halton
from .nearest import nearest_per_goal, rank_goal_entries, seen_from, table_distances_many

__all__ = ["DEFAULT_GOAL_TABLE_SEEDS", "DEFAULT_TABLE_SEEDS", "FrameFeatures", "SeedTable", "default_table_size",
           "kept_per_robot", "load_goal_helpers", "nearest_first", "nearest_order", "one_frame", "seed_table"]


#: Seed-table entries tried per target, nearest first (memetic's stage 2 and solve_many's batched rounds).
DEFAULT_TABLE_SEEDS = 17
#: Starts tried for a goal list before memetic's DE restarts (:meth:`SeedTable.goal_starts`; far cheaper than DE).
DEFAULT_GOAL_TABLE_SEEDS = 48
#: Target kinds a seed table serves, each with its own nearness features.
_KIND_KEYS = {KIND_POSE: "pose", KIND_POSITION: "position", KIND_PLANAR: "planar", KIND_PLANAR_YAW: "planar_yaw"}


class FrameFeatures(NamedTuple):
    """The table's features of one frame's pose (the tip's for a target kind, or a goal frame's): F (size, d), FT
    (d, size), sq (size,) their squared norms, gap (the median squared distance from an entry to its nearest other:
    a start nearer the target than this is as good as the table's nearest entry), sp and sr (the scales of the
    position and of the rotation's entries), positioned, oriented, planar (x, y and the heading only); FT32, sq32: FT
    and sq in single precision (a goal set's ranking)."""

    F: np.ndarray
    FT: np.ndarray
    sq: np.ndarray
    gap: float
    sp: float
    sr: float
    positioned: bool
    oriented: bool
    planar: bool
    FT32: np.ndarray
    sq32: np.ndarray

    def point(self, p: np.ndarray, R: np.ndarray) -> np.ndarray:
        """The features (d,) of one pose of the frame (p (3,) m, R (3, 3))."""
        return _pose_rows(*self[4:9], p[None], R[None])[0]


def _pose_rows(sp: float, sr: float, positioned: bool, oriented: bool, planar: bool, P: np.ndarray,
               R: np.ndarray) -> np.ndarray:
    """Features (N, d) of N poses (P (N, 3) m, R (N, 3, 3)) in :class:`FrameFeatures`' metric."""
    if planar:  # x, y, and the heading scaled like rotations
        return np.concatenate([P[:, :2]] + ([sr * R[:, :2, 0]] if oriented else []), axis=1)
    parts = ([sp * P] if positioned else []) + ([sr * R.reshape(-1, 9)] if oriented else [])
    return np.concatenate(parts, axis=1) if parts else np.zeros((P.shape[0], 0))


class SeedTable:
    """Configurations spread over a search box (the last: every joint at 0 clipped into it) and their tip poses,
    searchable by nearness to a target.

    Attributes:
        Q: (size, n) configurations. positions: (size, 3) tip positions (m); rotations: (size, 3, 3).
        weight: m per unit of rotation-matrix (Frobenius) distance in the pose metric."""

    def __init__(self, robot, lower: np.ndarray, upper: np.ndarray, size: int) -> None:
        # Halton point 0 is the box's lower corner (often a singular, limit-bound pose): skip it.
        self.Q = lower + halton(robot.n, size, skip=1) * (upper - lower)
        if size:  # the last entry: every joint at 0 clipped into the box, a humanoid URDF's upright stance
            self.Q[-1] = np.minimum(np.maximum(0.0, lower), upper)
        self.positions, self.rotations = robot.fk_batch(self.Q, validate=False)
        self._robot = weakref.proxy(robot)  # for the goal frames' poses (a table never outlives its robot's cache)
        self._goal_features: dict = {}  # (frames, goal_spec) -> goal_table_features; ("parts", ...) -> _goal_parts
        reach = float(np.sqrt((self.positions**2).sum(axis=1)).max()) if size else 1.0
        self.weight = 0.25 * max(reach, 1e-3)
        self._frames: dict = {}  # frame_features' key -> FrameFeatures
        self._trees: dict = {}  # feature key -> scipy.spatial.cKDTree
        self._free: dict = {}  # (scene id, version, margin) -> (weakref to the scene, free mask)
        self._joint_features: dict = {}  # wrap mask bytes -> (joint features (size, d), squared norms)
        self._stacked: dict = {}  # id(a _goal_parts list) -> (that list, goal_layout)
        if size:
            for key in _KIND_KEYS.values():  # one-time work here, not inside a solve's time budget
                self.frame_features(key)

    def frame_features(self, key) -> FrameFeatures:
        """The table's :class:`FrameFeatures` (cached): of the tip for a target kind (``key`` "pose", "position",
        "planar" or "planar_yaw"), or of a goal frame (``key`` (frame, the goal's :meth:`goal_spec` entry))."""
        hit = self._frames.get(key)
        if hit is None:
            if isinstance(key, str):
                shape = (1.0, self.weight, key in ("pose", "position"), key in ("pose", "planar_yaw"),
                         key.startswith("planar"))
                F = np.array(_pose_rows(*shape, self.positions, self.rotations), order="C")  # a copy
                sq = (F * F).sum(axis=1)
            else:
                frame, entry = key
                F, sq = self.goal_table_features((frame,), (entry,))
                shape = (entry[0], entry[0] * self.weight, len(entry) < 3, entry[1], False)
                if len(self._frames) > 12:  # the goal frames' go, the kinds' stay
                    self._frames = {k: v for k, v in self._frames.items() if isinstance(k, str)}
            FT = np.ascontiguousarray(F.T)
            hit = self._frames[key] = FrameFeatures(F, FT, sq, _typical_gap(F, sq), *shape, FT.astype(np.float32),
                                                    sq.astype(np.float32))
        return hit

    def frame_search(self, problem) -> FrameFeatures | None:
        """For a problem searched as one frame's pose (:func:`one_frame`: one goal on one frame), its
        :class:`FrameFeatures` (a plain pose, position or planar goal of weight 1 on the tip: the tip's of its kind);
        None for any other problem."""
        if not one_frame(problem):
            return None
        g = problem.goals[0]
        if g.kind in _KIND_KEYS and g.weight == 1.0 and g.frame == self._robot.tip:
            return self.frame_features(_KIND_KEYS[g.kind])
        return self.frame_features((g.frame, (float(np.sqrt(g.weight)), bool(g.has_orientation))
                                    + (() if g.has_position else (False,))))

    def target_point(self, problem, ff: FrameFeatures) -> np.ndarray:
        """The features (d,) of ``problem``'s one goal's target in ``ff``'s metric (:meth:`frame_search`'s)."""
        _, pt, Rt = problem.goal_stack()
        if ff.planar:  # (x, y, yaw): the heading's features from the yaw
            return self.encoded_features(problem.goals[0].kind, pt[:1], Rt[:1])[1][0]
        return ff.point(pt[0], Rt[0])

    def encoded_features(self, kind: int, P: np.ndarray, Rts: np.ndarray) -> tuple[str, np.ndarray]:
        """(kind key, features (N, d)) of N tip targets of one ``KIND_*`` in the kernel's encoding
        (:func:`~evoik_pin.goals.stack.encode_targets`: P (N, 3), Rts (N, 3, 3))."""
        key = _KIND_KEYS[kind]
        if kind == KIND_PLANAR_YAW:  # P[:, 2] is the yaw (rad): the heading, scaled like rotations
            yaw = P[:, 2]
            return key, np.concatenate([P[:, :2], self.weight * np.stack([np.cos(yaw), np.sin(yaw)], 1)], 1)
        return key, _pose_rows(*self.frame_features(key)[4:9], P, Rts)

    def ranked(self, ff: FrameFeatures, point: np.ndarray, k: int, allowed: np.ndarray | None = None):
        """Indices of the (up to) k entries nearest a one-frame problem's target (:meth:`frame_search`'s features
        ``ff``, :meth:`target_point`'s ``point``), nearest first, lazily (the nearest costs one product and an
        argmin); ``allowed`` (size,) bool: only those entries."""
        if k <= 0:
            return
        d = self.distances(ff, point)
        if allowed is not None:
            d = np.where(allowed, d, np.inf)
            k = min(k, int(np.count_nonzero(allowed)))
        yield from nearest_first(d, k)

    def joint_distances(self, q0: np.ndarray, wrap: np.ndarray) -> np.ndarray:
        """Each entry's squared joint distance (size,) to ``q0`` (n,), a ``wrap`` joint (bool (n,)) by its chord on the
        unit circle, ``2 - 2 cos d``: one product over features kept per ``wrap``."""
        key = wrap.tobytes()
        kept = self._joint_features.get(key)
        if kept is None:
            F = np.concatenate([self.Q[:, ~wrap], np.cos(self.Q[:, wrap]), np.sin(self.Q[:, wrap])], axis=1)
            kept = self._joint_features[key] = (F, np.einsum("ij,ij->i", F, F))
        f = np.concatenate([q0[~wrap], np.cos(q0[wrap]), np.sin(q0[wrap])])
        d = _less_norm(*kept, f)
        d += f @ f
        return d

    def distances(self, ff: FrameFeatures, f: np.ndarray) -> np.ndarray:
        """The table's squared distances (size,) to features ``f`` (d,) less ``|f|^2``, in the metric of ``ff``."""
        return _less_norm(ff.F, ff.sq, f)

    def ranked_goals(self, problem, k: int, allowed: np.ndarray | None = None):
        """:meth:`ranked` for a goal list (``problem.goals``): nearest in the goals' weighted summed nearness, each
        goal's frame posed by the entry (ties: the lower index first), by one compiled pass
        (:func:`~.nearest.rank_goal_entries`)."""
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
        """One-time set-up for a goal list: its features over the table and the compiled rankings its search calls."""
        self.goal_table_features(tuple(g.frame for g in goals), self.goal_spec(goals))
        self._goal_parts(goals)
        if len(goals) > 1:
            load_goal_helpers()
        if any(g.alternatives is not None for g in goals):
            load_goal_helpers(sets=True)

    def goal_starts(self, problem, k: int, allowed: np.ndarray | None = None):
        """Up to ``k`` starting configurations (n,) for a goal list, lazily: composed starts and table entries
        alternately, a composed one first.

        The j-th entry is :meth:`ranked_goals`' j-th. The j-th composed start takes, for each goal, the joints that move
        its frame (the floating base excepted) from the entry whose frame pose relative to the root link is the j-th
        nearest the goal's target (with a floating base: seen from the j-th entry's base, or from the base a pose goal
        on the trunk sets); the other joints are that entry's. A joint shared by several chains takes the last one's
        value."""
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
            out = [q.copy()]  # the entry (its base set), before the picks compose q
            if picks is not None:
                for (_, _, idx), e in zip(parts, picks, strict=True):
                    q[idx] = self.Q[e, idx]
                out.insert(0, q)
            yield from out[:k - made]
            made += len(out)
            if made >= k:
                return

    def _base_from_goals(self, problem, parts) -> np.ndarray | None:
        """The floating base's six entries (clipped into the box) putting the first pose goal on a frame only the base
        moves exactly on its target; None when no goal is such."""
        pt, Rt = seed_targets(problem)
        for g, (goal, (F, _, idx)) in enumerate(zip(problem.goals, parts, strict=True)):
            if goal.has_orientation and goal.has_position and idx.size == 0 and goal.kind < KIND_BEYOND_FRAME:
                s = np.sqrt(goal.weight)  # the features hold sqrt(weight) x the frame's pose relative to the root
                return base_onto(pt[g], Rt[g], F[0, :3] / s, F[0, 3:].reshape(3, 3) / (s * self.weight),
                                 problem.lower, problem.upper)
        return None

    def _goal_parts(self, goals) -> list[tuple[np.ndarray, np.ndarray, np.ndarray]]:
        """Per goal (cached): the table's features of its frame's pose relative to the root link, their squared norms,
        and the entries of q (the floating base's excepted) that move the frame."""
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
            spec = self.goal_spec(goals)
            for g, goal in enumerate(goals):
                F = self.goal_features(spec[g:g + 1], P[:, g:g + 1], R[:, g:g + 1])
                seeded = goal.kind < KIND_BEYOND_FRAME or _anchor(goal, goals) is not None
                idx = np.array([i for i in map(names.index, robot.moving_joints(goal.frame)) if i >= first
                                and seeded], dtype=np.intp)  # the other goals beyond one frame compose nothing
                hit.append((np.ascontiguousarray(F), (F * F).sum(axis=1), idx))
            _kept(self._goal_features, key, hit)
        return hit

    def _nearest_per_goal(self, goals, parts, pt: np.ndarray, Rt: np.ndarray, k: int,
                          allowed: np.ndarray | None) -> np.ndarray:
        """(G, <= k) indices of the entries nearest, goal by goal, targets pt (G, 3), Rt (G, 3, 3) relative to the root
        link, nearest first: one compiled call (:func:`~.nearest.nearest_per_goal`)."""
        k = min(k, self.Q.shape[0] if allowed is None else int(np.count_nonzero(allowed)))
        FT, sq, start, scale, positioned, oriented = self.goal_layout(goals, parts)[2:8]
        out = np.empty((len(parts), k), dtype=np.int64)
        if k > 0:
            nearest_per_goal(FT, sq, start, scale, positioned, oriented, self.weight, np.ascontiguousarray(pt),
                             np.ascontiguousarray(Rt), _EVERY if allowed is None else allowed, k, out)
        return out.astype(np.intp, copy=False)

    def goal_layout(self, goals, parts=None) -> tuple:
        """What the compiled rankings and compositions of a goal list read (:func:`~.nearest.rank_goal_entries`,
        :func:`~.nearest.nearest_per_goal`, :func:`~.guaranteed_runs.goal_guaranteed_runs`), cached: (FT (D, size), sq
        (size,) float32; PT (E, size), psq (G, size) float32, pstart (G + 1,): each goal's root-relative features
        stacked; scale (G,); positioned, oriented (G,) bool; idx (I,), idx_start (G + 1,): the entries of q each goal's
        chain sets)."""
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
            # single precision for the rankings (nearest.table_distances32): a start's order only
            hit = _kept(self._stacked, key, (parts, (FT.astype(np.float32), sq_rank.astype(np.float32),
                                                     PT.astype(np.float32), sq.astype(np.float32), start, scale,
                                                     positioned, oriented, idx, idx_start)))
        return hit[1]

    def goal_table_features(self, frames, spec) -> tuple[np.ndarray, np.ndarray]:
        """(features (size, d), squared norms (size,)) of the frames ``frames`` over the table, cached per frames and
        ``spec`` (:meth:`goal_spec`)."""
        key = (tuple(frames), tuple(spec))
        hit = self._goal_features.get(key)
        if hit is None:
            P, R = self._robot.fk_batch(self.Q, validate=False, frames=list(frames))
            F = self.goal_features(spec, P, R)
            hit = _kept(self._goal_features, key, (np.ascontiguousarray(F), (F * F).sum(axis=1)))
        return hit

    @staticmethod
    def goal_spec(goals) -> tuple[tuple, ...]:
        """Per goal, (sqrt(weight), has orientation), with a third False for a goal without a position: what its
        features depend on besides the frame. A goal beyond one frame without a target pose of its frame weighs 0."""
        return tuple((float(np.sqrt(g.weight)) if g.kind < KIND_BEYOND_FRAME or _anchor(g, goals) is not None
                      else 0.0, bool(g.has_orientation)) + (() if g.has_position else (False,)) for g in goals)

    def goal_features(self, spec, P: np.ndarray, R: np.ndarray) -> np.ndarray:
        """Features (N, d) of N poses of G goal frames, P (N, G, 3) m, R (N, G, 3, 3) (``spec``: :meth:`goal_spec`):
        per goal sqrt(weight) x its frame's position, then x ``self.weight`` its rotation's entries; one zero column
        when no goal has any (pointing goals alone: every entry as near)."""
        blocks = [_pose_rows(e[0], e[0] * self.weight, len(e) < 3 or e[2], e[1], False, P[:, g], R[:, g])
                  for g, e in enumerate(spec)]
        return np.concatenate([b for b in blocks if b.shape[1]] or [np.zeros((P.shape[0], 1))], axis=1)

    def free_mask(self, scene, margin: float) -> np.ndarray:
        """(size,) bool: the entries collision-free in ``scene`` at ``margin`` m by their convex-hull proxies
        (conservative), cached per scene version and margin."""
        key = (id(scene), scene.version, float(margin))
        hit = self._free.get(key)
        if hit is None or hit[0]() is not scene:
            hit = _kept(self._free, key, (weakref.ref(scene), ~scene.collides(self.Q, margin, proxy=True)))
        return hit[1]

    def nearest(self, kind: int, P: np.ndarray, Rts: np.ndarray, k: int, allowed: np.ndarray | None = None,
                eps: float = 0.0) -> np.ndarray:
        """Indices (N, k) of the k entries nearest each of N tip targets of one ``KIND_*`` (P (N, 3), Rts (N, 3, 3)),
        nearest first, by a k-d tree of the table's features (only ``allowed`` entries when a (size,) mask is given; k
        capped at their number); ``eps`` > 0: approximate neighbours (``cKDTree.query``'s)."""
        key, f = self.encoded_features(kind, P, Rts)
        tree_key = (key, None if allowed is None else allowed.tobytes())
        hit = self._trees.get(tree_key)
        if hit is None:
            from scipy.spatial import cKDTree

            index = np.arange(self.Q.shape[0]) if allowed is None else np.nonzero(allowed)[0]
            hit = _kept(self._trees, tree_key, (cKDTree(self.frame_features(key).F[index]), index), 16)
        tree, index = hit
        k = min(k, tree.n)
        N = f.shape[0]
        if k == 0 or N == 0:
            return np.zeros((N, 0), dtype=np.intp)
        _, idx = tree.query(f, k=k, eps=eps)
        return index[np.asarray(idx, dtype=np.intp).reshape(N, k)]


def load_goal_helpers(sets: bool = False) -> None:
    """Load (once per process; after an install: compile) the compiled rankings a goal list's starts call (``sets``:
    a goal set's), before a solve's clock."""
    what = "sets" if sets else "lists"
    if what in _LOADED:
        return
    FT, sq = np.zeros((3, 2), dtype=np.float32), np.zeros((1, 2), dtype=np.float32)
    scale, yes, no = np.ones(1), np.ones(1, dtype=bool), np.zeros(1, dtype=bool)
    pt, Rt = np.zeros((1, 3)), np.tile(np.eye(3), (1, 1, 1))
    if sets:
        calls = [(table_distances_many, (FT, sq[0], FT.T.copy(), np.empty((2, 2), dtype=np.float32)))]
    else:
        calls = [(rank_goal_entries, (FT, sq[0], scale, yes, no, 1.0, pt, Rt, _EVERY, 1, np.empty(1, dtype=np.int64))),
                 (nearest_per_goal, (FT, sq, np.array([0, 3], dtype=np.int64), scale, yes, no, 1.0, pt, Rt, _EVERY, 1,
                                     np.empty((1, 1), dtype=np.int64))),
                 (seen_from, (np.zeros(6), pt, Rt, np.empty((1, 3)), np.empty((1, 3, 3))))]
    compiling.load(f"the seed table's rankings for goal {what}", calls, RANKING_COMPILE_SECONDS)
    _LOADED.append(what)


def _kept(cache: dict, key, value, most: int = 8):
    """``value``, stored in ``cache`` under ``key`` (the cache emptied first when it holds more than ``most``)."""
    if len(cache) > most:
        cache.clear()
    cache[key] = value
    return value


def _less_norm(F: np.ndarray, sq: np.ndarray, f: np.ndarray) -> np.ndarray:
    """``sq - 2 F f`` (N,): the squared distances of rows F (N, d), squared norms sq (N,), to f (d,) less ``|f|^2``."""
    d = F @ f
    d *= -2.0
    d += sq
    return d


def _typical_gap(F: np.ndarray, sq: np.ndarray) -> float:
    """Median squared distance from an entry to its nearest other, over 64 entries, in features F (size, d) with
    squared norms sq (size,)."""
    sample = np.linspace(0, F.shape[0] - 1, min(64, F.shape[0])).astype(int)
    D = sq[sample, None] + sq[None, :] - 2.0 * F[sample] @ F.T
    D[np.arange(sample.size), sample] = np.inf
    return float(np.median(D.min(axis=1)))


def base_onto(p_t: np.ndarray, R_t: np.ndarray, p_f: np.ndarray, R_f: np.ndarray, lower: np.ndarray,
              upper: np.ndarray) -> np.ndarray:
    """The floating base's six entries (x, y, z m, yaw, pitch, roll rad; clipped into ``lower[:6]``, ``upper[:6]``)
    that put a frame whose pose relative to the base is (p_f (3,) m, R_f (3, 3)) on the target (p_t (3,) m, R_t)."""
    R = R_t @ R_f.T
    base = np.concatenate([p_t - R @ p_f, rpy(R)[0, ::-1]])
    return np.minimum(np.maximum(base, lower[:6]), upper[:6])


def _seen_from(base: np.ndarray, pt: np.ndarray, Rt: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Targets pt (G, 3), Rt (G, 3, 3) seen from a floating base's pose (:func:`~.nearest.seen_from`)."""
    P_out, R_out = np.empty((pt.shape[0], 3)), np.empty((pt.shape[0], 3, 3))
    seen_from(np.ascontiguousarray(base, dtype=float), np.ascontiguousarray(pt, dtype=float),
              np.ascontiguousarray(Rt, dtype=float), P_out, R_out)
    return P_out, R_out


_EVERY = np.zeros(0, dtype=bool)  # nearest_per_goal's mask for every entry
_LOADED: list = []  # the compiled rankings loaded in this process: "lists" (load_goal_helpers), "sets" (prepare_goals)
#: About how long (s, one core) compiling the goal lists' rankings (nearest.py) takes from an empty cache.
RANKING_COMPILE_SECONDS = 1.0
_TABLES: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()
_TABLES_PER_ROBOT = 4


def default_table_size(n: int) -> int:
    """Seed-table size for an n-joint robot: 2^(n+5), clamped to [256, 4096]."""
    return int(min(4096, max(256, 2 ** (n + 5))))


def seed_table(robot, lower: np.ndarray, upper: np.ndarray, size: int) -> SeedTable:
    """The cached :class:`SeedTable` of ``robot`` over [lower, upper] (built on first use; the last few boxes kept
    per robot)."""
    return kept_per_robot(_TABLES, robot, (lower.tobytes(), upper.tobytes(), int(size)),
                          lambda: SeedTable(robot, lower, upper, size), _TABLES_PER_ROBOT)


def kept_per_robot(store: weakref.WeakKeyDictionary, robot, key, make, most: int):
    """``store``'s value for ``robot`` and ``key``, made by ``make()`` on first use (None: none is made, None
    returned) and kept with the robot's last ``most`` others."""
    per_robot = store.setdefault(robot, {})
    value = per_robot.get(key)
    if value is None and make is not None:
        value = make()
        if len(per_robot) >= most:
            per_robot.pop(next(iter(per_robot)))
        per_robot[key] = value
    return value


def nearest_first(d: np.ndarray, k: int):
    """:func:`nearest_order` lazily: the first (the argmin) costs one pass, the others are ranked only if asked for."""
    if min(k, d.shape[0]) <= 0:
        return
    yield int(d.argmin())
    if k > 1 and d.shape[0] > 1:
        yield from nearest_order(d, k)[1:].tolist()


def nearest_order(d: np.ndarray, k: int) -> np.ndarray:
    """Indices of the (up to) ``k`` smallest of ``d`` (N,), smallest first: the argmin, then the others by value."""
    k = min(k, d.shape[0])
    if k <= 1:
        return np.array([int(d.argmin())] if k == 1 else [], dtype=np.intp)
    first = int(d.argmin())
    part = np.argpartition(d, k - 1)[:k]
    ranked = part[d[part].argsort()]
    return np.concatenate(([first], ranked[ranked != first]))


def one_frame(problem) -> bool:
    """Whether a problem is searched as one frame's pose (:meth:`SeedTable.frame_search`): a tip target, or a goal
    list of one goal on one frame with a position or an orientation to match (not a goal set, a pointing goal or a
    goal beyond one frame)."""
    goals = problem.goals
    g = goals[0]
    return (len(goals) == 1 and g.on_one_frame and g.alternatives is None
            and (g.kind not in (KIND_PLANAR, KIND_PLANAR_YAW) or g.frame == problem.robot.tip))


def _anchor(goal, goals):
    """For a relative pose goal, the index of a pose goal on its first frame (None when there is none, or for
    another goal)."""
    if goal.kind not in (KIND_RELATIVE_POSE, KIND_RELATIVE_POSE_AXES):  # with bands or free axes: T_1 T seeds too
        return None
    return next((i for i, g in enumerate(goals) if g.kind == KIND_POSE and g.frame == goal.frame_a), None)


def seed_targets(problem) -> tuple[np.ndarray, np.ndarray]:
    """The goals' targets pt (G, 3), Rt (G, 3, 3) as the table ranks them: a relative pose whose frame a has a pose
    goal ``T_1`` is frame b's pose ``T_1 T``."""
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
