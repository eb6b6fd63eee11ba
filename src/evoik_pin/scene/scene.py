"""A collision scene: the robot's collision geometry and obstacles at poses in its base frame (m), checked with
Pinocchio and coal on the robot's self-collision pairs and every (moving robot object, obstacle) pair: exactly on the
meshes, or on convex-hull proxies."""

from __future__ import annotations

import math
import os
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pinocchio as pin

from ..errors import ConfigurationError, SceneError
from ..io.datafile import naming
from ..io.scene_file import read_scene, write_scene
from .geometry import as_placement, convex_hulls, obstacle_model, robot_collision_model, self_collision_pairs

__all__ = ["Obstacle", "Scene"]


@dataclass(frozen=True)
class Obstacle:
    """One obstacle: ``kind`` (box, sphere, cylinder, capsule, mesh), its ``params`` (``size`` (3,) m, ``radius`` /
    ``length`` m, ``path`` and ``scale``), its ``pose`` in the base frame, its coal shape."""

    name: str
    kind: str
    params: dict
    pose: pin.SE3
    shape: object = field(default=None, compare=False, repr=False)


def _length(value, what: str, zero: bool = False) -> float:
    """``value`` (m) as a finite float > 0 (>= 0 with ``zero``), or a SceneError naming ``what``."""
    try:
        v = float(value)
    except (TypeError, ValueError):
        v = math.nan
    if not (math.isfinite(v) and (v >= 0 if zero else v > 0)):
        raise SceneError(f"{what} must be a finite number {'>= 0' if zero else '> 0'} (m), got {value!r}")
    return v


