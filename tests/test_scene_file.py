"""Scene files (YAML / JSON): Scene.from_file, Scene.to_file, the shipped examples/panda_shelf.yaml, bad files."""

import json
import re
import shutil
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest

import evoik_pin as ev
from evoik_pin.errors import SceneError
from evoik_pin.io import scene_file as file
from evoik_pin.scene import Scene
from evoik_pin.scene.examples import add_table_and_shelf

ROOT = Path(__file__).resolve().parents[1]


@pytest.fixture(scope="module")
def panda():
    return ev.load_robot("panda")


@pytest.fixture(scope="module")
def cube(tmp_path_factory):
    """A 10 cm cube STL in meshes/ of a fresh folder."""
    import trimesh

    folder = tmp_path_factory.mktemp("scene")
    (folder / "meshes").mkdir()
    trimesh.creation.box(extents=(0.1, 0.1, 0.1)).export(folder / "meshes" / "bin.stl")
    return folder / "meshes" / "bin.stl"


def _pose(xyz, rpy=(0.0, 0.0, 0.0)):
    return pin.SE3(pin.rpy.rpyToMatrix(*rpy), np.array(xyz, dtype=float))


def _every_kind(panda, mesh: Path) -> Scene:
    scene = Scene(panda)
    scene.add_box("table", (1.6, 1.2, 0.04), _pose([0.3, 0.0, -0.03]))
    scene.add_box("tilted", (0.1, 0.2, 0.3), _pose([0.5, -0.4, 0.3], [0.3, -0.2, 1.1]))
    scene.add_sphere("ball", 0.08, _pose([0.5, 0.3, 0.5]))
    scene.add_cylinder("post", 0.03, 0.8, _pose([-0.4, 0.4, 0.4], [np.pi / 2, 0.0, 0.0]))
    scene.add_capsule("bar", 0.02, 0.5, _pose([0.2, 0.6, 0.7], [0.0, np.pi / 2, 0.3]))
    scene.add_mesh("bin", mesh, _pose([0.6, -0.6, 0.05], [0.0, 0.0, 0.4]), scale=(1.0, 2.0, 0.5))
    scene.add_mesh("bin_mm", mesh, _pose([-0.6, -0.6, 0.05]), scale=0.5)
    return scene


def assert_same_obstacles(a: Scene, b: Scene) -> None:
    assert list(a.obstacles) == list(b.obstacles)
    for name, x in a.obstacles.items():
        y = b.obstacles[name]
        assert (x.kind, x.name) == (y.kind, y.name)
        assert x.params.keys() == y.params.keys()
        for key, value in x.params.items():
            if key == "path":
                assert Path(value).resolve() == Path(y.params[key]).resolve()
            else:
                assert np.allclose(value, y.params[key], rtol=0, atol=1e-15), (name, key)
        assert np.allclose(x.pose.homogeneous, y.pose.homogeneous, rtol=0, atol=1e-12), name
    assert (a.self_collision, a.srdf, a.pair_count) == (b.self_collision, b.srdf, b.pair_count)


# ---------------------------------------------------------------------------------------------- round trips
@pytest.mark.parametrize("suffix", [".yaml", ".yml", ".json"])
def test_round_trip_gives_the_same_obstacles(panda, cube, suffix):
    scene = _every_kind(panda, cube)
    path = scene.to_file(cube.parents[1] / f"every_kind{suffix}")
    again = Scene.from_file(panda, path)
    assert_same_obstacles(scene, again)
    Q = panda.random_configurations(40, np.random.default_rng(0))
    assert (scene.collides(Q) == again.collides(Q)).all()
    text = path.read_text()
    assert "meshes/bin.stl" in text and str(cube.parent) not in text  # written relative to the file's folder
    if suffix == ".json":
        assert json.loads(text)["obstacles"][0]["name"] == "table"


def test_relative_mesh_paths_resolve_against_the_files_folder(panda, cube, tmp_path, monkeypatch):
    scene = _every_kind(panda, cube)
    scene.to_file(cube.parents[1] / "moved.yaml")
    moved = tmp_path / "elsewhere"
    shutil.copytree(cube.parents[1], moved)
    monkeypatch.chdir(tmp_path)  # neither the file's folder nor the original one
    again = Scene.from_file(panda, Path("elsewhere") / "moved.yaml")
    assert Path(again.obstacles["bin"].params["path"]).resolve() == (moved / "meshes" / "bin.stl").resolve()
    assert np.allclose(again.obstacles["bin"].params["scale"], [1.0, 2.0, 0.5])


def test_self_collision_and_srdf_settings_round_trip(panda, tmp_path):
    srdf = tmp_path / "robot.srdf"
    shutil.copy(panda.srdf, srdf)
    scene = Scene(panda, srdf=srdf).add_sphere("ball", 0.05, _pose([0.5, 0.0, 0.5]))
    again = Scene.from_file(panda, scene.to_file(tmp_path / "s.yaml"))
    assert "srdf: robot.srdf" in (tmp_path / "s.yaml").read_text()
    assert_same_obstacles(scene, again)
    obstacles_only = Scene(panda, self_collision=False).add_sphere("ball", 0.05, _pose([0.5, 0.0, 0.5]))
    again = Scene.from_file(panda, obstacles_only.to_file(tmp_path / "o.json"))
    assert not again.self_collision and again.pair_count == obstacles_only.pair_count
    # the robot's own SRDF is the default: not written, found again
    assert "srdf" not in add_table_and_shelf(Scene(panda)).to_file(tmp_path / "d.yaml").read_text()


