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
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin

from ..errors import SceneError

__all__ = ["SelfCollisionCheck"]

#: Slack (m) added to the boxes' overlap test, so that rounding never drops a pair coal would call touching.
BOX_SLACK = 1e-9
#: Margin (m) of the hull filter: Qhull's hulls may leave a mesh vertex a few 1e-5 m outside (measured: a G1 knee 70
#: um into a shoulder, its hulls apart), so a pair goes on to the meshes when its hulls are within this of touching.
HULL_MARGIN = 1e-3
#: Verdicts kept by configuration (the last ones: a bisection's and a frame's few).
REMEMBERED = 64


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
        self._verdicts: dict[bytes, bool] = {}
        centres, halves = [], []
        for obj in geom.geometryObjects:
            shape = obj.geometry
            shape.computeLocalAABB()
            lo, hi = np.asarray(shape.aabb_local.min_), np.asarray(shape.aabb_local.max_)
            centres.append((lo + hi) / 2)
            halves.append((hi - lo) / 2)
        self._centre = np.array(centres).reshape(-1, 3)  # (G, 3) m, each object's own frame
        self._half = np.array(halves).reshape(-1, 3)

    def candidate_pairs(self, q) -> np.ndarray:
        """Indices of the checked pairs whose bounding boxes overlap at ``q`` (n,) (placements updated)."""
        robot = self.robot
        q_pin = robot.to_pinocchio(robot.check_q(q))
        pin.updateGeometryPlacements(robot.model, self._data, self._geom, self._gdata, q_pin)
        pin.updateGeometryPlacements(robot.model, self._data, self._hulls, self._hdata)  # same joint placements
        H = np.array([m.homogeneous for m in self._gdata.oMg])  # (G, 4, 4)
        R, t = H[:, :3, :3], H[:, :3, 3]
        centre = np.einsum("gij,gj->gi", R, self._centre) + t
        half = np.einsum("gij,gj->gi", np.abs(R), self._half)
        apart = np.abs(centre[self._a] - centre[self._b]) > half[self._a] + half[self._b] + BOX_SLACK
        return np.flatnonzero(~apart.any(axis=1))

    def _touching(self, k: int) -> bool:
        """Whether checked pair k touches at the placements last updated: hulls (within HULL_MARGIN) first, then
        meshes."""
        return pin.computeCollision(self._hulls, self._hdata, k) and pin.computeCollision(self._geom, self._gdata, k)

    def in_collision(self, q) -> bool:
        """True when a checked pair of the collision meshes is in contact at ``q`` (n,): ``scene.in_collision(q)``.
        The last :data:`REMEMBERED` verdicts are kept by ``q``'s bytes: a frame's answer is checked again as the next
        frame's previous one."""
        key = np.asarray(q, dtype=float).tobytes()
        verdict = self._verdicts.get(key)
        if verdict is None:
            verdict = any(self._touching(k) for k in self.candidate_pairs(q).tolist())
            if len(self._verdicts) >= REMEMBERED:
                self._verdicts.pop(next(iter(self._verdicts)))  # the oldest (dicts keep insertion order)
            self._verdicts[key] = verdict
        return verdict

    def colliding_pairs(self, q) -> list[tuple[str, str]]:
        """``scene.colliding_pairs(q)``: the (link, link) pairs in contact at ``q`` (n,), each once, in the scene's
        pair order."""
        names = self._names
        pairs = [(names[self._a[k]], names[self._b[k]]) for k in self.candidate_pairs(q).tolist() if self._touching(k)]
        return list(dict.fromkeys(pairs))  # once per pair of names (a link may have several shapes)
