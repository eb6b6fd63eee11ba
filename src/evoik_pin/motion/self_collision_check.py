"""A robot's self-collision check with a broad phase: the same verdict as
``Scene(robot, self_collision=True).in_collision(q)``, for the retargeter's many checks per frame.

The scene's check hands every pair (G1: ~580) to coal, whose per-pair call costs a few microseconds even when the
two meshes are far apart (~1.5 ms a configuration). Here the placements are updated once, each collision object
gets a world axis-aligned box bounding its mesh (its local box turned: centre ``R c + t``, half-extents ``|R| h``),
the pairs whose boxes overlap are picked in one NumPy step, and only those (a few) go to coal: first their convex
hulls (GJK, microseconds), then the meshes of the pairs whose hulls touch (a BVH traversal, ~0.1 ms a pair of
neighbouring links). A box contains its mesh, and a hull its mesh up to Qhull's rounding (the hull filter counts
pairs within :data:`HULL_MARGIN` as touching): a pair dropped at either step cannot touch, so the verdict is the exact
one.

The boxes come from the joints' placements in one compiled pass (:func:`_overlapping_pairs`), which also tests the
pairs whose world boxes overlap on their turned boxes (the oriented boxes' separating axes: a box turned with its
link is far tighter than its world-aligned box; about 2.5 times fewer pairs reach the hulls on G1 and Talos). A
pair's last verdict is kept with the values of the joints between its two links (those moving one and not the
other: its relative placement), so a check in which those did not move (a bisection stepping an arm back leaves the
legs where they were; a step back puts an arm where it was against a torso that moved with the pelvis) reuses it;
the pairs found touching last are tried first, so a colliding configuration (most of a bisection's) is told after a
few narrow-phase calls. None of these changes a verdict (a kept one may differ from a new one only by the world
placements' rounding, 1e-15 m). :meth:`SelfCollisionCheck.surely_free` is a cheaper, one-sided test for a step
back's bisection: hulls only for the pairs its joints move (True is exact, False may be "maybe"; a True is kept as the
configuration's verdict, so the step back's answer, checked again as the next frame's previous one, is a look-up).
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin
from numba import njit

from ..errors import SceneError

__all__ = ["SelfCollisionCheck"]

#: Slack (m) added to the boxes' overlap test, so that rounding never drops a pair coal would call touching.
BOX_SLACK = 1e-9
#: Margin (m) of the hull filter: Qhull's hulls may leave a mesh vertex a few 1e-5 m outside (measured: a G1 knee 70
#: um into a shoulder, its hulls apart), so a pair goes on to the meshes when its hulls are within this of touching.
HULL_MARGIN = 1e-3
#: Verdicts kept by configuration (the last ones: a bisection's, a frame's, and a clip's answers, which its report
#: checks again).
REMEMBERED = 4096
#: Pairs found touching that later checks try first.
RECENT_PAIRS = 8


@njit(cache=True, nogil=True)
def _overlapping_pairs(J, parent, P, centre, half, a, b, slack, out):  # pragma: no cover - compiled
    """The checked pairs (``a``, ``b``: (K,) object indices) whose boxes overlap, written into ``out`` (K,) in order;
    returns their count. ``J`` (nj, 4, 4): the joints' placements; ``parent`` (G,): each object's joint; ``P``
    (G, 4, 4): its placement on that joint; ``centre``, ``half`` (G, 3): its local box (m, own frame). The object is
    at ``J[parent] P``: its box is turned by R and moved by t (centre ``R c + t``). Two tests, each dropping only
    pairs some axis separates by more than ``slack`` (m): the world axis-aligned boxes (half-extents ``|R| h``), then
    the turned boxes themselves (the separating-axis test of two oriented boxes: their 3 + 3 face normals and 9 edge
    cross products; 1e-9 added to |cos| keeps near-parallel edges from separating anything)."""
    G = P.shape[0]
    wc = np.empty((G, 3))
    wh = np.empty((G, 3))
    WR = np.empty((G, 3, 3))
    for g in range(G):
        M = J[parent[g]]
        for i in range(3):
            t = M[i, 3]
            for j in range(3):
                WR[g, i, j] = M[i, 0] * P[g, 0, j] + M[i, 1] * P[g, 1, j] + M[i, 2] * P[g, 2, j]
                t += M[i, j] * P[g, j, 3]
            c = t
            h = 0.0
            for j in range(3):
                c += WR[g, i, j] * centre[g, j]
                h += abs(WR[g, i, j]) * half[g, j]
            wc[g, i] = c
            wh[g, i] = h
    R = np.empty((3, 3))
    AbsR = np.empty((3, 3))
    d = np.empty(3)
    tA = np.empty(3)
    count = 0
    for k in range(a.shape[0]):
        p, q = a[k], b[k]
        apart = False
        for i in range(3):
            if abs(wc[p, i] - wc[q, i]) > wh[p, i] + wh[q, i] + slack:
                apart = True
                break
        if not apart:
            # q's box in p's axes: R = Rp^T Rq, the centres' offset tA = Rp^T (cq - cp)
            for i in range(3):
                d[i] = wc[q, i] - wc[p, i]
            for i in range(3):
                tA[i] = WR[p, 0, i] * d[0] + WR[p, 1, i] * d[1] + WR[p, 2, i] * d[2]
                for j in range(3):
                    R[i, j] = WR[p, 0, i] * WR[q, 0, j] + WR[p, 1, i] * WR[q, 1, j] + WR[p, 2, i] * WR[q, 2, j]
                    AbsR[i, j] = abs(R[i, j]) + 1e-9
            hp, hq = half[p], half[q]
            for i in range(3):  # p's face normals
                if abs(tA[i]) > hp[i] + hq[0] * AbsR[i, 0] + hq[1] * AbsR[i, 1] + hq[2] * AbsR[i, 2] + slack:
                    apart = True
                    break
            if not apart:
                for j in range(3):  # q's face normals
                    dist = abs(tA[0] * R[0, j] + tA[1] * R[1, j] + tA[2] * R[2, j])
                    if dist > hp[0] * AbsR[0, j] + hp[1] * AbsR[1, j] + hp[2] * AbsR[2, j] + hq[j] + slack:
                        apart = True
                        break
            if not apart:
                for i in range(3):  # the edges' cross products
                    i1, i2 = (i + 1) % 3, (i + 2) % 3
                    for j in range(3):
                        j1, j2 = (j + 1) % 3, (j + 2) % 3
                        ra = hp[i1] * AbsR[i2, j] + hp[i2] * AbsR[i1, j]
                        rb = hq[j1] * AbsR[i, j2] + hq[j2] * AbsR[i, j1]
                        if abs(tA[i2] * R[i1, j] - tA[i1] * R[i2, j]) > ra + rb + slack:
                            apart = True
                            break
                    if apart:
                        break
        if not apart:
            out[count] = k
            count += 1
    return count


class SelfCollisionCheck:
    """Self-collision of ``scene.robot`` on the collision meshes, the pairs of ``scene`` (a
    :class:`~evoik_pin.Scene` with ``self_collision=True`` and no obstacles: adjacent and SRDF-disabled pairs
    ignored). :meth:`in_collision` and :meth:`colliding_pairs` are the scene's with a broad phase. Not thread-safe
    (its Pinocchio data is its own, reused)."""

    def __init__(self, scene) -> None:
        if scene.obstacles:
            raise SceneError(f"SelfCollisionCheck takes a scene without obstacles (self-collision only); this one has "
                             f"{', '.join(scene.obstacles)}")
        robot = self.robot = scene.robot
        self.scene = scene
        # the scene's own geometry models (meshes and their convex hulls: hulls take 0.2-0.5 s to build) and pairs,
        # read-only; placements go to this check's own data
        geom, self._hulls, pairs = scene._geom, scene._hulls, scene._pairs
        self._geom = geom
        self._gdata = pin.GeometryData(geom)
        self._hdata = pin.GeometryData(self._hulls)
        for request in self._hdata.collisionRequests:  # the hulls as a filter: near (HULL_MARGIN) counts as touching
            request.security_margin = HULL_MARGIN
        self._data = robot.model.createData()
        self._a = np.array([a for a, _ in pairs], dtype=np.intp)
        self._b = np.array([b for _, b in pairs], dtype=np.intp)
        # each object by its robot link's name (the scene's names: no obstacles here)
        self._names = [robot.model.frames[int(obj.parentFrame)].name for obj in geom.geometryObjects]
        #: (G, n) bool: the entries of q that move each object (its link), for surely_free
        moves = [set(robot.moving_joints(name)) for name in self._names]
        self._moved_by = np.array([[joint in m for joint in robot.joint_names] for m in moves],
                                  dtype=bool).reshape(len(moves), robot.n)
        #: per checked pair, the entries of q that move one of its links and not the other (what its verdict reads)
        self._pair_joints = [np.flatnonzero(self._moved_by[a] ^ self._moved_by[b]) for a, b in pairs]
        self._q = np.zeros(robot.n)  # the q last placed (candidate_pairs)
        self._candidates: np.ndarray | None = None  # its candidate pairs (None: nothing placed yet)
        self._verdicts: dict[bytes, int] = {}  # q's bytes -> the touching pair in_collision found, or -1
        self._pair_verdicts: dict[int, tuple[bytes, bool]] = {}  # pair -> (its _pair_key, verdict)
        self._recent: list[int] = []  # pairs found touching, the last first (RECENT_PAIRS)
        self._placements = np.zeros((0, 4, 4))  # (nj, 4, 4) the joints' placements at the last candidate_pairs
        centres, halves = [], []
        for obj in geom.geometryObjects:
            shape = obj.geometry
            shape.computeLocalAABB()
            lo, hi = np.asarray(shape.aabb_local.min_), np.asarray(shape.aabb_local.max_)
            centres.append((lo + hi) / 2)
            halves.append((hi - lo) / 2)
        self._centre = np.array(centres, dtype=float).reshape(-1, 3)  # (G, 3) m, each object's own frame
        self._half = np.array(halves, dtype=float).reshape(-1, 3)
        self._out = np.empty(len(self._a), dtype=np.intp)  # candidate_pairs' scratch
        self._parent = np.array([int(obj.parentJoint) for obj in geom.geometryObjects], dtype=np.intp)  # (G,)
        self._local = np.array([obj.placement.homogeneous for obj in geom.geometryObjects],
                               dtype=float).reshape(-1, 4, 4)  # (G, 4, 4) each object on its joint

    def candidate_pairs(self, q) -> np.ndarray:
        """Indices of the checked pairs whose bounding boxes overlap at ``q`` (n,) (placements updated; for the q
        last placed, its pairs again without placing), read-only."""
        robot = self.robot
        q = np.array(q, dtype=float)
        if self._candidates is not None and np.array_equal(q, self._q):
            # placed already (a step back's start tested on its hulls then on its meshes; a colliding answer's
            # pairs listed after its check): the same placements and pairs
            return self._candidates
        q_pin = robot.to_pinocchio(robot.check_q(q))
        self._q = q  # once checked: a q that raises is never taken for placed
        pin.updateGeometryPlacements(robot.model, self._data, self._geom, self._gdata, q_pin)
        pin.updateGeometryPlacements(robot.model, self._data, self._hulls, self._hdata)  # same joint placements
        # the joints' placements (fewer than the objects, and the objects' true inputs: a pair's verdict is a
        # function of its two joints' placements, _touching)
        J = self._placements = np.array([m.homogeneous for m in self._data.oMi.tolist()])  # (nj, 4, 4)
        out = self._out
        count = _overlapping_pairs(J, self._parent, self._local, self._centre, self._half, self._a, self._b,
                                   BOX_SLACK, out)
        self._candidates = out[:count].copy()
        self._candidates.setflags(write=False)
        return self._candidates

    def _pair_key(self, k: int) -> bytes:
        """What checked pair k's verdict depends on at the q last placed: the entries of q that move one of its two
        links and not the other (its relative placement: the joints between the links)."""
        return self._q[self._pair_joints[k]].tobytes()

    def _touching(self, k: int) -> bool:
        """Whether checked pair k touches at the placements last updated: hulls (within HULL_MARGIN) first, then
        meshes. The pair's last verdict is kept with :meth:`_pair_key`: a check where the joints between its links
        have the same values (a bisection moving other links; a frame moving the legs, not the arm against the torso)
        reuses it (the same relative placement, up to the rounding of the world placements: 1e-15 m)."""
        key = self._pair_key(k)
        kept = self._pair_verdicts.get(k)
        if kept is not None and kept[0] == key:
            return kept[1]
        verdict = pin.computeCollision(self._hulls, self._hdata, k) and pin.computeCollision(self._geom, self._gdata, k)
        self._pair_verdicts[k] = (key, verdict)
        return verdict

    def surely_free(self, q, moving: np.ndarray | None = None, others_free: bool = False) -> bool:
        """True when no checked pair touches at ``q`` (n,), told without a mesh test of a pair that ``moving`` (bool
        (n,): the entries of q a caller's segment changes, e.g. a bisection's; None: all) moves: every such pair whose
        boxes overlap has convex hulls farther apart than :data:`HULL_MARGIN` (a mesh lies inside its hull). The
        other pairs get the exact verdict (kept by placement: a segment does not move them). False means "touching,
        or maybe": a moving pair's hulls touch, which only :meth:`in_collision` (its meshes) tells. Microseconds a
        pair (GJK), where a mesh test of two links a hair apart costs ~0.1-1 ms. ``others_free``: the pairs ``moving``
        does not move are known apart (the caller found its segment's start surely free): not looked at. A True is
        remembered as :meth:`in_collision`'s verdict on q."""
        candidates = self.candidate_pairs(q)
        moved = self._moved_by.any(axis=1) if moving is None else (self._moved_by @ moving)  # (G,) bool
        moved_pair = moved[self._a[candidates]] | moved[self._b[candidates]]
        # the pairs the segment moves on their hulls first (the cheap test that most often says "maybe"), then the
        # others' exact verdicts (kept from the segment's last point: the same placements)
        kept = self._pair_verdicts
        for k in candidates[moved_pair].tolist():
            key = self._pair_key(k)
            verdict = kept.get(k)
            if verdict is not None and verdict[0] == key:
                if verdict[1]:
                    return False
            elif pin.computeCollision(self._hulls, self._hdata, k):
                return False
            else:
                kept[k] = (key, False)  # hulls apart: meshes apart, the exact verdict
        if not others_free and any(self._touching(k) for k in candidates[~moved_pair].tolist()):
            return False
        self._remember(self._q.tobytes(), -1)  # exact: in_collision(q) of a step back's answer is then a look-up
        return True

    def in_collision(self, q) -> bool:
        """True when a checked pair of the collision meshes is in contact at ``q`` (n,): ``scene.in_collision(q)``.
        The last :data:`REMEMBERED` verdicts are kept by ``q``'s bytes: a frame's answer is checked again as the next
        frame's previous one. The pairs found touching last are tried first (a retargeted clip's contacts recur: an
        arm against the hips), so a colliding configuration is told after a few narrow-phase calls."""
        return self._touching_pair(q) >= 0

    def touching_pair(self, q) -> tuple[str, str] | None:
        """A (link, link) pair in contact at ``q`` (n,) (one of :meth:`colliding_pairs`: the one :meth:`in_collision`
        found, the recent contacts first), or None when none is; no narrow phase beyond :meth:`in_collision`'s."""
        k = self._touching_pair(q)
        return (self._names[self._a[k]], self._names[self._b[k]]) if k >= 0 else None

    def _touching_pair(self, q) -> int:
        """The checked pair :meth:`in_collision` finds touching at ``q`` (n,), or -1; kept by ``q``'s bytes."""
        key = np.asarray(q, dtype=float).tobytes()
        hit = self._verdicts.get(key)
        if hit is None:
            candidates = self.candidate_pairs(q)
            hit = -1
            recent = [k for k in self._recent if k in candidates]  # np.ndarray membership: a few pairs
            for k in recent:
                if self._touching(k):
                    hit = k
                    break
            else:
                tried = set(recent)
                for k in candidates.tolist():
                    if k not in tried and self._touching(k):
                        hit = k
                        self._recent = [k, *self._recent[:RECENT_PAIRS - 1]]
                        break
            self._remember(key, hit)
        return hit

    def _remember(self, key: bytes, hit: int) -> None:
        """Keep ``hit`` (a touching pair, or -1) as the verdict of the q whose bytes are ``key`` (the last
        :data:`REMEMBERED`)."""
        if len(self._verdicts) >= REMEMBERED:
            self._verdicts.pop(next(iter(self._verdicts)))  # the oldest (dicts keep insertion order)
        self._verdicts[key] = hit

    def colliding_pairs(self, q, most: int | None = None) -> list[tuple[str, str]]:
        """``scene.colliding_pairs(q, most=most)``: the (link, link) pairs in contact at ``q`` (n,), each once, in the
        scene's pair order; with ``most``, the first ``most`` of them, the narrow phase stopping there."""
        names, pairs = self._names, {}  # once per pair of names (a link may have several shapes), in order
        for k in self.candidate_pairs(q).tolist():
            if self._touching(k):
                pairs[(names[self._a[k]], names[self._b[k]])] = None
                if most is not None and len(pairs) >= most:
                    break
        return list(pairs)
