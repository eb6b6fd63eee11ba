"""Meshcat web preview: a robot, IK targets, several solutions, a trajectory, and a static HTML export.

Built on :class:`pinocchio.visualize.MeshcatVisualizer`, which turns the robot's
:attr:`~evoik_pin.robot.Robot.visual_model` into meshcat objects (meshes of the example-robot-data arms,
the boxes/cylinders/spheres the papers' URDFs carry). A URDF without visual geometry is shown as a
skeleton: a sphere at every joint origin and a cylinder from each joint to the next (and to the tip).

Everything is drawn in the robot's base frame, the frame :meth:`Robot.fk` and the solvers use (m), so a
target or a path given in that frame lands where the tip does.

Scene tree (paths below meshcat's ``/meshcat`` root, each a checkbox in the browser's "Open Controls"):

- ``robot``: the robot at the configuration of :meth:`Viewer.show` (animated by :meth:`Viewer.animate`);
- ``<name>/<k>`` (default ``solutions/0``, ``solutions/1``, ...): ghost robots of :meth:`Viewer.show_solutions`;
- ``target``: a coordinate triad (x red, y green, z blue) or a point for a position-only target;
- ``path``: a polyline, e.g. the end-effector path of an animated trajectory;
- ``scene/visuals/<obstacle>``: the obstacles of a collision :class:`~evoik_pin.scene.Scene`, translucent grey
  (:meth:`Viewer.show_scene`, or ``show(q, scene=scene)``, which also draws the robot's links in collision red).

The meshcat server is a subprocess started per :class:`Viewer` (its web server and its ZeroMQ socket
listen on 127.0.0.1 only; busy ports are skipped: ZeroMQ from 6000, HTTP from 7000). It stops with
:meth:`Viewer.close`, at the end of a ``with`` block, when the Viewer is garbage collected, at interpreter
exit, or when the process that started it dies.

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
"""

from __future__ import annotations

import base64
import functools
import os
import re
import subprocess
import sys
import tempfile
import time
import warnings
import weakref
import webbrowser
from pathlib import Path

import numpy as np
import pinocchio as pin

from .errors import ConfigurationError, OptionError, TargetError, ViewerError
from .lie import rotation_to_z
from .robot import Robot
from .robot.frames import find_frame

__all__ = ["COLLISION_RGBA", "GHOST_COLORS", "OBSTACLE_RGBA", "Viewer", "html_commands", "obstacle_model",
           "skeleton_model"]

#: Ghost colours (RGB in [0, 1]), used in turn by :meth:`Viewer.show_solutions`.
GHOST_COLORS: tuple[tuple[float, float, float], ...] = (
    (0.12, 0.47, 0.71), (1.00, 0.50, 0.05), (0.17, 0.63, 0.17), (0.84, 0.15, 0.16), (0.58, 0.40, 0.74),
    (0.55, 0.34, 0.29), (0.89, 0.47, 0.76), (0.50, 0.50, 0.50), (0.74, 0.74, 0.13), (0.09, 0.75, 0.81),
)
#: Obstacles of a scene (RGBA in [0, 1]): translucent grey.
OBSTACLE_RGBA = (0.55, 0.55, 0.55, 0.6)
#: Robot links in collision: opaque red.
COLLISION_RGBA = (0.9, 0.05, 0.05, 1.0)
#: Most bytes of mesh files :meth:`Viewer.show_solutions` embeds for its ghosts before it draws skeletons.
GHOST_MESH_BUDGET = 50_000_000
#: Vertical field of view (degrees) of meshcat's default camera.
CAMERA_FOV_DEG = 75.0
#: Seconds to wait for an external server (``Viewer(zmq_url=...)``) to answer one request.
SERVER_TIMEOUT = 20.0
#: Seconds after which a Viewer's own server that neither answers (or prints its URLs) nor exits counts as
#: wedged. While it runs, it is waited for: a loaded machine (or a cold disk cache) slows it, it is no error;
#: its exit is noticed within :data:`_LIVENESS_POLL` s.
OWN_SERVER_HANG_S = 600.0
_LIVENESS_POLL = 0.25
#: Seconds to wait for an external server (``Viewer(zmq_url=...)``) to answer its first request.
PROBE_TIMEOUT = 5.0

