"""viz.py with collision scenes: obstacles drawn in the base frame, links in collision red (checked in the static
HTML export), bad input, and a headless-Chromium screenshot of the exported Panda + shelf scene."""

from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest
import test_viz as tv  # the viewer fixture and the browser helpers

from evoik_pin.errors import ConfigurationError, SceneError
from evoik_pin.robot import load_robot
from evoik_pin.scene import Scene
from evoik_pin.viz import COLLISION_RGBA, OBSTACLE_RGBA

ROOT = Path(__file__).resolve().parents[1]
SHELF = ROOT / "examples" / "panda_shelf.yaml"
#: A Panda configuration whose links 5 and 6 go through the shelf's top panel (and nothing else collides).
Q_IN_SHELF_TOP = np.array([0.0, 0.5, 0.0, -1.2, 0.0, 1.7, 0.8])
viewers = tv.viewers


@pytest.fixture(scope="module")
def panda():
    return load_robot("panda")


@pytest.fixture(scope="module")
def shelf(panda):
    return Scene.from_file(panda, SHELF)


def _hex(rgba) -> int:
    """The colour Pinocchio's visualizer gives a material of ``rgba``."""
    return sum(int(c * 255) << s for c, s in zip(rgba[:3], (16, 8, 0), strict=True))


def _set_objects(cmds) -> dict[str, dict]:
    return {c["path"]: c["object"] for c in cmds if c["type"] == "set_object"}


def _vertices(obj) -> np.ndarray:
    return np.frombuffer(obj["geometries"][0]["data"]["attributes"]["position"]["array"].data,
                         dtype=np.float32).reshape(-1, 3)


# ---------------------------------------------------------------------------------------------- the scene tree
def test_every_obstacle_kind_is_drawn_grey_in_the_base_frame(viewers, tmp_path):
    import trimesh

    robot = load_robot("panda", base="panda_link2", tip="panda_link8")  # its base frame is not the URDF's root
    mesh = tmp_path / "cube.stl"
    trimesh.creation.box(extents=(0.1, 0.1, 0.1)).export(mesh)
    pose = pin.SE3(pin.rpy.rpyToMatrix(0.3, -0.2, 1.1), np.array([0.3, 0.1, 0.2]))
    scene = (Scene(robot).add_box("box", (0.1, 0.2, 0.3), pose).add_sphere("ball", 0.05, pose)
             .add_cylinder("post", 0.03, 0.4, pose).add_capsule("bar", 0.02, 0.3, pose)
             .add_mesh("bin", mesh, pose, scale=(2.0, 1.0, 0.5)))
    v = viewers(robot, skeleton=True)
    nodes = v.show_scene(scene)
    assert nodes == [f"scene/visuals/{name}" for name in ("box", "ball", "post", "bar", "bin")]
    assert v.scene == {"scene": "5 obstacle(s): box, ball, post, bar, bin"}
    cmds = tv._scene(v, tmp_path)
    objects = _set_objects(cmds)
    kinds = {"box": "BoxGeometry", "ball": "SphereGeometry", "post": "CylinderGeometry", "bar": "BufferGeometry",
             "bin": "BufferGeometry"}
    group = tv._transform(cmds, "/meshcat/scene")
    for name, geometry in kinds.items():
        obj = objects[f"/meshcat/scene/visuals/{name}"]
        assert obj["geometries"][0]["type"] == geometry
        material = obj["materials"][0]
        assert material["color"] == _hex(OBSTACLE_RGBA) and material["transparent"]
        assert material["opacity"] == pytest.approx(OBSTACLE_RGBA[3])
        placed = group @ tv._transform(cmds, f"/meshcat/scene/visuals/{name}")  # in the viewer's (base) frame
        assert np.allclose(placed, pose.homogeneous, atol=1e-9), name
    # cylinders and capsules lie along the pose's z; the mesh keeps its scale
    post = np.array(objects["/meshcat/scene/visuals/post"]["object"]["matrix"]).reshape(4, 4).T
    assert np.allclose(np.abs(post[:3, :3] @ [0.0, 1.0, 0.0]), [0.0, 0.0, 1.0])  # meshcat's cylinders run along y
    assert np.allclose(np.ptp(_vertices(objects["/meshcat/scene/visuals/bar"]), axis=0), [0.04, 0.04, 0.34],
                       atol=1e-3)
    assert np.allclose(np.ptp(_vertices(objects["/meshcat/scene/visuals/bin"]), axis=0), [0.2, 0.1, 0.05], atol=1e-6)

    v.show_scene(scene.remove("bin").remove("bar"))  # drawn again: the group is replaced
    objects = _set_objects(tv._scene(v, tmp_path))
    assert {p for p in objects if p.startswith("/meshcat/scene/")} == {
        "/meshcat/scene/visuals/box", "/meshcat/scene/visuals/ball", "/meshcat/scene/visuals/post"}


