"""Meshcat web preview of a robot, targets and goals, solutions, trajectories, obstacles, and a static HTML export
(docs/API.md): :class:`Viewer`, in the robot's base frame (m). Nodes: ``robot``, ``solutions/<k>``, ``target``,
``goals/<frame>``, ``path``, ``scene/visuals/<obstacle>``; the drawing is the mixins' of the modules beside this one.
"""

from __future__ import annotations

import base64
import os
import re
import subprocess
import sys
import time
import warnings
import webbrowser
from pathlib import Path

import numpy as np
import pinocchio as pin

from ..errors import ConfigurationError, OptionError, ViewerError
from ..robot import Robot
from .camera import CAMERA_FOV_DEG, Camera
from .markers import MarkerDrawing
from .obstacles import COLLISION_RGBA, OBSTACLE_RGBA, ObstacleDrawing, obstacle_model
from .paths import PathDrawing
from .robot_drawing import GHOST_COLORS, GHOST_MESH_BUDGET, RobotDrawing, _reach, _visual_model, skeleton_model
from .server import _connect, _import_meshcat, _probe, _Server, _talks

__all__ = ["CAMERA_FOV_DEG", "COLLISION_RGBA", "GHOST_COLORS", "GHOST_MESH_BUDGET", "KEYPOINT_COLOR", "KEYPOINT_RADIUS",
           "OBSTACLE_RGBA", "OWN_SERVER_HANG_S", "PROBE_TIMEOUT", "SERVER_TIMEOUT", "Viewer", "html_commands",
           "obstacle_model", "save_clip_html", "save_solution_html", "skeleton_model"]

#: Seconds to wait for an external server (``Viewer(zmq_url=...)``) to answer one request.
SERVER_TIMEOUT = 20.0
#: Seconds after which a Viewer's own server that neither answers nor exits counts as wedged.
OWN_SERVER_HANG_S = 600.0
#: Seconds to wait for an external server (``Viewer(zmq_url=...)``) to answer its first request.
PROBE_TIMEOUT = 5.0
#: Radius (m) and colour (0xRRGGBB) of a source keypoint's sphere in :func:`save_clip_html`.
KEYPOINT_RADIUS = 0.015
KEYPOINT_COLOR = 0xFF8C00


_COMMAND_RE = re.compile(r'fetch\("data:application/octet-binary;base64,([A-Za-z0-9+/=]+)"\)')


def html_commands(html: str) -> list[dict]:
    """The meshcat commands (dicts with ``type``, ``path`` and the payload) the static HTML ``html``
    (:meth:`Viewer.save_html`) replays, in order."""
    import umsgpack

    return [umsgpack.unpackb(base64.b64decode(m)) for m in _COMMAND_RE.findall(html)]