# Started with ``python -c``: meshcat's own server, with its HTTP socket bound to 127.0.0.1 (meshcat
# binds every interface) and a watchdog that exits when the parent process is gone.
_SERVER_SCRIPT = r"""
import os, sys, threading, time
parent = int(sys.argv[1])
def _watch():
    while os.getppid() == parent:
        time.sleep(0.5)
    os._exit(0)
threading.Thread(target=_watch, daemon=True).start()
import tornado.web
from meshcat.servers import zmqserver
_listen = tornado.web.Application.listen
def _listen_local(self, port, address=None, **kwargs):
    return _listen(self, port, address="127.0.0.1", **kwargs)
tornado.web.Application.listen = _listen_local
sys.argv = ["meshcat-server"] + sys.argv[2:]
zmqserver.main()
"""

_COMMAND_RE = re.compile(r'fetch\("data:application/octet-binary;base64,([A-Za-z0-9+/=]+)"\)')


def html_commands(html: str) -> list[dict]:
    """The meshcat commands a static HTML export replays, in order.

    Args:
        html: the text of a file written by :meth:`Viewer.save_html` (or ``meshcat``'s ``static_html()``).

    Returns:
        One dict per command, decoded from its base64 msgpack blob: ``type`` (``set_object``,
        ``set_transform``, ``set_property``, ``set_animation``) and ``path`` (e.g. ``/meshcat/robot``),
        plus the command's payload.
    """
    import umsgpack

    return [umsgpack.unpackb(base64.b64decode(m)) for m in _COMMAND_RE.findall(html)]


# ---------------------------------------------------------------------------------------------- server
def _stop_process(proc: subprocess.Popen) -> None:
    if proc.poll() is None:
        proc.terminate()
        try:
            proc.wait(timeout=3)
        except subprocess.TimeoutExpired:  # pragma: no cover - meshcat exits on SIGTERM
            proc.kill()
            proc.wait()


class _Server:
    """A meshcat server subprocess listening on 127.0.0.1; ``stop()`` ends it (idempotent)."""

    def __init__(self, timeout: float | None = None):
        import meshcat

        timeout = OWN_SERVER_HANG_S if timeout is None else timeout

        self._out = tempfile.TemporaryFile()  # files, not pipes: a full pipe would block the server
        self._err = tempfile.TemporaryFile()
        env = dict(os.environ)
        site = str(Path(meshcat.__file__).resolve().parents[1])
        env["PYTHONPATH"] = os.pathsep.join([site, *filter(None, [env.get("PYTHONPATH")])])
        self.proc = subprocess.Popen([sys.executable, "-u", "-c", _SERVER_SCRIPT, str(os.getpid())],
                                     stdin=subprocess.DEVNULL, stdout=self._out, stderr=self._err, env=env)
        self._finalizer = weakref.finalize(self, _stop_process, self.proc)
        deadline = time.monotonic() + timeout
        urls: dict[str, str] = {}
        while len(urls) < 2:
            self._out.seek(0)
            for line in self._out.read().decode(errors="replace").splitlines():
                key, _, value = line.strip().partition("=")
                if key in ("zmq_url", "web_url") and value:
                    urls[key] = value
            if len(urls) == 2:
                break
            exited = self.proc.poll() is not None
            if exited or time.monotonic() > deadline:
                self._err.seek(0)
                detail = self._err.read().decode(errors="replace").strip().splitlines()[-3:]
                self.stop()
                why = (f"exited (code {self.proc.returncode})" if exited
                       else f"ran {timeout:g} s without printing its URLs")
                raise ViewerError(f"the meshcat server {why}: " + (" | ".join(detail) or "no output"))
            time.sleep(0.02)  # readiness is the URL lines; the deadline only catches a wedged server
        self.zmq_url, self.web_url = urls["zmq_url"], urls["web_url"]

    def stop(self) -> None:
        self._finalizer()
        for f in (self._out, self._err):
            f.close()


