"""viz.py: the meshcat scene (checked in the static HTML export), bad input, the server, the CLI, a browser."""

import runpy
import shutil
import signal
import socket
import subprocess
import sys
import tempfile
import textwrap
import threading
import time
import urllib.request
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pinocchio as pin
import pytest

from evoik_pin import viz
from evoik_pin.cli import main
from evoik_pin.errors import ConfigurationError, TargetError, ViewerError
from evoik_pin.robot import load_robot
from evoik_pin.viz import Viewer, html_commands

ROOT = Path(__file__).resolve().parents[1]
#: Seconds after which a wait for a server, a subprocess or a watchdog counts as a hang: a bound that stops a
#: broken test, never a speed the test asks for (the waits end on their event, however loaded the machine is).
HANG_S = 300

BARE_URDF = """<robot name="bare">
  <link name="a"/><link name="b"/><link name="c"/><link name="d"/>
  <joint name="j1" type="revolute"><parent link="a"/><child link="b"/><origin xyz="0 0 0.3"/>
    <axis xyz="0 0 1"/><limit lower="-3" upper="3" effort="1" velocity="1"/></joint>
  <joint name="j2" type="revolute"><parent link="b"/><child link="c"/><origin xyz="0 0 0.1"/>
    <axis xyz="0 1 0"/><limit lower="-3" upper="3" effort="1" velocity="1"/></joint>
  <joint name="j3" type="prismatic"><parent link="c"/><child link="d"/><origin xyz="0.4 0 0"/>
    <axis xyz="1 0 0"/><limit lower="0" upper="0.2" effort="1" velocity="1"/></joint>
</robot>"""


@pytest.fixture(scope="module")
def ax18():
    return load_robot("ax18")


@pytest.fixture
def viewers():
    """Make Viewers; teardown closes them and checks that no server process is left running."""
    made = []

    def make(robot, **kwargs):
        v = Viewer(robot, **kwargs)
        made.append(v)
        return v

    yield make
    procs = [v.server_process for v in made if v.server_process is not None]
    for v in made:
        v.close()
    assert all(p.poll() is not None for p in procs), "a meshcat server outlived its Viewer"


def _scene(v: Viewer, tmp_path: Path, name: str = "scene.html") -> list[dict]:
    return html_commands(v.save_html(tmp_path / name).read_text())


def _objects(cmds) -> set[str]:
    return {c["path"] for c in cmds if c["type"] == "set_object"}


def _transform(cmds, path: str) -> np.ndarray:
    matrix = [c["matrix"] for c in cmds if c["type"] == "set_transform" and c["path"] == path][-1]
    return np.array(matrix).reshape(4, 4).T  # meshcat sends column-major


def _geometry_names(robot) -> set[str]:
    return {g.name for g in robot.visual_model.geometryObjects}


