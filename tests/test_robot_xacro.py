"""xacro files (robot/urdf_text.py, through xacrodoc): macros, args, properties, includes, $(find pkg), clear
errors naming the file and the package, and nothing on stderr."""

import json

import numpy as np
import pytest

from evoik_pin.cli import main
from evoik_pin.errors import RobotLoadError
from evoik_pin.robot import load_robot

XACRO_NS = 'xmlns:xacro="http://www.ros.org/wiki/xacro"'

PARTS = f"""<?xml version="1.0"?>
<robot {XACRO_NS}>
  <xacro:macro name="revolute_link" params="name parent length axis:='0 0 1'">
    <link name="${{name}}_link"/>
    <joint name="${{name}}" type="revolute">
      <parent link="${{parent}}"/><child link="${{name}}_link"/>
      <origin xyz="0 0 ${{length}}"/><axis xyz="${{axis}}"/>
      <limit lower="-2" upper="2" effort="1" velocity="1"/>
    </joint>
  </xacro:macro>
</robot>
"""

ARM = f"""<?xml version="1.0"?>
<robot name="xarm2" {XACRO_NS}>
  <xacro:arg name="l1" default="0.3"/>
  <xacro:property name="l2" value="0.2"/>
  <xacro:include filename="parts/parts.xacro"/>
  <link name="base"/>
  <xacro:revolute_link name="j1" parent="base" length="$(arg l1)"/>
  <xacro:revolute_link name="j2" parent="j1_link" length="${{l2}}" axis="0 1 0"/>
  <link name="tool"/>
  <joint name="tool_joint" type="fixed"><parent link="j2_link"/><child link="tool"/><origin xyz="0.1 0 0"/></joint>
</robot>
"""


def _plain(l1: float) -> str:
    """The URDF ARM expands to."""
    joint = ('<joint name="{n}" type="revolute"><parent link="{p}"/><child link="{n}_link"/><origin xyz="0 0 {z}"/>'
             '<axis xyz="{a}"/><limit lower="-2" upper="2" effort="1" velocity="1"/></joint>')
    return ('<robot name="xarm2"><link name="base"/><link name="j1_link"/><link name="j2_link"/><link name="tool"/>'
            + joint.format(n="j1", p="base", z=l1, a="0 0 1") + joint.format(n="j2", p="j1_link", z=0.2, a="0 1 0")
            + '<joint name="tool_joint" type="fixed"><parent link="j2_link"/><child link="tool"/>'
              '<origin xyz="0.1 0 0"/></joint></robot>')


@pytest.fixture
def arm_dir(tmp_path):
    (tmp_path / "parts").mkdir()
    (tmp_path / "parts" / "parts.xacro").write_text(PARTS)
    (tmp_path / "arm.urdf.xacro").write_text(ARM)
    return tmp_path


def test_macros_args_properties_and_relative_includes(arm_dir, monkeypatch, capfd):
    monkeypatch.chdir("/")  # includes resolve against the xacro file, not the working directory
    robot = load_robot(arm_dir / "arm.urdf.xacro")
    assert robot.name == "arm" and robot.joint_names == ["j1", "j2"] and robot.tip == "tool"
    assert "xacro" not in robot.urdf_xml and robot.urdf_path == (arm_dir / "arm.urdf.xacro").resolve()
    q = np.array([0.4, -0.7])
    assert np.allclose(robot.fk(q).homogeneous, load_robot(_plain(0.3)).fk(q).homogeneous, atol=1e-12)
    longer = load_robot(arm_dir / "arm.urdf.xacro", xacro_args={"l1": 0.5})
    assert np.allclose(longer.fk(q).homogeneous, load_robot(_plain(0.5)).fk(q).homogeneous, atol=1e-12)
    assert capfd.readouterr().err == ""


def test_plain_xacro_suffix_and_xacro_text(arm_dir):
    (arm_dir / "arm.xacro").write_text(ARM)
    assert load_robot(arm_dir / "arm.xacro").name == "arm"
    text = ARM.replace('<xacro:include filename="parts/parts.xacro"/>', PARTS.split("<robot", 1)[1].split(">", 1)[1]
                       .rsplit("</robot>", 1)[0])
    robot = load_robot(text, xacro_args={"l1": "0.5"})
    assert robot.urdf_path is None and robot.joint_names == ["j1", "j2"]
    assert np.allclose(robot.fk([0.1, 0.2]).translation, load_robot(_plain(0.5)).fk([0.1, 0.2]).translation)


