"""Markers of targets and goals in the base frame: a triad (x red, y green, z blue) for a pose, a sphere for a
position, a goal's frame name as a label; and a goal-list answer with its goals (``show_solution``)."""

from __future__ import annotations

import numpy as np
import pinocchio as pin

from ..errors import TargetError
from ..lie import is_rotation
from .server import _talks

__all__ = ["GOAL_LABEL_HEIGHT"]

#: Height (m) of a goal's label as a fraction of its marker's size.
GOAL_LABEL_HEIGHT = 0.5
_POINT_COLOR = 0xE02020
_ORIGIN_COLOR = 0xF0C020
_AXIS_COLORS = (("x", 0xE02020), ("y", 0x20C020), ("z", 0x2040F0))


def _draw_marker(node, p: np.ndarray, R: np.ndarray | None, size: float) -> str:
    """Draw under meshcat node ``node`` a triad of axis length ``size`` (m) at (p, R), or a sphere of radius
    ``size / 4`` at ``p`` when ``R`` is None; returns "triad" or "point"."""
    import meshcat.geometry as mg

    if R is None:
        node["point"].set_object(mg.Sphere(size / 4), mg.MeshPhongMaterial(color=_POINT_COLOR))
    else:
        node["origin"].set_object(mg.Sphere(size / 12), mg.MeshPhongMaterial(color=_ORIGIN_COLOR))
        turn = {"x": pin.utils.rotate("z", -np.pi / 2), "y": np.eye(3), "z": pin.utils.rotate("x", np.pi / 2)}
        for axis, color in _AXIS_COLORS:
            node[axis].set_object(mg.Cylinder(size, size / 30), mg.MeshPhongMaterial(color=color))
            T = np.eye(4)
            T[:3, :3] = turn[axis]  # meshcat's cylinder runs along y
            T[:3, 3] = turn[axis] @ np.array([0.0, size / 2, 0.0])
            node[axis].set_transform(T)
    node.set_transform(pin.SE3(np.eye(3) if R is None else R, p).homogeneous)
    return "point" if R is None else "triad"


def _label(text: str):
    """A meshcat sprite showing ``text``, facing the camera (a ``_text`` texture, 256 x 256 px)."""
    import meshcat.geometry as mg

    class _TextTexture(mg.Texture):
        def lower(self, object_data):
            return {"uuid": self.uuid, "type": "_text", "text": text, "font_size": 48, "font_face": "sans-serif"}

    class _SpriteMaterial(mg.Material):
        _type = "SpriteMaterial"

        def lower(self, object_data):
            return {"uuid": self.uuid, "type": self._type, "map": _TextTexture().lower_in_object(object_data),
                    "transparent": True, "depthTest": False}

    class _Sprite(mg.Object):
        _type = "Sprite"

        def lower(self):
            data = super().lower()
            data["object"]["renderOrder"] = 1  # after the meshes: a label is not hidden by the link it names
            return data

    # a Sprite takes no geometry of its own; meshcat's Object wants one, and three.js ignores it
    return _Sprite(mg.Box([1e-3, 1e-3, 1e-3]), _SpriteMaterial())


class MarkerDrawing:
    """The Viewer's target and goal markers."""

    def _marker_size(self, size: float | None) -> float:
        """Axis length (m) of a triad: ``size``, or 15 % of the robot's reach within [2 cm, 20 cm]."""
        return float(np.clip(0.15 * self._reach, 0.02, 0.2)) if size is None else float(size)

    @_talks
    def show_target(self, position, rotation=None, name: str = "target", size: float | None = None) -> None:
        """Draw an IK target at ``position`` (3,) m (or a ``pin.SE3``) under node ``name``: a triad of axis length
        ``size`` m (default 15 % of the reach, within [2, 20] cm) with a ``rotation`` (3, 3), else a point."""
        if isinstance(position, pin.SE3):
            position, rotation = position.translation, position.rotation if rotation is None else rotation
        p = np.asarray(position, dtype=float)
        if p.shape != (3,) or not np.all(np.isfinite(p)):
            raise TargetError(f"target position must be 3 finite numbers (m), got shape {p.shape}: {p}")
        R = None if rotation is None else np.asarray(rotation, dtype=float)
        if R is not None:
            if R.shape != (3, 3) or not np.all(np.isfinite(R)):
                raise TargetError(f"target rotation must be a finite (3, 3) matrix, got shape {R.shape}")
            if not is_rotation(R):
                raise TargetError("target rotation is not a rotation matrix (R^T R != I or det R != 1)")
        node, name = self._fresh(name)
        self.scene[name] = "target " + _draw_marker(node, p, R, self._marker_size(size))

    @_talks
    def show_goals(self, goals, name: str = "goals", size: float | None = None, labels: bool = True) -> list[str]:
        """Draw a marker ``<name>/<frame>`` per goal of a goal list that has a place (``goal.marker()``), ``size`` as
        for :meth:`show_target`, with ``labels`` its frame name (``<name>/<frame>/label``); return the node names."""
        from ..goals import bind

        goals, s = bind(self.robot, goals)[0], self._marker_size(size)
        root, name = self._fresh(name)
        nodes = []
        for goal in goals:
            marker = goal.marker()  # (node name, point, rotation or None), or None: no place to mark
            if marker is None:
                continue
            frame, p, R = marker
            node = f"{name}/{frame}"
            if node in nodes:  # the same frame twice (bind refuses clashing targets)
                continue
            kind = _draw_marker(root[frame], p, R, s)
            if labels:
                label = root[frame]["label"]
                label.set_object(_label(frame))
                # above the marker along the base frame's z (R^T: the offset would turn with the pose)
                T = np.diag([s * 4 * GOAL_LABEL_HEIGHT] * 3 + [1.0])  # the 256 px canvas: text ~ a quarter of it
                T[:3, 3] = (R.T if R is not None else np.eye(3)) @ np.array([0.0, 0.0, 0.6 * s])
                label.set_transform(T)
            self.scene[node] = f"goal {kind}: {frame}"
            nodes.append(node)
        return nodes

    @_talks
    def show_solution(self, result, goals, scene=None, margin: float = 0.0, name: str = "goals",
                      frame: bool = True) -> list[tuple[str, str]] | None:
        """Draw a goal-list answer: the robot at ``result.q`` (:meth:`show` with ``scene`` and ``margin``, whose
        return this returns), the ``goals`` under ``name`` (:meth:`show_goals`), and with ``frame`` the camera on
        the links and goals (:meth:`frame`)."""
        pairs = self.show(result, scene=scene, margin=margin)
        self.show_goals(goals, name=name)
        if frame:
            links = [i for i, f in enumerate(self.robot.model.frames) if f.type == pin.FrameType.BODY]
            poses = self.robot.frame_poses_unchecked(self._q(result), links)
            self.frame(np.array([M.translation for M in poses]
                                + [m[1] for m in (g.marker() for g in goals) if m is not None]))
        return pairs

