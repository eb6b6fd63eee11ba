"""Reachability maps (reach.py): the planar 2R's annulus, the Panda's map against FK sampling, a scene's obstacles,
the files written (npz, png, html) and the command line."""

import numpy as np
import pinocchio as pin
import pytest

import evoik_pin as ev
from evoik_pin.cli import main
from evoik_pin.errors import OptionError
from evoik_pin.reach import ReachMap, reachability_map, so3_samples
from evoik_pin.scene import Scene
from evoik_pin.viz import html_commands

A1, A2 = 0.25, 0.16  # robots/planar2r.urdf's link lengths (m)


@pytest.fixture(scope="module")
def planar_map():
    return reachability_map("planar2r", voxel=0.02, progress=False)


@pytest.fixture(scope="module")
def panda():
    return ev.load_robot("panda")


@pytest.fixture(scope="module")
def panda_map(panda):
    return reachability_map(panda, voxel=0.15, orientations=32, seed=1, progress=False)


def test_planar_2r_reaches_its_annulus_and_nothing_else(planar_map):
    m = planar_map
    assert m.kind == "planar" and m.orientations == 1 and m.shape[2] == 1
    assert np.all(m.centers[:, 2] == 0.0) and set(np.unique(m.index)) == {0.0, 1.0}
    r = np.hypot(m.centers[:, 0], m.centers[:, 1])
    half = m.voxel / np.sqrt(2)  # a voxel's centre is within this of every point of the voxel
    inside = (r > abs(A1 - A2) + half) & (r < A1 + A2 - half)
    outside = (r < abs(A1 - A2) - half) | (r > A1 + A2 + half)
    assert inside.sum() > 1000 and outside.sum() > 300
    assert m.index[inside].min() == 1.0 and m.index[outside].max() == 0.0
    # the best manipulability of a 2R at radius r is |det J| = a1 a2 |sin q2|, q2 fixed by r
    cos_q2 = (r**2 - A1**2 - A2**2) / (2 * A1 * A2)
    expect = A1 * A2 * np.sqrt(np.clip(1 - cos_q2**2, 0, 1))
    reached = m.index > 0
    assert np.allclose(m.manipulability[reached], expect[reached], atol=1e-6)
    assert np.all(m.manipulability[~reached] == 0.0)


def test_panda_map_agrees_with_fk_sampling(panda, panda_map):
    m = panda_map
    assert m.kind == "pose" and m.orientations == 32 and m.index.shape == m.manipulability.shape == (len(m.centers),)
    assert np.all((m.index >= 0) & (m.index <= 1)) and np.allclose(m.index * 32, np.round(m.index * 32))
    P = panda.positions_batch(panda.random_configurations(3000, np.random.default_rng(9)))
    lo = m.centers.min(axis=0) - m.voxel / 2
    hit = np.unique(np.ravel_multi_index(np.floor((P - lo) / m.voxel).astype(int).T, m.shape))
    assert hit.size > 500
    # voxels FK samples fall in are reached in some orientation, but for boundary voxels whose centre (where the
    # map asks) lies outside the workspace: IK on the centres alone tells which those are
    centre = np.array([r.success for r in ev.solve_many(panda, m.centers[hit], seed=0, timeout=None, max_restarts=3)])
    assert np.mean(m.index[hit] > 0) >= 0.85 and centre.mean() >= 0.85
    assert np.mean(m.index[hit][centre] > 0) >= 0.97
    shoulder = np.array([0.0, 0.0, 0.333])  # the Panda's joint 2, the centre of its reach
    far = np.linalg.norm(m.centers - shoulder, axis=1) > 0.95 + m.voxel  # beyond the arm's stretched length
    assert far.sum() > 100 and m.index[far].max() == 0.0
    assert np.all(m.manipulability[m.index == 0] == 0.0) and np.all(m.manipulability[m.index > 0] > 0.0)
    assert 0.3 < m.index[m.index > 0].mean() < 1.0  # orientations matter: neither all nor hardly any


def test_a_scene_removes_the_voxels_inside_an_obstacle(panda):
    scene = Scene(panda)
    scene.add_box("block", (0.3, 1.2, 0.3), pin.SE3(np.eye(3), np.array([0.6, 0.0, 0.5])))
    free = reachability_map(panda, voxel=0.15, orientations=4, seed=1, progress=False)
    m = reachability_map(panda, voxel=0.15, orientations=4, seed=1, scene=scene, progress=False)
    inside = np.all(np.abs(m.centers - [0.6, 0.0, 0.5]) < [0.15, 0.6, 0.15], axis=1)
    assert inside.sum() >= 2 and free.index[inside].min() > 0  # reached without the block
    assert m.index[inside].max() == 0.0
    assert m.index.sum() < free.index.sum()


def test_files_and_round_trip(planar_map, tmp_path):
    robot = ev.load_robot("planar2r")
    paths = planar_map.save(tmp_path / "out", robot=robot)
    assert paths["npz"].name == "planar2r_reach.npz"
    back = ReachMap.load(paths["npz"])
    assert np.array_equal(back.centers, planar_map.centers) and np.array_equal(back.index, planar_map.index)
    assert back.voxel == 0.02 and back.seed == 0 and back.settings["backend"] == "local"
    with np.load(paths["npz"]) as z:
        assert {"centers", "index", "manipulability", "voxel", "orientations", "seed"} <= set(z.files)
    assert paths["png"].read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    commands = html_commands(paths["html"].read_text())
    clouds = [c for c in commands if c.get("path", "").endswith("/reach") and c["type"] == "set_object"]
    assert len(clouds) == 1
    geometry = clouds[0]["object"]["geometries"][0]
    assert geometry["type"] == "BufferGeometry"
    position = geometry["data"]["attributes"]["position"]["array"].data  # float32 x, y, z of every reached voxel
    assert len(position) == 4 * 3 * int((planar_map.index > 0).sum())


