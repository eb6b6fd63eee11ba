"""The static exports: the scene (with its animation) as one self-contained HTML file, a retargeted clip as one (the
robot playing it, the source's keypoints beside it as small spheres moving with it), and reading one back."""

from __future__ import annotations

import base64
import os
import re
from pathlib import Path

import numpy as np
import pinocchio as pin

from ..errors import ViewerError
from .server import _talks

__all__ = ["KEYPOINT_COLOR", "KEYPOINT_RADIUS", "html_commands", "save_clip_html"]

_COMMAND_RE = re.compile(r'fetch\("data:application/octet-binary;base64,([A-Za-z0-9+/=]+)"\)')
#: Radius (m) and colour (0xRRGGBB) of a source keypoint's sphere in :func:`save_clip_html`.
KEYPOINT_RADIUS = 0.015
KEYPOINT_COLOR = 0xFF8C00


def html_commands(html: str) -> list[dict]:
    """The meshcat commands (dicts with ``type``, ``path`` and the payload) the static HTML ``html``
    (:meth:`Viewer.save_html`) replays, in order, decoded from its base64 msgpack blobs."""
    import umsgpack

    return [umsgpack.unpackb(base64.b64decode(m)) for m in _COMMAND_RE.findall(html)]


class HtmlExport:
    """The Viewer's export method."""

    @_talks
    def save_html(self, path: str | os.PathLike) -> Path:
        """Write the scene (with its animation) as one self-contained HTML file (no server needed); return its path."""
        html = self._check_open().static_html()
        html = html.replace("<title>MeshCat</title>", f"<title>evoik_pin: {self.robot.name}</title>", 1)
        out = Path(path).expanduser()
        try:
            out.write_text(html, encoding="utf-8")
        except OSError as exc:
            raise ViewerError(f"cannot write the HTML scene to {str(out)!r}: {exc.strerror or exc}") from exc
        return out


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
