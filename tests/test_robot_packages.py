"""ROS packages named by robot files ($(find pkg), package://pkg/...) found without ROS: given folders
(package_dirs, --package-dir), ROS_PACKAGE_PATH, the file's own tree, a package.xml; clear errors naming the
package, the file naming it and the folders searched (robot/packages.py, urdf_text.py, loading.py)."""

import json
from pathlib import Path

import numpy as np
import pytest

from evoik_pin.cli import main
from evoik_pin.errors import RobotLoadError, RobotNotFoundError
from evoik_pin.robot import load_robot

NS = 'xmlns:xacro="http://www.ros.org/wiki/xacro"'

# my_pkg/urdf/arm.xacro: a 2R arm macro whose links have meshes under package://my_pkg/meshes/
ARM_MACRO = f"""<?xml version="1.0"?>
<robot {NS}>
  <xacro:macro name="two_link_arm" params="parent length">
    <link name="l1"><visual><geometry><mesh filename="package://my_pkg/meshes/l1.stl"/></geometry></visual></link>
    <link name="l2"/>
    <joint name="j1" type="revolute"><parent link="${{parent}}"/><child link="l1"/><axis xyz="0 0 1"/>
      <limit lower="-2" upper="2" effort="1" velocity="1"/></joint>
    <joint name="j2" type="revolute"><parent link="l1"/><child link="l2"/><origin xyz="${{length}} 0 0"/>
      <axis xyz="0 0 1"/><limit lower="-2" upper="2" effort="1" velocity="1"/></joint>
  </xacro:macro>
</robot>
"""
TOP = f"""<?xml version="1.0"?>
<robot name="top" {NS}>
  <xacro:include filename="$(find my_pkg)/urdf/arm.xacro"/>
  <link name="base"/>
  <xacro:two_link_arm parent="base" length="0.3"/>
</robot>
"""
STL = """solid t
facet normal 0 0 1
outer loop
vertex 0 0 0
vertex 0.1 0 0
vertex 0 0.1 0
endloop
endfacet
endsolid t
"""


def _package(root: Path, length: float = 0.3, package_xml: str | None = None) -> Path:
    """A ROS package ``my_pkg`` (no package.xml unless given) at ``root``: the arm macro and a mesh."""
    (root / "urdf").mkdir(parents=True)
    (root / "meshes").mkdir()
    (root / "urdf" / "arm.xacro").write_text(ARM_MACRO.replace("${length}", str(length))
                                              if length != 0.3 else ARM_MACRO)
    (root / "meshes" / "l1.stl").write_text(STL)
    if package_xml is not None:
        (root / "package.xml").write_text(f"<package><name>{package_xml}</name></package>")
    return root


def _top(folder: Path, text: str = TOP) -> Path:
    folder.mkdir(parents=True, exist_ok=True)
    (folder / "top.urdf.xacro").write_text(text)
    return folder / "top.urdf.xacro"


def _mesh_files(robot) -> list[str]:
    return [g.meshPath for g in robot.visual_model.geometryObjects if g.meshPath]


def test_a_package_beside_the_files_tree_needs_no_package_xml(tmp_path, monkeypatch):
    monkeypatch.delenv("ROS_PACKAGE_PATH", raising=False)
    pkg = _package(tmp_path / "ws" / "my_pkg")
    top = _top(tmp_path / "ws" / "robot_description" / "robots")  # my_pkg sits beside an ancestor folder
    robot = load_robot(top)
    assert robot.joint_names == ["j1", "j2"] and robot.tip == "l2"
    assert robot.packages == {"my_pkg": str(pkg.resolve())}
    assert _mesh_files(robot) == [str((pkg / "meshes" / "l1.stl").resolve())]


def test_a_folder_named_like_the_package_above_the_file(tmp_path, monkeypatch):
    monkeypatch.delenv("ROS_PACKAGE_PATH", raising=False)
    pkg = _package(tmp_path / "my_pkg")
    top = _top(pkg / "robots")  # the file is inside my_pkg itself
    assert load_robot(top).packages == {"my_pkg": str(pkg.resolve())}