def test_links_in_collision_are_red_and_get_their_colours_back(panda, shelf, viewers, tmp_path):
    v = viewers(panda)
    pairs = v.show(Q_IN_SHELF_TOP, scene=shelf)
    assert set(pairs) == {("panda_link5", "shelf_top"), ("panda_link6", "shelf_top")}
    assert v.scene["robot"] == "robot, links in collision (red): panda_link5, panda_link6"
    assert v.scene["scene"].startswith("6 obstacle(s): table")  # drawn by show
    objects = _set_objects(tv._scene(v, tmp_path))
    red = {p for p, o in objects.items() if p.startswith("/meshcat/robot/") and o.get("materials")
           and o["materials"][0]["color"] == _hex(COLLISION_RGBA)}
    assert red == {"/meshcat/robot/visuals/panda_link5_0", "/meshcat/robot/visuals/panda_link6_0"}
    assert objects["/meshcat/robot/visuals/panda_link4_0"]["object"]["type"] == "_meshfile_object"  # its own colours
    assert len([p for p in objects if p.startswith("/meshcat/scene/visuals/")]) == 6

    free = np.array([0.0, -0.3, 0.0, -2.2, 0.0, 2.0, 0.8]) + [0, 0, 0, 0.6, 0, -0.4, 0]
    assert v.show(free, scene=shelf) == [] and v.scene["robot"] == "robot"
    assert v.show(Q_IN_SHELF_TOP, scene=shelf)  # red again
    v.show(Q_IN_SHELF_TOP)  # no scene: the robot's own colours
    objects = _set_objects(tv._scene(v, tmp_path))
    assert all(objects[f"/meshcat/robot/visuals/panda_link{k}_0"]["object"]["type"] == "_meshfile_object"
               for k in (5, 6))
    assert "/meshcat/scene/visuals/table" in objects  # the obstacles stay until deleted


def test_a_skeleton_is_red_on_the_joints_carrying_the_links_in_collision(panda, shelf, viewers, tmp_path):
    v = viewers(panda, skeleton=True)
    v.show(Q_IN_SHELF_TOP, scene=shelf, margin=0.0)
    objects = _set_objects(tv._scene(v, tmp_path))
    red = {p.rsplit("/", 1)[1] for p, o in objects.items()
           if p.startswith("/meshcat/robot/") and o["materials"][0]["color"] == _hex(COLLISION_RGBA)}
    # links 5 and 6 ride on joints 5 and 6: their spheres, and the cylinder from joint 6 on to joint 7
    assert {"skeleton_panda_joint5", "skeleton_panda_joint6", "skeleton_to_panda_joint7"} <= red
    assert not red & {"skeleton_panda_joint4", "skeleton_to_panda_joint5", "skeleton_panda_joint2"}


def test_bad_scenes_are_clear_errors_and_draw_nothing(panda, shelf, viewers):
    v = viewers(panda, skeleton=True)
    with pytest.raises(SceneError, match="scene must be an evoik_pin.Scene, got str"):
        v.show_scene("examples/panda_shelf.yaml")
    ur5 = load_robot("ur5")
    with pytest.raises(SceneError, match="built for"):
        v.show(np.zeros(7), scene=Scene(ur5))
    with pytest.raises(SceneError, match="margin"):
        v.show(np.zeros(7), scene=shelf, margin=-0.01)
    with pytest.raises(ConfigurationError, match="opacity"):
        v.show_scene(shelf, opacity=0.0)
    assert v.scene == {}
    # the same arm loaded again is the same chain: its scene draws
    v.show(np.zeros(7), scene=Scene.from_file(load_robot("panda"), SHELF))
    assert v.scene["robot"] == "robot" and "scene" in v.scene


