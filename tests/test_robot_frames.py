"""robot/frames.py: frame look-up by name (BODY frames first), the root link, the deepest link."""

import pinocchio as pin

from evoik_pin.robot import load_robot
from evoik_pin.robot.frames import body_frame_names, deepest_body, find_frame, root_link


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
    assert body_frame_names(model) == ["a", "b", "c", "tool"]
    assert root_link(model) == "a"
    assert deepest_body(model) == "tool"  # the last deepest: the tool fixed after link c


def test_robot_defaults_come_from_the_frames():
    robot = load_robot(URDF)
    assert robot.base == "a" and robot.tip == "tool" and robot.n == 2
    panda = load_robot("panda")
    assert panda.base == root_link(panda.full_model) == "panda_link0"
