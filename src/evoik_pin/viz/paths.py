"""Point clouds, polylines and trajectories: reachability maps (``show_points``), tip paths (``draw_path``) and
the robot animated along a trajectory (``animate``).

``animate`` keys the geometry nodes' poses into one meshcat ``Animation``; meshcat puts an object under
``<path>/<object>``, so the animated group nodes survive in the static export, where the animation command is
replayed before the objects.
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin

from ..errors import ConfigurationError, TargetError
from .ghosts import GHOST_COLORS
from .server import _talks


def _hex(rgb) -> int:
    """0xRRGGBB of an RGB triple in [0, 1] (clipped)."""
    r, g, b = (int(round(255 * float(np.clip(c, 0.0, 1.0)))) for c in rgb[:3])
    return (r << 16) | (g << 8) | b


class PathDrawing:
    """The Viewer's point clouds, polylines and animation."""

    @_talks
    def show_points(self, points, values=None, name: str = "points", size: float | None = None,
                    cmap: str = "viridis", vmin: float = 0.0, vmax: float = 1.0) -> None:
        """Draw a point cloud (e.g. the voxels of a reachability map), coloured by ``values``.

        Args:
            points: (N, 3) positions in m in the base frame.
            values: (N,) numbers mapped through the matplotlib colormap ``cmap`` over [vmin, vmax]; None: one colour.
            name: node name. size: point size in m (default 2 % of the robot's reach, within [5 mm, 5 cm]).
        """
        import matplotlib
        import meshcat.geometry as mg

        P = np.asarray(points, dtype=float)
        if P.ndim != 2 or P.shape[1] != 3 or P.shape[0] < 1 or not np.all(np.isfinite(P)):
            raise TargetError(f"points must be a finite (N, 3) array with N >= 1 (m), got shape {P.shape}")
        if values is None:
            colors = np.tile(GHOST_COLORS[0], (P.shape[0], 1))
        else:
            v = np.asarray(values, dtype=float).reshape(-1)
            if v.shape != (P.shape[0],) or not np.all(np.isfinite(v)) or not vmax > vmin:
                raise ConfigurationError(f"values must be {P.shape[0]} finite numbers and vmax > vmin; got shape "
                                         f"{v.shape}, vmin {vmin}, vmax {vmax}")
            colors = matplotlib.colormaps[cmap](np.clip((v - vmin) / (vmax - vmin), 0.0, 1.0))[:, :3]
        s = float(np.clip(0.02 * self._reach, 0.005, 0.05)) if size is None else float(size)
        vis = self._check_open()
        name = name.strip("/")
        self.delete(name)
        vis[name].set_object(mg.PointCloud(P.T.astype(np.float32), colors.T.astype(np.float32), size=s))
        self.scene[name] = f"cloud of {P.shape[0]} points"

    @_talks
    def draw_path(self, points, name: str = "path", color=(0.85, 0.1, 0.6)) -> None:
        """Draw a polyline through ``points`` (N, 3) in m in the base frame (N >= 2), e.g. a tip path."""
        import meshcat.geometry as mg

        P = np.asarray(points, dtype=float)
        if P.ndim != 2 or P.shape[1] != 3 or P.shape[0] < 2 or not np.all(np.isfinite(P)):
            raise TargetError(f"path points must be a finite (N, 3) array with N >= 2 (m), got shape {P.shape}")
        vis = self._check_open()
        name = name.strip("/")
        self.delete(name)
        vis[name].set_object(mg.Line(mg.PointsGeometry(P.T.astype(np.float32)),
                                     mg.LineBasicMaterial(color=_hex(color), linewidth=2)))
        self.scene[name] = f"line of {P.shape[0]} points"

    @_talks
    def animate(self, trajectory, dt: float = 0.05, path: bool = True, repetitions: int = 1) -> None:
        """Animate the robot along a trajectory (a meshcat animation, so the HTML export keeps it).

        Args:
            trajectory: joint vectors (N, n) in rad/m (a list, an array, or results with ``.q``).
            dt: time between two configurations (s).
            path: also draw the tip's path through the trajectory (node ``path``).
            repetitions: how many times the animation plays (the browser's Animations panel replays it).

        The robot is left displayed at the first configuration; one animation exists at a time (a new one
        replaces it).
        """
        import meshcat.animation

        Q = self._qs(trajectory)
        if not (np.isfinite(dt) and dt > 0):
            raise ConfigurationError(f"dt must be a positive number of seconds, got {dt}")
        vis = self._check_open()
        viz = self._load("robot")
        anim = meshcat.animation.Animation(default_framerate=1.0 / dt)
        geom = viz.visual_model
        nodes = [viz.getViewerNodeName(g, pin.GeometryType.VISUAL) for g in geom.geometryObjects]
        for k, q in enumerate(Q):
            placements = self.robot.geometry_placements(geom, q)
            with anim.at_frame(vis, k) as frame:
                for node, M in zip(nodes, placements, strict=True):  # rigid poses: the mesh scale stays as loaded
                    frame[node].set_transform(M.homogeneous)
        self.show(Q[0])
        vis.set_animation(anim, play=True, repetitions=int(repetitions))
        self.scene["animation"] = f"{Q.shape[0]} frames, dt {dt:g} s"
        if path:
            P, _ = self.robot.fk_batch(Q)
            if P.shape[0] >= 2:
                self.draw_path(P)