def test_package_dirs_and_ros_package_path(tmp_path, monkeypatch, capsys):
    monkeypatch.delenv("ROS_PACKAGE_PATH", raising=False)
    shelf = tmp_path / "shelf"
    pkg = _package(shelf / "my_pkg")
    top = _top(tmp_path / "robot" / "urdf")  # my_pkg is nowhere in the file's tree
    with pytest.raises(RobotLoadError, match="package 'my_pkg' not found"):
        load_robot(top)
    for dirs in (shelf, [str(shelf)], [pkg]):  # a folder holding my_pkg/, or my_pkg itself
        robot = load_robot(top, package_dirs=dirs)
        assert robot.packages == {"my_pkg": str(pkg.resolve())} and _mesh_files(robot)
    monkeypatch.setenv("ROS_PACKAGE_PATH", f"/no/such/folder:{shelf}")
    assert load_robot(top).joint_names == ["j1", "j2"]
    monkeypatch.delenv("ROS_PACKAGE_PATH")
    assert main(["fk", str(top), "--package-dir", str(shelf), "--rad", "--q", "0.1", "0.2", "--json"]) == 0
    assert np.allclose(json.loads(capsys.readouterr().out)["position_m"],
                       load_robot(top, package_dirs=shelf).fk([0.1, 0.2]).translation)


def test_given_folders_come_before_the_files_tree(tmp_path, monkeypatch):
    monkeypatch.delenv("ROS_PACKAGE_PATH", raising=False)
    _package(tmp_path / "ws" / "my_pkg")  # length 0.3, found by the tree rule
    other = _package(tmp_path / "elsewhere" / "my_pkg", length=0.5)
    top = _top(tmp_path / "ws" / "robots")
    assert np.allclose(load_robot(top).fk([0.0, 0.0]).translation, [0.3, 0, 0])
    assert np.allclose(load_robot(top, package_dirs=[other.parent]).fk([0.0, 0.0]).translation, [0.5, 0, 0])
    monkeypatch.setenv("ROS_PACKAGE_PATH", str(other.parent))
    assert np.allclose(load_robot(top).fk([0.0, 0.0]).translation, [0.5, 0, 0])


def test_a_package_xml_names_a_differently_named_folder(tmp_path, monkeypatch):
    """ROS's rule (the ridgeback case): package my_pkg lives in folder clearpath_my_pkg, found by its
    package.xml while walking up from the file; its mesh URIs resolve there too."""
    monkeypatch.delenv("ROS_PACKAGE_PATH", raising=False)
    pkg = _package(tmp_path / "clearpath_my_pkg", package_xml="my_pkg")
    robot = load_robot(_top(pkg / "urdf" / "robots"))
    assert robot.packages == {"my_pkg": str(pkg.resolve())}
    assert _mesh_files(robot) == [str((pkg / "meshes" / "l1.stl").resolve())]


def test_a_missing_package_names_itself_the_file_naming_it_and_the_folders_searched(tmp_path, monkeypatch, capfd):
    monkeypatch.delenv("ROS_PACKAGE_PATH", raising=False)
    shelf = tmp_path / "shelf"
    shelf.mkdir()
    pkg = _package(tmp_path / "ws" / "my_pkg")
    # the package that cannot be found is named by the included file, not by the file loaded
    (pkg / "urdf" / "arm.xacro").write_text(ARM_MACRO.replace(
        "<xacro:macro", '<xacro:include filename="$(find absent_pkg)/urdf/x.xacro"/>\n  <xacro:macro', 1))
    top = _top(tmp_path / "ws" / "robots")
    with pytest.raises(RobotLoadError) as e:
        load_robot(top, package_dirs=[shelf])
    text = str(e.value)
    assert "package 'absent_pkg' not found" in text and "$(find absent_pkg)" in text
    assert str((pkg / "urdf" / "arm.xacro").resolve()) in text  # the file naming it
    assert str(shelf.resolve()) in text and "ROS_PACKAGE_PATH" in text and str(top.parent.resolve()) in text
    assert capfd.readouterr().err == ""


def test_a_missing_mesh_package_loads_and_fails_only_for_meshes(tmp_path, monkeypatch):
    monkeypatch.delenv("ROS_PACKAGE_PATH", raising=False)
    f = tmp_path / "arm.urdf"
    f.write_text('<robot name="a"><link name="base"/><link name="l1"><visual><geometry>'
                 '<mesh filename="package://gone_pkg/meshes/l1.stl"/></geometry></visual></link>'
                 '<joint name="j1" type="revolute"><parent link="base"/><child link="l1"/><axis xyz="0 0 1"/>'
                 '<limit lower="-1" upper="1" effort="1" velocity="1"/></joint></robot>')
    robot = load_robot(f)  # IK needs no mesh
    assert robot.packages == {} and list(robot.missing_packages) == ["gone_pkg"]
    with pytest.raises(RobotLoadError, match=r"package 'gone_pkg' not found \(used as package://gone_pkg/"):
        _ = robot.visual_model