def test_the_shipped_panda_shelf_equals_the_example_scene(panda):
    shipped = Scene.from_file(panda, ROOT / "examples" / "panda_shelf.yaml")
    assert_same_obstacles(add_table_and_shelf(Scene(panda)), shipped)


def test_the_file_format_knows_every_obstacle_kind_of_the_scene():
    """The file module does not import the Scene (it parses into plain data): each kind it reads is a Scene.add_<kind>
    taking the kind's keys, and every add_<kind> is a kind it reads."""
    import inspect

    assert {m.removeprefix("add_") for m in dir(Scene) if m.startswith("add_")} == set(file.KIND_KEYS)
    for kind, (required, optional) in file.KIND_KEYS.items():
        taken = set(inspect.signature(getattr(Scene, f"add_{kind}")).parameters) - {"self", "name", "pose"}
        assert set(required + optional) == taken


def test_reading_a_file_gives_plain_checked_data():
    spec = file.read_scene(ROOT / "examples" / "panda_shelf.yaml")
    assert isinstance(spec, file.SceneFile) and spec.self_collision is True
    assert [kind for _, kind, _, _ in spec.obstacles] and all(isinstance(pose, pin.SE3) for *_, pose in spec.obstacles)


def test_the_format_in_the_module_docstring_loads(panda, cube):
    """The documented example (every kind, both pose forms, a relative mesh path) is a valid scene file."""
    example = file.__doc__.split("::\n\n", 1)[1].split("\n\n", 1)[0]
    path = cube.parents[1] / "documented.yaml"
    shutil.copy(panda.srdf, path.parent / "panda.srdf")
    path.write_text(re.sub(r"(?m)^    ", "", example))
    scene = Scene.from_file(panda, path)
    assert {o.kind for o in scene.obstacles.values()} == {"box", "sphere", "cylinder", "capsule", "mesh"}
    assert np.allclose(scene.obstacles["bin"].params["scale"], 0.001)
    assert np.allclose(scene.obstacles["bin"].pose.translation, [0.5, -0.3, 0.0])
    assert np.allclose(scene.obstacles["bar"].pose.rotation, pin.rpy.rpyToMatrix(0, 1.5708, 0))


# ---------------------------------------------------------------------------------------------- bad files
GOOD_BOX = "  - {name: table, kind: box, size: [1, 1, 0.04], pose: {xyz: [0.3, 0, -0.03]}}\n"