# ---------------------------------------------------------------------------------------------- scene
def test_scene_tree_after_each_call(ax18, viewers, tmp_path):
    v = viewers(ax18)
    assert v.url.startswith("http://127.0.0.1:") and v.scene == {} and not v.skeleton
    assert not any(p.startswith("/meshcat/") for p in _objects(_scene(v, tmp_path)))

    q = np.array([0.3, 0.8, -0.5, 0.2])
    v.show(q)
    cmds = _scene(v, tmp_path)
    robot_objects = {p.rsplit("/", 1)[1] for p in _objects(cmds) if p.startswith("/meshcat/robot/visuals/")}
    assert robot_objects == _geometry_names(ax18) and v.scene == {"robot": "robot"}
    tool = _transform(cmds, "/meshcat/robot/visuals/tool_0")  # the tip sphere sits on the tip frame
    assert np.allclose(tool[:3, 3], ax18.fk(q).translation, atol=1e-6)

    T = ax18.fk(q)
    v.show_target(T)
    v.show_target([0.1, 0.1, 0.1], name="goal")
    cmds = _scene(v, tmp_path)
    assert {f"/meshcat/target/{a}" for a in ("origin", "x", "y", "z")} | {"/meshcat/goal/point"} <= _objects(cmds)
    assert np.allclose(_transform(cmds, "/meshcat/target"), T.homogeneous, atol=1e-6)
    assert np.allclose(_transform(cmds, "/meshcat/goal")[:3, 3], [0.1, 0.1, 0.1])
    assert v.scene["target"] == "target triad" and v.scene["goal"] == "target point"

    rng = np.random.default_rng(0)
    nodes = v.show_solutions(ax18.random_configurations(3, rng))
    assert nodes == ["solutions/0", "solutions/1", "solutions/2"]
    cmds = _scene(v, tmp_path)
    colours = set()
    for k in range(3):
        ghost = [c for c in cmds if c["type"] == "set_object" and c["path"].startswith(f"/meshcat/solutions/{k}/")]
        assert {c["path"].rsplit("/", 1)[1] for c in ghost} == _geometry_names(ax18)
        materials = [m for c in ghost for m in c["object"]["materials"]]
        assert all(m["transparent"] and m["opacity"] == pytest.approx(0.4) for m in materials)
        colours |= {m["color"] for m in materials}
    assert len(colours) == 3  # one colour per ghost

    v.show_solutions([q], name="solutions")  # drawing the group again replaces it
    assert not any(p.startswith("/meshcat/solutions/1/") for p in _objects(_scene(v, tmp_path)))
    assert [k for k in v.scene if k.startswith("solutions/")] == ["solutions/0"]

    Q = np.linspace([0.0, 0.3, 0.3, 0.0], [2.0, 1.2, -1.0, 0.5], 25)
    v.animate(Q, dt=0.1)
    cmds = _scene(v, tmp_path)
    (anim,) = [c for c in cmds if c["type"] == "set_animation"]
    clips = {a["path"]: a["clip"] for a in anim["animations"]}
    assert set(clips) == {f"/meshcat/robot/visuals/{g}" for g in _geometry_names(ax18)}
    tool_clip = clips["/meshcat/robot/visuals/tool_0"]
    assert tool_clip["fps"] == pytest.approx(10.0)
    (position,) = [t for t in tool_clip["tracks"] if t["name"] == ".position"]
    assert len(position["keys"]) == 25
    assert np.allclose(position["keys"][-1]["value"], ax18.fk(Q[-1]).translation, atol=1e-6)
    (line,) = [c for c in cmds if c["type"] == "set_object" and c["path"] == "/meshcat/path"]
    assert line["object"]["object"]["type"] == "Line"
    assert v.scene["path"] == "line of 25 points" and v.scene["animation"].startswith("25 frames")

    v.draw_path([[0, 0, 0], [0.1, 0, 0], [0.1, 0.1, 0]], name="square")
    v.delete("goal")
    objects = _objects(_scene(v, tmp_path))
    assert "/meshcat/square" in objects and "/meshcat/goal/point" not in objects and "goal" not in v.scene


def test_results_fronts_and_lists_are_accepted(ax18, viewers, tmp_path):
    v = viewers(ax18)
    rng = np.random.default_rng(1)
    Q = ax18.random_configurations(4, rng)
    v.show(SimpleNamespace(q=Q[0]))  # a Result
    assert v.show_solutions(SimpleNamespace(q=Q, objectives=None)) == [f"solutions/{k}" for k in range(4)]  # a Front
    result = SimpleNamespace(q=Q[0], solutions=[SimpleNamespace(q=q) for q in Q[:2]], front=None)
    assert len(v.show_solutions(result, name="all")) == 2  # a solve_all-style result: its solutions
    nsga = SimpleNamespace(q=Q[0], solutions=None, front=SimpleNamespace(q=Q[:3]))
    assert len(v.show_solutions(nsga, name="front")) == 3  # a multi-objective result: its front's rows
    assert len(v.show_solutions(list(Q[0]), name="one")) == 1  # one joint vector as a flat list
    v.animate([SimpleNamespace(q=q) for q in Q], path=False)  # solve_trajectory-style list of results
    assert "path" not in v.scene
    with pytest.warns(UserWarning, match="drawing 2 of them"):
        assert v.show_solutions(Q, name="few", limit=2) == ["few/0", "few/1"]
    assert v.show_solutions(Q[:2], name="sk", style="skeleton") and v.scene["sk/0"] == "ghost skeleton"
    assert any(p.startswith("/meshcat/sk/0/visuals/skeleton_") for p in _objects(_scene(v, tmp_path)))


