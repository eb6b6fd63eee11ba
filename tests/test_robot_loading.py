"""robot/loading.py: names, the bundled and example-robot-data arms, URDF paths and strings, default tips,
mesh package directories, and bad sources."""

from pathlib import Path

import numpy as np
import pytest

import evoik_pin
from evoik_pin.errors import RobotLoadError, RobotNotFoundError
from evoik_pin.robot import BUNDLED_ROBOTS, EXAMPLE_ARMS, example_robot_data_dir, list_robots, load_robot
from evoik_pin.robot.loading import bundled_robots_dir

ROOT = Path(__file__).resolve().parents[1]


def test_list_robots():
    names = list_robots()
    for required in ["ax18", "planar2r", "puma3r", "redundant7r", "vehicle_arm", "aerial6r",
                     "panda", "ur3", "ur5", "ur10", "kinova", "z1", "xarm", "so_arm"]:
        assert required in names


def test_example_robot_data_dir_from_metadata():
    d = example_robot_data_dir()
    assert (d / "panda_description" / "urdf" / "panda.urdf").is_file()


def test_urdf_string_and_path(tmp_path):
    text = load_robot("planar2r").urdf_xml
    r1 = load_robot(text)
    assert r1.urdf_path is None and r1.n == 2 and r1.tip == "tool"
    f = tmp_path / "arm.urdf"
    f.write_text(text)
    r2 = load_robot(f)
    assert r2.urdf_path == f.resolve() and r2.name == "arm"
    assert np.allclose(r2.fk([0.1, 0.2]).translation, r1.fk([0.1, 0.2]).translation)


def test_bundled_robots_dir_finds_ax18():
    d = bundled_robots_dir()
    assert (d / "ax18.urdf").is_file()
    assert all((d / f"{name}.urdf").is_file() for name in BUNDLED_ROBOTS)
    if Path(evoik_pin.__file__).resolve().parent == ROOT / "src" / "evoik_pin":  # a checkout (editable install)
        assert d == ROOT / "robots"
    else:  # an installed wheel: robots/ is package data (tests/test_packaging.py builds one)
        assert d == Path(evoik_pin.__file__).resolve().parent / "robots"


def test_default_tips():
    for name in BUNDLED_ROBOTS:
        assert load_robot(name).tip == "tool"
    for name in ("panda", "ur5", "kinova"):
        assert load_robot(name).tip == EXAMPLE_ARMS[name].tip
    assert load_robot("panda", tip="panda_link8").tip == "panda_link8"


def test_package_dirs_start_at_the_urdf_file(tmp_path):
    f = tmp_path / "arm.urdf"
    f.write_text(load_robot("planar2r").urdf_xml)
    erd = example_robot_data_dir()
    assert load_robot(f).package_dirs == [str(tmp_path), str(tmp_path.parent), str(erd), str(erd.parents[1])]
    assert load_robot(f.read_text()).package_dirs == [str(erd), str(erd.parents[1])]


# ---------------------------------------------------------------------------- bad input
def test_missing_file():
    with pytest.raises(RobotNotFoundError, match="not found"):
        load_robot("/no/such/arm.urdf")


def test_unknown_name_lists_known_ones():
    with pytest.raises(RobotNotFoundError, match="panda") as info:
        load_robot("pandaa")
    assert "ax18" in str(info.value)


def test_malformed_xml(tmp_path):
    f = tmp_path / "bad.urdf"
    f.write_text("<robot name='x'><link name='a'></robot>")
    with pytest.raises(RobotLoadError, match="malformed URDF XML"):
        load_robot(f)
    with pytest.raises(RobotLoadError, match="expected <robot>"):
        load_robot("<sdf></sdf>")


@pytest.mark.parametrize("name", list(EXAMPLE_ARMS))
def test_example_arm_meshes_resolve(name):
    """Mesh URIs of example-robot-data arms resolve through robot.package_dirs (for the meshcat viewer)."""
    geom = load_robot(name).visual_model
    assert geom.ngeoms > 0
    assert all(not g.meshPath or Path(g.meshPath).is_file() for g in geom.geometryObjects)