BAD_FILES = [
    # (text after "obstacles:\n" or a whole file, regex the message must match)
    (GOOD_BOX + "  - {name: ball, kind: sphear, radius: 0.1, pose: {xyz: [0, 0, 1]}}",
     r"obstacle 1 \('ball'\): unknown kind 'sphear'; accepted kinds: box, sphere, cylinder, capsule, mesh"),
    ("  - {name: ball, radius: 0.1, pose: {xyz: [0, 0, 1]}}", r"obstacle 0 \('ball'\): missing kind"),
    ("  - {name: post, kind: cylinder, radius: 0.1, pose: {xyz: [0, 0, 1]}}",
     r"obstacle 0 \('post'\): missing field 'length' \(a cylinder needs radius, length\)"),
    ("  - {name: ball, kind: sphere, radius: 0.1}", r"obstacle 0 \('ball'\): missing field 'pose' \(pose: \{xyz"),
    ("  - {kind: sphere, radius: 0.1, pose: {xyz: [0, 0, 1]}}", r"obstacle 0: missing or empty name"),
    ("  - {name: ball, kind: sphere, radius: big, pose: {xyz: [0, 0, 1]}}",
     r"obstacle 0 \('ball'\): radius \(m\) must be a finite number > 0, got 'big'"),
    ("  - {name: ball, kind: sphere, radius: .nan, pose: {xyz: [0, 0, 1]}}", r"radius \(m\) must be a finite number"),
    ("  - {name: ball, kind: sphere, radius: -0.1, pose: {xyz: [0, 0, 1]}}",
     r"obstacle 0 \('ball'\): radius \(m\) must be a finite number > 0, got -0.1"),
    ("  - {name: b, kind: box, size: [1, 1], pose: {xyz: [0, 0, 1]}}",
     r"obstacle 0 \('b'\): size \(m\) must be a list of 3 numbers > 0, got \[1, 1\]"),
    ("  - {name: b, kind: box, size: [1, 0, 1], pose: {xyz: [0, 0, 1]}}",
     r"obstacle 0 \('b'\): size \(m\)\[1\] must be a finite number > 0, got 0"),
    ("  - {name: ball, kind: sphere, raduis: 0.1, radius: 0.1, pose: {xyz: [0, 0, 1]}}",
     r"obstacle 0 \('ball'\), a sphere: unknown key\(s\) 'raduis'; accepted: name, kind, radius, pose"),
    ("  - {name: ball, kind: sphere, radius: 0.1, pose: {xyz: [0, 0]}}",
     r"obstacle 0 \('ball'\): pose xyz \(m\) must be a list of 3 numbers"),
    ("  - {name: ball, kind: sphere, radius: 0.1, pose: {rpy: [0, 0, 1]}}", r"obstacle 0 \('ball'\): pose needs xyz"),
    ("  - {name: ball, kind: sphere, radius: 0.1, pose: {xyz: [0, 0, 1], quat: [1, 0, 0, 0]}}",
     r"pose: unknown key\(s\) 'quat'; accepted: xyz, rpy"),
    ("  - {name: ball, kind: sphere, radius: 0.1, pose: up there}", r"obstacle 0 \('ball'\): bad pose 'up there'"),
    ("  - {name: ball, kind: sphere, radius: 0.1, pose: [[1, 0.3, 0, 0], [0, 1, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1]]}",
     r"obstacle 0 \('ball'\): pose is not a rigid transform .*scaling and shear are not accepted"),
    ("  - {name: ball, kind: sphere, radius: 0.1, pose: [[1, 0, 0], [0, 1, 0], [0, 0, 1]]}", r"bad pose"),
    (GOOD_BOX + "  - {name: table, kind: sphere, radius: 0.1, pose: {xyz: [0, 0, 1]}}",
     r"obstacle 1 \('table'\): the name 'table' is already obstacle 0's; names must be unique"),
    ("  - {name: panda_hand, kind: sphere, radius: 0.1, pose: {xyz: [0, 0, 1]}}",
     r"obstacle 0 \('panda_hand'\):.*name of one of the robot's links"),
    ("  - {name: bin, kind: mesh, path: meshes/none.stl, pose: {xyz: [0, 0, 1]}}",
     r"obstacle 0 \('bin'\): mesh 'bin': file not found: '.*/meshes/none.stl'"),
    ("  - {name: bin, kind: mesh, path: meshes/bin.stl, scale: 0, pose: {xyz: [0, 0, 1]}}",
     r"obstacle 0 \('bin'\): scale \(one factor or three\) must be a finite number > 0, got 0"),
    ("  - name: ball\n    kind: sphere\n    radius: [0.1\n    pose: {xyz: [0, 0, 1]}",
     r"YAML syntax error at line 6, column 9: while parsing a flow sequence \(begun at line 5, column 13\): "
     r"expected ',' or '\]'"),
    ("  - 3", r"obstacle 0: expected a mapping with name, kind, pose"),
    ("WHOLE units: mm\nobstacles: []",
     r"units: only 'm' is accepted \(lengths in metres, angles in radians\), got 'mm'"),
    ("WHOLE self_collision: maybe\n", r"self_collision must be true or false, got 'maybe'"),
    ("WHOLE obstacle:\n  - {name: ball}\n", r"top level: unknown key\(s\) 'obstacle'; accepted: units, self_collision"),
    ("WHOLE obstacles: {name: ball}\n", r"obstacles must be a list of obstacles"),
    ("WHOLE - {name: ball}\n", r"the top level must be a mapping"),
    ("WHOLE \n", r"the file is empty"),
    ("WHOLE srdf: nowhere.srdf\n", r"SRDF file not found: '.*nowhere.srdf'"),
]


@pytest.mark.parametrize(("text", "match"), BAD_FILES, ids=[m[:40] for _, m in BAD_FILES])
def test_bad_scene_files_name_the_file_the_obstacle_and_the_problem(panda, cube, text, match):
    path = cube.parents[1] / "bad.yaml"
    path.write_text(text[6:] if text.startswith("WHOLE ") else "units: m\nobstacles:\n" + text + "\n")
    with pytest.raises(SceneError, match=match) as info:
        Scene.from_file(panda, path)
    assert str(info.value).startswith(f"scene file {str(path)!r}: ")


def test_bad_json_files_and_paths(panda, tmp_path):
    path = tmp_path / "bad.json"
    path.write_text('{"obstacles": [\n  {"name": "ball", "kind": "sphere" "radius": 0.1}\n]}')
    with pytest.raises(SceneError, match=r"bad.json': JSON syntax error at line 2, column 37"):
        Scene.from_file(panda, path)
    with pytest.raises(SceneError, match=r"unknown extension '.txt'; use .yaml, .yml, .json"):
        Scene.from_file(panda, tmp_path / "scene.txt")
    with pytest.raises(SceneError, match=r"missing.yaml': not found"):
        Scene.from_file(panda, tmp_path / "missing.yaml")
    with pytest.raises(SceneError, match=r"unknown extension"):
        Scene(panda).to_file(tmp_path / "scene.txt")
    with pytest.raises(SceneError, match="Scene needs a loaded Robot"):
        Scene.from_file("panda", ROOT / "examples" / "panda_shelf.yaml")