def test_so3_samples_spread_over_rotations():
    R = so3_samples(64)
    assert R.shape == (64, 3, 3)
    assert np.allclose(R.transpose(0, 2, 1) @ R, np.eye(3), atol=1e-12) and np.allclose(np.linalg.det(R), 1.0)
    angles = [np.linalg.norm(pin.log3(R[i].T @ R[j])) for i in range(64) for j in range(i)]
    assert min(angles) > 0.3  # no two alike: a cover of SO(3), not a cluster


def test_cli_reach(tmp_path, capsys):
    assert main(["reach", "planar2r", "--voxel", "0.05", "--out", str(tmp_path), "--no-progress", "--no-html"]) == 0
    out = capsys.readouterr().out
    assert "planar2r:" in out and "voxels of 0.05 m reached" in out
    assert (tmp_path / "planar2r_reach.npz").exists() and (tmp_path / "planar2r_reach.png").exists()
    assert main(["reach", "planar2r", "--voxel", "-1", "--out", str(tmp_path)]) == 2
    assert "voxel" in capsys.readouterr().err
    (tmp_path / "a_file").write_text("")
    assert main(["reach", "planar2r", "--out", str(tmp_path / "a_file" / "maps"), "--no-progress"]) == 2
    assert "cannot create the output directory" in capsys.readouterr().err


@pytest.mark.parametrize("kwargs, match", [({"voxel": 0}, "voxel"), ({"orientations": 0}, "orientations"),
                                           ({"backend": "gpu"}, "backend"), ({"workers": 0}, "workers"),
                                           ({"voxel": 1e-4}, "more than")])
def test_bad_input(kwargs, match):
    with pytest.raises(OptionError, match=match):
        reachability_map("planar2r", progress=False, **kwargs)


def _camera(commands: list[dict]) -> tuple[np.ndarray, np.ndarray]:
    """(position, target) (3,) in m, base frame, of the camera an exported page opens with: meshcat looks at the
    world origin, where the last translation of the /meshcat tree puts the target."""
    shift = [c["matrix"] for c in commands if c["type"] == "set_transform" and c["path"] == "/meshcat"]
    target = -np.asarray(shift[-1], dtype=float).reshape(4, 4, order="F")[:3, 3] if shift else np.zeros(3)
    cam = [c["value"] for c in commands if c["type"] == "set_property" and c["path"].startswith("/Cameras/default")
           and c["property"] == "position"][-1]
    return target + np.array([cam[0], -cam[2], cam[1]]), target  # meshcat's y-up (x, z, -y) back to z-up


def test_html_frames_the_map_not_the_robot(tmp_path):
    """A small map off to one side (1.2 m from the planar 2R's base; its reach is 0.41 m): the page's camera looks
    at the map's box centre from a distance at which the box fills most of the view, the robot aside."""
    from evoik_pin.viz import CAMERA_FOV_DEG

    robot = ev.load_robot("planar2r")
    voxel = 0.02
    axis = (np.arange(5) + 0.5) * voxel
    X, Y = np.meshgrid(1.2 + axis, -0.3 + axis, indexing="ij")
    centers = np.stack([X.ravel(), Y.ravel(), np.zeros(X.size)], axis=1)
    index = np.ones(len(centers))
    index[0] = 0.0  # not reached: outside the box that is framed
    rmap = ReachMap(centers, index, index.copy(), voxel, 1, "planar", 0, robot.name, robot.tip, robot.base, (5, 5, 1),
                    0.0)
    lo, hi = centers[1:].min(axis=0) - voxel / 2, centers[1:].max(axis=0) + voxel / 2
    assert np.allclose(rmap.box(), (lo, hi))
    commands = html_commands(rmap.save_html(tmp_path / "map.html", robot).read_text())
    position, target = _camera(commands)
    assert np.allclose(target, (lo + hi) / 2, atol=1e-6)
    # the box's bounding sphere spans 0.8 of the vertical field of view
    radius = np.linalg.norm(hi - lo) / 2
    assert np.arcsin(radius / np.linalg.norm(position - target)) == pytest.approx(0.8 * np.radians(CAMERA_FOV_DEG) / 2)
    # the grid and the axes moved with the drawing: the robot's base stays at the grid's centre
    for node in ("/Grid", "/Axes"):
        moved = [c["matrix"] for c in commands if c["type"] == "set_transform" and c["path"] == node]
        M = np.asarray(moved[-1]).reshape(4, 4, order="F")
        assert np.allclose(M[:3, 3], -target) and np.allclose(M[:3, :3], np.eye(3))


def test_camera_target_defaults_to_the_origin_and_is_checked(tmp_path):
    from evoik_pin.errors import ConfigurationError, TargetError
    from evoik_pin.viz import Viewer

    robot = ev.load_robot("planar2r")
    with Viewer(robot) as v:
        v.set_camera([1.0, 0.5, 0.5])
        assert not any(c["path"] == "/meshcat" for c in html_commands(v.save_html(tmp_path / "a.html").read_text()))
        v.set_camera([1.0, 0.5, 0.5], target=[0.2, 0.0, 0.1])
        v.set_camera([1.0, 0.5, 0.5])  # back to the origin
        position, target = _camera(html_commands(v.save_html(tmp_path / "b.html").read_text()))
        assert np.allclose(target, 0.0) and np.allclose(position, [1.0, 0.5, 0.5])
        with pytest.raises(ConfigurationError, match="camera target"):
            v.set_camera(target=[0.0, np.nan, 0.0])
        with pytest.raises(TargetError, match="points to frame"):
            v.frame(np.zeros((0, 3)))
