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


# ---------------------------------------------------------------------------- encodings and garbage
LATIN1 = ('<?xml version="1.0" encoding="ISO-8859-1"?>\n<!-- bras à deux axes, épaule et coude -->\n'
          '<robot name="bras"><link name="base"/><link name="épaule"/><link name="outil"/>'
          '<joint name="j_épaule" type="revolute"><parent link="base"/><child link="épaule"/><axis xyz="0 0 1"/>'
          '<limit lower="-1" upper="1" effort="1" velocity="1"/></joint>'
          '<joint name="coude" type="revolute"><parent link="épaule"/><child link="outil"/><origin xyz="0.3 0 0"/>'
          '<axis xyz="0 1 0"/><limit lower="-2" upper="2" effort="1" velocity="1"/></joint></robot>\n')


def test_latin1_urdf_honours_its_xml_declaration(tmp_path):
    f = tmp_path / "bras.urdf"
    f.write_bytes(LATIN1.encode("latin-1"))
    with pytest.raises(UnicodeDecodeError):
        f.read_text(encoding="utf-8")  # the old way of reading it
    robot = load_robot(f)
    assert robot.joint_names == ["j_épaule", "coude"] and robot.tip == "outil"
    assert "épaule" in robot.urdf_xml
    assert np.allclose(robot.fk([0.0, 0.0]).translation, [0.3, 0.0, 0.0])
    assert load_robot(LATIN1.encode("latin-1")).joint_names == robot.joint_names  # bytes given directly
    g = tmp_path / "bras16.urdf"  # UTF-16 with a byte-order mark
    g.write_bytes(LATIN1.replace("ISO-8859-1", "UTF-16").encode("utf-16"))
    assert load_robot(g).joint_names == robot.joint_names


@pytest.mark.parametrize("content, message", [
    (bytes(np.random.default_rng(0).integers(0, 256, 4096, dtype=np.uint8)), "not decodable as utf-8"),
    (b"", "is empty"),
    (b"  \n\t ", "is empty"),
    (b"\x7fELF\x02\x01\x01\x00" + bytes(200), "binary file"),
    (b"\x89PNG\r\n\x1a\n" + bytes(range(256)), "binary file"),
    (b'<?xml version="1.0" encoding="klingon"?><robot/>', "unknown encoding 'klingon'"),
    (b'<?xml version="1.0" encoding="ascii"?><robot name="\xe9"/>', "not decodable as ascii"),
    (b"just some text", "malformed URDF XML"),
])
def test_unreadable_files_are_robot_load_errors_naming_the_file(tmp_path, content, message):
    f = tmp_path / "arm.urdf"
    f.write_bytes(content)
    with pytest.raises(RobotLoadError, match=message) as info:
        load_robot(f)
    assert str(f) in str(info.value)


def test_a_directory_is_not_a_missing_file(tmp_path):
    (tmp_path / "urdf").mkdir()
    (tmp_path / "urdf" / "arm.urdf").write_text(load_robot("planar2r").urdf_xml)
    with pytest.raises(RobotLoadError, match="is a directory, not a URDF file.*urdf/arm.urdf"):
        load_robot(tmp_path)
    with pytest.raises(RobotLoadError, match="is a directory"):
        load_robot(str(tmp_path / "urdf"))


def test_default_tips_belong_to_names_not_to_paths(tmp_path):
    panda = load_robot("panda")
    for name in ("panda", "ur5", "ax18"):
        f = tmp_path / f"{name}.urdf"
        f.write_text(load_robot(name).urdf_xml)
        robot = load_robot(f)
        assert robot.name == name and robot.tip == load_robot(robot.urdf_xml).tip  # the file's deepest link
    assert load_robot(tmp_path / "panda.urdf").tip != panda.tip == "panda_hand_tcp"
    assert load_robot(tmp_path / "ax18.urdf").tip == "tool"  # ax18's deepest link happens to be its tool


# ---------------------------------------------------------------------------- what a URDF must be
def _urdf(joints: str, links=("base", "l1", "l2")) -> str:
    return '<robot name="r">' + "".join(f'<link name="{x}"/>' for x in links) + joints + "</robot>"