def test_bad_input_is_a_clear_error(ax18, viewers):
    v = viewers(ax18)
    with pytest.raises(ConfigurationError, match=r"expected \(4,\)"):
        v.show([0.1, 0.2])
    with pytest.raises(ConfigurationError, match=r"expected \(4,\)"):
        v.show_solutions([[0, 0, 0, 0], [0, 0, 0]])
    with pytest.raises(ConfigurationError, match=r"\(N, 4\)"):
        v.animate(np.zeros((5, 3)))
    with pytest.raises(ConfigurationError, match="NaN"):
        v.show([0, np.nan, 0, 0])
    with pytest.raises(ConfigurationError, match="no configurations"):
        v.show_solutions([])
    with pytest.raises(ConfigurationError, match="dt"):
        v.animate(np.zeros((3, 4)), dt=0)
    with pytest.raises(ConfigurationError, match="opacity"):
        v.show_solutions([np.zeros(4)], opacity=0)
    with pytest.raises(TargetError, match="3 finite numbers"):
        v.show_target([0.1, 0.2])
    with pytest.raises(TargetError, match="not a rotation"):
        v.show_target([0.1, 0.2, 0.3], 2 * np.eye(3))
    with pytest.raises(TargetError, match=r"\(N, 3\)"):
        v.draw_path([[0, 0, 0]])
    assert v.scene == {}  # nothing was drawn
    v.close()
    with pytest.raises(ViewerError, match="closed"):
        v.show(np.zeros(4))


def test_robot_without_visual_geometry_is_drawn_as_a_skeleton(viewers, tmp_path):
    robot = load_robot(BARE_URDF)
    with pytest.warns(UserWarning, match=r"no <visual> geometry; drawing a skeleton"):
        v = viewers(robot)
    assert v.skeleton
    q = np.array([0.5, 0.6, 0.1])
    v.show(q)
    cmds = _scene(v, tmp_path)
    names = {p.rsplit("/", 1)[1] for p in _objects(cmds) if p.startswith("/meshcat/robot/visuals/")}
    assert {"skeleton_j1", "skeleton_j2", "skeleton_j3", "skeleton_d", "skeleton_to_j2", "skeleton_rail_j3"} <= names
    tip = _transform(cmds, "/meshcat/robot/visuals/skeleton_d")
    assert np.allclose(tip[:3, 3], robot.fk(q).translation, atol=1e-6)  # the tip sphere is on the tip


def test_a_sub_chain_is_drawn_in_its_base_frame(viewers, tmp_path):
    robot = load_robot("panda", base="panda_link2", tip="panda_link8")
    v = viewers(robot, skeleton=True)
    q = np.array([0.3, -0.4, 0.5, -1.0, 0.2])
    v.show(q)
    v.show_target(robot.fk(q))
    cmds = _scene(v, tmp_path)
    tip = _transform(cmds, "/meshcat/robot") @ _transform(cmds, "/meshcat/robot/visuals/skeleton_panda_link8")
    assert np.allclose(tip[:3, 3], robot.fk(q).translation, atol=1e-6)  # where the target triad is drawn
    assert np.allclose(_transform(cmds, "/meshcat/target")[:3, 3], robot.fk(q).translation)


def test_missing_meshes_fall_back_to_a_skeleton_and_skeleton_can_be_forced(ax18, viewers):
    urdf = BARE_URDF.replace('<link name="b"/>', '<link name="b"><visual><geometry>'
                             '<mesh filename="package://nowhere/b.stl"/></geometry></visual></link>')
    with pytest.warns(UserWarning, match="could not be loaded.*skeleton"):
        assert viewers(load_robot(urdf)).skeleton
    import warnings

    with warnings.catch_warnings():
        warnings.simplefilter("error")  # asked for: no warning
        v = viewers(ax18, skeleton=True)
    v.show(np.zeros(4))
    assert v.skeleton


# ---------------------------------------------------------------------------------------------- server
def _listening_addresses(port: int) -> set[str]:
    """Local addresses (hex, as in /proc/net/tcp) of the sockets listening on ``port``."""
    found = set()
    for table in ("/proc/net/tcp", "/proc/net/tcp6"):
        for line in Path(table).read_text().splitlines()[1:]:
            fields = line.split()
            address, hex_port = fields[1].split(":")
            if fields[3] == "0A" and int(hex_port, 16) == port:
                found.add(address)
    return found


def _port(url: str) -> int:
    return int(url.rstrip("/").split(":")[2].split("/")[0])