def _probe(zmq_url: str, timeout: float) -> str:
    """The web URL of the meshcat server at ``zmq_url``, or a ViewerError when none answers in time."""
    import zmq

    sock = zmq.Context.instance().socket(zmq.REQ)
    sock.setsockopt(zmq.LINGER, 0)
    sock.setsockopt(zmq.RCVTIMEO, int(timeout * 1000))
    try:
        sock.connect(zmq_url)
        sock.send(b"url")
        return sock.recv().decode()
    except zmq.error.Again:
        raise ViewerError(
            f"no meshcat server answers at {zmq_url} within {timeout:g} s; start one with `meshcat-server`, "
            "or pass zmq_url=None to let the Viewer start its own"
        ) from None
    except zmq.error.ZMQError as exc:
        raise ViewerError(f"cannot reach a meshcat server at {zmq_url!r}: {exc}") from None
    finally:
        sock.close()


class _OwnServerSocket:
    """The REQ socket to a Viewer's own server: ``recv`` waits as long as the server process runs (a busy machine
    delays its answer) and raises ``zmq.ZMQError`` once it has exited (or ``zmq.Again`` after
    :data:`OWN_SERVER_HANG_S` s without an answer). Everything else is the wrapped socket's."""

    def __init__(self, sock, proc: subprocess.Popen):
        self._sock, self._proc = sock, proc

    def recv(self, *args, **kwargs):
        import zmq

        deadline = time.monotonic() + OWN_SERVER_HANG_S
        while not self._sock.poll(int(_LIVENESS_POLL * 1000)):
            if self._proc.poll() is not None:
                raise zmq.error.ZMQError(msg=f"the server process exited (code {self._proc.returncode})")
            if time.monotonic() > deadline:
                raise zmq.error.Again()
        return self._sock.recv(*args, **kwargs)

    def __getattr__(self, name):
        return getattr(self._sock, name)


def _connect(zmq_url: str, web_url: str, proc: subprocess.Popen | None = None):
    """A ``meshcat.Visualizer`` talking to the server at ``zmq_url``; a silent server raises instead of hanging.

    ``proc``: the server process when it is the Viewer's own (answers are waited for while it runs); None for an
    external server (:data:`SERVER_TIMEOUT` s per answer).
    """
    import zmq
    from meshcat.visualizer import ViewerWindow, Visualizer

    # ViewerWindow(zmq_url, start_server=False) would print the URL and leave a first socket open: the
    # server's URL is already known (probed, or printed by our own server), so set the window up directly.
    window = ViewerWindow.__new__(ViewerWindow)
    window.server_proc, window.zmq_url, window.web_url = None, zmq_url, web_url
    window.connect_zmq()
    window.zmq_socket.setsockopt(zmq.LINGER, 0)
    if proc is None:
        window.zmq_socket.setsockopt(zmq.RCVTIMEO, int(SERVER_TIMEOUT * 1000))
    else:
        window.zmq_socket = _OwnServerSocket(window.zmq_socket, proc)
    return Visualizer(window=window)


def _import_meshcat() -> None:
    """Import meshcat and Pinocchio's visualizer once, hiding the pyzmq deprecation meshcat's import triggers."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", DeprecationWarning)
        import meshcat.visualizer  # noqa: F401
        import pinocchio.visualize  # noqa: F401


def _talks(method):
    """Report a lost meshcat server (a ZeroMQ timeout or error) as a ViewerError."""

    @functools.wraps(method)
    def wrapper(self, *args, **kwargs):
        import zmq

        try:
            return method(self, *args, **kwargs)
        except zmq.error.ZMQError as exc:
            raise ViewerError(f"the meshcat server at {self.zmq_url} did not answer ({exc}); it may have "
                              "stopped") from None

    return wrapper


# ---------------------------------------------------------------------------------------------- geometry
def _fcl():
    """Pinocchio's collision library module (``coal``; ``hppfcl`` before Pinocchio 3.4)."""
    try:
        import coal

        return coal
    except ImportError:  # pragma: no cover - older Pinocchio
        import hppfcl

        return hppfcl


def _segments(robot: Robot) -> list[tuple[int, pin.SE3]]:
    """The skeleton's points: (parent joint, placement in that joint) of each joint origin and the tip."""
    model = robot.model
    points = [(model.parents[j], model.jointPlacements[j]) for j in range(1, model.njoints)]
    tip = model.frames[find_frame(model, robot.tip)]
    points.append((tip.parentJoint, tip.placement))
    return points


