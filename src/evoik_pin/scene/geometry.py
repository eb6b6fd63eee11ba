"""A robot's collision geometry and the pairs worth checking, a scene's obstacles as a geometry model, and convex-hull
proxies."""

from __future__ import annotations

from itertools import combinations

import numpy as np
import pinocchio as pin

from ..errors import SceneError
from ..lie import is_rotation

__all__ = ["convex_hulls", "obstacle_model", "robot_collision_model", "self_collision_pairs"]


def robot_collision_model(robot) -> pin.GeometryModel:
    """A copy of ``robot.collision_model``; SceneError when the URDF has no ``<collision>`` element."""
    geom = robot.collision_model
    if geom.ngeoms == 0:
        raise SceneError(f"{robot.name} has no <collision> geometry in its URDF: a scene needs the robot's "
                         "collision shapes (add <collision> elements to the links)")
    return geom.copy()


def self_collision_pairs(robot, geom: pin.GeometryModel, srdf: str | None) -> list[tuple[int, int]]:
    """Index pairs (a, b), a < b, of the robot's collision objects worth checking: not on the same or adjacent joints
    (rigidly attached, or touching by construction), nor disabled by the SRDF."""
    parents = robot.model.parents
    adjacent = {(min(j, int(parents[j])), max(j, int(parents[j]))) for j in range(1, robot.model.njoints)}
    joint = [int(o.parentJoint) for o in geom.geometryObjects]
    pairs = [(a, b) for a, b in combinations(range(geom.ngeoms), 2)
             if joint[a] != joint[b] and (min(joint[a], joint[b]), max(joint[a], joint[b])) not in adjacent]
    if srdf is None or not pairs:
        return pairs
    probe = geom.copy()
    probe.removeAllCollisionPairs()
    for a, b in pairs:
        probe.addCollisionPair(pin.CollisionPair(a, b))
    try:
        pin.removeCollisionPairs(robot.model, probe, str(srdf))
    except (RuntimeError, ValueError) as exc:
        raise SceneError(f"cannot read the SRDF {srdf!r}: {exc}") from None
    return [(int(p.first), int(p.second)) for p in probe.collisionPairs]


def obstacle_model(scene) -> pin.GeometryModel:
    """The obstacles of a :class:`~evoik_pin.scene.Scene` as a ``pin.GeometryModel`` on the universe of
    ``scene.robot.model`` (its world frame), one object per obstacle, named as the obstacle."""
    base, geom = scene.robot.base_placement, pin.GeometryModel()
    for ob in scene.obstacles.values():  # base frame -> the model's world frame
        geom.addGeometryObject(pin.GeometryObject(ob.name, 0, 0, base * ob.pose, ob.shape))
    return geom


def convex_hulls(geom: pin.GeometryModel) -> pin.GeometryModel:
    """A copy of ``geom`` whose meshes are replaced by their convex hulls: conservative checks and lower-bound
    distances, much cheaper."""
    hulls = geom.copy()
    for obj in hulls.geometryObjects:
        shape = obj.geometry
        if hasattr(shape, "buildConvexHull") and getattr(shape, "num_vertices", 0) >= 4:
            shape.buildConvexHull(True, "Qt")
            obj.geometry = shape.convex
    return hulls


def as_placement(pose, what: str) -> pin.SE3:
    """A ``pin.SE3`` from a ``pin.SE3`` or a (4, 4) homogeneous matrix (m); SceneError naming ``what`` unless it is
    a rigid transform."""
    if isinstance(pose, pin.SE3):
        return pin.SE3(pose)
    try:
        H = np.asarray(pose, dtype=float)
    except (TypeError, ValueError):
        raise SceneError(f"{what}: pose must be a pin.SE3 or a 4 x 4 homogeneous matrix, got {pose!r}") from None
    if H.shape != (4, 4) or not np.isfinite(H).all():
        raise SceneError(f"{what}: pose must be a finite 4 x 4 homogeneous matrix (or a pin.SE3), got shape {H.shape}")
    R = H[:3, :3]
    if not is_rotation(R) or np.abs(H[3] - [0.0, 0.0, 0.0, 1.0]).max() > 1e-9:
        raise SceneError(f"{what}: pose is not a rigid transform (the rotation block must be orthonormal with "
                         "det +1 and the bottom row [0 0 0 1]); scaling and shear are not accepted")
    return pin.SE3(R, H[:3, 3])
