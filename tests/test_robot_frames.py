"""robot/frames.py: frame look-up by name (BODY frames first), the root link, the deepest link, and locking
joints in models whose joints and links share names (anymal_c, b1-z1)."""

import numpy as np
import pinocchio as pin
import pytest
from urdf_helpers import yourdfpy_pose

from evoik_pin.robot import example_robot_data_dir, load_robot
from evoik_pin.robot.frames import deepest_body, find_frame, frame_names, reduced_model, root_link


def _joint(name: str, kind: str, parent: str, child: str, xyz: str, axis: str = "0 0 1") -> str:
    limit = '<limit lower="-3" upper="3" effort="1" velocity="1"/>' if kind == "revolute" else ""
    return (f'<joint name="{name}" type="{kind}"><parent link="{parent}"/><child link="{child}"/>'
            f'<origin xyz="{xyz}"/><axis xyz="{axis}"/>{limit}</joint>')


# joint "b" and link "b" share a name; "tool" is fixed after the last joint's link
URDF = ('<robot name="frames">' + "".join(f'<link name="{link}"/>' for link in ("a", "b", "c", "tool"))
        + _joint("b", "revolute", "a", "b", "0 0 0.3") + _joint("j2", "revolute", "b", "c", "0 0 0.2", "0 1 0")
        + _joint("fix", "fixed", "c", "tool", "0.1 0 0") + "</robot>")


def test_find_frame_prefers_the_body_frame():
    model = pin.buildModelFromXML(URDF)
    same_name = [i for i, f in enumerate(model.frames) if f.name == "b"]
    assert len(same_name) == 2  # the joint frame and the link frame
    i = find_frame(model, "b")
    assert i in same_name and model.frames[i].type == pin.FrameType.BODY
    j = find_frame(model, "j2")
    assert model.frames[j].name == "j2" and model.frames[j].type == pin.FrameType.JOINT
    assert find_frame(model, "nowhere") == -1


def test_body_frames_root_and_deepest():
    model = pin.buildModelFromXML(URDF)
    assert frame_names(model, bodies=True) == ["a", "b", "c", "tool"]
    assert root_link(model) == "a"
    assert deepest_body(model) == "tool"  # the last deepest: the tool fixed after link c


def test_robot_defaults_come_from_the_frames():
    robot = load_robot(URDF)
    assert robot.base == "a" and robot.tip == "tool" and robot.n == 2
    panda = load_robot("panda")
    assert panda.base == root_link(panda.full_model) == "panda_link0"


# ------------------------------------------------------------------------- names shared by joints and links
@pytest.mark.parametrize("urdf, tip, dofs, pin_fails", [
    ("anymal_c_simple_description/urdf/anymal.urdf", "LF_FOOT", ["LF_HAA", "LF_HFE", "LF_KFE"], True),  # joint == link
    ("anymal_c_simple_description/urdf/anymal.urdf", "RH_SHANK", ["RH_HAA", "RH_HFE", "RH_KFE"], True),
    ("b1_description/urdf/b1-z1.urdf", "gripperMover", [f"joint{k}" for k in range(1, 7)] + ["jointGripper"],
     True),  # the fixed joint gripperStator and the link gripperStator
    ("b1_description/urdf/b1-z1.urdf", "gripperStator", [f"joint{k}" for k in range(1, 7)], False),
])
def test_frames_pinocchio_finds_ambiguous_load(urdf, tip, dofs, pin_fails, rng):
    """pin.buildReducedModel looks frames up by name only ("Several frames match the filter"); reduced_model
    renames the clashing joint frames around it, and the chain's FK still equals an independent parser's."""
    path = example_robot_data_dir() / urdf
    if pin_fails:
        with pytest.raises(ValueError, match="Several frames match"):  # why reduced_model exists
            full = pin.buildModelFromUrdf(str(path))
            pin.buildReducedModel(full, [j for j in range(1, full.njoints) if full.names[j] not in dofs],
                                  pin.neutral(full))
    robot = load_robot(path, tip=tip)
    assert robot.joint_names == dofs and robot.tip == tip
    assert [robot.model.names[j] for j in range(1, robot.model.njoints)] == dofs  # names restored
    for q in robot.random_configurations(5, rng):
        assert np.abs(robot.fk(q).homogeneous - yourdfpy_pose(robot, q)).max() < 1e-9
    if "anymal" in urdf:  # the geometry reduction goes through the same renaming (b1's meshes load slowly)
        assert robot.visual_model.ngeoms > 0


def test_reduced_model_keeps_every_frame_name():
    model = pin.buildModelFromXML(URDF)
    reduced = reduced_model(model, [model.getJointId("j2")], pin.neutral(model))
    assert reduced.njoints == 2 and reduced.names[1] == "b"
    assert {f.name for f in reduced.frames} == {f.name for f in model.frames}
    assert [f.name for f in model.frames].count("b") == 2  # the input model is untouched
