"""Drawing a robot at a configuration, or at several as translucent ghosts (``<name>/<k>``, one colour each):
``robot.visual_model`` (or :func:`skeleton_model`), one ``pinocchio.visualize.MeshcatVisualizer`` per node."""

from __future__ import annotations

import os
import warnings
from pathlib import Path

import numpy as np
import pinocchio as pin

from ..errors import ConfigurationError
from ..lie import rotation_to_z
from ..robot import Robot
from ..robot.frames import find_frame
from .server import _talks

__all__ = ["GHOST_COLORS", "GHOST_MESH_BUDGET", "skeleton_model"]

#: Ghost colours (RGB in [0, 1]), used in turn by :meth:`Viewer.show_solutions`.
GHOST_COLORS: tuple[tuple[float, float, float], ...] = (
    (0.12, 0.47, 0.71), (1.00, 0.50, 0.05), (0.17, 0.63, 0.17), (0.84, 0.15, 0.16), (0.58, 0.40, 0.74),
    (0.55, 0.34, 0.29), (0.89, 0.47, 0.76), (0.50, 0.50, 0.50), (0.74, 0.74, 0.13), (0.09, 0.75, 0.81),
)
#: Most bytes of mesh files :meth:`Viewer.show_solutions` embeds for its ghosts before it draws skeletons.
GHOST_MESH_BUDGET = 50_000_000


def _tip_frames(robot: Robot) -> list[str]:
    """The tip and ``tips``, each once."""
    return list(dict.fromkeys([robot.tip, *robot.tips]))


def _segments(robot: Robot) -> list[tuple[int, pin.SE3]]:
    """(parent joint, placement in it) of each joint origin, then of each of :func:`_tip_frames`."""
    model = robot.model
    points = [(model.parents[j], model.jointPlacements[j]) for j in range(1, model.njoints)]
    for name in _tip_frames(robot):
        tip = model.frames[find_frame(model, name)]
        points.append((tip.parentJoint, tip.placement))
    return points


def _base_joints(robot: Robot) -> int:
    """How many of the model's first joints are a floating base's (drawn as nothing)."""
    return 6 if robot.floating_base else 0


def skeleton_model(robot: Robot, radius: float | None = None) -> pin.GeometryModel:
    """A visual ``pin.GeometryModel`` on ``robot.model``'s joints: spheres of ``radius`` m (default 2 % of the
    reach, within [3, 30] mm) at the joint origins and tip frames, cylinders between, rails along prismatic ranges."""
    import coal

    model, geom = robot.model, pin.GeometryModel()
    r = float(np.clip(0.02 * _reach(robot), 0.003, 0.03)) if radius is None else float(radius)
    joint_rgba, link_rgba, rail_rgba = np.array([[0.9, 0.5, 0.1, 1.0], [0.55, 0.6, 0.7, 1.0], [0.3, 0.3, 0.35, 1.0]])

    def add(name: str, joint: int, placement: pin.SE3, shape, rgba: np.ndarray) -> None:
        frame = next(i for i, f in enumerate(model.frames) if f.parentJoint == joint)
        obj = pin.GeometryObject(name, joint, frame, placement, shape)
        obj.meshColor = rgba
        geom.addGeometryObject(obj)

    def cylinder(name: str, joint: int, p0: np.ndarray, p1: np.ndarray, radius: float, rgba: np.ndarray) -> None:
        length = float(np.linalg.norm(p1 - p0))
        if length > 1e-9:
            add(name, joint, pin.SE3(rotation_to_z(p1 - p0), (p0 + p1) / 2), coal.Cylinder(radius, length), rgba)

    revolute, axes, lower, upper = robot.chain_joints()
    tips = _tip_frames(robot)
    for k, (parent, M) in enumerate(_segments(robot)):
        is_tip = k >= model.njoints - 1
        if k < _base_joints(robot):
            continue
        child = k + 1 if not is_tip else parent
        name = tips[k - (model.njoints - 1)] if is_tip else model.names[k + 1]
        add(f"skeleton_{name}", child, pin.SE3.Identity() if not is_tip else M,
            coal.Sphere(r * (0.8 if is_tip else 1.0)), joint_rgba)
        cylinder(f"skeleton_to_{name}", parent, np.zeros(3), M.translation, 0.6 * r, link_rgba)
        if not is_tip and not revolute[k]:  # a prismatic joint slides along a rail spanning its bounds
            a = M.rotation @ axes[k]
            lo, hi = M.translation + lower[k] * a, M.translation + upper[k] * a
            cylinder(f"skeleton_rail_{name}", parent, lo, hi, 0.3 * r, rail_rgba)
    return geom


def _reach(robot: Robot) -> float:
    """The robot's size (m, >= 0.1): the longest polyline from the root through the joint origins to a tip frame, at
    rest, plus prismatic travel."""
    model = robot.model
    revolute, _, lower, upper = robot.chain_joints()
    travel = np.where(revolute, 0.0, np.maximum(np.abs(lower), np.abs(upper)))
    travel[:_base_joints(robot)] = 0.0
    if not robot.floating_base and len(robot.moving_joints(robot.tip)) == robot.n:
        links = sum(np.linalg.norm(M.translation) for _, M in _segments(robot))
        return max(0.1, float(links + travel.sum()))
    depth = np.zeros(model.njoints)  # path length from the root to each joint origin
    for j in range(1, model.njoints):
        own = 0.0 if j <= _base_joints(robot) else float(np.linalg.norm(model.jointPlacements[j].translation))
        depth[j] = depth[model.parents[j]] + own + travel[j - 1]
    ends = [depth[parent] + float(np.linalg.norm(M.translation)) for parent, M in _segments(robot)[model.njoints - 1:]]
    return max(0.1, float(max([*depth, *ends])))


