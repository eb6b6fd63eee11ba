"""Point clouds (``show_points``), polylines (``draw_path``) and the robot animated along a trajectory (``animate``:
one meshcat ``Animation``, which the static export keeps)."""

from __future__ import annotations

import numpy as np
import pinocchio as pin

from ..errors import ConfigurationError
from .camera import checked_points
from .robot_drawing import GHOST_COLORS
from .server import _talks


class PathDrawing:
    """The Viewer's point clouds, polylines and animation."""

    @_talks
    def show_points(self, points, values=None, name: str = "points", size: float | None = None,
                    cmap: str = "viridis", vmin: float = 0.0, vmax: float = 1.0) -> None:
        """Draw a point cloud ``points`` (N, 3) m under node ``name``, coloured by ``values`` (N,) through the
        matplotlib colormap ``cmap`` over [vmin, vmax] (None: one colour); ``size`` m (default from the reach)."""
        import matplotlib
        import meshcat.geometry as mg

        P = checked_points(points, "points", 1)
        if values is None:
            colors = np.tile(GHOST_COLORS[0], (P.shape[0], 1))
        else:
            v = np.asarray(values, dtype=float).reshape(-1)
            if v.shape != (P.shape[0],) or not np.all(np.isfinite(v)) or not vmax > vmin:
                raise ConfigurationError(f"values must be {P.shape[0]} finite numbers and vmax > vmin; got shape "
                                         f"{v.shape}, vmin {vmin}, vmax {vmax}")
            colors = matplotlib.colormaps[cmap](np.clip((v - vmin) / (vmax - vmin), 0.0, 1.0))[:, :3]
        s = float(np.clip(0.02 * self._reach, 0.005, 0.05)) if size is None else float(size)
        node, name = self._fresh(name)
        node.set_object(mg.PointCloud(P.T.astype(np.float32), colors.T.astype(np.float32), size=s))
        self.scene[name] = f"cloud of {P.shape[0]} points"

    @_talks
    def draw_path(self, points, name: str = "path", color=(0.85, 0.1, 0.6)) -> None:
        """Draw a polyline through ``points`` (N, 3) in m in the base frame (N >= 2), e.g. a tip path."""
        import meshcat.geometry as mg

        P = checked_points(points, "path points", 2)
        r, g, b = (int(round(255 * float(np.clip(c, 0.0, 1.0)))) for c in color[:3])  # 0xRRGGBB of RGB in [0, 1]
        node, name = self._fresh(name)
        node.set_object(mg.Line(mg.PointsGeometry(P.T.astype(np.float32)),
                                mg.LineBasicMaterial(color=(r << 16) | (g << 8) | b, linewidth=2)))
        self.scene[name] = f"line of {P.shape[0]} points"

    @_talks
    def animate(self, trajectory, dt: float = 0.05, path: bool = True, repetitions: int = 1) -> None:
        """Animate the robot along ``trajectory`` (N, n) (joint vectors or results) at ``dt`` s per configuration,
        ``repetitions`` times, with ``path`` the tip's path (node ``path``); the robot is left at the first."""
        Q = self._qs(trajectory)
        if not (np.isfinite(dt) and dt > 0):
            raise ConfigurationError(f"dt must be a positive number of seconds, got {dt}")
        self._animate_robot(Q, 1.0 / dt, repetitions)
        self.scene["animation"] = f"{Q.shape[0]} frames, dt {dt:g} s"
        if path:
            P, _ = self.robot.fk_batch(Q)
            if P.shape[0] >= 2:
                self.draw_path(P)

    def _animate_robot(self, Q: np.ndarray, fps: float, repetitions: int = 1, each_frame=None) -> None:
        """Key the robot's geometry poses at each row of ``Q`` (N, n) into one meshcat animation at ``fps``
        (``each_frame(frame, k)`` keys more nodes), show ``Q[0]`` and play it."""
        import meshcat.animation

        vis, viz = self._check_open(), self._load("robot")
        anim = meshcat.animation.Animation(default_framerate=float(fps))
        geom = viz.visual_model
        nodes = [viz.getViewerNodeName(g, pin.GeometryType.VISUAL) for g in geom.geometryObjects]
        for k, q in enumerate(Q):
            with anim.at_frame(vis, k) as frame:
                for node, M in zip(nodes, self.robot.geometry_placements(geom, q), strict=True):
                    frame[node].set_transform(M.homogeneous)
                if each_frame is not None:
                    each_frame(frame, k)
        self.show(Q[0])
        vis.set_animation(anim, play=True, repetitions=int(repetitions))
