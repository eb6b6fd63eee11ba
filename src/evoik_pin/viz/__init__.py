"""Meshcat web preview: a robot (a chain or a whole tree), IK targets and goals, several solutions, a trajectory,
and a static HTML export.

Built on :class:`pinocchio.visualize.MeshcatVisualizer` (:mod:`.robot`; a URDF without visual geometry is drawn
as a skeleton). Everything is drawn in the robot's base frame, the frame :meth:`Robot.fk` and the solvers use (m;
with a floating base: the world frame the root link moves in).

Scene tree (paths below meshcat's ``/meshcat`` root, each a checkbox in the browser's "Open Controls"):

- ``robot``: the robot at the configuration of :meth:`Viewer.show` (animated by :meth:`Viewer.animate`), every
  link of its model;
- ``<name>/<k>`` (default ``solutions/0``, ``solutions/1``, ...): ghost robots of :meth:`Viewer.show_solutions`;
- ``target``: a coordinate triad (x red, y green, z blue) or a point for a position-only target;
- ``goals/<frame>``: one marker per goal of a goal list (:meth:`Viewer.show_goals`), a triad for a pose, a sphere
  for a position, with its frame name as a label (``goals/<frame>/label``);
- ``path``: a polyline, e.g. the end-effector path of an animated trajectory;
- ``scene/visuals/<obstacle>``: the obstacles of a collision :class:`~evoik_pin.scene.Scene`, translucent grey
  (:meth:`Viewer.show_scene`, or ``show(q, scene=scene)``, which also draws the robot's links in collision red).

The meshcat server is a subprocess started per :class:`Viewer` (its web server and its ZeroMQ socket
listen on 127.0.0.1 only; busy ports are skipped: ZeroMQ from 6000, HTTP from 7000). It stops with
:meth:`Viewer.close`, at the end of a ``with`` block, when the Viewer is garbage collected, at interpreter
exit, or when the process that started it dies.

Modules: :mod:`.server`, :mod:`.robot`, :mod:`.ghosts`, :mod:`.markers`, :mod:`.obstacles`, :mod:`.paths`,
:mod:`.camera`, :mod:`.html`; this one holds the :class:`Viewer` they make up, its life cycle, inputs and time
limits.

Example::

    from evoik_pin import load_robot
    from evoik_pin.viz import Viewer

    robot = load_robot("panda")
    with Viewer(robot) as v:
        print(v.url)                        # open it in a browser
        v.show(q)                           # (n,) joint vector (rad, m), or a result with a .q attribute
        v.show_target(T.translation, T.rotation)
        v.show_solutions([q1, q2, q3])      # ghosts, one colour each
        v.animate(trajectory, dt=0.05)      # (N, n); draws the tip path too
        v.show(q, scene=scene)              # obstacles in grey, links in collision at q in red
        v.save_html("scene.html")           # self-contained file, opens without a server or network

    talos = load_robot("talos", floating_base=True)
    result = evoik_pin.solve(talos, goals)  # goals: [Pose("left_sole_link", T), Position("arm_right_7_link", p)]
    with Viewer(talos) as v:
        v.show_solution(result, goals)      # the whole robot, a marker per goal, the camera on both
        v.save_html("talos.html")           # or, in one call: save_solution_html(talos, result, goals, "talos.html")
"""

from __future__ import annotations

import os
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
from .ghosts import GHOST_COLORS, GHOST_MESH_BUDGET, GhostDrawing
from .html import HtmlExport, html_commands
from .markers import MarkerDrawing
from .obstacles import COLLISION_RGBA, OBSTACLE_RGBA, ObstacleDrawing, obstacle_model
from .paths import PathDrawing
from .robot import RobotDrawing, _reach, _visual_model, skeleton_model
from .server import _connect, _import_meshcat, _probe, _Server, _talks

__all__ = ["CAMERA_FOV_DEG", "COLLISION_RGBA", "GHOST_COLORS", "GHOST_MESH_BUDGET", "OBSTACLE_RGBA",
           "OWN_SERVER_HANG_S", "PROBE_TIMEOUT", "SERVER_TIMEOUT", "Viewer", "html_commands", "obstacle_model",
           "save_solution_html", "skeleton_model"]