def _visual_model(robot: Robot) -> tuple[pin.GeometryModel | None, str]:
    """(robot.visual_model or None, reason it is unusable)."""
    try:
        geom = robot.visual_model
    except (ValueError, RuntimeError, OSError) as exc:
        return None, f"its visual geometry could not be loaded ({exc})"
    if geom.ngeoms == 0:
        return None, "its URDF has no <visual> geometry"
    return geom, ""


def _meshcat_visualizer_class():
    from pinocchio.visualize import MeshcatVisualizer

    class _Visualizer(MeshcatVisualizer):
        """MeshcatVisualizer that can load Collada meshes as plain geometry, so a ghost colour applies."""

        plain_meshes = False

        def loadMeshFromFile(self, geometry_object):  # noqa: N802 - Pinocchio's name
            if self.plain_meshes and Path(geometry_object.meshPath).suffix.lower() == ".dae":
                import meshcat.geometry as mg

                return mg.DaeMeshGeometry.from_file(geometry_object.meshPath)
            return super().loadMeshFromFile(geometry_object)

    return _Visualizer


class RobotDrawing:
    """The Viewer's robot nodes."""

    def _load(self, node: str, rgba=None, geom: pin.GeometryModel | None = None):
        """Load the robot's geometry (or ``geom``) under ``node``, once; ``rgba`` colours every part (a ghost)."""
        vis = self._check_open()
        if node in self._viz:
            return self._viz[node]
        viz = _meshcat_visualizer_class()(self.robot.model, visual_model=self._geom if geom is None else geom)
        viz.plain_meshes = rgba is not None
        viz.initViewer(viewer=vis)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", UserWarning)  # Pinocchio skips unsupported parts
            viz.loadViewerModel(rootNodeName=node, visual_color=None if rgba is None else list(rgba))
        vis[node].set_transform(self._baseMo.homogeneous)
        self._viz[node] = viz
        return viz

    @_talks
    def show(self, q, scene=None, margin: float = 0.0) -> list[tuple[str, str]] | None:
        """Draw the robot (node ``robot``) at ``q`` (n,) or a result's ``.q``. With a collision ``scene``: its
        obstacles too (:meth:`show_scene`, when it changed) and the links in collision at ``q`` (closer than
        ``margin`` m) in red; returns then ``scene.colliding_pairs(q, margin)`` (None without a scene)."""
        q, pairs, links = self._q(q), None, set()
        if scene is not None:
            self._check_scene(scene)
            pairs = scene.colliding_pairs(q, margin)
        viz = self._load("robot")
        viz.display(self.robot.to_pinocchio(q))
        self.scene["robot"] = "robot"
        if scene is not None:
            if "scene" not in self.scene or self._drawn_scenes.get("scene") != (id(scene), scene.version):
                self.show_scene(scene)
            links = {name for pair in pairs for name in pair} - set(scene.obstacles)
        self._paint_links(viz, links)
        if links:
            self.scene["robot"] = f"robot, links in collision (red): {', '.join(sorted(links))}"
        return pairs

    @_talks
    def show_solutions(self, solutions, name: str = "solutions", opacity: float = 0.4, limit: int = 64,
                       style: str = "auto") -> list[str]:
        """Draw configurations (any form :class:`~evoik_pin.viz.Viewer` takes) as translucent ghosts ``<name>/<k>``,
        one colour each, at most ``limit`` (evenly spaced, with a warning); return their node names.

        ``style``: ``"mesh"``, ``"skeleton"``, or ``"auto"``: meshes unless the ghosts' mesh files exceed
        :data:`GHOST_MESH_BUDGET` bytes in all (each ghost embeds a copy). ConfigurationError for nothing to draw."""
        empty = getattr(solutions, "solutions", solutions)
        if isinstance(empty, list) and not empty:
            why = getattr(solutions, "message", "")
            raise ConfigurationError("show_solutions: no configurations given (an empty list of solutions)"
                                     + (f": {why}" if why else ""))
        Q = self._qs(solutions)
        name = name.strip("/")
        if not name or not 0.0 < opacity <= 1.0 or limit < 1 or style not in ("auto", "mesh", "skeleton"):
            raise ConfigurationError(f"show_solutions needs a non-empty name, 0 < opacity <= 1, limit >= 1 and style "
                                     f"'auto', 'mesh' or 'skeleton'; got name={name!r}, opacity={opacity}, "
                                     f"limit={limit}, style={style!r}")
        if Q.shape[0] > limit:
            keep = np.unique(np.linspace(0, Q.shape[0] - 1, limit).round().astype(int))
            warnings.warn(f"{Q.shape[0]} solutions: drawing {keep.size} of them (limit={limit})", UserWarning,
                          stacklevel=3)
            Q = Q[keep]
        if style == "auto":
            paths = [g.meshPath for g in self._geom.geometryObjects]
            mesh_bytes = sum(os.path.getsize(f) for f in paths if f and os.path.isfile(f))
            style = "skeleton" if Q.shape[0] * mesh_bytes > GHOST_MESH_BUDGET else "mesh"
        geom = None
        if style == "skeleton" and not self.skeleton:
            if self._skeleton_geom is None:
                self._skeleton_geom = skeleton_model(self.robot)
            geom = self._skeleton_geom
        self.delete(name)
        for k, q in enumerate(Q):
            rgba = (*GHOST_COLORS[k % len(GHOST_COLORS)], opacity)
            self._load(f"{name}/{k}", rgba, geom).display(self.robot.to_pinocchio(q))
            self.scene[f"{name}/{k}"] = "ghost skeleton" if style == "skeleton" else "ghost"
        return [f"{name}/{k}" for k in range(Q.shape[0])]