class Viewer(RobotDrawing, MarkerDrawing, ObstacleDrawing, PathDrawing, Camera):
    """A meshcat scene of one robot: configurations, ghosts, targets and goals, paths, animation, HTML export.

    ``robot``: a :class:`~evoik_pin.robot.Robot`; ``zmq_url``: a running meshcat server to draw into (None: a
    private one on 127.0.0.1); ``open``: open the scene in the browser; ``skeleton``: True draws spheres and
    cylinders, None the URDF's visuals when it has some. Attributes: ``url``, ``zmq_url``, ``scene`` (``{node path:
    description}`` of what was drawn), ``skeleton``, ``vis`` (the ``meshcat.Visualizer``).

    Configurations are ``(n,)`` joint vectors (rad, m) or objects with ``.q`` (a :class:`~evoik_pin.Result`); a list
    of them may also be an ``(N, n)`` array, a :class:`~evoik_pin.Front`, or a result with ``solutions`` or ``front``.
    """

    def __init__(self, robot: Robot, zmq_url: str | None = None, open: bool = False, skeleton: bool | None = None):
        _import_meshcat()
        self.robot = robot
        self.vis, self._server = None, None
        self.scene: dict[str, str] = {}
        self._viz = {}  # node name -> pinocchio MeshcatVisualizer drawing the robot there
        self._red: tuple[object, frozenset[str]] = (None, frozenset())  # (robot visualizer, its red geometry names)
        self._drawn_scenes: dict[str, tuple[int, int]] = {}  # node -> (id, version) of the Scene drawn there
        geom, why = (None, "") if skeleton else _visual_model(robot)
        self.skeleton = geom is None
        if geom is None:
            if why:
                warnings.warn(f"{robot.name}: {why}; drawing a skeleton (spheres at the joints, cylinders "
                              "between them) instead", UserWarning, stacklevel=2)
            geom = skeleton_model(robot)
        self._geom, self._skeleton_geom = geom, None
        self._reach = _reach(robot)
        self._baseMo = robot.base_placement.inverse()  # the model's world frame seen from the base frame
        self._camera_target = np.zeros(3)  # the point the camera looks at (m, base frame)
        try:
            if zmq_url is None:
                self._server = _Server(OWN_SERVER_HANG_S)
                self.zmq_url, self.url = self._server.zmq_url, self._server.web_url
            else:
                self.zmq_url, self.url = zmq_url, _probe(zmq_url, timeout=PROBE_TIMEOUT)
            self.vis = _connect(self.zmq_url, self.url, self.server_process, SERVER_TIMEOUT, OWN_SERVER_HANG_S)
            self.set_camera()
        except BaseException:
            self.close()
            raise
        if open:
            webbrowser.open(self.url, new=2)

    # ------------------------------------------------------------------ life cycle
    def close(self) -> None:
        """Disconnect and stop the Viewer's own server (a server given by ``zmq_url`` keeps running)."""
        vis = getattr(self, "vis", None)
        if vis is not None:
            vis.window.zmq_socket.close(linger=0)
            self.vis = None
        if self._server is not None:
            self._server.stop()
            self._server = None

    def __enter__(self) -> Viewer:
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    @property
    def server_process(self) -> subprocess.Popen | None:
        """The meshcat server subprocess this Viewer started (None when it uses an external server)."""
        return self._server.proc if self._server is not None else None

    def block(self, message: str | None = None, file=None) -> None:
        """Keep the server running until Ctrl-C (or its exit), then close the Viewer. ``message``: a line printed
        to ``file`` (default stdout) first."""
        if message is not None and not isinstance(message, str):
            raise OptionError(f"Viewer.block: message must be a str (a line to print) or None, not "
                              f"{type(message).__name__}")
        try:
            if message is not None:
                print(message, file=sys.stdout if file is None else file, flush=True)
            while self._server is None or self._server.proc.poll() is None:
                time.sleep(0.5)
        except KeyboardInterrupt:
            pass
        finally:
            self.close()

    def _check_open(self):
        if self.vis is None:
            raise ViewerError("this Viewer is closed")
        return self.vis

    # ------------------------------------------------------------------ inputs
    def _q(self, q) -> np.ndarray:
        return self.robot.check_q(getattr(q, "q", q))

    def _qs(self, items) -> np.ndarray:
        """(N, n) configurations from joint vectors / results, an (N, n) array, a front or a multi-solution result."""
        if getattr(items, "solutions", None) is not None:
            items = items.solutions
        elif getattr(items, "front", None) is not None:
            items = items.front.q
        elif hasattr(items, "q"):  # a Front (q is (M, n)) or a single Result
            items = items.q
        if not isinstance(items, np.ndarray):
            items = list(items)
            if items and all(np.ndim(getattr(it, "q", it)) == 0 for it in items):
                items = [items]  # one joint vector given as a flat list
            items = [self._q(it) for it in items]
        arr = np.asarray(items, dtype=float)
        if arr.ndim == 1 and arr.size:
            arr = self._q(arr)[None, :]
        if arr.size == 0:
            raise ConfigurationError("no configurations given (an empty list)")
        return self.robot.check_population(arr)

    @_talks
    def delete(self, name: str) -> None:
        """Remove a node and everything below it (e.g. ``"solutions"``, ``"target"``) from the scene."""
        vis = self._check_open()
        name = name.strip("/")
        if not name:
            raise ConfigurationError("delete needs a node name; an empty name would clear the whole scene")
        vis[name].delete()
        for drawn in (self.scene, self._viz):
            for key in [k for k in drawn if k == name or k.startswith(name + "/")]:
                del drawn[key]

    def _fresh(self, name: str):
        """(meshcat node, name) of the node ``name`` (slashes stripped), deleted for a new drawing."""
        name = name.strip("/")
        self.delete(name)
        return self._check_open()[name], name

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

    def __repr__(self) -> str:
        return f"Viewer({self.robot.name!r}, url={getattr(self, 'url', None)!r}, scene={list(self.scene)})"


def save_solution_html(robot: Robot, result, goals, path: str | os.PathLike, scene=None,
                       margin: float = 0.0) -> Path:
    """Write :meth:`Viewer.show_solution` of ``result`` (or a joint vector (n,)) for ``goals`` (and a collision
    ``scene`` with its ``margin``, m) as one self-contained HTML file ``path``; return its path."""
    with Viewer(robot) as viewer:
        viewer.show_solution(result, goals, scene=scene, margin=margin)
        return viewer.save_html(path)


def save_clip_html(robot, clip, path: str | os.PathLike, keypoints: bool = True) -> Path:
    """Write ``clip`` (a :class:`~evoik_pin.motion.Clip` of ``robot``) as a self-contained HTML page playing it at
    its fps; return the path. ``keypoints``: also ``clip.keypoints``, as spheres under ``keypoints/<name>``."""
    import meshcat.geometry as mg

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