def test_missing_package_is_named(tmp_path, capfd):
    f = tmp_path / "uses_pkg.urdf.xacro"
    f.write_text(f'<robot name="m" {XACRO_NS}><xacro:include filename="$(find missing_pkg)/urdf/parts.xacro"/>'
                 '<link name="base"/></robot>')
    message = r"package 'missing_pkg' not found \(used as \$\(find missing_pkg\)\)"
    with pytest.raises(RobotLoadError, match=message) as e:
        load_robot(f)
    assert str(f) in str(e.value)
    assert capfd.readouterr().err == ""


def test_find_resolves_a_package_above_the_file(tmp_path, tmp_path_factory):
    pkg = tmp_path / "my_arm_description"
    (pkg / "urdf" / "parts").mkdir(parents=True)
    (pkg / "package.xml").write_text("<package><name>my_arm_description</name></package>")
    (pkg / "urdf" / "parts" / "parts.xacro").write_text(PARTS)
    (pkg / "urdf" / "arm.urdf.xacro").write_text(
        ARM.replace('filename="parts/parts.xacro"', 'filename="$(find my_arm_description)/urdf/parts/parts.xacro"'))
    assert load_robot(pkg / "urdf" / "arm.urdf.xacro").joint_names == ["j1", "j2"]
    # the package finder is restored: another file (in another tree: a folder named my_arm_description beside
    # one of the file's folders would be found by its name) does not see my_arm_description
    other = tmp_path_factory.mktemp("elsewhere") / "other.xacro"
    other.write_text(f'<robot name="o" {XACRO_NS}><xacro:include filename="$(find my_arm_description)/x.xacro"/>'
                     '</robot>')
    with pytest.raises(RobotLoadError, match="'my_arm_description' not found"):
        load_robot(other)


def test_xacro_errors_name_the_file_and_what_failed(tmp_path, capfd):
    f = tmp_path / "bad.xacro"
    f.write_text(f'<robot name="b" {XACRO_NS}><link name="$(arg needed)"/></robot>')
    with pytest.raises(RobotLoadError, match="needed") as e:
        load_robot(f)
    assert str(f) in str(e.value) and "xacro_args" in str(e.value)
    f.write_text(f'<robot name="b" {XACRO_NS}><link name="${{undefined_property}}"/></robot>')
    with pytest.raises(RobotLoadError, match="undefined_property"):
        load_robot(f)
    f.write_text(f'<robot name="b" {XACRO_NS}><xacro:include filename="nowhere.xacro"/></robot>')
    with pytest.raises(RobotLoadError, match="nowhere.xacro"):
        load_robot(f)
    f.write_text(f'<robot name="b" {XACRO_NS}><link name="a"></robot>')
    with pytest.raises(RobotLoadError, match="cannot expand xacro file"):
        load_robot(f)
    assert capfd.readouterr().err == ""


def test_xacro_args_need_a_xacro_source():
    with pytest.raises(RobotLoadError, match="not a xacro file"):
        load_robot("ax18", xacro_args={"a": 1})


def test_cli_xacro_arg(arm_dir, capsys):
    path = str(arm_dir / "arm.urdf.xacro")
    assert main(["fk", path, "--rad", "--q", "0.4", "-0.7", "--xacro-arg", "l1=0.5", "--json"]) == 0
    info = json.loads(capsys.readouterr().out)
    assert np.allclose(info["position_m"], load_robot(_plain(0.5)).fk([0.4, -0.7]).translation)
    assert main(["fk", path, "--xacro-arg", "l1"]) == 2
    assert "NAME=VALUE" in capsys.readouterr().err


def test_xacro_is_recognised_by_its_constructs_not_its_namespace(arm_dir):
    (arm_dir / "named_urdf.urdf").write_text(ARM)  # xacro content in a .urdf file
    assert load_robot(arm_dir / "named_urdf.urdf").joint_names == ["j1", "j2"]
    panda = load_robot("panda").urdf_xml  # generated by xacro: keeps xmlns:xacro, has ${...} only in comments
    assert 'xmlns:xacro="http://www.ros.org/wiki/xacro"' in panda
    assert load_robot(panda).urdf_xml == panda  # not run through xacro (which would rewrite it)
    with pytest.raises(RobotLoadError, match="not a xacro file"):
        load_robot(panda, xacro_args={"a": 1})
