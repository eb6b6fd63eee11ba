"""The camera: where meshcat's default camera stands and what it looks at, and framing a set of points."""

from __future__ import annotations

import numpy as np

from ..errors import ConfigurationError, TargetError
from .server import _talks

__all__ = ["CAMERA_FOV_DEG", "checked_points"]

#: Vertical field of view (degrees) of meshcat's default camera.
CAMERA_FOV_DEG = 75.0
#: Direction (front, side, above) the default camera looks from.
_VIEW_DIRECTION = np.array([0.9, 0.7, 0.55])


def checked_points(points, what: str, least: int) -> np.ndarray:
    """``points`` as a finite (N, 3) array (m) with N >= ``least``, or a TargetError naming ``what``."""
    P = np.asarray(points, dtype=float)
    if P.ndim != 2 or P.shape[1] != 3 or P.shape[0] < least or not np.all(np.isfinite(P)):
        raise TargetError(f"{what} must be a finite (N, 3) array with N >= {least} (m), got shape {P.shape}")
    return P


class Camera:
    """The Viewer's camera methods."""

    @_talks
    def set_camera(self, position=None, target=None) -> None:
        """Place the camera at ``position`` (3,) m (default: in front of, beside and above ``target`` at the robot's
        reach), looking at ``target`` (3,) m (default: the base). Meshcat's camera looks at the origin: the drawing
        is translated by ``-target`` instead."""
        vis = self._check_open()
        t = np.zeros(3) if target is None else np.asarray(target, dtype=float)
        if t.shape != (3,) or not np.all(np.isfinite(t)):
            raise ConfigurationError(f"camera target must be 3 finite numbers (m), got {t}")
        c = t + self._reach * _VIEW_DIRECTION if position is None else np.asarray(position, dtype=float)
        if c.shape != (3,) or not np.all(np.isfinite(c)):
            raise ConfigurationError(f"camera position must be 3 finite numbers (m), got {c}")
        if not np.array_equal(t, self._camera_target):
            shift = np.eye(4)
            shift[:3, 3] = -t
            for node in ("/meshcat", "/Grid", "/Axes"):  # the grid's and the axes' own transforms are identities
                vis[node].set_transform(shift)
            self._camera_target = t.copy()
        d = c - t
        # meshcat's camera lives in a y-up frame rotated onto the z-up world: world (x, y, z) -> (x, z, -y)
        vis["/Cameras/default/rotated/<object>"].set_property("position", [float(d[0]), float(d[2]), float(-d[1])])

    def frame(self, points, fill: float = 0.8) -> tuple[np.ndarray, np.ndarray]:
        """Point the camera at the bounding box of ``points`` (N, 3) m, backed off until the box fills about ``fill``
        of the view's height; returns (position, target), each (3,) m."""
        P = checked_points(points, "points to frame", 1)
        if not 0 < fill <= 1:
            raise ConfigurationError(f"fill must be in (0, 1], got {fill}")
        lo, hi = P.min(axis=0), P.max(axis=0)
        target = (lo + hi) / 2
        radius = max(0.5 * float(np.linalg.norm(hi - lo)), 0.01)  # the box's bounding sphere; a point: 1 cm
        # the sphere's silhouette spans 2 asin(radius / distance) of the vertical field of view
        distance = radius / np.sin(fill * np.radians(CAMERA_FOV_DEG) / 2)
        position = target + distance * _VIEW_DIRECTION / np.linalg.norm(_VIEW_DIRECTION)
        self.set_camera(position, target)
        return position, target