def test_server_listens_on_localhost_and_skips_busy_ports(ax18, viewers):
    first = viewers(ax18)
    # Also occupy the next port we can hold, so the second viewer has two of ours to skip. A port someone else
    # holds right now is no substitute: it may be free again when the second server looks.
    busy, held = socket.socket(), _port(first.url) + 1
    try:
        while True:
            try:
                busy.bind(("127.0.0.1", held))
                break
            except OSError:
                held += 1
        busy.listen()
        second = viewers(ax18)
        assert _port(second.url) not in (_port(first.url), held)
        assert _port(second.zmq_url) != _port(first.zmq_url)
        for v in (first, second):
            assert urllib.request.urlopen(v.url, timeout=HANG_S).status == 200
            if Path("/proc/net/tcp").exists():
                for port in (_port(v.url), _port(v.zmq_url)):
                    assert _listening_addresses(port) == {"0100007F"}, "the server must listen on 127.0.0.1 only"
    finally:
        busy.close()


def test_external_server(ax18, viewers, monkeypatch, tmp_path):
    # The server is there: its answers end the waits, however slow a loaded machine makes them.
    monkeypatch.setattr(viz, "PROBE_TIMEOUT", HANG_S)
    monkeypatch.setattr(viz, "SERVER_TIMEOUT", HANG_S)
    owner = viewers(ax18)
    guest = viewers(ax18, zmq_url=owner.zmq_url)  # draws into the first viewer's server
    assert guest.server_process is None and guest.url == owner.url
    guest.show(np.zeros(4))
    guest.close()
    assert owner.server_process.poll() is None  # not ours to stop
    assert "/meshcat/robot/visuals/tool_0" in _objects(_scene(owner, tmp_path))

    monkeypatch.setattr(viz, "PROBE_TIMEOUT", 0.3)
    with socket.socket() as s:  # bound, not listening, for the whole check: no one else can serve on this port
        s.bind(("127.0.0.1", 0))
        with pytest.raises(ViewerError, match="no meshcat server answers"):
            Viewer(ax18, zmq_url=f"tcp://127.0.0.1:{s.getsockname()[1]}")


def test_server_stops_with_the_viewer_and_with_its_parent(ax18, tmp_path):
    with Viewer(ax18) as v:
        proc = v.server_process
        assert proc.poll() is None
    assert proc.poll() is not None
    with pytest.raises(ViewerError):
        v.save_html(tmp_path / "x.html")

    # a parent killed without any cleanup (no atexit, no finalizer): the server's watchdog ends it
    parent = textwrap.dedent("""
        import os, subprocess, sys
        server = subprocess.Popen([sys.executable, "-c", sys.argv[1], str(os.getpid())],
                                  stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        print(server.pid, flush=True)
        os._exit(0)
    """)
    out = subprocess.run([sys.executable, "-c", parent, viz.server._SERVER_SCRIPT], capture_output=True, text=True,
                         timeout=HANG_S)
    pid = int(out.stdout.split()[0])
    deadline = time.monotonic() + HANG_S  # the watchdog looks every 0.5 s once it runs; a loaded machine delays it
    while _alive(pid) and time.monotonic() < deadline:
        time.sleep(0.1)
    assert not _alive(pid), "the meshcat server survived its parent"


def test_own_server_is_waited_for_while_it_lives(ax18, viewers, monkeypatch, tmp_path):
    """A loaded machine slows the Viewer's own server down, it does not make it an error: its answers are waited
    for as long as the process lives (SERVER_TIMEOUT only bounds an external server's answers)."""
    monkeypatch.setattr(viz, "SERVER_TIMEOUT", 0.3)  # far below a server's start-up (a Python start, tornado, zmq)
    v = viewers(ax18)
    proc = v.server_process
    proc.send_signal(signal.SIGSTOP)  # a server that gets no CPU for a while, as under load
    resume = threading.Timer(1.0, proc.send_signal, (signal.SIGCONT,))
    resume.start()
    try:
        v.show(np.zeros(4))  # waits for the stopped server instead of giving up after SERVER_TIMEOUT
    finally:
        resume.join()
    assert "/meshcat/robot/visuals/tool_0" in _objects(_scene(v, tmp_path))
    proc.kill()
    proc.wait()
    with pytest.raises(ViewerError, match=r"exited \(code -9\)"):  # a dead server is an error at once
        v.show(np.ones(4))