#: Seconds to wait for an external server (``Viewer(zmq_url=...)``) to answer one request.
SERVER_TIMEOUT = 20.0
#: Seconds after which a Viewer's own server that neither answers (or prints its URLs) nor exits counts as
#: wedged. While it runs, it is waited for: a loaded machine (or a cold disk cache) slows it, it is no error;
#: its exit is noticed within a quarter of a second.
OWN_SERVER_HANG_S = 600.0
#: Seconds to wait for an external server (``Viewer(zmq_url=...)``) to answer its first request.
PROBE_TIMEOUT = 5.0


class Viewer(RobotDrawing, GhostDrawing, MarkerDrawing, ObstacleDrawing, PathDrawing, Camera, HtmlExport):
    """A meshcat scene of one robot: configurations, ghosts, targets and goals, paths, animation, HTML export.

    Args:
        robot: a :class:`~evoik_pin.robot.Robot` (from :func:`~evoik_pin.load_robot`): a chain or a whole robot.
        zmq_url: ZeroMQ URL of a running meshcat server (e.g. ``"tcp://127.0.0.1:6000"`` from
            ``meshcat-server``) to draw into; default ``None`` starts a private server on 127.0.0.1 that
            stops with the Viewer.
        open: open the scene in the default web browser.
        skeleton: ``True`` draws spheres and cylinders instead of the URDF's visuals; default ``None``
            uses the visuals when the URDF has some (with a warning when it falls back).

    Attributes:
        url: the web address of the live scene (``http://127.0.0.1:7000/static/`` or the next free port).
        zmq_url: the ZeroMQ address of the server.
        scene: what this Viewer drew, ``{path below /meshcat: description}``, e.g. ``{"robot": "robot",
            "solutions/0": "ghost", "target": "target triad", "path": "line of 50 points"}``.
        skeleton: True when the robot is drawn as a skeleton.
        vis: the underlying ``meshcat.Visualizer`` (to draw anything else).

    Joint vectors are ``(n,)`` arrays in rad (m for prismatic joints; a floating base's first six entries are
    its position, m, and yaw, pitch, roll, rad); positions are in m in the base frame. Every method that takes a
    configuration also takes an object with a ``.q`` attribute (a :class:`~evoik_pin.Result`). A list of
    configurations may be a list of joint vectors or of results (``solve_all``, ``solve_trajectory``), an
    ``(N, n)`` array, a :class:`~evoik_pin.Front` (its ``q`` rows), or a result carrying ``solutions`` or a
    ``front``.
    """

    def __init__(self, robot: Robot, zmq_url: str | None = None, open: bool = False, skeleton: bool | None = None):
        _import_meshcat()
        self.robot = robot
        self.vis = None
        self._server: _Server | None = None
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
        self._geom = geom
        self._skeleton_geom: pin.GeometryModel | None = None
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
        """Keep the server running until Ctrl-C (or until the server exits), then close the Viewer.

        Args:
            message: a line to print (and flush) to ``file`` (default ``sys.stdout``) inside the wait, so a
                Ctrl-C right after it still stops the Viewer cleanly, e.g. "Press Ctrl-C to stop the viewer."
        """
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
        if getattr(items, "solutions", None) is not None:  # a Result of an all-solutions method
            items = items.solutions
        elif getattr(items, "front", None) is not None:  # a Result of a multi-objective method
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
        for key in [k for k in self.scene if k == name or k.startswith(name + "/")]:
            del self.scene[key]
        for key in [k for k in self._viz if k == name or k.startswith(name + "/")]:
            del self._viz[key]

    def __repr__(self) -> str:
        return f"Viewer({self.robot.name!r}, url={getattr(self, 'url', None)!r}, scene={list(self.scene)})"


def save_solution_html(robot: Robot, result, goals, path: str | os.PathLike, scene=None,
                       margin: float = 0.0) -> Path:
    """Write the answer of a goal-list solve as one self-contained HTML scene and return its path: the whole robot
    at ``result.q``, a marker per goal, the camera on both (:meth:`Viewer.show_solution`, :meth:`Viewer.save_html`).
    A Viewer's meshcat server is started for it and stopped. (What ``evoik solve ... --html`` writes for a goal
    list.)

    Args:
        robot: the :class:`~evoik_pin.robot.Robot` solved for. result: its :class:`~evoik_pin.Result` (or a joint
            vector (n,)). goals: the goal list. path: the HTML file to write.
        scene, margin: a collision :class:`~evoik_pin.scene.Scene` of ``robot`` (its obstacles drawn, the links in
            collision red) and its margin (m), as for :meth:`Viewer.show`.
    """
    with Viewer(robot) as viewer:
        viewer.show_solution(result, goals, scene=scene, margin=margin)
        return viewer.save_html(path)
