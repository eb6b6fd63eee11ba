"""A retargeted clip as one self-contained HTML page: the robot playing the clip, the source's keypoints beside it
as small spheres moving with it (one meshcat animation, so the static export keeps both)."""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np
import pinocchio as pin

__all__ = ["KEYPOINT_COLOR", "KEYPOINT_RADIUS", "save_clip_html"]

#: Radius (m) and colour (0xRRGGBB) of a source keypoint's sphere.
KEYPOINT_RADIUS = 0.015
KEYPOINT_COLOR = 0xFF8C00


def save_clip_html(robot, clip, path: str | os.PathLike, keypoints: bool = True) -> Path:
    """Write ``clip`` (a :class:`~evoik_pin.motion.Clip` of ``robot``) as a self-contained HTML page playing it at
    its fps, and return the path. ``keypoints``: also the source keypoints the robot followed (``clip.keypoints``,
    scaled into the robot's world), as orange spheres under ``keypoints/<name>``."""
    import meshcat.geometry as mg

    from . import Viewer

    with Viewer(robot) as viewer:
        Q, vis = viewer._qs(clip.q), viewer._check_open()
        points = clip.keypoints if keypoints and clip.keypoints is not None else None
        for name in clip.keypoint_names if points is not None else ():
            vis["keypoints"][name].set_object(mg.Sphere(KEYPOINT_RADIUS), mg.MeshLambertMaterial(color=KEYPOINT_COLOR))

        def move_keypoints(frame, k: int) -> None:
            for name, p in zip(clip.keypoint_names, points[k], strict=True):
                frame["keypoints"][name].set_transform(pin.SE3(np.eye(3), p).homogeneous)

        viewer._animate_robot(Q, clip.fps, each_frame=move_keypoints if points is not None else None)
        viewer.scene["animation"] = f"{Q.shape[0]} frames at {clip.fps:g} fps"
        return viewer.save_html(path)