def test_missing_macros_are_named(tmp_path, monkeypatch):
    monkeypatch.delenv("ROS_PACKAGE_PATH", raising=False)
    _package(tmp_path / "ws" / "my_pkg")
    top = _top(tmp_path / "ws" / "robots", TOP.replace("xacro:two_link_arm", "xacro:three_link_arm"))
    with pytest.raises(RobotLoadError, match="three_link_arm"):
        load_robot(top)
    # a file that only defines macros (it has a robot name, but makes no link) names them
    macros = tmp_path / "ws" / "my_pkg" / "urdf" / "arm.xacro"
    macros.write_text(ARM_MACRO.replace("<robot ", '<robot name="arm" '))
    with pytest.raises(RobotLoadError, match="defines the xacro macro.*two_link_arm.*calls none"):
        load_robot(macros)


def test_bad_package_dirs(tmp_path):
    with pytest.raises(RobotNotFoundError, match="no_such_dir"):
        load_robot("planar2r", package_dirs=[tmp_path / "no_such_dir"])
    with pytest.raises(RobotLoadError, match="package_dirs"):
        load_robot("planar2r", package_dirs=[3])
    assert main(["fk", "planar2r", "--package-dir", str(tmp_path / "nope"), "--q", "0", "0"]) != 0


def test_a_package_shipped_under_another_name_loads_with_an_alias(tmp_path, monkeypatch, capsys):
    """rtb-data ships the packages its KUKA and irb140 xacros name (kuka_<model>_support, abb_irb140) under other
    folder names with no package.xml naming them: an alias says which name to look for."""
    monkeypatch.delenv("ROS_PACKAGE_PATH", raising=False)
    pkg = _package(tmp_path / "ws" / "arm_files")
    top = _top(tmp_path / "ws" / "robots")
    with pytest.raises(RobotLoadError) as e:
        load_robot(top)
    assert "package_aliases={'my_pkg': 'that_name'}" in str(e.value) and "--package-alias my_pkg=" in str(e.value)
    robot = load_robot(top, package_aliases={"my_pkg": "arm_files"})
    assert robot.joint_names == ["j1", "j2"]
    assert robot.packages == {"my_pkg": str(pkg.resolve())}  # the mesh URIs resolve through the alias too
    assert _mesh_files(robot) == [str((pkg / "meshes" / "l1.stl").resolve())]
    with pytest.raises(RobotLoadError, match=r"looked for as 'nowhere_pkg': package_aliases"):
        load_robot(top, package_aliases={"my_pkg": "nowhere_pkg"})
    for bad in ({"my_pkg": ""}, {"my_pkg": "a/b"}, ["my_pkg"], {3: "x"}):
        with pytest.raises(RobotLoadError, match="package_aliases"):
            load_robot(top, package_aliases=bad)
    assert main(["fk", str(top), "--package-alias", "my_pkg=arm_files", "--rad", "--q", "0.1", "0.2",
                 "--json"]) == 0
    assert np.allclose(json.loads(capsys.readouterr().out)["position_m"], robot.fk([0.1, 0.2]).translation)
    assert main(["fk", str(top), "--package-alias", "my_pkg", "--q", "0", "0"]) != 0
    assert "--package-alias needs NAME=SHIPPED_AS" in capsys.readouterr().err


@pytest.mark.parametrize(("named", "shipped"), [("my_pkg_support", "my_pkg"), ("my_pkg", "my_pkg_description"),
                                                ("my_pkg_support", "my_pkg_description")])
def test_a_package_shipped_under_a_sibling_name_is_found_without_an_alias(tmp_path, monkeypatch, named, shipped):
    """ROS-Industrial's <robot>_support and <robot>_description packages are shipped one as the other (rtb-data's
    KUKA and irb140 xacros): a package no rule finds is looked for under those names."""
    from evoik_pin.robot.packages import sibling_names

    monkeypatch.delenv("ROS_PACKAGE_PATH", raising=False)
    pkg = _package(tmp_path / "ws" / shipped)
    (pkg / "urdf" / "arm.xacro").write_text(ARM_MACRO.replace("package://my_pkg/", f"package://{named}/"))
    top = _top(tmp_path / "ws" / "robots", TOP.replace("$(find my_pkg)", f"$(find {named})"))
    robot = load_robot(top)
    assert robot.packages == {named: str(pkg.resolve())}
    assert shipped in sibling_names(named) and named not in sibling_names(named)
    exact = _package(tmp_path / "ws" / named, length=0.5)  # a package of the exact name wins over a sibling
    (exact / "urdf" / "arm.xacro").write_text(ARM_MACRO.replace("package://my_pkg/", f"package://{named}/")
                                              .replace("${length}", "0.5"))
    assert load_robot(top).packages == {named: str(exact.resolve())}