LIM = '<limit lower="-1" upper="1" effort="1" velocity="1"/>'
J1 = f'<joint name="j1" type="revolute"><parent link="base"/><child link="l1"/><axis xyz="0 0 1"/>{LIM}</joint>'


@pytest.mark.parametrize("joints, links, message", [
    (J1 + f'<joint name="j2" type="revolute"><parent link="l1"/><child link="l2"/><axis xyz="0 0 0"/>{LIM}</joint>',
     None, "joint 'j2' has a zero-length axis '0 0 0'"),
    (J1 + '<joint name="j2" type="revolute"><parent link="l1"/><child link="l2"/>'
          '<limit lower="1" upper="-1" effort="1" velocity="1"/></joint>',
     None, "joint 'j2' has inverted limits: lower 1 > upper -1"),
    (J1 + '<joint name="j2" type="revolute"><parent link="l1"/><child link="l2"/></joint>',
     None, "revolute joint 'j2' has no <limit> element.*type=\"continuous\""),
    (J1 + '<joint name="j2" type="prismatic"><parent link="l1"/><child link="l2"/><limit lower="0" upper="1"/></joint>',
     None, "the <limit> of joint 'j2' has no effort attribute"),
    (J1 + f'<joint name="j2" type="revolute"><parent link="l1"/><child link="l2"/>{LIM}</joint>'
          f'<joint name="j3" type="revolute"><parent link="base"/><child link="l2"/>{LIM}</joint>',
     None, "link 'l2' is the child of two joints, 'j2' and 'j3' \\(a closed loop\\)"),
    (f'<joint name="j1" type="revolute"><parent link="l2"/><child link="l1"/>{LIM}</joint>'
     f'<joint name="j2" type="revolute"><parent link="l1"/><child link="l2"/>{LIM}</joint>',
     None, "links 'l1', 'l2' are not connected to the root link 'base'.*cycle"),
    (J1, None, r"has 2 root links \(links no joint has as child\): 'base', 'l2'"),
    (J1 + J1.replace('child link="l1"', 'child link="l2"'), None, "two joints are named 'j1'"),
    (J1, ("base", "l1", "l1"), "two links are named 'l1'"),
    (J1.replace('type="revolute"', 'type="hinge"'), ("base", "l1"), "type 'hinge'; URDF joint types are revolute"),
    (J1.replace('<axis', '<origin xyz="0 nan 0"/><axis'), ("base", "l1"), "origin xyz of joint 'j1' is '0 nan 0'"),
    (J1.replace('<axis xyz="0 0 1"/>', '<axis xyz="0 1"/>'), ("base", "l1"), "the axis of joint 'j1' is '0 1'"),
    (J1.replace('lower="-1"', 'lower="low"'), ("base", "l1"), "the lower limit of joint 'j1' is 'low'"),
    (J1.replace('child link="l1"', 'child link="l9"'), ("base", "l1"), "child link 'l9', which the file does not"),
    (J1.replace('<parent link="base"/>', ''), ("base", "l1"), "joint 'j1' has no <parent link"),
])
def test_bad_urdfs_say_what_is_wrong(joints, links, message, capfd):
    with pytest.raises(RobotLoadError, match=message) as info:
        load_robot(_urdf(joints, links or ("base", "l1", "l2")))
    assert "URDF string" in str(info.value)
    assert capfd.readouterr().err == ""  # urdfdom's C++ messages do not reach the terminal


def test_urdfdom_messages_go_into_the_error_not_the_terminal(capfd):
    # a bad number in an element we leave to urdfdom: its reasons end up in the error, not on stderr
    bad = _urdf(J1.replace("</joint>", '<dynamics damping="x"/></joint>'), ("base", "l1"))
    with pytest.raises(RobotLoadError, match=r"URDF string: .* urdfdom said: damping value \(x\) is not a valid "
                                             r"float; Could not parse joint_dynamics element for joint \[j1\]"):
        load_robot(bad)
    assert capfd.readouterr().err == ""
    with pytest.raises(RobotLoadError, match="no name attribute"):
        load_robot('<robot><link name="a"/></robot>')