def skeleton_model(robot: Robot, radius: float | None = None) -> pin.GeometryModel:
    """Simple visual geometry of ``robot``'s chain: spheres at the joint origins and the tip, cylinders between.

    Args:
        robot: the chain to draw.
        radius: sphere radius (m); links get 0.6 of it, the rails prismatic joints slide on 0.3. Default:
            2 % of the chain's length (with prismatic travel), within [3 mm, 30 mm].

    Returns:
        A ``pin.GeometryModel`` attached to ``robot.model``'s joints (usable as a visual model).
    """
    fcl = _fcl()
    model = robot.model
    reach = _reach(robot)
    r = float(np.clip(0.02 * reach, 0.003, 0.03)) if radius is None else float(radius)
    geom = pin.GeometryModel()
    joint_rgba = np.array([0.9, 0.5, 0.1, 1.0])
    link_rgba = np.array([0.55, 0.6, 0.7, 1.0])
    rail_rgba = np.array([0.3, 0.3, 0.35, 1.0])

    def add(name: str, joint: int, placement: pin.SE3, shape, rgba: np.ndarray) -> None:
        frame = next(i for i, f in enumerate(model.frames) if f.parentJoint == joint)
        obj = pin.GeometryObject(name, joint, frame, placement, shape)
        obj.meshColor = rgba
        geom.addGeometryObject(obj)

    def cylinder(name: str, joint: int, p0: np.ndarray, p1: np.ndarray, radius: float, rgba: np.ndarray) -> None:
        d = p1 - p0
        if np.linalg.norm(d) > 1e-9:
            length = float(np.linalg.norm(d))
            add(name, joint, pin.SE3(rotation_to_z(d), (p0 + p1) / 2), fcl.Cylinder(radius, length), rgba)

    revolute, axes, lower, upper = robot.chain_joints()  # model's joints: mimic joints on the chain included
    for k, (parent, M) in enumerate(_segments(robot)):
        is_tip = k == model.njoints - 1
        child = k + 1 if not is_tip else parent
        name = robot.tip if is_tip else model.names[k + 1]
        # sphere at this point, attached to the joint it moves with (the joint itself, or the tip's parent)
        add(f"skeleton_{name}", child, pin.SE3.Identity() if not is_tip else M,
            fcl.Sphere(r * (0.8 if is_tip else 1.0)), joint_rgba)
        cylinder(f"skeleton_to_{name}", parent, np.zeros(3), M.translation, 0.6 * r, link_rgba)
        if not is_tip and not revolute[k]:  # a prismatic joint slides along a rail spanning its bounds
            a = M.rotation @ axes[k]
            lo, hi = M.translation + lower[k] * a, M.translation + upper[k] * a
            cylinder(f"skeleton_rail_{name}", parent, lo, hi, 0.3 * r, rail_rgba)
    return geom


def _reach(robot: Robot) -> float:
    """Length (m) of the chain's polyline base -> joints -> tip at rest plus prismatic travel, >= 0.1 m."""
    links = sum(np.linalg.norm(M.translation) for _, M in _segments(robot))
    revolute, _, lower, upper = robot.chain_joints()
    travel = np.maximum(np.abs(lower), np.abs(upper))[~revolute].sum()
    return max(0.1, float(links + travel))


def obstacle_model(scene) -> pin.GeometryModel:
    """The obstacles of a :class:`~evoik_pin.scene.Scene` as a ``pin.GeometryModel`` attached to the universe of
    ``scene.robot.model`` (boxes, spheres, cylinders and capsules along their pose's z, meshes at their scale),
    one object per obstacle, named as the obstacle."""
    fcl = _fcl()
    base = scene.robot.base_placement
    geom = pin.GeometryModel()
    for ob in scene.obstacles.values():
        p = ob.params
        if ob.kind == "box":
            shape = fcl.Box(*p["size"])
        elif ob.kind == "sphere":
            shape = fcl.Sphere(p["radius"])
        elif ob.kind in ("cylinder", "capsule"):
            shape = (fcl.Cylinder if ob.kind == "cylinder" else fcl.Capsule)(p["radius"], p["length"])
        else:
            shape = fcl.MeshLoader().load(p["path"], np.asarray(p["scale"], dtype=float))
        geom.addGeometryObject(pin.GeometryObject(ob.name, 0, 0, base * ob.pose, shape))  # base frame -> world
    return geom


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