def test_server_output_is_read_without_moving_the_servers_write_offset():
    """The Viewer reads its server's output (a temporary file) while the server writes to it through the same open
    file, whose offset the two share: a reader that seeks to 0 lets a line written meanwhile land at the start, over
    the first one (a server's zmq_url line lost that way kept a Viewer waiting for its 600 s hang guard). Here a
    writer thread appends numbered lines through a duplicate of the file's descriptor (a shared offset, as the
    server's stdout) while the reader reads again and again: every line arrives, whole and in order."""
    import os
    import tempfile

    f = tempfile.TemporaryFile()
    writer_fd = os.dup(f.fileno())
    lines = [f"line {i:05d} " + "x" * (i % 40) for i in range(4000)]
    done = threading.Event()

    def write():
        for line in lines:
            os.write(writer_fd, (line + "\n").encode())
        done.set()

    thread = threading.Thread(target=write)
    thread.start()
    looks = 0
    while not done.is_set() or looks == 0:
        viz.server._printed(f)
        looks += 1
    thread.join()
    os.close(writer_fd)
    assert viz.server._printed(f).splitlines() == lines
    f.close()


def _alive(pid: int) -> bool:
    try:
        state = Path(f"/proc/{pid}/stat").read_text().split(")")[-1].split()[0]
    except OSError:
        return False
    return state != "Z"  # a zombie has exited


# ---------------------------------------------------------------------------------------------- CLI, example
def test_cli_view(tmp_path, capsys):
    html = tmp_path / "ax18.html"
    assert main(["view", "ax18", "--q", "45", "72.42", "-2.29", "-133.6", "--html", str(html), "--no-block"]) == 0
    out = capsys.readouterr().out
    assert "http://127.0.0.1:" in out and str(html) in out
    objects = _objects(html_commands(html.read_text()))
    assert "/meshcat/robot/visuals/tool_0" in objects and "/meshcat/target/x" in objects
    assert main(["view", "ax18", "--q", "1", "2", "--no-block"]) == 2
    assert "expected (4,)" in capsys.readouterr().err


#: ``python -m evoik_pin.cli`` with Python's own Ctrl-C handling. A process started by a non-interactive shell in
#: the background (``pytest &``, CI runners, scripts/test_stress.py beside busy processes) ignores SIGINT, and its
#: children inherit that, so a SIGINT sent to the CLI would be lost; a user at a terminal has the default.
_CLI_WITH_CTRL_C = ("import runpy, signal; signal.signal(signal.SIGINT, signal.default_int_handler); "
                    "runpy.run_module('evoik_pin.cli', run_name='__main__', alter_sys=True)")


def test_cli_view_blocks_until_ctrl_c():
    proc = subprocess.Popen([sys.executable, "-c", _CLI_WITH_CTRL_C, "view", "planar2r"], stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True)
    try:
        line = proc.stdout.readline()  # the readiness signal: printed once the server answers
        assert "meshcat viewer of planar2r: http://127.0.0.1:" in line
        assert "Ctrl-C" in proc.stdout.readline()
        url = line.split(": ", 1)[1].strip()
        assert urllib.request.urlopen(url, timeout=HANG_S).status == 200
        server = subprocess.run(["ps", "-o", "pid=", "--ppid", str(proc.pid)], capture_output=True, text=True)
        proc.send_signal(signal.SIGINT)
        assert proc.wait(timeout=HANG_S) == 0
        for pid in server.stdout.split():
            assert not _alive(int(pid))
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()


def test_example_script(tmp_path, capsys):
    example = runpy.run_path(str(ROOT / "examples" / "view_solution.py"), run_name="example")
    html = tmp_path / "example.html"
    assert example["main"](["ax18", "--html", str(html), "--no-block"]) == 0
    assert "meshcat viewer: http://127.0.0.1:" in capsys.readouterr().out
    cmds = html_commands(html.read_text())
    assert any(c["type"] == "set_animation" for c in cmds)
    assert {"/meshcat/robot/visuals/tool_0", "/meshcat/target/x", "/meshcat/path"} <= _objects(cmds)


# ---------------------------------------------------------------------------------------------- browser
# Headless Chromium renders WebGL on the CPU through ANGLE + SwiftShader (Chromium >= 120 wants the last
# two flags spelled out; --use-gl=swiftshader no longer gives a WebGL context).
CHROMIUM_FLAGS = ["--headless", "--no-sandbox", "--disable-gpu", "--no-first-run", "--disable-background-networking",
                  "--disable-component-update", "--disable-sync", "--disable-quic", "--use-angle=swiftshader",
                  "--enable-unsafe-swiftshader", "--window-size=800,600", "--virtual-time-budget=5000"]