class Scene:
    """The body of ``robot`` and the obstacles around it; ``self_collision``: check the robot against itself too;
    ``srdf``: an SRDF whose ``disable_collisions`` pairs are not checked (default the robot's own)."""

    def __init__(self, robot, self_collision: bool = True, srdf: str | os.PathLike | None = None) -> None:
        from ..robot import Robot

        if not isinstance(robot, Robot):
            raise SceneError(f"Scene needs a loaded Robot (evoik_pin.load_robot(...)), got {type(robot).__name__}")
        self.robot = robot
        self.self_collision = bool(self_collision)
        self.srdf = getattr(robot, "srdf", None) if srdf is None else str(srdf)
        if self.srdf is not None and not Path(self.srdf).is_file():
            raise SceneError(f"SRDF file not found: {self.srdf!r}")
        self._robot_geom = robot_collision_model(robot)
        self._self_pairs = self_collision_pairs(robot, self._robot_geom, self.srdf) if self.self_collision else []
        self._moving = [i for i, o in enumerate(self._robot_geom.geometryObjects) if int(o.parentJoint) != 0]
        self._obstacles: dict[str, Obstacle] = {}
        self._data = robot.model.createData()
        self.version = 0
        self._build()

    # ------------------------------------------------------------------ obstacles
    @property
    def obstacles(self) -> dict[str, Obstacle]:
        """The obstacles by name (a copy)."""
        return dict(self._obstacles)

    def _add(self, name: str, kind: str, params: dict, shape, pose) -> Scene:
        if not isinstance(name, str) or not name.strip():
            raise SceneError(f"an obstacle needs a non-empty name, got {name!r}")
        if name in self._obstacles:
            raise SceneError(f"an obstacle named {name!r} is already in the scene; remove it first or pick "
                             "another name")
        if name in {self._object_name(i) for i in range(self._robot_geom.ngeoms)}:
            raise SceneError(f"obstacle name {name!r} is the name of one of the robot's links")
        self._obstacles[name] = Obstacle(name, kind, params, as_placement(pose, f"obstacle {name!r}"), shape)
        self._build()
        return self

    def add_box(self, name: str, size, pose) -> Scene:
        """A box of edge lengths ``size`` (3,) m centred at ``pose`` (base frame)."""
        import coal

        try:
            s = np.asarray(size, dtype=float).reshape(3)
        except (TypeError, ValueError):
            raise SceneError(f"box {name!r}: size must be three lengths (x, y, z) in m, got {size!r}") from None
        s = [_length(v, f"box {name!r}: size") for v in s]
        return self._add(name, "box", {"size": s}, coal.Box(*s), pose)

    def add_sphere(self, name: str, radius, pose) -> Scene:
        """A sphere of ``radius`` m centred at ``pose``."""
        return self._add_round(name, "sphere", pose, radius=radius)

    def add_cylinder(self, name: str, radius, length, pose) -> Scene:
        """A cylinder of ``radius`` and ``length`` (m) centred at ``pose``, its axis along the pose's z."""
        return self._add_round(name, "cylinder", pose, radius=radius, length=length)

    def add_capsule(self, name: str, radius, length, pose) -> Scene:
        """A capsule (a cylinder of ``length`` with hemispherical caps of ``radius``, m) centred at ``pose``,
        its axis along the pose's z."""
        return self._add_round(name, "capsule", pose, radius=radius, length=length)

    def _add_round(self, name: str, kind: str, pose, **sizes) -> Scene:
        """A sphere, cylinder or capsule of ``sizes`` (radius, and length), in m."""
        import coal

        params = {key: _length(value, f"{kind} {name!r}: {key}") for key, value in sizes.items()}
        return self._add(name, kind, params, getattr(coal, kind.capitalize())(*params.values()), pose)

    def add_mesh(self, name: str, path, pose, scale=1.0) -> Scene:
        """A mesh file (STL, OBJ, DAE, ... anything assimp reads) at ``pose``, its vertices in m times ``scale``
        (a number or three factors)."""
        import coal

        p = Path(os.fspath(path)).expanduser()
        if not p.is_file():
            raise SceneError(f"mesh {name!r}: file not found: {str(path)!r}")
        sc = np.array([_length(v, f"mesh {name!r}: scale") for v in np.broadcast_to(np.asarray(scale, float), (3,))])
        try:
            shape = coal.MeshLoader().load(str(p), sc)
        except Exception as exc:  # assimp / coal report unreadable files with various exception types
            raise SceneError(f"mesh {name!r}: cannot read {str(p)!r} as a mesh: {exc}") from None
        return self._add(name, "mesh", {"path": str(p), "scale": sc.tolist()}, shape, pose)

    def remove(self, name: str) -> Scene:
        """Remove the obstacle ``name``."""
        if name not in self._obstacles:
            raise SceneError(f"no obstacle named {name!r} in the scene; obstacles: "
                             f"{', '.join(self._obstacles) or '(none)'}")
        del self._obstacles[name]
        self._build()
        return self

    # ------------------------------------------------------------------ scene files
    @classmethod
    def from_file(cls, robot, path: str | os.PathLike) -> Scene:
        """A scene of ``robot`` read from a YAML or JSON scene file (:mod:`evoik_pin.io.scene_file`); SceneError
        naming the file, the obstacle and the problem."""
        spec = read_scene(path)
        with naming(f"scene file {str(spec.path)!r}", SceneError):
            scene = cls(robot, self_collision=spec.self_collision, srdf=spec.srdf)
            for k, (name, kind, kw, pose) in enumerate(spec.obstacles):
                with naming(f"obstacle {k} ({name!r})", SceneError):
                    getattr(scene, f"add_{kind}")(name, pose=pose, **kw)
        return scene

    def to_file(self, path: str | os.PathLike) -> Path:
        """Write this scene as a scene file (YAML or JSON; :meth:`from_file` reads it back) and return its path."""
        return write_scene(self, path)

    # ------------------------------------------------------------------ geometry models
    def _object_name(self, i: int) -> str:
        """The name of collision object i: the robot link it belongs to, or the obstacle's name."""
        model = self.robot.model
        if i < self._robot_geom.ngeoms:
            return model.frames[int(self._robot_geom.geometryObjects[i].parentFrame)].name
        return self._names[i - self._robot_geom.ngeoms]

    def _build(self) -> None:
        """(Re)build the exact and the hull geometry models with every pair to check."""
        geom, self._names = self._robot_geom.copy(), list(self._obstacles)
        for obj in obstacle_model(self).geometryObjects:
            geom.addGeometryObject(obj)
        n_robot = self._robot_geom.ngeoms
        self._pairs = [*self._self_pairs, *((i, n_robot + k) for i in self._moving for k in range(len(self._names)))]
        geom.removeAllCollisionPairs()
        for a, b in self._pairs:
            geom.addCollisionPair(pin.CollisionPair(a, b))
        self._geom, self._gdata = geom, pin.GeometryData(geom)
        self._hulls = convex_hulls(geom)
        self._hdata = pin.GeometryData(self._hulls)
        self._margin = {id(self._gdata): 0.0, id(self._hdata): 0.0}
        self.version += 1

    def _q(self, q) -> np.ndarray:
        with naming("scene query", ConfigurationError):
            q = self.robot.check_q(q)
        return self.robot.to_pinocchio(q)

    def _check(self, q_pin: np.ndarray, margin: float, hulls: bool, stop_at_first: bool) -> bool:
        geom, gdata = (self._hulls, self._hdata) if hulls else (self._geom, self._gdata)
        if self._margin[id(gdata)] != margin:
            for req in gdata.collisionRequests:
                req.security_margin = margin
            self._margin[id(gdata)] = margin
        pin.updateGeometryPlacements(self.robot.model, self._data, geom, gdata, q_pin)
        return bool(pin.computeCollisions(geom, gdata, stop_at_first))

    # ------------------------------------------------------------------ queries
    @property
    def pair_count(self) -> int:
        """Number of checked pairs (self-collision pairs plus robot-obstacle pairs)."""
        return len(self._pairs)

    def in_collision(self, q, margin: float = 0.0) -> bool:
        """True when a checked pair of the collision meshes is in contact at ``q`` (or closer than ``margin`` m)."""
        return self._check(self._q(q), _length(margin, "margin", zero=True), hulls=False, stop_at_first=True)

    def colliding_pairs(self, q, margin: float = 0.0, most: int | None = None) -> list[tuple[str, str]]:
        """The (name, name) pairs in contact at ``q`` (closer than ``margin`` m), each once: robot links by link
        name, obstacles by their name; with ``most`` (an int >= 1), the first ``most`` of them. SceneError for
        another ``most``."""
        if most is not None and not (isinstance(most, int) and most >= 1):
            raise SceneError(f"most must be None or an int >= 1 (pairs listed at most), got {most!r}")
        self._check(self._q(q), _length(margin, "margin", zero=True), hulls=False, stop_at_first=False)
        pairs = [(self._object_name(a), self._object_name(b))
                 for (a, b), res in zip(self._pairs, self._gdata.collisionResults, strict=True) if res.isCollision()]
        return list(dict.fromkeys(pairs))[:most]  # a link may have several shapes

    def collides(self, Q, margin: float = 0.0, proxy: bool = False) -> np.ndarray:
        """(N,) bool: :meth:`in_collision` of each row of ``Q`` (N, n); ``proxy=True`` on the convex hulls
        (conservative, cheaper)."""
        Q, margin = self.robot.check_population(Q), _length(margin, "margin", zero=True)
        return np.fromiter((self._check(self.robot.to_pinocchio(q), margin, proxy, True) for q in Q), dtype=bool,
                           count=Q.shape[0])

    def distance(self, q) -> float:
        """Signed distance (m) of the closest checked pair at ``q``: the exact mesh clearance when positive, the
        convex hulls' penetration depth in contact, ``inf`` without pairs."""
        if not self._pairs:
            return math.inf
        q_pin, model = self._q(q), self.robot.model
        pin.updateGeometryPlacements(model, self._data, self._hulls, self._hdata, q_pin)
        pin.computeDistances(self._hulls, self._hdata)
        lower = np.array([r.min_distance for r in self._hdata.distanceResults])
        pin.updateGeometryPlacements(model, self._data, self._geom, self._gdata, q_pin)
        best = math.inf
        for k in np.argsort(lower):  # the hull distances bound the exact ones from below
            if lower[k] >= best:
                break
            d = pin.computeDistance(self._geom, self._gdata, int(k)).min_distance
            if d <= 0.0:  # in contact: coal reports 0 (or a depth for primitives)
                d = min(d, lower[k])
            best = min(best, d)
        return float(best)

    def check_robot(self, robot) -> None:
        """SceneError unless the scene was built for ``robot`` (the same loaded object)."""
        if robot is not self.robot:
            raise SceneError(f"this scene was built for {self.robot!r}, not for {robot!r}: build a Scene of the robot "
                             "you solve for (Scene(robot))")

    def __repr__(self) -> str:
        return (f"Scene({self.robot.name!r}, obstacles={list(self._obstacles)}, pairs={self.pair_count}, "
                f"self_collision={self.self_collision})")