def _hex(rgb) -> int:
    r, g, b = (int(round(255 * float(np.clip(c, 0.0, 1.0)))) for c in rgb[:3])
    return (r << 16) | (g << 8) | b


# ---------------------------------------------------------------------------------------------- viewer
class Viewer:
    """A meshcat scene of one robot: configurations, ghosts, targets, paths, animation, HTML export.

    Args:
        robot: a :class:`~evoik_pin.robot.Robot` (from :func:`~evoik_pin.load_robot`).
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

    Joint vectors are ``(n,)`` arrays in rad (m for prismatic joints); positions are in m in the base
    frame. Every method that takes a configuration also takes an object with a ``.q`` attribute (a
    :class:`~evoik_pin.Result`). A list of configurations may be a list of joint vectors or of results
    (``solve_all``, ``solve_trajectory``), an ``(N, n)`` array, a :class:`~evoik_pin.Front` (its ``q``
    rows), or a result carrying ``solutions`` or a ``front``.
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
                self._server = _Server()
                self.zmq_url, self.url = self._server.zmq_url, self._server.web_url
            else:
                self.zmq_url, self.url = zmq_url, _probe(zmq_url, timeout=PROBE_TIMEOUT)
            self.vis = _connect(self.zmq_url, self.url, self.server_process)
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
            message: a line to print (and flush) to ``file`` (default ``sys.stdout``) once Ctrl-C stops the Viewer
                cleanly, e.g. "Press Ctrl-C to stop the viewer.". Printed before the call, a Ctrl-C that came
                between the print and the wait ended the program with a KeyboardInterrupt traceback.
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

    # ------------------------------------------------------------------ drawing
    def _load(self, node: str, rgba=None, geom: pin.GeometryModel | None = None):
        """Load the robot's geometry (or ``geom``) under ``node``, once; ``rgba`` colours every part (a ghost)."""
        vis = self._check_open()
        if node in self._viz:
            return self._viz[node]
        cls = _meshcat_visualizer_class()
        viz = cls(self.robot.model, visual_model=self._geom if geom is None else geom)
        viz.plain_meshes = rgba is not None
        viz.initViewer(viewer=vis)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", UserWarning)  # unsupported parts are skipped, as Pinocchio does
            viz.loadViewerModel(rootNodeName=node, visual_color=None if rgba is None else list(rgba))
        vis[node].set_transform(self._baseMo.homogeneous)
        self._viz[node] = viz
        return viz

    def _mesh_bytes(self) -> int:
        """Bytes of mesh files one copy of the robot's visual geometry embeds in the scene."""
        paths = [g.meshPath for g in self._geom.geometryObjects]
        return sum(os.path.getsize(f) for f in paths if f and os.path.isfile(f))

    @_talks
    def show(self, q, scene=None, margin: float = 0.0) -> list[tuple[str, str]] | None:
        """Draw the robot (node ``robot``) at joint vector ``q`` (n,) in rad/m, or a result's ``.q``.

        With a collision ``scene`` (:class:`~evoik_pin.scene.Scene` of this robot): its obstacles are drawn too
        (node ``scene``, as :meth:`show_scene`; again only when the scene changed), and the robot's links in
        collision at ``q`` (closer than ``margin`` m) are drawn red (:data:`COLLISION_RGBA`); a later ``show``
        gives links no longer in collision their own colours back.

        Returns:
            With a scene, the pairs in collision (``scene.colliding_pairs(q, margin)``: link or obstacle names,
            empty when ``q`` is collision-free); None without.
        """
        q = self._q(q)
        pairs = None
        if scene is not None:
            self._check_scene(scene)
            pairs = scene.colliding_pairs(q, margin)
        viz = self._load("robot")
        viz.display(self.robot.to_pinocchio(q))
        self.scene["robot"] = "robot"
        links: set[str] = set()
        if scene is not None:
            if "scene" not in self.scene or self._drawn_scenes.get("scene") != (id(scene), scene.version):
                self.show_scene(scene)
            links = {name for pair in pairs for name in pair} - set(scene.obstacles)
        self._paint_links(viz, links)
        if links:
            self.scene["robot"] = f"robot, links in collision (red): {', '.join(sorted(links))}"
        return pairs

    def _check_scene(self, scene) -> None:
        """SceneError unless ``scene`` is a Scene of this Viewer's robot (the same object, or the same chain)."""
        from .errors import SceneError
        from .scene import Scene

        if not isinstance(scene, Scene):
            raise SceneError(f"scene must be an evoik_pin.Scene, got {type(scene).__name__}")
        other = scene.robot
        if other is not self.robot and (other.name, other.base, list(other.joint_names)) != (
                self.robot.name, self.robot.base, list(self.robot.joint_names)):
            scene.check_robot(self.robot)  # raises, naming both robots

    def _paint_links(self, viz, links: set[str]) -> None:
        """Draw the visual geometry of ``links`` (link names) red and give the others their own colours back."""
        model = self.robot.model
        if self.skeleton:  # skeleton parts hang on joints: the joints that carry the links
            joints = {model.frames[model.getFrameId(name)].parentJoint for name in links}
            red = {g.name for g in viz.visual_model.geometryObjects if g.parentJoint in joints}
        else:
            red = {g.name for g in viz.visual_model.geometryObjects if model.frames[g.parentFrame].name in links}
        before = self._red[1] if self._red[0] is viz else frozenset()
        plain = viz.plain_meshes
        try:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore", UserWarning)
                for g in viz.visual_model.geometryObjects:
                    if (g.name in red) != (g.name in before):  # reloaded: red plain geometry, or its own again
                        viz.plain_meshes = g.name in red
                        viz.loadViewerGeometryObject(g, pin.GeometryType.VISUAL,
                                                     list(COLLISION_RGBA) if g.name in red else None)
        finally:
            viz.plain_meshes = plain
        self._red = (viz, frozenset(red))

    @_talks
    def show_scene(self, scene, name: str = "scene", color=OBSTACLE_RGBA[:3],
                   opacity: float = OBSTACLE_RGBA[3]) -> list[str]:
        """Draw the obstacles of a collision :class:`~evoik_pin.scene.Scene` in the base frame: boxes, spheres,
        cylinders and capsules (axis along their pose's z) and meshes, translucent grey by default.

        Args:
            scene: a Scene of this Viewer's robot (e.g. ``Scene.from_file(robot, "shelf.yaml")``).
            name: group node; obstacle ``o`` is ``<name>/visuals/<o>``. Drawing the same name again replaces it.
            color: RGB in [0, 1]. opacity: in (0, 1].

        Returns:
            The obstacles' node names (none for a scene without obstacles).
        """
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

    @_talks
    def show_solutions(self, solutions, name: str = "solutions", opacity: float = 0.4, limit: int = 64,
                       style: str = "auto") -> list[str]:
        """Draw several configurations at once as translucent ghost robots, one colour each.

        Args:
            solutions: a list of joint vectors (n,) or of results with a ``.q``, an (N, n) array, or an
                object whose ``.q`` is (N, n) (e.g. a Pareto front) or that has ``.solutions``.
            name: group node; ghost k is ``<name>/<k>`` (a checkbox each in the browser). Drawing the same
                name again replaces the group.
            opacity: ghost opacity in (0, 1].
            limit: at most this many ghosts (evenly spaced, with a warning, when there are more).
            style: ``"mesh"`` (the robot's own visuals), ``"skeleton"`` (spheres and cylinders), or
                ``"auto"``: meshes unless the ghosts' mesh files would exceed :data:`GHOST_MESH_BUDGET`
                bytes in all (every ghost embeds a copy: 11 MB of mesh files per Panda).

        Returns:
            The ghosts' node names.

        Raises:
            ConfigurationError: no configuration to draw, e.g. the empty list :func:`evoik_pin.solve_all` returns
                for an unreachable target (the error quotes that list's ``message``: why it is empty).
        """
        empty = getattr(solutions, "solutions", solutions)
        if isinstance(empty, list) and not empty:
            why = getattr(solutions, "message", "")
            raise ConfigurationError("show_solutions: no configurations given (an empty list of solutions)"
                                     + (f": {why}" if why else ""))
        Q = self._qs(solutions)
        name = name.strip("/")
        if not name or not 0.0 < opacity <= 1.0 or limit < 1 or style not in ("auto", "mesh", "skeleton"):
            raise ConfigurationError(
                f"show_solutions needs a non-empty name, 0 < opacity <= 1, limit >= 1 and style 'auto', 'mesh' or "
                f"'skeleton'; got name={name!r}, opacity={opacity}, limit={limit}, style={style!r}"
            )
        if Q.shape[0] > limit:
            keep = np.unique(np.linspace(0, Q.shape[0] - 1, limit).round().astype(int))
            warnings.warn(f"{Q.shape[0]} solutions: drawing {keep.size} of them (limit={limit})", UserWarning,
                          stacklevel=3)
            Q = Q[keep]
        if style == "auto":
            style = "skeleton" if Q.shape[0] * self._mesh_bytes() > GHOST_MESH_BUDGET else "mesh"
        geom = None
        if style == "skeleton" and not self.skeleton:
            if self._skeleton_geom is None:
                self._skeleton_geom = skeleton_model(self.robot)
            geom = self._skeleton_geom
        self.delete(name)
        nodes = []
        for k, q in enumerate(Q):
            node = f"{name}/{k}"
            rgba = (*GHOST_COLORS[k % len(GHOST_COLORS)], opacity)
            self._load(node, rgba, geom).display(self.robot.to_pinocchio(q))
            self.scene[node] = "ghost skeleton" if style == "skeleton" else "ghost"
            nodes.append(node)
        return nodes

    @_talks
    def show_target(self, position, rotation=None, name: str = "target", size: float | None = None) -> None:
        """Draw an IK target: a coordinate triad (x red, y green, z blue), or a point without ``rotation``.

        Args:
            position: (3,) in m in the base frame, or a ``pin.SE3`` (then its rotation is used too).
            rotation: (3, 3) rotation matrix, or None for a position-only target (drawn as a point).
            name: node name (draw several targets under different names).
            size: axis length (m) of the triad; the point's radius is a quarter of it. Default: 15 % of
                the chain's length, within [2 cm, 20 cm].
        """
        import meshcat.geometry as mg

        if isinstance(position, pin.SE3):
            position, rotation = position.translation, position.rotation if rotation is None else rotation
        p = np.asarray(position, dtype=float)
        if p.shape != (3,) or not np.all(np.isfinite(p)):
            raise TargetError(f"target position must be 3 finite numbers (m), got shape {p.shape}: {p}")
        R = None
        if rotation is not None:
            R = np.asarray(rotation, dtype=float)
            if R.shape != (3, 3) or not np.all(np.isfinite(R)):
                raise TargetError(f"target rotation must be a finite (3, 3) matrix, got shape {R.shape}")
            if not (np.allclose(R.T @ R, np.eye(3), atol=1e-6) and np.linalg.det(R) > 0):
                raise TargetError("target rotation is not a rotation matrix (R^T R != I or det R != 1)")
        s = float(np.clip(0.15 * self._reach, 0.02, 0.2)) if size is None else float(size)
        vis = self._check_open()
        name = name.strip("/")
        self.delete(name)
        node = vis[name]
        if R is None:
            node["point"].set_object(mg.Sphere(s / 4), mg.MeshPhongMaterial(color=0xE02020))
            self.scene[name] = "target point"
        else:
            node["origin"].set_object(mg.Sphere(s / 12), mg.MeshPhongMaterial(color=0xF0C020))
            turn = {"x": pin.utils.rotate("z", -np.pi / 2), "y": np.eye(3), "z": pin.utils.rotate("x", np.pi / 2)}
            for axis, color in (("x", 0xE02020), ("y", 0x20C020), ("z", 0x2040F0)):
                node[axis].set_object(mg.Cylinder(s, s / 30), mg.MeshPhongMaterial(color=color))
                T = np.eye(4)
                T[:3, :3] = turn[axis]  # meshcat's cylinder runs along y
                T[:3, 3] = turn[axis] @ np.array([0.0, s / 2, 0.0])
                node[axis].set_transform(T)
            self.scene[name] = "target triad"
        T = np.eye(4)
        T[:3, 3] = p
        if R is not None:
            T[:3, :3] = R
        node.set_transform(T)

    @_talks
    def show_points(self, points, values=None, name: str = "points", size: float | None = None,
                    cmap: str = "viridis", vmin: float = 0.0, vmax: float = 1.0) -> None:
        """Draw a point cloud (e.g. the voxels of a reachability map), coloured by ``values``.

        Args:
            points: (N, 3) positions in m in the base frame.
            values: (N,) numbers mapped through the matplotlib colormap ``cmap`` over [vmin, vmax]; None: one colour.
            name: node name. size: point size in m (default 2 % of the chain's length, within [5 mm, 5 cm]).
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

    @_talks
    def set_camera(self, position=None, target=None) -> None:
        """Place the camera at ``position`` (3,) in m (base frame), looking at ``target`` (3,) in m (default: the
        origin, the robot's base).

        Default position: ``target`` plus, in front of, beside and above it, 1.25 times the chain's stretched
        length. Meshcat's orbit controls always look at (and turn about) the world origin, so a ``target`` other
        than the origin moves the drawing instead: the ``/meshcat`` tree, the grid and the axes are translated
        by ``-target`` (every object keeps its place relative to the others and to the grid).
        """
        vis = self._check_open()
        t = np.zeros(3) if target is None else np.asarray(target, dtype=float)
        if t.shape != (3,) or not np.all(np.isfinite(t)):
            raise ConfigurationError(f"camera target must be 3 finite numbers (m), got {t}")
        c = t + self._reach * np.array([0.9, 0.7, 0.55]) if position is None else np.asarray(position, dtype=float)
        if c.shape != (3,) or not np.all(np.isfinite(c)):
            raise ConfigurationError(f"camera position must be 3 finite numbers (m), got {c}")
        if not np.array_equal(t, self._camera_target):  # unchanged: no command (the export stays as it was)
            shift = np.eye(4)
            shift[:3, 3] = -t
            for node in ("/meshcat", "/Grid", "/Axes"):  # the grid's and the axes' own transforms are identities
                vis[node].set_transform(shift)
            self._camera_target = t.copy()
        d = c - t
        # meshcat's camera lives in a y-up frame rotated onto the z-up world: world (x, y, z) -> (x, z, -y)
        vis["/Cameras/default/rotated/<object>"].set_property("position", [float(d[0]), float(d[2]), float(-d[1])])

    def frame(self, points, fill: float = 0.8) -> tuple[np.ndarray, np.ndarray]:
        """Point the camera at the bounding box of ``points`` (N, 3) in m (base frame) and back it off until the
        box fills about ``fill`` of the view's height, from the default direction (front, side, above).

        Returns:
            (position, target), each (3,) in m: the camera and the box centre it looks at.
        """
        P = np.asarray(points, dtype=float)
        if P.ndim != 2 or P.shape[1] != 3 or P.shape[0] < 1 or not np.all(np.isfinite(P)):
            raise TargetError(f"points to frame must be a finite (N, 3) array with N >= 1 (m), got shape {P.shape}")
        if not 0 < fill <= 1:
            raise ConfigurationError(f"fill must be in (0, 1], got {fill}")
        lo, hi = P.min(axis=0), P.max(axis=0)
        target = (lo + hi) / 2
        radius = max(0.5 * float(np.linalg.norm(hi - lo)), 0.01)  # the box's bounding sphere; a point: 1 cm
        # the sphere's silhouette spans 2 asin(radius / distance) of the vertical field of view
        distance = radius / np.sin(fill * np.radians(CAMERA_FOV_DEG) / 2)
        direction = np.array([0.9, 0.7, 0.55]) / np.linalg.norm([0.9, 0.7, 0.55])
        position = target + distance * direction
        self.set_camera(position, target)
        return position, target

    @_talks
    def save_html(self, path: str | os.PathLike) -> Path:
        """Write the current scene (with its animation) as one self-contained HTML file and return its path.

        The file embeds three.js and every mesh: it opens offline in any WebGL browser, without a server.
        """
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