# ---------------------------------------------------------------------------------------------- browser
def _box_corners(ob) -> np.ndarray:
    half = np.array(ob.params["size"]) / 2
    signs = np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)])
    return (ob.pose.rotation @ (signs * half).T).T + ob.pose.translation


def _region(points: np.ndarray, camera: np.ndarray, pad: int = 0) -> tuple[slice, slice]:
    px = tv._project(points, camera)
    x0, y0 = np.floor(px.min(axis=0) - pad).astype(int).clip(0)
    x1, y1 = np.ceil(px.max(axis=0) + pad).astype(int)
    return slice(y0, min(y1, tv.HEIGHT)), slice(x0, min(x1, tv.WIDTH))


def test_browser_shows_the_obstacles_grey_and_the_links_in_collision_red(panda, shelf, tmp_path):
    """The exported Panda + shelf scene, opened by headless Chromium: grey where the camera sees the obstacles (and
    nothing changed elsewhere), red where it sees links 5 and 6 of a configuration through the shelf's top."""
    from evoik_pin.viz import Viewer

    chromium = tv._chromium()
    camera = np.array([1.0, 1.6, 1.1])  # m: beside and in front of the arm, the shelf on the left
    with Viewer(panda) as v:
        v.set_camera(camera)
        jobs = [(v.save_html(tmp_path / "empty.html"), tmp_path / "empty.png")]
        v.show_scene(shelf)
        jobs.append((v.save_html(tmp_path / "shelf.html"), tmp_path / "shelf.png"))
        v.show(Q_IN_SHELF_TOP, scene=shelf)
        jobs.append((v.save_html(tmp_path / "collision.html"), tmp_path / "collision.png"))
    with ThreadPoolExecutor(max_workers=len(jobs)) as pool:  # the Chromiums run side by side
        empty, with_shelf, collision = pool.map(lambda job: tv._screenshot(chromium, *job), jobs)

    top = empty[5:15, 5:100].mean(axis=(0, 1))  # meshcat's sky-blue background: WebGL did render
    assert top[2] > 200 and top[2] > top[0] + 40, f"no WebGL rendering (background {top}); see {tmp_path}"
    changed = np.abs(with_shelf - empty).sum(axis=2) > 30
    grey = changed & (np.ptp(with_shelf, axis=2) < 30) & (with_shelf.min(axis=2) > 70)
    obstacles = shelf.obstacles
    shelf_box = _region(np.concatenate([_box_corners(o) for n, o in obstacles.items() if n.startswith("shelf")]),
                        camera)
    assert grey[shelf_box].mean() > 0.8, f"the shelf is not grey in its region {shelf_box}; see {tmp_path}"
    everything = _region(np.concatenate([_box_corners(o) for o in obstacles.values()]), camera, pad=5)
    assert grey[everything].sum() > 30000, f"too few grey pixels; see {tmp_path}"
    assert changed[everything].sum() > 0.99 * changed.sum(), f"pixels changed outside the obstacles; see {tmp_path}"

    def red(image):
        return (image[..., 0] > 150) & (image[..., 1] < 70) & (image[..., 2] < 70)

    new_red = red(collision) & ~red(with_shelf)  # the x axis of meshcat's triad is red in every image
    data = panda.model.createData()
    pin.forwardKinematics(panda.model, data, panda.to_pinocchio(Q_IN_SHELF_TOP))
    # link 5 reaches from the elbow (joint 4) to the wrist, link 6 from there to joint 7
    links = _region(np.array([data.oMi[j].translation for j in (4, 5, 6, 7)]), camera, pad=40)
    assert new_red[links].sum() > 500, f"no red links in their region {links}; see {tmp_path}"
    assert new_red[links].sum() > 0.95 * new_red.sum(), f"red outside the colliding links' region; see {tmp_path}"
