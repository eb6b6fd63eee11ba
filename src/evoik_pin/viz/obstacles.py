"""Collision scenes in the viewer: a Scene's obstacles in translucent grey, the robot's links in contact in red
(reloaded as plain geometry: ``set_object`` commands, which the static export keeps)."""

from __future__ import annotations

import warnings

import pinocchio as pin

from ..errors import ConfigurationError, SceneError
from ..scene.geometry import obstacle_model
from .server import _talks

__all__ = ["COLLISION_RGBA", "OBSTACLE_RGBA", "obstacle_model"]

#: Obstacles of a scene (RGBA in [0, 1]): translucent grey.
OBSTACLE_RGBA = (0.55, 0.55, 0.55, 0.6)
#: Robot links in collision: opaque red.
COLLISION_RGBA = (0.9, 0.05, 0.05, 1.0)


class ObstacleDrawing:
    """The Viewer's scene nodes: obstacles, and the robot's links in collision painted red."""

    def _check_scene(self, scene) -> None:
        """SceneError unless ``scene`` is a Scene of this Viewer's robot (the same object or chain)."""
        from ..scene import Scene

        if not isinstance(scene, Scene):
            raise SceneError(f"scene must be an evoik_pin.Scene, got {type(scene).__name__}")
        other = scene.robot
        if other is not self.robot and (other.name, other.base, list(other.joint_names)) != (
                self.robot.name, self.robot.base, list(self.robot.joint_names)):
            scene.check_robot(self.robot)  # raises

    def _paint_links(self, viz, links: set[str]) -> None:
        """Draw the visual geometry of ``links`` (link names) red and give the others their own colours back."""
        model = self.robot.model
        if self.skeleton:  # skeleton parts hang on the joints carrying the links
            joints = {model.frames[model.getFrameId(name)].parentJoint for name in links}
            red = {g.name for g in viz.visual_model.geometryObjects if g.parentJoint in joints}
        else:
            red = {g.name for g in viz.visual_model.geometryObjects if model.frames[g.parentFrame].name in links}
        before, plain = self._red[1] if self._red[0] is viz else frozenset(), viz.plain_meshes
        try:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore", UserWarning)
                for g in viz.visual_model.geometryObjects:
                    if (g.name in red) != (g.name in before):
                        viz.plain_meshes = g.name in red
                        viz.loadViewerGeometryObject(g, pin.GeometryType.VISUAL,
                                                     list(COLLISION_RGBA) if g.name in red else None)
        finally:
            viz.plain_meshes = plain
        self._red = (viz, frozenset(red))

    @_talks
    def show_scene(self, scene, name: str = "scene", color=OBSTACLE_RGBA[:3],
                   opacity: float = OBSTACLE_RGBA[3]) -> list[str]:
        """Draw the obstacles of a :class:`~evoik_pin.scene.Scene` of this robot as ``<name>/visuals/<o>`` in
        ``color`` (RGB in [0, 1]) and ``opacity``; return their node names."""
        self._check_scene(scene)
        name = name.strip("/")
        if not name or not 0.0 < opacity <= 1.0:
            raise ConfigurationError(f"show_scene needs a non-empty name and 0 < opacity <= 1; got name={name!r}, "
                                     f"opacity={opacity}")
        self.delete(name)
        geom = obstacle_model(scene)
        self._drawn_scenes[name] = (id(scene), scene.version)
        self.scene[name] = f"{geom.ngeoms} obstacle(s)" + (f": {', '.join(scene.obstacles)}" if geom.ngeoms else "")
        if geom.ngeoms == 0:
            return []
        viz = self._load(name, (*color, opacity), geom)
        viz.display(pin.neutral(self.robot.model))
        return [viz.getViewerNodeName(g, pin.GeometryType.VISUAL) for g in geom.geometryObjects]