WIDTH, HEIGHT, FOV_DEG = 800, 600, 75.0  # the window, and meshcat's default camera's vertical field of view


def _chromium() -> str:
    for name in ("chromium", "chromium-browser", "google-chrome", "google-chrome-stable"):
        if path := shutil.which(name):
            return path
    pytest.skip("Chromium not found: install it (Debian: apt-get install chromium; .ci/run does) to run the "
                "browser rendering test")


def _screenshot(chromium: str, html: Path, png: Path):
    from PIL import Image

    with tempfile.TemporaryDirectory() as profile:
        out = subprocess.run([chromium, *CHROMIUM_FLAGS, f"--user-data-dir={profile}", f"--screenshot={png}",
                              html.resolve().as_uri()], capture_output=True, text=True, timeout=HANG_S)
    assert png.is_file(), f"Chromium wrote no screenshot: {out.stderr[-2000:]}"
    return np.asarray(Image.open(png).convert("RGB")).astype(int)


def _project(points: np.ndarray, camera: np.ndarray) -> np.ndarray:
    """Pixel (x, y) of world points (N, 3) seen by meshcat's camera at ``camera`` looking at the origin."""
    f = -camera / np.linalg.norm(camera)
    r = np.cross(f, [0.0, 0.0, 1.0])
    r /= np.linalg.norm(r)
    u = np.cross(r, f)
    d = points - camera
    t = np.tan(np.radians(FOV_DEG) / 2)
    x = (d @ r) / ((d @ f) * t * WIDTH / HEIGHT)
    y = (d @ u) / ((d @ f) * t)
    return np.stack([(x + 1) / 2 * WIDTH, (1 - y) / 2 * HEIGHT], axis=1)


def test_browser_shows_the_robot(tmp_path):
    """An exported scene, opened by headless Chromium, shows the robot where the camera sees it."""
    chromium = _chromium()
    cases = {"ax18": [0.3, 0.5, 0.2, 0.3],  # primitives of the papers' URDFs
             "ur5": [0.4, -1.2, 1.4, -0.6, 1.2, 0.0]}  # example-robot-data Collada meshes
    camera = np.array([0.8, 0.65, 0.5])  # m; both robots fit, so one empty scene serves both
    jobs, regions = [], {}
    for name, q in cases.items():
        robot = load_robot(name)
        q = np.asarray(q)
        data = robot.model.createData()
        pin.framesForwardKinematics(robot.model, data, robot.to_pinocchio(q))
        points = np.array([data.oMi[j].translation for j in range(1, robot.model.njoints)]
                          + [robot.fk(q).translation])
        regions[name] = _project(points, camera)
        with Viewer(robot) as v:
            v.set_camera(camera)
            if not jobs:
                jobs.append((v.save_html(tmp_path / "empty.html"), tmp_path / "empty.png"))
            v.show(q)
            jobs.append((v.save_html(tmp_path / f"{name}.html"), tmp_path / f"{name}.png"))
    with ThreadPoolExecutor(max_workers=len(jobs)) as pool:  # the Chromiums run side by side
        pngs = list(pool.map(lambda job: _screenshot(chromium, *job), jobs))
    shots = {png.stem: image for (_, png), image in zip(jobs, pngs, strict=True)}

    empty = shots["empty"]
    top = empty[5:15, 5:100].mean(axis=(0, 1))  # meshcat's sky-blue background: WebGL did render
    assert top[2] > 200 and top[2] > top[0] + 40, f"no WebGL rendering (background {top}); see {tmp_path}"
    for name, px in regions.items():
        changed = np.abs(shots[name] - empty).sum(axis=2) > 30
        x0, y0 = np.floor(px.min(axis=0) - 40).astype(int).clip(0)
        x1, y1 = np.ceil(px.max(axis=0) + 40).astype(int)
        inside = changed[y0:y1, x0:x1].sum()
        assert inside > 200, f"{name}: the robot is not visible in its region x {x0}:{x1}, y {y0}:{y1}; see {tmp_path}"
        assert inside > 0.9 * changed.sum(), f"{name}: pixels changed outside the robot's region; see {tmp_path}"
